//! A recording written as a run of a BIDS-EEG data set: the plan checked before any work
//! ([`ExportPlan::new`]), then each run ([`ExportPlan::write_run`]) and the data set's own files
//! ([`ExportPlan::finish`]). Every file is written atomically.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::tsv::{self, Table};
use super::{channel_type, BidsError, Entities, BIDS_VERSION};
use crate::brainvision::{write_brainvision, BvWriteSummary};
use crate::edf::{write_edf_plus_with, EdfWriteOptions, EdfWriteSummary};
use crate::{write_atomic, Format, IoError, Recording};

/// The data file format of an export's runs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum ExportFormat {
    /// EDF+ (`_eeg.edf`): 16-bit samples, each channel's step its range / 65535.
    #[default]
    Edf,
    /// BrainVision (`_eeg.vhdr` with `_eeg.vmrk` and `_eeg.eeg`): IEEE float32 samples in µV
    /// ([`write_brainvision`]), each the recording's value to 2⁻²⁴ relative.
    BrainVision,
}

impl ExportFormat {
    /// Both formats.
    pub const ALL: [ExportFormat; 2] = [ExportFormat::Edf, ExportFormat::BrainVision];

    /// The extension of the run's data file (the one a reader is given).
    pub fn extension(self) -> &'static str {
        match self {
            ExportFormat::Edf => "edf",
            ExportFormat::BrainVision => "vhdr",
        }
    }

    /// Every file the format writes for a run, by extension.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            ExportFormat::Edf => &["edf"],
            ExportFormat::BrainVision => &["vhdr", "vmrk", "eeg"],
        }
    }
}

/// What the command line (or any front end) says about an export.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExportOptions {
    /// The subject label (`sub-<label>`).
    pub subject: String,
    /// The session label (`ses-<label>`), if any.
    pub session: Option<String>,
    /// The task label; `None`: the first file's name, letters and digits only ([`default_task`]).
    pub task: Option<String>,
    /// Replace runs already written.
    pub overwrite: bool,
    /// The mains frequency, Hz (`PowerLineFrequency`); `None` writes `n/a`.
    pub power_line_frequency: Option<f64>,
    /// `EEGReference`; `None` writes `n/a`.
    pub reference: Option<String>,
    /// The runs' data file format (EDF+ unless asked).
    pub format: ExportFormat,
}

/// One input file and the run it becomes.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRun {
    pub source: PathBuf,
    pub entities: Entities,
    /// The format its data file is written in.
    pub format: ExportFormat,
}

impl PlannedRun {
    /// The run's data file under `root` (`_eeg.edf`, or the BrainVision header `_eeg.vhdr`).
    pub fn eeg_path(&self, root: &Path) -> PathBuf {
        self.sidecar(root, &format!("eeg.{}", self.format.extension()))
    }

    /// The run's data files in `format` that are already under `root`.
    fn existing(&self, root: &Path, format: ExportFormat) -> Vec<PathBuf> {
        format
            .extensions()
            .iter()
            .map(|ext| self.sidecar(root, &format!("eeg.{ext}")))
            .filter(|p| p.exists())
            .collect()
    }

    /// `root/sub-…/eeg/<stem>_<suffix>`.
    pub fn sidecar(&self, root: &Path, suffix: &str) -> PathBuf {
        root.join(self.entities.eeg_dir())
            .join(format!("{}_{suffix}", self.entities.stem()))
    }
}

/// A checked export: the data set's root and the run each file becomes (runs `1..=n` when there
/// are several files, no run entity for one).
#[derive(Debug, Clone, PartialEq)]
pub struct ExportPlan {
    pub root: PathBuf,
    pub runs: Vec<PlannedRun>,
    pub options: ExportOptions,
}

/// What one run's export wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// The data file (EDF+, or the BrainVision header).
    pub eeg: PathBuf,
    pub n_channels: usize,
    pub n_times: usize,
    /// Stimulus events (rows with a code).
    pub n_events: usize,
    /// Markers that are not stimuli (rows with `value` `n/a`).
    pub n_annotations: usize,
    /// What the data file's writer wrote.
    pub data: RunData,
    /// Data files of the run in the other format, there from an earlier export and removed
    /// (a run has one data file).
    pub replaced: Vec<PathBuf>,
    /// The original copied under `sourcedata/` (XDF files).
    pub source_copy: Option<PathBuf>,
}

/// What a run's data file writer wrote.
#[derive(Debug, Clone, PartialEq)]
pub enum RunData {
    Edf(EdfWriteSummary),
    BrainVision(BvWriteSummary),
}

/// A task label from a file name: its stem's letters and digits (`eeg3_1.dat` → `eeg31`), or
/// `task` when it has none.
pub fn default_task(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let t: String = stem.chars().filter(|c| c.is_ascii_alphanumeric()).collect();
    if t.is_empty() {
        "task".into()
    } else {
        t
    }
}

