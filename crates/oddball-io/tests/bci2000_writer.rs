//! The BCI2000 writer: round trips through the reader (samples bit-exact when they are float32
//! values, events, every state, parameters), a property test, every refusal, the real speller
//! file re-written, and the small file `tools/golden/io/check_written_bci2000.py` checks with
//! the peer reader.

mod common;

use std::path::Path;

use common::{bci2000_file, TempDir};
use ndarray::Array2;
use oddball_io::{
    bci2000::{encode_value, ParamCell},
    read, stimulus_states, write_bci2000, Bci2000WriteOptions, DataFormat, Format, IoError,
    Recording, StateColumn, StateProblem,
};
use oddball_signal::{Event, Events, Raw};
use proptest::prelude::*;

fn raw_of(data: Array2<f64>, sfreq: f64, names: &[&str], events: Vec<Event>) -> Raw {
    let names = names.iter().map(|s| s.to_string()).collect();
    Raw::new(data, sfreq, names, Events::new(events)).unwrap()
}

/// Writes, reads back, and checks what every round trip must keep: format, header, names,
/// rate, samples (equal to their float32 rounding), every state, and the summary.
fn round_trip(
    raw: &Raw,
    states: &[StateColumn],
    options: &Bci2000WriteOptions,
    dir: &Path,
) -> Recording {
    let path = dir.join("rt.dat");
    let summary = write_bci2000(&path, raw, states, options).unwrap();
    assert_eq!(summary.n_samples, raw.n_times());
    assert_eq!(summary.n_channels, raw.n_channels());
    assert_eq!(summary.bytes, std::fs::metadata(&path).unwrap().len());
    let back = read(&path).unwrap();
    assert_eq!(back.format, Format::Bci2000);
    assert_eq!(back.raw.ch_names(), raw.ch_names());
    assert_eq!(back.raw.sfreq(), raw.sfreq());
    assert_eq!(back.raw.n_times(), raw.n_times());
    let mut max_rounding = 0.0f64;
    for ((c, t), &x) in raw.data().indexed_iter() {
        let y = back.raw.data()[[c, t]];
        assert_eq!(y, f64::from(x as f32), "channel {c} sample {t}");
        max_rounding = max_rounding.max((y - x).abs());
    }
    assert_eq!(summary.max_rounding_uv, max_rounding);

    let info = back.bci2000().unwrap();
    assert_eq!(info.header.version, "1.1");
    assert_eq!(info.header.data_format, DataFormat::Float32);
    assert_eq!(info.gains, vec![1.0; raw.n_channels()]);
    assert_eq!(info.offsets, vec![0.0; raw.n_channels()]);
    let bits: u32 = info.states.defs().iter().map(|d| d.length).sum();
    assert_eq!(info.header.statevector_len, bits.div_ceil(8) as usize);
    assert_eq!(
        info.parameters
            .get("StateVectorLength")
            .and_then(|p| p.as_str()),
        Some(info.header.statevector_len.to_string().as_str())
    );
    // States packed bit by bit in the given order, `Running` (all 1) first unless given.
    let mut names: Vec<&str> = states.iter().map(|s| s.name.as_str()).collect();
    if !names.contains(&"Running") {
        names.insert(0, "Running");
        assert_eq!(info.states.get("Running").unwrap(), vec![1; raw.n_times()]);
    }
    assert_eq!(info.states.names(), names);
    let mut bit = 0usize;
    for d in info.states.defs() {
        assert_eq!(
            (d.byte_location, d.bit_location as usize),
            (bit / 8, bit % 8),
            "{}",
            d.name
        );
        assert_eq!(Some(d.default), info.states.value_at(&d.name, 0));
        bit += d.length as usize;
    }
    for s in states {
        let d = info.states.def(&s.name).unwrap();
        assert_eq!(d.length, s.bits, "{}", s.name);
        assert_eq!(info.states.get(&s.name).unwrap(), s.values, "{}", s.name);
    }
    back
}

