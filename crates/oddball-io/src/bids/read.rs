//! A BIDS-EEG run read with its sidecars ([`read_bids_run`]), and a BIDS data set as a
//! benchmark manifest ([`dataset_manifest`]). The rules are in the module doc of [`super`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ndarray::s;
use oddball_signal::{Event, Events, Raw};
use serde::Deserialize;
use serde_json::Value;

use super::tsv::{read_text, Table};
use super::BidsError;
use crate::manifest::Subject;
use crate::{CodeOrder, Format, IoError, Manifest, Recording, Speller};

/// The data file extensions BIDS-EEG allows (`*_eeg.<ext>`).
pub const RUN_EXTENSIONS: [&str; 4] = ["edf", "bdf", "vhdr", "set"];

/// The largest speller matrix read from a sidecar (rows and columns each).
const MAX_SPELLER_SIDE: usize = 64;

/// `sub-…_eeg` without `_eeg.<ext>`, when `path` names a BIDS-EEG data file.
fn run_stem(path: &Path) -> Option<String> {
    let name = path.file_name()?.to_str()?;
    let (base, ext) = name.rsplit_once('.')?;
    let ext = ext.to_ascii_lowercase();
    let stem = base.strip_suffix("_eeg")?;
    (RUN_EXTENSIONS.contains(&ext.as_str()) && stem.starts_with("sub-")).then(|| stem.to_string())
}

fn beside(path: &Path, stem: &str, suffix: &str) -> PathBuf {
    path.with_file_name(format!("{stem}_{suffix}"))
}

/// Whether `path` is a run of a BIDS-EEG data set: `sub-…_eeg.<ext>` (one of
/// [`RUN_EXTENSIONS`]) with a `sub-…_events.tsv` beside it.
pub fn is_bids_run(path: &Path) -> bool {
    run_stem(path).is_some_and(|stem| beside(path, &stem, "events.tsv").is_file())
}

/// Reads a BIDS-EEG run: the samples by the data file's reader, the events from its
/// `_events.tsv`, the channels kept by its `_channels.tsv`, the speller from its
/// `_events.json`, the length from its `_eeg.json` (EDF/BDF record padding cut).
pub fn read_bids_run(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let stem = run_stem(path).ok_or_else(|| BidsError::Dataset {
        path: path.to_path_buf(),
        what: format!(
            "not a BIDS-EEG data file (sub-…_eeg.<{}>)",
            RUN_EXTENSIONS.join("|")
        ),
    })?;
    let mut rec = crate::dispatch::read_format(path)?;
    let signal = |source| IoError::Signal {
        path: path.to_path_buf(),
        source,
    };

    // The length, without the padding of an EDF/BDF file's last record.
    let eeg_json = beside(path, &stem, "eeg.json");
    let padded = matches!(
        rec.format,
        Format::Edf | Format::EdfPlus | Format::Bdf | Format::BdfPlus
    );
    let mut n_times = rec.raw.n_times();
    if padded && eeg_json.is_file() {
        let v = read_json(&eeg_json)?;
        match v.get("RecordingDuration") {
            None => {}
            Some(Value::Number(d)) if d.as_f64().is_some_and(|d| d.is_finite() && d > 0.0) => {
                let n = (d.as_f64().unwrap_or(0.0) * rec.raw.sfreq()).round() as usize;
                n_times = n_times.min(n.max(1));
            }
            Some(other) => {
                return Err(json_fault(
                    &eeg_json,
                    format!("RecordingDuration: expected seconds > 0, found {other}"),
                )
                .into())
            }
        }
    }
    let (data, sfreq, names, _) = std::mem::replace(
        &mut rec.raw,
        Raw::new(
            ndarray::Array2::zeros((1, 1)),
            1.0,
            vec!["x".into()],
            Events::default(),
        )
        .map_err(signal)?,
    )
    .into_parts();
    let data = if n_times < data.ncols() {
        data.slice(s![.., ..n_times]).to_owned()
    } else {
        data
    };

    // The events.
    let events_path = beside(path, &stem, "events.tsv");
    let events = read_events(&Table::read(&events_path)?, sfreq, n_times)?;
    let mut raw = Raw::new(data, sfreq, names, Events::new(events)).map_err(signal)?;

    // The channels: EEG only, bad ones dropped.
    let channels_path = beside(path, &stem, "channels.tsv");
    if channels_path.is_file() {
        let keep = eeg_channels(&Table::read(&channels_path)?, raw.ch_names())?;
        raw = raw.pick_channels(&keep).map_err(signal)?;
    }
    rec.raw = raw;

    // The speller.
    let events_json = beside(path, &stem, "events.json");
    if events_json.is_file() {
        if let Some(s) = read_json(&events_json)?
            .get("oddball")
            .and_then(|o| o.get("speller"))
        {
            rec.speller = Some(speller(s, &events_json)?);
        }
    }
    Ok(rec)
}