impl ExportPlan {
    /// Checks the labels, that every file is there and that no run is already there (unless
    /// `overwrite`), before anything is read or written.
    pub fn new(root: &Path, files: &[PathBuf], options: ExportOptions) -> Result<Self, IoError> {
        let Some(first) = files.first() else {
            return Err(BidsError::Dataset {
                path: root.to_path_buf(),
                what: "no recording to export".into(),
            }
            .into());
        };
        if root.exists() && !root.is_dir() {
            return Err(BidsError::Dataset {
                path: root.to_path_buf(),
                what: "exists and is not a folder".into(),
            }
            .into());
        }
        let task = options.task.clone().unwrap_or_else(|| default_task(first));
        let several = files.len() > 1;
        let runs: Vec<PlannedRun> = files
            .iter()
            .enumerate()
            .map(|(i, f)| PlannedRun {
                source: f.clone(),
                entities: Entities {
                    subject: options.subject.clone(),
                    session: options.session.clone(),
                    task: task.clone(),
                    run: several.then_some(i as u32 + 1),
                },
                format: options.format,
            })
            .collect();
        runs[0].entities.check()?;
        for (i, r) in runs.iter().enumerate() {
            if let Some(j) = files[..i].iter().position(|f| f == &r.source) {
                return Err(BidsError::SameRun {
                    first: files[j].clone(),
                    second: r.source.clone(),
                    run: r.entities.stem(),
                }
                .into());
            }
            // The run in either format (a run has one data file).
            if !options.overwrite {
                if let Some(path) = ExportFormat::ALL
                    .iter()
                    .find_map(|&f| r.existing(root, f).into_iter().next())
                {
                    return Err(BidsError::Exists { path }.into());
                }
            }
        }
        for f in files {
            crate::check_file(f)?;
        }
        Ok(Self {
            root: root.to_path_buf(),
            runs,
            options,
        })
    }

    /// Writes run `i` from its recording: the data file (EDF+ or BrainVision), `_eeg.json`,
    /// `_channels.tsv`, `_events.tsv`, `_events.json`, and an XDF original under `sourcedata/`;
    /// the run's data files in the other format, left by an earlier export, are removed.
    pub fn write_run(&self, i: usize, rec: &Recording) -> Result<RunSummary, IoError> {
        let run = &self.runs[i];
        let raw = &rec.raw;
        let dir = self.root.join(run.entities.eeg_dir());
        create_dir(&dir)?;
        let eeg = run.eeg_path(&self.root);
        let data = match run.format {
            ExportFormat::Edf => RunData::Edf(write_edf_plus_with(
                &eeg,
                raw,
                &EdfWriteOptions {
                    patient: format!("{} X X X", run.entities.subject),
                    ..EdfWriteOptions::default()
                },
            )?),
            ExportFormat::BrainVision => RunData::BrainVision(write_brainvision(&eeg, raw)?),
        };
        let mut replaced = Vec::new();
        for other in ExportFormat::ALL.into_iter().filter(|&f| f != run.format) {
            for p in run.existing(&self.root, other) {
                std::fs::remove_file(&p).map_err(|source| IoError::Io {
                    path: p.clone(),
                    action: "remove",
                    source,
                })?;
                replaced.push(p);
            }
        }

        // Channels.
        let types: Vec<&str> = raw.ch_names().iter().map(|n| channel_type(n)).collect();
        let rows: Vec<Vec<String>> = raw
            .ch_names()
            .iter()
            .zip(&types)
            .map(|(n, t)| vec![n.clone(), t.to_string(), "µV".into(), "good".into()])
            .collect();
        write_atomic(
            run.sidecar(&self.root, "channels.tsv"),
            tsv::format(&["name", "type", "units", "status"], &rows),
        )?;

        // The recording's sidecar.
        let count = |t: &str| types.iter().filter(|&&x| x == t).count();
        let na = || Value::from("n/a");
        let mut sidecar = json!({
            "TaskName": run.entities.task,
            "EEGReference": self.options.reference.clone().map_or_else(na, Value::from),
            "SamplingFrequency": raw.sfreq(),
            "PowerLineFrequency": self.options.power_line_frequency.map_or_else(na, Value::from),
            "SoftwareFilters": "n/a",
            "EEGChannelCount": count("EEG"),
            "RecordingDuration": raw.n_times() as f64 / raw.sfreq(),
            "RecordingType": "continuous",
        });
        for (t, key) in [
            ("EOG", "EOGChannelCount"),
            ("ECG", "ECGChannelCount"),
            ("EMG", "EMGChannelCount"),
            ("TRIG", "TriggerChannelCount"),
            ("MISC", "MiscChannelCount"),
        ] {
            if count(t) > 0 {
                sidecar[key] = count(t).into();
            }
        }
        write_json(&run.sidecar(&self.root, "eeg.json"), &sidecar)?;

        // Events, and the markers that are not stimuli.
        let sfreq = raw.sfreq();
        let mut rows: Vec<(usize, Vec<String>)> = raw
            .events()
            .iter()
            .map(|e| {
                let trial_type = match (e.target, &e.label) {
                    (Some(true), _) => "target".to_string(),
                    (Some(false), _) => "nontarget".to_string(),
                    (None, Some(l)) => tsv::cell(l),
                    (None, None) => "n/a".into(),
                };
                (
                    e.onset,
                    event_row(e.onset, sfreq, trial_type, e.code.to_string()),
                )
            })
            .collect();
        let n_events = rows.len();
        if let Some(x) = rec.xdf() {
            let stimuli: BTreeSet<(usize, u32)> =
                raw.events().iter().map(|e| (e.onset, e.code)).collect();
            for m in &x.markers {
                if let Some(s) = m.sample.filter(|s| !stimuli.contains(&(*s, m.code))) {
                    rows.push((s, event_row(s, sfreq, tsv::cell(&m.text), "n/a".into())));
                }
            }
        }
        let n_annotations = rows.len() - n_events;
        rows.sort_by_key(|r| r.0);
        let rows: Vec<Vec<String>> = rows.into_iter().map(|r| r.1).collect();
        write_atomic(
            run.sidecar(&self.root, "events.tsv"),
            tsv::format(
                &["onset", "duration", "sample", "trial_type", "value"],
                &rows,
            ),
        )?;
        write_json(
            &run.sidecar(&self.root, "events.json"),
            &events_sidecar(rec),
        )?;

        // The original, for XDF.
        let source_copy = match rec.format {
            Format::Xdf => Some(self.copy_source(run)?),
            _ => None,
        };
        Ok(RunSummary {
            eeg,
            n_channels: raw.n_channels(),
            n_times: raw.n_times(),
            n_events,
            n_annotations,
            data,
            replaced,
            source_copy,
        })
    }