fn app_parameters() -> Vec<String> {
    vec![
        "Application:Oddball string Paradigm= four-bulb%20oddball // stimulus layout".into(),
        format!(
            "Application:Oddball list BulbNames= 4 up down left {} // one per bulb",
            encode_value("far right")
        ),
        "Application:Oddball matrix BulbDirections= { up down left right } { x y } 0 1 0 -1 -1 0 1 0 // unit vectors".into(),
        "Application:Oddball string Note= % // empty".into(),
        "Source:Signal%20Properties:DataIOFilter int SampleBlockSize= 5 // caller's block".into(),
    ]
}

#[test]
fn synthetic_round_trip() {
    let n = 400;
    // Float32 values (multiples of 1/64 below 2^17), so the round trip is bit-exact.
    let data = Array2::from_shape_fn((4, n), |(c, t)| {
        let x = ((t * 7919 + c * 104_729) % 20_011) as f64 / 64.0 - 150.0;
        if c == 3 {
            x * 1024.0
        } else {
            x
        }
    });
    let events = vec![
        Event::new(0, 1).with_target(false),
        Event::new(10, 12).with_target(true),
        Event::new(40, 3).with_target(false),
        Event::new(47, 4).with_target(true),
        Event::new(49, 7).with_target(false),
        Event::new(399, 2).with_target(true),
    ];
    let raw = raw_of(data, 500.0, &["Fz", "C z", "P%3", "Oz/µ"], events.clone());
    let mut states = stimulus_states(raw.events(), n, 25);
    states.push(StateColumn::new(
        "PhaseInSequence",
        2,
        (0..n as u64).map(|t| (t / 100) % 4).collect(),
    ));
    states.push(StateColumn::new(
        "Wide",
        32,
        (0..n as u64)
            .map(|t| (t * 2_654_435_761) & 0xffff_ffff)
            .collect(),
    ));
    states.push(StateColumn::new(
        "Odd",
        3,
        (0..n as u64).map(|t| t % 8).collect(),
    ));
    let options = Bci2000WriteOptions {
        extra_parameters: app_parameters(),
    };
    let tmp = TempDir::new("bciw-synth");
    let back = round_trip(&raw, &states, &options, tmp.path());
    assert_eq!(back.raw.events().as_slice(), events.as_slice());
    assert!(back.speller.is_none());

    let p = &back.bci2000().unwrap().parameters;
    assert_eq!(
        p.get("Paradigm").unwrap().as_str(),
        Some("four-bulb oddball")
    );
    assert_eq!(p.get("Paradigm").unwrap().section, "Application:Oddball");
    assert_eq!(p.get("Paradigm").unwrap().comment, "stimulus layout");
    assert_eq!(
        p.get("BulbNames").unwrap().list_items().unwrap(),
        vec!["up", "down", "left", "far right"]
    );
    let rows = p.get("BulbDirections").unwrap().matrix_rows().unwrap();
    assert_eq!(rows.len(), 4);
    assert_eq!(
        rows[3],
        vec![ParamCell::Value("1".into()), ParamCell::Value("0".into())]
    );
    assert_eq!(p.get("Note").unwrap().as_str(), Some(""));
    assert_eq!(p.get("SampleBlockSize").unwrap().as_str(), Some("5"));
    assert_eq!(
        p.names()
            .iter()
            .filter(|n| **n == "SampleBlockSize")
            .count(),
        1
    );
    assert_eq!(p.get("SamplingRate").unwrap().as_str(), Some("500Hz"));
    assert_eq!(p.get("SourceCh").unwrap().as_str(), Some("4"));
    assert_eq!(
        p.get("ChannelNames").unwrap().list_items().unwrap(),
        vec!["Fz", "C z", "P%3", "Oz/µ"]
    );

    // The header as BCI2000 lays it out.
    let bytes = std::fs::read(tmp.path().join("rt.dat")).unwrap();
    let hl = back.bci2000().unwrap().header.header_len;
    let head = std::str::from_utf8(&bytes[..hl]).unwrap();
    assert!(
        head.starts_with(&format!(
            "BCI2000V= 1.1 HeaderLen= {hl} SourceCh= 4 StatevectorLen= 6 DataFormat= float32\r\n[ State Vector Definition ]\r\nRunning 1 1 0 0\r\nStimulusCode 8 1 0 1\r\nStimulusType 1 0 1 1\r\n"
        )),
        "{head}"
    );
    assert!(head.ends_with("\r\n\r\n"));
    assert!(!head.replace("\r\n", "").contains('\n'));
    assert!(head.contains(
        "\r\nSource:Signal%20Properties:DataIOFilter list ChannelNames= 4 Fz C%20z P%253 Oz%2f%c2%b5 // list of channel names\r\n"
    ));
    assert!(head.contains(" floatlist SourceChGain= 4 1 1 1 1 //"));
    assert!(head.contains(" floatlist SourceChOffset= 4 0 0 0 0 //"));
}

