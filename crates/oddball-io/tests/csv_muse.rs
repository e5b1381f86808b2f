//! The CSV reader on the real Muse files (NeuroTechX eeg-notebooks, subject 1), and errors on
//! truncated or mangled copies.

mod common;

use std::path::PathBuf;

use common::{data_dir, TempDir};
use oddball_io::{read, read_csv, CsvOptions, Format, IoError};

fn muse_files(test: &str) -> Option<Vec<PathBuf>> {
    let dir = data_dir(test)?.join("muse-visual-p300-eeg-notebooks/subject1");
    let mut files = Vec::new();
    for session in ["session1", "session2", "session3"] {
        let Ok(entries) = std::fs::read_dir(dir.join(session)) else {
            eprintln!("skipping {test}: {} not found", dir.join(session).display());
            return None;
        };
        files.extend(
            entries
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|x| x == "csv")),
        );
    }
    files.sort();
    Some(files)
}

#[test]
fn subject1_marker_totals() {
    let Some(files) = muse_files("subject1_marker_totals") else {
        return;
    };
    assert_eq!(files.len(), 16);
    let (mut targets, mut nontargets, mut samples) = (0, 0, 0);
    for f in &files {
        let rec = read(f).unwrap();
        assert_eq!(rec.format, Format::Csv);
        let raw = &rec.raw;
        assert_eq!(
            raw.ch_names(),
            ["TP9", "AF7", "AF8", "TP10"],
            "{}",
            f.display()
        );
        assert_eq!(raw.sfreq(), 256.0);
        let info = rec.csv().unwrap();
        assert_eq!(info.marker_column.as_deref(), Some("Marker"));
        let est = info.estimated_sfreq.unwrap();
        assert!(
            (est - 256.0).abs() < 0.05,
            "{}: {est} Hz from timestamps",
            f.display()
        );
        assert_eq!(info.timestamps.as_ref().unwrap().len(), raw.n_times());
        assert!(raw
            .events()
            .iter()
            .all(|e| (e.code == 2) == (e.target == Some(true))));
        assert!(raw.events().iter().all(|e| e.code == 1 || e.code == 2));
        targets += raw.events().n_targets();
        nontargets += raw.events().n_nontargets();
        samples += raw.n_times();
    }
    assert_eq!((targets, nontargets, samples), (483, 2606, 491_700));
}

#[test]
fn first_file_values() {
    let Some(files) = muse_files("first_file_values") else {
        return;
    };
    let f = files
        .iter()
        .find(|p| p.ends_with("session1/data_2017-02-04-15_45_13.csv"))
        .unwrap();
    let rec = read_csv(f, &CsvOptions::muse()).unwrap();
    let raw = &rec.raw;
    assert_eq!(raw.n_times(), 30732);
    let d = raw.data();
    let first: Vec<f64> = (0..4).map(|c| d[[c, 0]]).collect();
    assert_eq!(first, [-44.922, 27.832, 32.715, 58.105]);
    let last: Vec<f64> = (0..4).map(|c| d[[c, raw.n_times() - 1]]).collect();
    assert_eq!(last, [73.242, 26.855, 46.387, 83.008]);
    let ts = rec.csv().unwrap().timestamps.as_ref().unwrap();
    assert_eq!(ts[0], 1486223115.483);
    assert_eq!(ts[ts.len() - 1], 1486223235.513);
    assert_eq!(raw.events().n_targets(), 32);
    assert_eq!(raw.events().n_nontargets(), 165);

    // Choosing columns by hand: AUX included, time column as rate source.
    let o = CsvOptions {
        time_column: Some("timestamps".into()),
        marker_column: Some("Marker".into()),
        channels: Some(vec!["Right AUX".into(), "TP9".into()]),
        ..CsvOptions::default()
    };
    let rec = read_csv(f, &o).unwrap();
    assert_eq!(rec.raw.ch_names(), ["Right AUX", "TP9"]);
    // The timestamps give 256.0276 Hz (kept as the estimate); the rate is Muse's nominal 256.
    let estimate = rec.csv().unwrap().estimated_sfreq.unwrap();
    assert!((estimate - 256.0276).abs() < 1e-3, "{estimate}");
    assert_eq!(rec.raw.sfreq(), 256.0);
    assert!(rec.raw.events().iter().all(|e| e.target.is_none()));
    assert_eq!(rec.raw.events().len(), 197);
}

fn csv_line(e: &IoError) -> (usize, usize) {
    match e {
        IoError::Csv { line, column, .. } => (*line, *column),
        other => panic!("expected a CSV error, got {other}"),
    }
}

#[test]
fn truncated_copies_name_the_line() {
    let Some(files) = muse_files("csv truncated_copies") else {
        return;
    };
    let bytes = std::fs::read(&files[0]).unwrap();
    let tmp = TempDir::new("csv-trunc");
    for cut in [5usize, 30, 100, 1_000_003, bytes.len() - 3, bytes.len() - 1] {
        let file = tmp.write("cut.csv", &bytes[..cut]);
        let want_line = bytes[..cut].iter().filter(|&&b| b == b'\n').count() + 1;
        for e in [
            read(&file).unwrap_err(),
            read_csv(&file, &CsvOptions::muse()).unwrap_err(),
        ] {
            let (line, _) = csv_line(&e);
            assert_eq!(line, want_line, "cut at {cut}: {e}");
            assert!(e.to_string().contains("cut.csv"), "{e}");
        }
    }
}

#[test]
fn mangled_cells_name_line_and_column() {
    let Some(files) = muse_files("csv mangled_cells") else {
        return;
    };
    let text = std::fs::read_to_string(&files[0]).unwrap();
    let tmp = TempDir::new("csv-mangle");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Line 100: the TP9 cell replaced by a malformed number.
    let mut cells: Vec<&str> = lines[99].split(',').collect();
    cells[1] = "12.3.4";
    lines[99] = cells.join(",");
    // Line 200: marker 3.5.
    let mut cells: Vec<String> = lines[199].split(',').map(str::to_string).collect();
    cells[6] = "3.5".into();
    let bad_marker = cells.join(",");
    let file = tmp.write("bad.csv", (lines.join("\n") + "\n").as_bytes());
    let e = read(&file).unwrap_err();
    assert_eq!(csv_line(&e), (100, 2));
    assert!(e.to_string().contains("TP9"), "{e}");
    let mut lines2: Vec<String> = text.lines().map(str::to_string).collect();
    lines2[199] = bad_marker;
    let file = tmp.write("bad2.csv", (lines2.join("\n") + "\n").as_bytes());
    assert_eq!(csv_line(&read(&file).unwrap_err()), (200, 7));
    // A header that lost its marker column: named as missing by the Muse preset.
    let file = tmp.write(
        "bad3.csv",
        text.replacen(",Marker\n", ",Mark\n", 1).as_bytes(),
    );
    let e = read_csv(&file, &CsvOptions::muse()).unwrap_err();
    assert!(
        matches!(&e, IoError::Missing { name, .. } if name == "Marker"),
        "{e}"
    );
}