    fn copy_source(&self, run: &PlannedRun) -> Result<PathBuf, IoError> {
        let ext = run
            .source
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_else(|| "xdf".into());
        let dir = self.root.join("sourcedata").join(run.entities.eeg_dir());
        create_dir(&dir)?;
        let to = dir.join(format!("{}_eeg.{ext}", run.entities.stem()));
        let io = |path: &Path, action, source| IoError::Io {
            path: path.to_path_buf(),
            action,
            source,
        };
        let mut from = std::fs::File::open(&run.source).map_err(|e| io(&run.source, "read", e))?;
        let mut file = crate::AtomicFile::create(&to)?;
        std::io::copy(&mut from, file.file()).map_err(|e| io(&to, "write", e))?;
        file.commit()?;
        Ok(to)
    }

    /// Writes the data set's own files: `dataset_description.json` and `README` when absent
    /// (or when overwriting), and `participants.tsv`/`.json` listing every `sub-*` folder.
    pub fn finish(&self) -> Result<(), IoError> {
        create_dir(&self.root)?;
        let description = self.root.join("dataset_description.json");
        if !description.exists() || self.options.overwrite {
            let name = self
                .root
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "oddball export".into());
            write_json(
                &description,
                &json!({
                    "Name": name,
                    "BIDSVersion": BIDS_VERSION,
                    "DatasetType": "raw",
                    "GeneratedBy": [{
                        "Name": "oddball",
                        "Version": env!("CARGO_PKG_VERSION"),
                        "Description": "oddball export --bids"
                    }]
                }),
            )?;
        }
        let readme = self.root.join("README");
        if !readme.exists() {
            write_atomic(
                &readme,
                "EEG recordings exported to BIDS-EEG by oddball (`oddball export --bids`).\n\
                 Events: trial_type target/nontarget, value = stimulus code; a P300 speller's \
                 geometry is in each *_events.json under \"oddball\".\n",
            )?;
        }
        self.write_participants()
    }

    fn write_participants(&self) -> Result<(), IoError> {
        let path = self.root.join("participants.tsv");
        let mut subjects = BTreeSet::new();
        let entries = std::fs::read_dir(&self.root).map_err(|source| IoError::Io {
            path: self.root.clone(),
            action: "read",
            source,
        })?;
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with("sub-") && e.path().is_dir() {
                subjects.insert(name);
            }
        }
        // Keep the rows (and columns) of a participants.tsv already there.
        let (header, mut rows) = if path.is_file() {
            let t = Table::read(&path)?;
            let id = t.required("participant_id")?;
            for (_, r) in &t.rows {
                subjects.remove(&r[id]);
            }
            let rows: Vec<Vec<String>> = t.rows.into_iter().map(|r| r.1).collect();
            (t.header, rows)
        } else {
            (vec!["participant_id".to_string()], Vec::new())
        };
        let id = header
            .iter()
            .position(|h| h == "participant_id")
            .unwrap_or(0);
        for s in subjects {
            let mut row = vec!["n/a".to_string(); header.len()];
            row[id] = s;
            rows.push(row);
        }
        rows.sort_by(|a, b| a[id].cmp(&b[id]));
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        write_atomic(&path, tsv::format(&header, &rows))?;
        let json_path = self.root.join("participants.json");
        if !json_path.exists() {
            write_json(
                &json_path,
                &json!({"participant_id": {"Description": "The subject's label (sub-<label>)"}}),
            )?;
        }
        Ok(())
    }
}