#[test]
fn rounding_is_reported_and_default_block_size_divides() {
    let data = Array2::from_shape_fn((2, 30), |(c, t)| 0.1 * t as f64 - 1e3 * c as f64);
    let raw = raw_of(data, 256.0, &["a", "b"], vec![]);
    let tmp = TempDir::new("bciw-round");
    let back = round_trip(&raw, &[], &Bci2000WriteOptions::default(), tmp.path());
    assert!(back.raw.events().is_empty());
    let info = back.bci2000().unwrap();
    assert_eq!(info.states.names(), vec!["Running"]);
    assert_eq!(
        info.parameters.get("SampleBlockSize").unwrap().as_str(),
        Some("10")
    );
    // The summary's rounding is the largest error, and within float32's half ulp.
    let s = write_bci2000(
        tmp.path().join("again.dat"),
        &raw,
        &[],
        &Bci2000WriteOptions::default(),
    )
    .unwrap();
    assert!(s.max_rounding_uv > 0.0);
    assert!(s.max_rounding_uv <= 1e3 * f64::from(f32::EPSILON));
}

#[test]
fn running_given_by_the_caller_is_kept_in_place() {
    let raw = raw_of(Array2::zeros((1, 6)), 100.0, &["Cz"], vec![]);
    let states = vec![
        StateColumn::new("StimulusCode", 4, vec![0, 9, 9, 0, 15, 0]),
        StateColumn::new("Running", 1, vec![1, 1, 1, 1, 1, 0]),
    ];
    let tmp = TempDir::new("bciw-running");
    let back = round_trip(&raw, &states, &Bci2000WriteOptions::default(), tmp.path());
    let codes: Vec<(usize, u32, Option<bool>)> = back
        .raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target))
        .collect();
    // No StimulusType state: the reader leaves the target unknown.
    assert_eq!(codes, vec![(1, 9, None), (4, 15, None)]);
}

#[test]
fn overwrites_an_existing_file_without_leftovers() {
    let tmp = TempDir::new("bciw-over");
    let path = tmp.write("x.dat", b"old contents");
    let raw = raw_of(Array2::ones((1, 3)), 10.0, &["Cz"], vec![]);
    write_bci2000(&path, &raw, &[], &Bci2000WriteOptions::default()).unwrap();
    assert_eq!(read(&path).unwrap().raw.data(), raw.data());
    assert_eq!(dir_names(tmp.path()), vec!["x.dat"]);
}

