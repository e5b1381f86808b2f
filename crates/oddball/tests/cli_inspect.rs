//! `oddball inspect` on the real recordings in `../shared/data` (skipped with a message when absent).

mod common;

use common::{data_dir, oddball};

fn inspect(args: &[&str]) -> (bool, String, String) {
    let mut all = vec!["inspect"];
    all.extend_from_slice(args);
    oddball(&all)
}

#[test]
fn speller_file_summary() {
    let Some(dir) = data_dir() else { return };
    let f = dir.join("bci2000-samplefiles-p300/eeg3_1.dat");
    let (ok, out, err) = inspect(&[f.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(
        out.contains("channels   8: Fz Cz P3 Pz P4 PO7 Oz PO8"),
        "{out}"
    );
    assert!(out.contains("sfreq      256 Hz"), "{out}");
    assert!(out.contains("events     720 "), "{out}");
    assert!(
        out.contains("targets    120 target, 600 non-target"),
        "{out}"
    );
    assert!(
        out.contains("text       T3OF (TextToSpell; decoded from the target flashes: T3OF)"),
        "{out}"
    );
}

#[test]
fn oddball_and_muse_summaries_and_erp_plot() {
    let Some(dir) = data_dir() else { return };
    let eeg2 = dir.join("bci2000-samplefiles-p300/eeg2_1.dat");
    let muse =
        dir.join("muse-visual-p300-eeg-notebooks/subject1/session1/data_2017-02-04-15_45_13.csv");
    let tmp = oddball_testkit::TempDir::new("erp");
    let plot = tmp.join("erp.svg");
    let (ok, out, err) = inspect(&[eeg2.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("channels   64:"), "{out}");
    assert!(out.contains("sfreq      160 Hz"), "{out}");
    assert!(
        out.contains("events     100 (per code: 1×20 2×80)"),
        "{out}"
    );
    assert!(out.contains("targets    20 target, 80 non-target"), "{out}");
    let (ok, out, err) = inspect(&[muse.to_str().unwrap(), "--plot", plot.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("channels   4: TP9 AF7 AF8 TP10"), "{out}");
    assert!(out.contains("per code: 1×165 2×32"), "{out}");
    let svg = std::fs::read_to_string(&plot).expect("plot written");
    assert!(
        svg.contains("<svg") && svg.contains("TP10"),
        "the ERP plot names its channels"
    );
    let _ = std::fs::remove_file(plot);
}

#[test]
fn a_truncated_file_is_a_clear_error() {
    let Some(dir) = data_dir() else { return };
    let bytes = std::fs::read(dir.join("bci2000-samplefiles-p300/eeg3_1.dat")).unwrap();
    let tmp = oddball_testkit::TempDir::new("cut");
    let cut = tmp.join("cut.dat");
    std::fs::write(&cut, &bytes[..bytes.len() / 2 + 3]).unwrap();
    let (ok, _, err) = inspect(&[cut.to_str().unwrap()]);
    let _ = std::fs::remove_file(&cut);
    assert!(!ok, "a truncated file must fail");
    assert!(err.contains("oddball: error:"), "{err}");
    assert!(
        err.contains("offset") || err.contains("byte"),
        "the error names the offset: {err}"
    );
}
