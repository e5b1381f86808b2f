//! A rate estimated from real-world timestamps is the amplifier's nominal rate: a CSV whose time
//! column (seconds since 1970, as recorders write them) gives 500.0000x Hz trains a model at
//! 500 Hz, and that model evaluates an EDF of the same EEG and drives `demo --model` (before,
//! the estimate was stored in the model and every other file or stream was "another rate").
//! A CSV whose rate cannot be found says which option gives it.

mod common;

use std::fmt::Write as _;

use common::{oddball, oddball_ok, tmp_dir};

#[test]
fn a_csv_with_wall_clock_timestamps_trains_a_model_at_the_nominal_rate() {
    let tmp = tmp_dir("cli-rates");
    let demo = tmp.join("demo");
    oddball_ok(&[
        "demo",
        "--commands",
        "up,left",
        "--out",
        demo.to_str().unwrap(),
    ]);
    let rec = oddball_io::read(demo.join("session.dat")).unwrap();
    let raw = &rec.raw;
    assert_eq!(raw.sfreq(), 500.0);
    // The CSV a recorder writes: wall-clock seconds (6 decimals), the channels, a marker column
    // (1 target flash, 2 non-target).
    let mut marker = vec![0u32; raw.n_times()];
    for e in raw.events().iter() {
        marker[e.onset] = if e.target == Some(true) { 1 } else { 2 };
    }
    let mut csv = format!("time,{},marker\n", raw.ch_names().join(","));
    let t0 = 1_764_288_000.0_f64;
    for (i, m) in marker.iter().enumerate() {
        write!(csv, "{:.6}", t0 + i as f64 / 500.0).unwrap();
        for c in 0..raw.n_channels() {
            write!(csv, ",{}", raw.data()[[c, i]]).unwrap();
        }
        writeln!(csv, ",{m}").unwrap();
    }
    let csv_path = tmp.join("session.csv");
    std::fs::write(&csv_path, csv).unwrap();
    let back = oddball_io::read(&csv_path).unwrap();
    let estimate = back.csv().unwrap().estimated_sfreq.unwrap();
    println!("estimated from the timestamps: {estimate:.12} Hz");
    assert_ne!(
        estimate, 500.0,
        "the timestamps give an estimate that is not exactly 500"
    );
    assert_eq!(back.raw.sfreq(), 500.0);

    let edf = tmp.join("session.edf");
    oddball_io::write_edf_plus(&edf, raw).unwrap();

    let model = tmp.join("csv.json");
    let events = ["--target-events", "1", "--nontarget-events", "2"];
    let mut train = vec![
        "train",
        csv_path.to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
    ];
    train.extend(events);
    oddball_ok(&train);
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(m["sfreq"], 500.0, "the model's rate is the nominal rate");

    let out = oddball_ok(&[
        "evaluate",
        "--model",
        model.to_str().unwrap(),
        "--test",
        edf.to_str().unwrap(),
    ]);
    println!("{out}");
    assert!(out.contains("session.edf") || out.contains("AUC"), "{out}");

    oddball_ok(&[
        "demo",
        "--model",
        model.to_str().unwrap(),
        "--commands",
        "up,left",
        "--out",
        tmp.join("demo2").to_str().unwrap(),
    ]);
}

#[test]
fn a_csv_whose_rate_cannot_be_found_names_the_option_that_gives_it() {
    let tmp = tmp_dir("cli-rates-none");
    let path = tmp.join("no-time.csv");
    std::fs::write(&path, "Cz,Pz,marker\n1,2,0\n3,4,1\n5,6,0\n").unwrap();
    let (ok, _, err) = oddball(&["inspect", path.to_str().unwrap()]);
    assert!(!ok);
    println!("{err}");
    assert!(err.contains("--sfreq"), "{err}");
}