/// The events of an `_events.tsv` (see the module doc of [`super`]).
fn read_events(t: &Table, sfreq: f64, n_times: usize) -> Result<Vec<Event>, BidsError> {
    let onset = t.required("onset")?;
    let sample = t.column("sample");
    let trial_type = t.column("trial_type");
    let value = t.column("value");
    let mut type_codes: Vec<String> = Vec::new();
    let mut events = Vec::with_capacity(t.rows.len());
    for (line, row) in &t.rows {
        let line = *line;
        let kind = trial_type.map(|c| row[c].as_str()).unwrap_or("n/a");
        let code = match value {
            Some(c) if row[c] == "n/a" => continue,
            Some(c) => match row[c].parse::<f64>() {
                Ok(v) if v >= 0.0 && v <= u32::MAX as f64 && v.fract() == 0.0 => v as u32,
                _ => {
                    return Err(t.fault(
                        line,
                        c,
                        format!(
                            "expected a stimulus code (a whole number ≥ 0) or n/a, found {:?}",
                            crate::error::bounded(&row[c])
                        ),
                    ))
                }
            },
            None => match type_codes.iter().position(|k| k == kind) {
                Some(i) => i as u32 + 1,
                None => {
                    type_codes.push(kind.to_string());
                    type_codes.len() as u32
                }
            },
        };
        let at = match sample.filter(|&c| row[c] != "n/a") {
            Some(c) => row[c].parse::<usize>().map_err(|_| {
                t.fault(
                    line,
                    c,
                    format!(
                        "expected a sample index, found {:?}",
                        crate::error::bounded(&row[c])
                    ),
                )
            })?,
            None => match row[onset].parse::<f64>() {
                Ok(o) if o.is_finite() && o >= 0.0 => (o * sfreq).round() as usize,
                _ => {
                    return Err(t.fault(
                        line,
                        onset,
                        format!(
                            "expected seconds ≥ 0, found {:?}",
                            crate::error::bounded(&row[onset])
                        ),
                    ))
                }
            },
        };
        if at >= n_times {
            let c = sample.unwrap_or(onset);
            return Err(t.fault(
                line,
                c,
                format!("sample {at} is past the recording's {n_times} samples"),
            ));
        }
        let mut e = Event::new(at, code);
        match kind.to_ascii_lowercase().as_str() {
            "target" => e.target = Some(true),
            "nontarget" | "non-target" | "non_target" => e.target = Some(false),
            "n/a" => {}
            _ => e.label = Some(kind.to_string()),
        }
        events.push(e);
    }
    Ok(events)
}

