//! The BCI Competition layout's rules for other MAT files: a sampling-rate variable, and a speller
//! only when the codes are the 12 rows and columns.

use oddball_io::{read_mat, read_mat_with, IoError, MatOptions};
use oddball_testkit::{write_mat_v5, TempDir};

/// 2 channels × 400 samples, flashes every 20 samples with `code(k)`.
fn write(
    dir: &TempDir,
    name: &str,
    extra: &[(&str, usize, usize, &[f64])],
    code: impl Fn(usize) -> u32,
) -> std::path::PathBuf {
    let n = 400;
    let signal: Vec<f64> = (0..2 * n).map(|i| (i % 7) as f64).collect();
    let codes: Vec<f64> = (0..n)
        .map(|t| {
            if t % 20 == 5 {
                f64::from(code(t / 20))
            } else {
                0.0
            }
        })
        .collect();
    let mut vars: Vec<(&str, usize, usize, &[f64])> =
        vec![("signal", n, 2, &signal), ("StimulusCode", n, 1, &codes)];
    vars.extend_from_slice(extra);
    let path = dir.join(name);
    write_mat_v5(&path, &vars);
    path
}

#[test]
fn a_rate_variable_sets_sfreq_and_the_options_override_it() {
    let dir = TempDir::new("mat-layout-rate");
    let p = write(&dir, "fs.mat", &[("fs", 1, 1, &[500.0])], |k| {
        1 + (k % 2) as u32
    });
    let rec = read_mat(&p).unwrap();
    assert_eq!(rec.raw.sfreq(), 500.0);
    assert!(rec.mat().unwrap().sfreq_given);
    let opts = MatOptions {
        sfreq: Some(128.0),
        ..MatOptions::default()
    };
    assert_eq!(read_mat_with(&p, &opts).unwrap().raw.sfreq(), 128.0);
    // Without one: the competitions' 240 Hz, and it says so.
    let p = write(&dir, "none.mat", &[], |k| 1 + (k % 2) as u32);
    let rec = read_mat(&p).unwrap();
    assert_eq!(rec.raw.sfreq(), 240.0);
    assert!(!rec.mat().unwrap().sfreq_given);
    // A rate that is no rate names the variable and its offset.
    let p = write(&dir, "bad.mat", &[("srate", 1, 1, &[-3.0])], |k| {
        1 + (k % 2) as u32
    });
    let err = read_mat(&p).unwrap_err();
    assert!(matches!(err, IoError::InvalidField { .. }), "{err}");
    let text = err.to_string();
    assert!(text.contains("\"srate\"") && text.contains("-3"), "{text}");
}

#[test]
fn only_the_twelve_codes_make_a_speller() {
    let dir = TempDir::new("mat-layout-speller");
    let oddball = write(&dir, "oddball.mat", &[], |k| 1 + (k % 2) as u32);
    let rec = read_mat(&oddball).unwrap();
    assert!(rec.speller.is_none());
    assert_eq!(rec.raw.events().len(), 20);
    let speller = write(&dir, "speller.mat", &[], |k| 1 + (k % 12) as u32);
    // 20 flashes do not cover 1–12 twice, but they do once: codes 1..=12 all present.
    let rec = read_mat(&speller).unwrap();
    assert!(rec.speller.is_some());
}

/// BCI Competition III data set II's layout (one block per character, `Signal` 3-D) against
/// scipy's reading of a file scipy wrote (`tools/golden/mat/make_competition3.py`): the blocks one
/// after the other, the flashes with their codes and targets, `TargetChar` as the spelled text.
#[test]
fn competition_iii_blocks_read_as_scipy_concatenates_them() {
    #[derive(serde::Deserialize)]
    struct Golden {
        sfreq: f64,
        data: Vec<Vec<f64>>,
        events: Vec<(usize, u32, bool)>,
        text: String,
        flashes_per_character: usize,
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mat");
    let g: Golden = serde_json::from_str(
        &std::fs::read_to_string(dir.join("competition3_small.json")).unwrap(),
    )
    .unwrap();
    let rec = read_mat(dir.join("competition3_small.mat")).unwrap();
    assert_eq!(rec.raw.sfreq(), g.sfreq);
    let data = rec.raw.data();
    assert_eq!(data.dim(), (g.data.len(), g.data[0].len()));
    for (c, row) in g.data.iter().enumerate() {
        for (t, &v) in row.iter().enumerate() {
            assert_eq!(data[[c, t]], v, "channel {c}, sample {t}");
        }
    }
    let events: Vec<(usize, u32, bool)> = rec
        .raw
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target.unwrap()))
        .collect();
    assert_eq!(events, g.events);
    let sp = rec.speller.as_ref().expect("a speller: codes 1-12");
    assert_eq!(sp.text_to_spell.as_deref(), Some(g.text.as_str()));
    assert_eq!(sp.flashes_per_character, Some(g.flashes_per_character));
    assert_eq!(sp.decode(rec.raw.events()), "CAT");
    // The options still win.
    let o = MatOptions {
        text_to_spell: Some("DOG".into()),
        ..Default::default()
    };
    let rec = read_mat_with(dir.join("competition3_small.mat"), &o).unwrap();
    assert_eq!(rec.speller.unwrap().text_to_spell.as_deref(), Some("DOG"));
}
