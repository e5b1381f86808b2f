//! `oddball export --bids` and BIDS in: every shared recording oddball reads written as BIDS-EEG
//! and checked by the official validator (`ODDBALL_BIDS_VALIDATOR`, `npm ci` in `tools/bids`),
//! read back (samples to EDF's 16-bit step, or exactly to f32 as BrainVision; events, codes,
//! targets, speller), and benchmarked from the BIDS root with the AUC it has on the originals.

mod common;

use std::path::{Path, PathBuf};

use common::{data_dir, oddball, oddball_ok, tmp_dir};
use oddball_io::events::EventKey;
use oddball_io::{EventMapping, Manifest, Recording};

const TEST: &str = "cli_bids (BIDS validator)";

/// Letters and digits only (a BIDS label).
fn label(s: &str) -> String {
    s.chars().filter(|c| c.is_ascii_alphanumeric()).collect()
}

fn keys(k: &[EventKey]) -> String {
    k.iter()
        .map(|k| match k {
            EventKey::Code(c) => c.to_string(),
            EventKey::Text(t) => t.clone(),
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// `--target-events T --nontarget-events N` of a manifest's mapping.
fn mapping_args(m: Option<&EventMapping>) -> Vec<String> {
    match m {
        Some(m) => vec![
            "--target-events".into(),
            keys(&m.target),
            "--nontarget-events".into(),
            keys(&m.nontarget),
        ],
        None => Vec::new(),
    }
}

/// Exports `files` as one subject (and session) into `root`.
fn export(
    root: &Path,
    subject: &str,
    session: Option<&str>,
    task: &str,
    files: &[PathBuf],
    extra: &[String],
) -> String {
    let mut args: Vec<String> = vec![
        "export".into(),
        "--bids".into(),
        root.display().to_string(),
        "--subject".into(),
        subject.into(),
        "--task".into(),
        task.into(),
    ];
    if let Some(s) = session {
        args.extend(["--session".into(), s.into()]);
    }
    args.extend(extra.iter().cloned());
    args.extend(files.iter().map(|f| f.display().to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    oddball_ok(&args)
}

/// Every subject and session of a shipped manifest exported into `root`, labelled by it
/// (`--manifest`, a copy whose `root` is `data`: its speller and test texts label the runs).
fn export_manifest(manifest: &Path, data: &Path, root: &Path) {
    let m = Manifest::load_with_root(manifest, Some(data)).unwrap();
    let text = std::fs::read_to_string(manifest).unwrap();
    let copy = root.with_extension("toml");
    let rooted: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with("root =") {
                format!("root = {:?}", data.display().to_string())
            } else {
                l.to_string()
            }
        })
        .collect();
    std::fs::write(&copy, rooted.join("\n")).unwrap();
    let mut extra = mapping_args(m.events.as_ref());
    extra.extend(["--manifest".into(), copy.display().to_string()]);
    // --manifest also gives its [read] options (the montage naming IIb's and eeg2's channels);
    // the rate is passed as a flag too, which must agree.
    if let Some(r) = &m.read {
        if let Some(f) = r.sfreq {
            extra.extend(["--sfreq".into(), f.to_string()]);
        }
    }
    for s in &m.subjects {
        let sessions = s.session_runs();
        let named = s.sessions.is_some();
        for (ses, runs) in &sessions {
            let ses = label(ses);
            export(
                root,
                &label(&s.id),
                named.then_some(ses.as_str()),
                &label(&m.name),
                runs,
                &extra,
            );
        }
    }
}

/// A short simulated session recorded by `oddball online` (XDF: flashes with targets, cues,
/// decisions), under `dir`.
fn session_xdf(dir: &Path) -> PathBuf {
    let out = dir.join("session");
    oddball_ok(&[
        "online",
        "--calibrate",
        "--calibration-per-bulb",
        "2",
        "--fast",
        "--commands",
        "up,left",
        "--source",
        "sim",
        "--out",
        out.to_str().unwrap(),
    ]);
    out.join("session.xdf")
}

/// The validator's (errors, warnings) on `root`, by their codes (`exe`: from
/// `ODDBALL_BIDS_VALIDATOR`).
fn validate(exe: &std::ffi::OsStr, root: &Path) -> (Vec<String>, Vec<String>) {
    let out = std::process::Command::new(exe)
        .arg("--json")
        .arg(root)
        .output()
        .expect("the BIDS validator runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let start = text
        .find('{')
        .unwrap_or_else(|| panic!("validator output: {text}"));
    let v: serde_json::Value = serde_json::from_str(&text[start..])
        .unwrap_or_else(|e| panic!("validator JSON: {e}: {text}"));
    let list = |k: &str| -> Vec<String> {
        v["issues"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i["key"].as_str().unwrap_or("?").to_string())
            .collect()
    };
    (list("errors"), list("warnings"))
}

#[test]
fn every_shared_recording_exports_as_valid_bids() {
    let Some(data) = data_dir() else { return };
    let ws = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tmp_dir("cli-bids-all");
    let mut roots = Vec::new();
    for name in [
        "bci2000-eeg2",
        "bci2000-eeg3",
        "muse-visual-p300",
        "bci-competition-ii-iib",
    ] {
        let root = dir.join(name);
        export_manifest(&ws.join(format!("datasets/{name}.toml")), &data, &root);
        roots.push(root);
    }
    // The test session of BCI Competition II IIb has no labels in its files: the manifest's
    // test texts (HAM, PIE) label it on export, so its events say target / nontarget.
    let iib = dir.join("bci-competition-ii-iib/sub-AAS/ses-12/eeg");
    let events = std::fs::read_to_string(
        iib.join("sub-AAS_ses-12_task-bcicompetitioniiiib_run-1_events.tsv"),
    )
    .unwrap();
    assert_eq!(events.matches("\ttarget\t").count(), 90, "{events}");
    let gdf = dir.join("openvibe");
    export(
        &gdf,
        "1",
        None,
        "p300",
        &[data.join("openvibe-p300-gdf/data_sample_8ch.gdf")],
        &[],
    );
    roots.push(gdf);
    // oddball's own session recording (XDF with flashes, targets, cues and decisions).
    let session = session_xdf(&dir);
    let xdf = dir.join("xdf");
    let out = export(
        &xdf,
        "01",
        None,
        "online",
        std::slice::from_ref(&session),
        &[],
    );
    assert!(
        out.contains("other markers") && out.contains("original copied"),
        "{out}"
    );
    assert!(xdf
        .join("sourcedata/sub-01/eeg/sub-01_task-online_eeg.xdf")
        .is_file());
    let events =
        std::fs::read_to_string(xdf.join("sub-01/eeg/sub-01_task-online_events.tsv")).unwrap();
    assert!(events.contains("\tdecision 1\tn/a"), "{events}");
    roots.push(xdf);

    for root in &roots {
        for f in ["dataset_description.json", "participants.tsv", "README"] {
            assert!(root.join(f).is_file(), "{}/{f}", root.display());
        }
    }
    // Without ODDBALL_BIDS_VALIDATOR: skipped (a failure under ODDBALL_REQUIRE_DATA=1).
    let Some(exe) = oddball_testkit::tool(
        "ODDBALL_BIDS_VALIDATOR",
        TEST,
        "npm ci in tools/bids, then tools/bids/node_modules/.bin/bids-validator",
    ) else {
        return;
    };
    for root in &roots {
        let (errors, warnings) = validate(&exe, root);
        eprintln!(
            "validator on {}: {} errors, {} warnings {warnings:?}",
            root.file_name().unwrap().to_string_lossy(),
            errors.len(),
            warnings.len()
        );
        assert!(errors.is_empty(), "{}: {errors:#?}", root.display());
    }
}

/// The largest |exported − original| over all samples, as a fraction of the channel's 16-bit
/// step ((max − min) / 65535).
fn max_step_fraction(a: &Recording, b: &Recording) -> (f64, f64) {
    let (da, db) = (a.raw.data(), b.raw.data());
    assert_eq!(da.dim(), db.dim());
    let (mut worst_uv, mut worst_frac) = (0.0f64, 0.0f64);
    for (ra, rb) in da.rows().into_iter().zip(db.rows()) {
        let (lo, hi) = ra
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let step = ((hi - lo) / 65535.0).max(1e-12);
        let d = ra
            .iter()
            .zip(rb.iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        worst_uv = worst_uv.max(d);
        worst_frac = worst_frac.max(d / step);
    }
    (worst_uv, worst_frac)
}

#[test]
fn exported_runs_read_back_with_the_same_samples_events_and_speller() {
    let Some(data) = data_dir() else { return };
    let dir = tmp_dir("cli-bids-back");
    let muse =
        data.join("muse-visual-p300-eeg-notebooks/subject1/session1/data_2017-02-04-15_45_13.csv");
    let cases: Vec<(PathBuf, Option<EventMapping>)> = vec![
        (data.join("bci2000-samplefiles-p300/eeg3_1.dat"), None),
        (data.join("bci-competition-ii-iib/AAS010R01.mat"), None),
        (data.join("openvibe-p300-gdf/data_sample_8ch.gdf"), None),
        (muse, Some(EventMapping::parse("2", "1").unwrap())),
        (session_xdf(&dir), None),
    ];
    for (i, (file, mapping)) in cases.iter().enumerate() {
        let root = dir.join(format!("r{i}"));
        let extra = mapping_args(mapping.as_ref());
        export(&root, "1", None, "x", std::slice::from_ref(file), &extra);
        let bids = root.join("sub-1/eeg/sub-1_task-x_eeg.edf");
        let original =
            oddball_eval::dataset::read_mapped(file, mapping.as_ref(), &Default::default())
                .unwrap();
        let back = oddball_io::read(&bids).unwrap();
        assert_eq!(back.raw.ch_names(), original.raw.ch_names());
        assert_eq!(back.raw.sfreq(), original.raw.sfreq());
        assert_eq!(
            back.raw.n_times(),
            original.raw.n_times(),
            "{}",
            file.display()
        );
        let (uv, frac) = max_step_fraction(&original, &back);
        eprintln!(
            "{}: read back, max |diff| {uv:.3e} µV = {frac:.3} of a 16-bit step",
            file.display()
        );
        assert!(frac <= 0.55, "{}: {frac} steps", file.display());
        let key = |r: &Recording| {
            r.raw
                .events()
                .iter()
                .map(|e| (e.onset, e.code, e.target))
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&back), key(&original), "{}", file.display());
        assert_eq!(back.speller, original.speller, "{}", file.display());
    }
    // The commands read a BIDS run as any recording.
    let out = oddball_ok(&[
        "inspect",
        dir.join("r0/sub-1/eeg/sub-1_task-x_eeg.edf")
            .to_str()
            .unwrap(),
    ]);
    assert!(
        out.contains("120 target, 600 non-target") && out.contains("speller    6×6"),
        "{out}"
    );
}

/// Each result row's (AUC, epochs, targets).
fn aucs(json: &Path) -> Vec<(f64, u64, u64)> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    v["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let n = |k: &str| r[k].as_u64().unwrap();
            (r["auc"].as_f64().unwrap(), n("n_epochs"), n("n_targets"))
        })
        .collect()
}

#[test]
fn benchmark_on_the_exported_root_gives_the_originals_auc() {
    let Some(data) = data_dir() else { return };
    let ws = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tmp_dir("cli-bids-bench");
    let manifest = ws.join("datasets/bci2000-eeg3.toml");
    let root = dir.join("eeg3");
    export_manifest(&manifest, &data, &root);
    let (a, b) = (dir.join("orig.json"), dir.join("bids.json"));
    let common = [
        "--pipeline",
        "lda",
        "--protocol",
        "within-session",
        "--threads",
        "1",
    ];
    let mut args = vec![
        "benchmark",
        manifest.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--json",
        a.to_str().unwrap(),
    ];
    args.extend(common);
    oddball_ok(&args);
    let mut args = vec![
        "benchmark",
        root.to_str().unwrap(),
        "--json",
        b.to_str().unwrap(),
    ];
    args.extend(common);
    let out = oddball_ok(&args);
    assert!(out.contains("eeg3 / subject PXB"), "{out}");
    let (orig, bids) = (aucs(&a), aucs(&b));
    eprintln!("within-session lda AUC: originals {orig:?}, BIDS {bids:?}");
    assert_eq!(orig.len(), 1);
    assert_eq!(orig.len(), bids.len());
    for (x, y) in orig.iter().zip(&bids) {
        assert!((x.0 - y.0).abs() <= 1e-3, "{x:?} vs {y:?}");
        assert_eq!((x.1, x.2), (y.1, y.2), "epochs and targets");
    }
    // train-test needs a split a BIDS tree does not give: not applicable, said so.
    let (ok, _, err) = oddball(&[
        "benchmark",
        root.to_str().unwrap(),
        "--protocol",
        "train-test",
        "--pipeline",
        "lda",
    ]);
    assert!(
        !ok && err.contains("train-test on \"eeg3\" subject \"PXB\": it needs train and test runs"),
        "{err}"
    );
}

#[test]
fn export_checks_labels_and_existing_runs_before_any_work() {
    let dir = tmp_dir("cli-bids-plan");
    let csv = dir.join("run.csv");
    let (d, markers, sfreq) = oddball_testkit::synthetic_oddball(4, 3);
    oddball_testkit::write_codes_csv(&csv, &d, &markers, sfreq);
    let root = dir.join("bids");
    let r = root.to_str().unwrap();
    let c = csv.to_str().unwrap();
    let (ok, _, err) = oddball(&["export", "--bids", r, "--subject", "s_1", c]);
    assert!(
        !ok && err.contains("sub label \"s_1\"") && err.contains("--subject"),
        "{err}"
    );
    assert!(!root.exists(), "nothing written before the checks");
    let (ok, _, err) = oddball(&["export", "--bids", r, "--subject", "1", "--task", "a-b", c]);
    assert!(!ok && err.contains("--task"), "{err}");
    let flags = ["--target-events", "2", "--nontarget-events", "1"];
    let mut args = vec!["export", "--bids", r, "--subject", "1", c];
    args.extend(flags);
    let out = oddball_ok(&args);
    assert!(out.contains("sub-1_task-run_eeg.edf"), "{out}");
    let (ok, _, err) = oddball(&args);
    assert!(
        !ok && err.contains("exists") && err.contains("--overwrite"),
        "{err}"
    );
    args.push("--overwrite");
    oddball_ok(&args);
    // The BIDS run trains as any labelled file (targets from its events.tsv).
    let model = dir.join("m.json");
    let bids = root.join("sub-1/eeg/sub-1_task-run_eeg.edf");
    oddball_ok(&[
        "train",
        bids.to_str().unwrap(),
        "--pipeline",
        "lda",
        "-o",
        model.to_str().unwrap(),
    ]);
    // A hostile events.tsv: the file, line and column named.
    let events = root.join("sub-1/eeg/sub-1_task-run_events.tsv");
    let text = std::fs::read_to_string(&events).unwrap();
    let broken = text.replacen("\t2\n", "\tx2\n", 1);
    std::fs::write(&events, broken).unwrap();
    let (ok, _, err) = oddball(&["inspect", bids.to_str().unwrap()]);
    assert!(
        !ok && err.contains("sub-1_task-run_events.tsv: line") && err.contains("column \"value\""),
        "{err}"
    );
}

/// `--format brainvision`: the shared recordings (a BCI2000 speller, a BCI Competition `.mat`,
/// the OpenViBE GDF, a Muse CSV with its mapping, an oddball session XDF) as one BrainVision
/// data set: valid for the validator (no error), and every sample read back is the original
/// rounded to f32, with the events, targets and speller of the original.
#[test]
fn a_brainvision_export_validates_and_reads_back_to_f32() {
    let Some(data) = data_dir() else { return };
    let dir = tmp_dir("cli-bids-bv");
    let muse =
        data.join("muse-visual-p300-eeg-notebooks/subject1/session1/data_2017-02-04-15_45_13.csv");
    let cases: Vec<(PathBuf, Option<EventMapping>)> = vec![
        (data.join("bci2000-samplefiles-p300/eeg3_1.dat"), None),
        (data.join("bci-competition-ii-iib/AAS010R01.mat"), None),
        (data.join("openvibe-p300-gdf/data_sample_8ch.gdf"), None),
        (muse, Some(EventMapping::parse("2", "1").unwrap())),
        (session_xdf(&dir), None),
    ];
    let root = dir.join("bv");
    for (i, (file, mapping)) in cases.iter().enumerate() {
        let mut extra = mapping_args(mapping.as_ref());
        extra.extend(["--format".into(), "brainvision".into()]);
        let subject = format!("{}", i + 1);
        let out = export(
            &root,
            &subject,
            None,
            "x",
            std::slice::from_ref(file),
            &extra,
        );
        let vhdr = root.join(format!("sub-{subject}/eeg/sub-{subject}_task-x_eeg.vhdr"));
        assert!(out.contains(&vhdr.display().to_string()), "{out}");
        let original =
            oddball_eval::dataset::read_mapped(file, mapping.as_ref(), &Default::default())
                .unwrap();
        let back = oddball_io::read(&vhdr).unwrap();
        assert_eq!(back.raw.ch_names(), original.raw.ch_names());
        assert_eq!(back.raw.sfreq(), original.raw.sfreq(), "{}", file.display());
        assert_eq!(back.raw.n_times(), original.raw.n_times());
        let mut worst = 0.0f64;
        for (a, b) in original.raw.data().iter().zip(back.raw.data().iter()) {
            assert_eq!(*b, f64::from(*a as f32), "{}", file.display());
            worst = worst.max((a - b).abs());
        }
        eprintln!(
            "{}: BrainVision read back, max |diff| {worst:.3e} µV (f32)",
            file.display()
        );
        let key = |r: &Recording| {
            r.raw
                .events()
                .iter()
                .map(|e| (e.onset, e.code, e.target))
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&back), key(&original), "{}", file.display());
        assert_eq!(back.speller, original.speller, "{}", file.display());
    }
    // The EDF export of the same run replaces the BrainVision files (a run has one data file).
    let out = export(
        &root,
        "1",
        None,
        "x",
        std::slice::from_ref(&cases[0].0),
        &["--overwrite".into()],
    );
    assert!(
        out.contains("removed") && out.contains("_eeg.vhdr"),
        "{out}"
    );
    assert!(!root.join("sub-1/eeg/sub-1_task-x_eeg.eeg").exists());
    let Some(exe) = oddball_testkit::tool(
        "ODDBALL_BIDS_VALIDATOR",
        TEST,
        "npm ci in tools/bids, then tools/bids/node_modules/.bin/bids-validator",
    ) else {
        return;
    };
    // Validated as BrainVision (the EDF of subject 1 written back as BrainVision first).
    let extra = [
        "--overwrite".to_string(),
        "--format".into(),
        "brainvision".into(),
    ];
    export(
        &root,
        "1",
        None,
        "x",
        std::slice::from_ref(&cases[0].0),
        &extra,
    );
    let (errors, warnings) = validate(&exe, &root);
    eprintln!(
        "validator on the BrainVision export: {} errors, {} warnings {warnings:?}",
        errors.len(),
        warnings.len()
    );
    assert!(errors.is_empty(), "{errors:#?}");
}