fn dir_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Writes that must fail: the error, and no new or changed file in the directory.
fn refused(raw: &Raw, states: &[StateColumn], extra: &[&str]) -> IoError {
    let tmp = TempDir::new("bciw-refuse");
    let keep = tmp.write("keep.dat", b"previous file");
    let options = Bci2000WriteOptions {
        extra_parameters: extra.iter().map(|s| s.to_string()).collect(),
    };
    let err = write_bci2000(&keep, raw, states, &options).unwrap_err();
    assert_eq!(err.path(), keep);
    assert_eq!(std::fs::read(&keep).unwrap(), b"previous file");
    let err2 = write_bci2000(tmp.path().join("new.dat"), raw, states, &options).unwrap_err();
    assert_eq!(
        err.to_string().replace("keep.dat", "new.dat"),
        err2.to_string()
    );
    assert_eq!(dir_names(tmp.path()), vec!["keep.dat"]);
    err
}

fn state_problem(err: IoError) -> (String, StateProblem) {
    match err {
        IoError::InvalidState { state, problem, .. } => (state, problem),
        e => panic!("not a state error: {e}"),
    }
}

#[test]
fn refuses_bad_states() {
    let raw = raw_of(Array2::zeros((2, 5)), 100.0, &["Fz", "Cz"], vec![]);
    let col = |name: &str, bits: u32, values: &[u64]| StateColumn::new(name, bits, values.to_vec());
    let ok = col("Good", 3, &[0, 1, 7, 2, 0]);

    let e = refused(&raw, &[ok.clone(), col("Short", 3, &[0, 1, 2, 3])], &[]);
    assert!(
        e.to_string()
            .contains("4 values for a recording of 5 samples"),
        "{e}"
    );
    assert_eq!(
        state_problem(e),
        ("Short".into(), StateProblem::Length { len: 4, n_times: 5 })
    );

    let e = refused(&raw, &[col("StimulusType", 1, &[0, 1, 2, 0, 0])], &[]);
    assert!(
        e.to_string()
            .contains("value 2 at sample 2 does not fit in 1 bits"),
        "{e}"
    );
    assert_eq!(
        state_problem(e),
        (
            "StimulusType".into(),
            StateProblem::ValueTooWide {
                sample: 2,
                value: 2,
                bits: 1
            }
        )
    );
    let e = refused(&raw, &[col("W", 32, &[0, 0, 0, 0, 1 << 32])], &[]);
    assert_eq!(
        state_problem(e).1,
        StateProblem::ValueTooWide {
            sample: 4,
            value: 1 << 32,
            bits: 32
        }
    );

    for (name, reason) in [
        ("Stimulus Code", "contains whitespace"),
        ("Tab\there", "contains whitespace"),
        ("", "empty"),
        ("Phase\u{e9}", "not printable ASCII"),
        ("[x]", "starts with `[` (a header section line)"),
    ] {
        let e = refused(&raw, &[col(name, 3, &[0; 5])], &[]);
        assert_eq!(
            state_problem(e),
            (name.into(), StateProblem::Name { reason })
        );
    }

    let e = refused(&raw, &[ok.clone(), col("X", 1, &[0; 5]), ok.clone()], &[]);
    assert!(
        e.to_string().contains("given twice (columns 0 and 2)"),
        "{e}"
    );
    assert_eq!(
        state_problem(e),
        (
            "Good".into(),
            StateProblem::Duplicate {
                first: 0,
                second: 2
            }
        )
    );

    for bits in [0, 33, 64] {
        let e = refused(&raw, &[col("B", bits, &[0; 5])], &[]);
        assert_eq!(state_problem(e), ("B".into(), StateProblem::Bits { bits }));
    }
}

#[test]
fn refuses_unwritable_samples() {
    for (value, reason) in [
        (f64::NAN, "not a finite number"),
        (f64::NEG_INFINITY, "not a finite number"),
        (1e39, "beyond the float32 range"),
    ] {
        let mut data = Array2::zeros((3, 8));
        data[[1, 6]] = value;
        let raw = raw_of(data, 100.0, &["Fz", "C z", "Pz"], vec![]);
        let e = refused(&raw, &[], &[]);
        assert!(
            e.to_string()
                .contains("channel \"C z\" (index 1), sample 6"),
            "{e}"
        );
        match e {
            IoError::UnwritableSample {
                channel,
                channel_index,
                sample,
                value: v,
                reason: r,
                ..
            } => {
                assert_eq!(
                    (channel.as_str(), channel_index, sample, r),
                    ("C z", 1, 6, reason)
                );
                assert!(v == value || (v.is_nan() && value.is_nan()));
            }
            e => panic!("{e}"),
        }
    }
}