/// The names of a `_channels.tsv`'s good EEG channels, each checked against the data file's.
fn eeg_channels(t: &Table, names: &[String]) -> Result<Vec<String>, BidsError> {
    let name = t.required("name")?;
    let kind = t.required("type")?;
    let status = t.column("status");
    let mut keep = Vec::new();
    for (line, row) in &t.rows {
        if !names.contains(&row[name]) {
            return Err(t.fault(
                *line,
                name,
                format!(
                    "{:?} is not a channel of the data file (its channels: {})",
                    crate::error::bounded(&row[name]),
                    crate::error::bounded(&names.join(", "))
                ),
            ));
        }
        let bad = status.is_some_and(|c| row[c].eq_ignore_ascii_case("bad"));
        if row[kind].eq_ignore_ascii_case("EEG") && !bad {
            keep.push(row[name].clone());
        }
    }
    if keep.is_empty() {
        return Err(BidsError::Table {
            path: t.path.clone(),
            line: 1,
            column: "type".into(),
            what: "no channel is of type EEG with a status other than bad".into(),
        });
    }
    Ok(keep)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpellerSidecar {
    matrix: Vec<Vec<String>>,
    #[serde(default)]
    code_order: CodeOrder,
    #[serde(default)]
    flashes_per_character: Option<usize>,
    #[serde(default)]
    text_to_spell: Option<String>,
}

/// The speller geometry of `"oddball": {"speller": …}`, checked.
fn speller(v: &Value, path: &Path) -> Result<Speller, BidsError> {
    let s: SpellerSidecar = serde_json::from_value(v.clone())
        .map_err(|e| json_fault(path, format!("oddball.speller: {e}")))?;
    let too_big = s.matrix.len() > MAX_SPELLER_SIDE
        || s.matrix.iter().any(|r| r.len() > MAX_SPELLER_SIDE)
        || s.matrix.iter().flatten().any(|c| c.chars().count() > 16);
    if too_big {
        return Err(json_fault(
            path,
            format!(
                "oddball.speller.matrix: more than {MAX_SPELLER_SIDE} rows or columns, or a \
                 symbol longer than 16 characters"
            ),
        ));
    }
    if s.flashes_per_character == Some(0) {
        return Err(json_fault(
            path,
            "oddball.speller.flashes_per_character: must be at least 1".into(),
        ));
    }
    let mut sp =
        Speller::new(s.matrix, s.text_to_spell, s.flashes_per_character).ok_or_else(|| {
            json_fault(
                path,
                "oddball.speller.matrix: no symbols, or rows of different lengths".into(),
            )
        })?;
    sp.code_order = s.code_order;
    Ok(sp)
}

fn json_fault(path: &Path, what: String) -> BidsError {
    BidsError::Json {
        path: path.to_path_buf(),
        what,
    }
}

fn read_json(path: &Path) -> Result<Value, IoError> {
    let text = read_text(path)?;
    let v: Value =
        serde_json::from_str(&text).map_err(|e| json_fault(path, format!("not JSON: {e}")))?;
    if !v.is_object() {
        return Err(json_fault(path, "expected a JSON object".into()).into());
    }
    Ok(v)
}

/// Sorts run files by their name without the run entity, then by run number (`run-10` after
/// `run-2`).
fn run_order(p: &Path) -> (String, u64) {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut base = Vec::new();
    let mut run = 0;
    for part in name.split('_') {
        match part.strip_prefix("run-").and_then(|r| r.parse().ok()) {
            Some(n) => run = n,
            None => base.push(part),
        }
    }
    (base.join("_"), run)
}

fn sorted_dir(dir: &Path, prefix: &str) -> Result<Vec<PathBuf>, IoError> {
    let entries = std::fs::read_dir(dir).map_err(|source| IoError::Io {
        path: dir.to_path_buf(),
        action: "read",
        source,
    })?;
    let mut out: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(prefix))
        })
        .collect();
    out.sort();
    Ok(out)
}

fn eeg_runs(dir: &Path) -> Result<Vec<PathBuf>, IoError> {
    let eeg = dir.join("eeg");
    if !eeg.is_dir() {
        return Ok(Vec::new());
    }
    let mut runs: Vec<PathBuf> = sorted_dir(&eeg, "sub-")?
        .into_iter()
        .filter(|p| is_bids_run(p))
        .collect();
    runs.sort_by_key(|p| run_order(p));
    Ok(runs)
}