fn event_row(onset: usize, sfreq: f64, trial_type: String, value: String) -> Vec<String> {
    vec![
        format!("{:.6}", onset as f64 / sfreq),
        "0".into(),
        onset.to_string(),
        trial_type,
        value,
    ]
}

/// `*_events.json`: the columns described, the speller under `"oddball"`.
fn events_sidecar(rec: &Recording) -> Value {
    let mut v = json!({
        "onset": {"Description": "Time of the stimulus onset from the first sample", "Units": "s"},
        "duration": {"Description": "Not recorded: 0 (an instantaneous marker)", "Units": "s"},
        "sample": {"Description": "Index of the onset sample, 0 for the first sample"},
        "trial_type": {
            "Description": "target / nontarget when the recording says whether the flashed item was the attended one, else the event's label (e.g. a marker's text)",
            "Levels": {
                "target": "A flash of the attended item (P300 expected)",
                "nontarget": "A flash of another item"
            }
        },
        "value": {"Description": "The stimulus code (a P300 speller's row or column code, a marker value); n/a for markers that are not stimuli (cues, decisions)"},
    });
    if let Some(s) = &rec.speller {
        v["oddball"] = json!({ "speller": s });
    }
    v
}

fn write_json(path: &Path, v: &Value) -> Result<(), IoError> {
    let mut text = serde_json::to_string_pretty(v).map_err(|e| BidsError::Json {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    text.push('\n');
    write_atomic(path, text)
}

fn create_dir(dir: &Path) -> Result<(), IoError> {
    std::fs::create_dir_all(dir).map_err(|source| IoError::Io {
        path: dir.to_path_buf(),
        action: "create",
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_checks_before_work() {
        let dir = tempfile::tempdir().unwrap();
        let files = vec![dir.path().join("eeg3_1.dat"), dir.path().join("eeg3_2.dat")];
        for f in &files {
            std::fs::write(f, b"x").unwrap();
        }
        let opts = ExportOptions {
            subject: "PXB".into(),
            ..ExportOptions::default()
        };
        let plan = ExportPlan::new(dir.path(), &files, opts.clone()).unwrap();
        assert_eq!(plan.runs[1].entities.stem(), "sub-PXB_task-eeg31_run-2");
        assert_eq!(
            plan.runs[0].eeg_path(dir.path()),
            dir.path()
                .join("sub-PXB/eeg/sub-PXB_task-eeg31_run-1_eeg.edf")
        );
        let bad = ExportOptions {
            subject: "P_1".into(),
            ..opts.clone()
        };
        assert!(matches!(
            ExportPlan::new(dir.path(), &files, bad),
            Err(IoError::Bids(b)) if matches!(*b, BidsError::Label { entity: "sub", .. })
        ));
        let twice = vec![files[0].clone(), files[0].clone()];
        assert!(matches!(
            ExportPlan::new(dir.path(), &twice, opts.clone()),
            Err(IoError::Bids(b)) if matches!(*b, BidsError::SameRun { .. })
        ));
        let eeg = plan.runs[1].eeg_path(dir.path());
        std::fs::create_dir_all(eeg.parent().unwrap()).unwrap();
        std::fs::write(&eeg, b"x").unwrap();
        assert!(matches!(
            ExportPlan::new(dir.path(), &files, opts.clone()),
            Err(IoError::Bids(b)) if matches!(*b, BidsError::Exists { .. })
        ));
        let over = ExportOptions {
            overwrite: true,
            ..opts
        };
        assert!(ExportPlan::new(dir.path(), &files, over.clone()).is_ok());
        let missing = vec![dir.path().join("nope.dat")];
        assert!(matches!(
            ExportPlan::new(dir.path(), &missing, over),
            Err(IoError::NotFound { .. })
        ));
        assert_eq!(
            default_task(Path::new("x/data_2017-02-04.csv")),
            "data20170204"
        );
        assert_eq!(default_task(Path::new("x/__.csv")), "task");
    }
}