#[test]
fn refuses_bad_parameters_and_recordings() {
    let raw = raw_of(Array2::zeros((1, 4)), 100.0, &["Cz"], vec![]);
    let param_err = |e: IoError| match e {
        IoError::InvalidParameterLine {
            index,
            expected,
            found,
            ..
        } => (index, expected, found),
        e => panic!("not a parameter error: {e}"),
    };
    let good = "Application:A string Mode= x // ok";
    let (i, expected, _) = param_err(refused(&raw, &[], &[good, "just words"]));
    assert_eq!(i, 1);
    assert!(expected.contains("Section Type Name= value"), "{expected}");
    let (_, expected, _) = param_err(refused(&raw, &[], &["S list L= 3 a b // short"]));
    assert!(expected.contains("3 list items"), "{expected}");
    let (_, expected, found) = param_err(refused(
        &raw,
        &[],
        &["Source:X float SamplingRate= 1000Hz // no"],
    ));
    assert!(expected.contains("does not write itself"), "{expected}");
    assert_eq!(found, "SamplingRate");
    let (i, _, found) = param_err(refused(&raw, &[], &[good, "B int Mode= 1"]));
    assert_eq!((i, found.as_str()), (1, "Mode again (first in line 0)"));
    let (_, expected, found) = param_err(refused(&raw, &[], &["A string S= a\r\nB int X= 1"]));
    assert!(expected.contains("printable ASCII"), "{expected}");
    assert_eq!(found, "\r");
    let (_, _, found) = param_err(refused(&raw, &[], &["A string S= caf\u{e9}"]));
    assert_eq!(found, "\u{e9}");
    let (_, expected, _) = param_err(refused(&raw, &[], &["[ Parameter Definition ]"]));
    assert!(expected.contains("section header"), "{expected}");

    let unsupported = |e: IoError| match e {
        IoError::Unsupported { what, .. } => what,
        e => panic!("not unsupported: {e}"),
    };
    let what = unsupported(refused(
        &raw_of(Array2::zeros((2, 3)), 100.0, &["Fz", ""], vec![]),
        &[],
        &[],
    ));
    assert!(what.contains("channel 1 has an empty name"), "{what}");
    let what = unsupported(refused(
        &raw_of(Array2::zeros((1, 0)), 100.0, &["Fz"], vec![]),
        &[],
        &[],
    ));
    assert!(
        what.contains("empty recording (1 channels, 0 samples)"),
        "{what}"
    );
    // A rate no reader takes cannot even make a recording (`oddball_signal::check_sfreq`).
    assert!(Raw::new(
        Array2::zeros((1, 3)),
        2e6,
        vec!["Fz".into()],
        Events::default()
    )
    .is_err());
}