/// A BIDS data set as a benchmark manifest: its `dataset_description.json`'s `Name`; one
/// subject per `sub-*` folder holding EEG runs; its `ses-*` folders as sessions (none: one
/// session); every run a training run and no test run, so train → test does not apply (within-
/// session and cross-subject do). Events and speller come from each run's sidecars.
pub fn dataset_manifest(root: &Path) -> Result<Manifest, IoError> {
    let description = root.join("dataset_description.json");
    if !description.is_file() {
        return Err(BidsError::Dataset {
            path: root.to_path_buf(),
            what: "no dataset_description.json: not a BIDS data set".into(),
        }
        .into());
    }
    let v = read_json(&description)?;
    let name = match v.get("Name") {
        Some(Value::String(n)) if !n.trim().is_empty() => n.clone(),
        _ => root
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "bids".into()),
    };
    let mut subjects = Vec::new();
    for sub in sorted_dir(root, "sub-")? {
        if !sub.is_dir() {
            continue;
        }
        let id = sub
            .file_name()
            .map(|n| n.to_string_lossy().trim_start_matches("sub-").to_string())
            .unwrap_or_default();
        let mut sessions = BTreeMap::new();
        for ses in sorted_dir(&sub, "ses-")? {
            let runs = eeg_runs(&ses)?;
            if !runs.is_empty() {
                let label = ses
                    .file_name()
                    .map(|n| n.to_string_lossy().trim_start_matches("ses-").to_string())
                    .unwrap_or_default();
                sessions.insert(label, runs);
            }
        }
        let (train, sessions) = if sessions.is_empty() {
            (eeg_runs(&sub)?, None)
        } else {
            (
                sessions.values().flatten().cloned().collect(),
                Some(sessions),
            )
        };
        if !train.is_empty() {
            subjects.push(Subject {
                id,
                train,
                test: Vec::new(),
                test_text: None,
                sessions,
            });
        }
    }
    if subjects.is_empty() {
        return Err(BidsError::Dataset {
            path: root.to_path_buf(),
            what: format!(
                "no EEG run: no sub-*/[ses-*/]eeg/sub-*_eeg.<{}> with its _events.tsv",
                RUN_EXTENSIONS.join("|")
            ),
        }
        .into());
    }
    Ok(Manifest {
        name,
        root: Some(root.to_path_buf()),
        events: None,
        speller: None,
        read: None,
        subjects,
        path: description,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> Table {
        Table::parse(text, Path::new("e.tsv")).unwrap()
    }

    #[test]
    fn events_from_tsv() {
        let t = table(
            "onset\tduration\tsample\ttrial_type\tvalue\n\
             0.5\t0\t128\ttarget\t3\n1.0\t0\tn/a\tnontarget\t4\n2.0\t0\t512\tdecision A\tn/a\n",
        );
        let e = read_events(&t, 256.0, 1000).unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!((e[0].onset, e[0].code, e[0].target), (128, 3, Some(true)));
        assert_eq!((e[1].onset, e[1].code, e[1].target), (256, 4, Some(false)));
        let t = table("onset\tduration\ttrial_type\n0.5\t0\tTarget\n1\t0\tstd\n2\t0\tTarget\n");
        let e = read_events(&t, 100.0, 1000).unwrap();
        assert_eq!(e.iter().map(|e| e.code).collect::<Vec<_>>(), [1, 2, 1]);
        assert_eq!(e[1].label.as_deref(), Some("std"));
        let t = table("onset\tduration\tvalue\n0.5\t0\t-1\n");
        let err = read_events(&t, 100.0, 1000).unwrap_err().to_string();
        assert!(err.contains("line 2, column \"value\""), "{err}");
        let t = table("onset\tduration\tvalue\n50\t0\t1\n");
        let err = read_events(&t, 100.0, 1000).unwrap_err().to_string();
        assert!(err.contains("past the recording"), "{err}");
    }

    #[test]
    fn channels_from_tsv() {
        let names = vec!["Cz".to_string(), "Pz".into(), "AUX".into()];
        let t = table(
            "name\ttype\tunits\tstatus\nCz\tEEG\tµV\tgood\nPz\tEEG\tµV\tbad\nAUX\tMISC\tµV\tgood\n",
        );
        assert_eq!(eeg_channels(&t, &names).unwrap(), ["Cz"]);
        let t = table("name\ttype\tunits\nOz\tEEG\tµV\n");
        assert!(eeg_channels(&t, &names)
            .unwrap_err()
            .to_string()
            .contains("\"Oz\""));
    }

    proptest::proptest! {
        /// Any text as an events or channels table: a result or an error, never a panic.
        #[test]
        fn any_table_text_is_refused_or_read(text in "[a-z0-9/\\t\\n.\\-]{0,200}", header in 0usize..3) {
            let head = ["onset\tduration\tsample\ttrial_type\tvalue\n", "onset\tvalue\n", "name\ttype\tstatus\n"][header];
            let text = format!("{head}{text}");
            if let Ok(t) = Table::parse(&text, Path::new("p.tsv")) {
                let _ = read_events(&t, 256.0, 1000);
                let _ = eeg_channels(&t, &["a".to_string(), "b".into()]);
            }
        }
    }

    #[test]
    fn speller_checked() {
        let p = Path::new("e.json");
        let v = serde_json::json!({"matrix": [["A","B"],["C","D"]], "code_order": "ColumnsFirst", "flashes_per_character": 40, "text_to_spell": null});
        let s = speller(&v, p).unwrap();
        assert_eq!(s.n_cols(), 2);
        assert_eq!(s.code_order, CodeOrder::ColumnsFirst);
        let v = serde_json::json!({"matrix": [["A","B"],["C"]]});
        assert!(speller(&v, p).is_err());
        let v = serde_json::json!({"matrix": [["A"]], "extra": 1});
        assert!(speller(&v, p).is_err());
        assert_eq!(run_order(Path::new("sub-1_task-a_run-10_eeg.edf")).1, 10);
        assert!(run_stem(Path::new("sub-1_task-a_eeg.edf")).is_some());
        assert!(run_stem(Path::new("sub-1_task-a_eeg.csv")).is_none());
    }
}