#[test]
fn failed_io_leaves_no_file() {
    let tmp = TempDir::new("bciw-io");
    let raw = raw_of(Array2::zeros((1, 4)), 100.0, &["Cz"], vec![]);
    let opts = Bci2000WriteOptions::default();
    // The directory does not exist: the temporary file cannot be created.
    let e = write_bci2000(tmp.path().join("no/such/dir/x.dat"), &raw, &[], &opts).unwrap_err();
    assert!(
        matches!(
            e,
            IoError::Io {
                action: "create",
                ..
            }
        ),
        "{e}"
    );
    // The final name is a non-empty directory: the rename fails and the temporary file goes.
    std::fs::create_dir_all(tmp.path().join("d.dat/inner")).unwrap();
    let e = write_bci2000(tmp.path().join("d.dat"), &raw, &[], &opts).unwrap_err();
    assert!(
        matches!(
            e,
            IoError::Io {
                action: "rename",
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(dir_names(tmp.path()), vec!["d.dat"]);
}

fn arb_raw_and_states() -> impl Strategy<Value = (Raw, Vec<StateColumn>)> {
    (
        1usize..5,
        1usize..40,
        prop::sample::select(vec![1.0, 128.0, 250.0, 512.5, 1e6]),
    )
        .prop_flat_map(|(n_ch, n_times, sfreq)| {
            let samples = prop::collection::vec(
                prop::num::f32::NORMAL | prop::num::f32::ZERO | prop::num::f32::SUBNORMAL,
                n_ch * n_times,
            );
            let state = (1u32..=32).prop_flat_map(move |bits| {
                prop::collection::vec(0u64..(1u64 << bits), n_times)
                    .prop_map(move |values| (bits, values))
            });
            (
                Just((n_ch, n_times, sfreq)),
                samples,
                prop::collection::vec(state, 0..6),
                any::<bool>(),
            )
        })
        .prop_map(|((n_ch, n_times, sfreq), samples, states, with_running)| {
            let data = Array2::from_shape_vec(
                (n_ch, n_times),
                samples.into_iter().map(f64::from).collect(),
            )
            .unwrap();
            let names: Vec<String> = (0..n_ch).map(|c| format!("ch {c}")).collect();
            let raw = Raw::new(data, sfreq, names, Events::default()).unwrap();
            let mut cols: Vec<StateColumn> = states
                .into_iter()
                .enumerate()
                .map(|(i, (bits, values))| StateColumn::new(format!("S{i}"), bits, values))
                .collect();
            if with_running && !cols.is_empty() {
                cols[0].name = "Running".into();
            }
            (raw, cols)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_recordings_round_trip((raw, states) in arb_raw_and_states()) {
        let tmp = TempDir::new("bciw-prop");
        let back = round_trip(&raw, &states, &Bci2000WriteOptions::default(), tmp.path());
        prop_assert_eq!(back.raw.data(), raw.data());
    }
}

#[test]
fn real_speller_file_rewritten() {
    let Some(src) = bci2000_file("real_speller_file_rewritten", "eeg3_1.dat") else {
        return;
    };
    let orig = read(&src).unwrap();
    let info = orig.bci2000().unwrap();
    let n = orig.raw.n_times();
    let code = info.states.get("StimulusCode").unwrap();
    let kind = info.states.get("StimulusType").unwrap();
    let states = vec![
        StateColumn::new("StimulusCode", 16, code.clone()),
        StateColumn::new("StimulusType", 1, kind.clone()),
    ];
    let tmp = TempDir::new("bciw-real");
    let path = tmp.path().join("eeg3_1_f32.dat");
    // The original block size, passed through as an extra parameter line.
    let block = info
        .parameters
        .get("SampleBlockSize")
        .unwrap()
        .as_str()
        .unwrap();
    let options = Bci2000WriteOptions {
        extra_parameters: vec![format!(
            "Source:Signal%20Properties:DataIOFilter int SampleBlockSize= {block} // as recorded"
        )],
    };
    let s = write_bci2000(&path, &orig.raw, &states, &options).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(back.raw.sfreq(), 256.0);
    assert_eq!(back.raw.ch_names(), orig.raw.ch_names());
    assert_eq!(back.raw.events(), orig.raw.events());
    assert_eq!(back.raw.events().len(), 720);
    let b = back.bci2000().unwrap();
    assert_eq!(b.states.get("StimulusCode").unwrap(), code);
    assert_eq!(b.states.get("StimulusType").unwrap(), kind);
    assert_eq!(
        b.parameters.get("SampleBlockSize").unwrap().as_str(),
        Some("8")
    );
    let mut worst = 0.0f64;
    for ((c, t), &x) in orig.raw.data().indexed_iter() {
        let y = back.raw.data()[[c, t]];
        assert_eq!(y, f64::from(x as f32), "channel {c} sample {t}");
        assert!((y - x).abs() <= x.abs() * f64::from(f32::EPSILON) / 2.0);
        worst = worst.max((y - x).abs());
    }
    assert_eq!(s.max_rounding_uv, worst);
    assert!(worst < 1e-3, "{worst} µV");

    // The same events come back from stimulus_states with the 125 ms (32-sample) flashes.
    let derived = stimulus_states(orig.raw.events(), n, 32);
    let path2 = tmp.path().join("eeg3_1_derived.dat");
    write_bci2000(&path2, &orig.raw, &derived, &Bci2000WriteOptions::default()).unwrap();
    let back2 = read(&path2).unwrap();
    assert_eq!(back2.raw.events(), orig.raw.events());
    assert_eq!(
        back2.bci2000().unwrap().states.get("StimulusCode").unwrap(),
        code,
        "eeg3 flashes last 32 samples"
    );
}

/// Writes the small file the golden script checks with the peer reader, and the values it
/// must find, to `target/tmp/bci2000_written_small.{dat,json}` (see
/// `tools/golden/io/check_written_bci2000.py`).
#[test]
fn small_file_for_the_peer_reader() {
    let n = 50;
    let data = Array2::from_shape_fn((4, n), |(c, t)| {
        let x = t as f64;
        match c {
            0 => x * 0.25 - 5.0,
            1 => 30.0 * (x * 0.3).sin(),
            2 => 1e5 + 0.1 * x,
            _ => -1e-3 * x,
        }
    });
    let events = vec![
        Event::new(2, 1).with_target(false),
        Event::new(12, 4).with_target(true),
        Event::new(22, 2).with_target(false),
        Event::new(32, 300).with_target(true),
    ];
    let raw = raw_of(data, 500.0, &["Fz", "C z", "P%3", "Oz/µ"], events);
    let mut states = stimulus_states(raw.events(), n, 5);
    states.push(StateColumn::new(
        "Phase",
        2,
        (0..n as u64).map(|t| t / 13).collect(),
    ));
    states.push(StateColumn::new(
        "Wide",
        32,
        (0..n as u64)
            .map(|t| (t * 2_654_435_761) & 0xffff_ffff)
            .collect(),
    ));
    states.push(StateColumn::new(
        "Flag",
        1,
        (0..n as u64).map(|t| t % 2).collect(),
    ));
    let options = Bci2000WriteOptions {
        extra_parameters: app_parameters(),
    };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("bci2000_written_small.dat");
    let s = write_bci2000(&path, &raw, &states, &options).unwrap();
    let back = read(&path).unwrap();
    assert_eq!(back.raw.events(), raw.events());

    let json = serde_json::json!({
        "ch_names": raw.ch_names(),
        "sfreq": raw.sfreq(),
        "samples_uv": raw.data().rows().into_iter().map(|r| r.to_vec()).collect::<Vec<_>>(),
        "max_rounding_uv": s.max_rounding_uv,
        "states": states
            .iter()
            .map(|c| serde_json::json!({"name": c.name, "bits": c.bits, "values": c.values}))
            .collect::<Vec<_>>(),
        "events": raw.events().iter().map(|e| (e.onset, e.code, e.target == Some(true))).collect::<Vec<_>>(),
        "parameters": {
            "Paradigm": "four-bulb oddball",
            "BulbNames": ["up", "down", "left", "far right"],
            "BulbDirections": [["0", "1"], ["0", "-1"], ["-1", "0"], ["1", "0"]],
            "Note": "",
            "SampleBlockSize": "5",
        },
        "bytes": s.bytes,
    });
    std::fs::write(
        dir.join("bci2000_written_small.json"),
        serde_json::to_string_pretty(&json).unwrap(),
    )
    .unwrap();
}
