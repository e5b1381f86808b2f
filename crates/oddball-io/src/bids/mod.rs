//! BIDS-EEG in and out: a recording written as a run of a BIDS data set ([`ExportPlan`]), a run
//! of a BIDS data set read with its events and channels ([`read_bids_run`], which [`crate::read`]
//! calls for any `*_eeg.<ext>` file with a sibling `*_events.tsv`), and a BIDS data set as a
//! benchmark [`Manifest`](crate::Manifest) ([`dataset_manifest`]).
//!
//! # What an export writes
//! ```text
//! OUT/dataset_description.json           Name, BIDSVersion 1.9.0, DatasetType raw, GeneratedBy oddball
//! OUT/README                             (when absent)
//! OUT/participants.tsv, .json            participant_id (the subjects found under OUT)
//! OUT/sub-S/[ses-T/]eeg/sub-S[_ses-T]_task-K[_run-N]_eeg.edf       EDF+ (16-bit), µV, or
//!                                  …_eeg.vhdr, .vmrk, .eeg  BrainVision (float32 µV;
//!                                                  ExportFormat::BrainVision)
//!                                  …_eeg.json      TaskName, EEGReference, SamplingFrequency,
//!                                                  PowerLineFrequency, SoftwareFilters (REQUIRED);
//!                                                  EEGChannelCount, MISC/EOG/…ChannelCount,
//!                                                  RecordingDuration, RecordingType "continuous"
//!                                  …_channels.tsv  name, type, units (µV), status (good)
//!                                  …_events.tsv    onset (s), duration (0), sample, trial_type,
//!                                                  value (the stimulus code)
//!                                  …_events.json   the columns described; the speller geometry
//!                                                  under "oddball" (below)
//! OUT/sourcedata/sub-S/[ses-T/]eeg/ORIGINAL.xdf     an XDF original, copied as it is
//! ```
//! `trial_type` is `target` or `nontarget` for events whose file says which, else the event's
//! label (e.g. an EDF+ annotation's text), else `n/a`. Markers that are not stimuli (an oddball
//! session's cues and decisions in its XDF) are rows with `value` `n/a`, and reading skips them.
//!
//! # The speller geometry
//! BIDS has no field for a P300 speller's matrix, so the `*_events.json` sidecar carries it
//! under the key `"oddball"`:
//! ```json
//! "oddball": {"speller": {"matrix": [["A","B",…],…], "code_order": "RowsFirst",
//!                         "flashes_per_character": 180, "text_to_spell": "THE"}}
//! ```
//! `code_order` is `RowsFirst` (rows are codes `1..=n_rows`, then the columns) or
//! `ColumnsFirst`; `flashes_per_character` and `text_to_spell` may be `null`. Reading checks
//! it as it checks any outside input.
//!
//! # What a read takes from the tree
//! The samples come from the data file's own reader (by extension); the events from
//! `*_events.tsv` (`trial_type` target/nontarget → the target flag, other text → the label;
//! `value` → the code, a row whose `value` is `n/a` skipped; `sample`, else `onset` × rate →
//! the onset; a file with no `value` column numbers its `trial_type`s 1, 2, … in order of first
//! appearance); the channels from `*_channels.tsv` when present (type EEG only, status `bad`
//! dropped); the speller from `*_events.json`; and `RecordingDuration` from `*_eeg.json` cuts
//! the padding an EDF/BDF file's last record adds. Sidecars are taken from beside the data file
//! only (BIDS's inheritance from upper folders is not followed). Every TSV and JSON file is
//! outside input: sizes bounded, each fault naming the file, line and column.

mod read;
mod tsv;
mod write;

use std::path::PathBuf;

pub use read::{dataset_manifest, is_bids_run, read_bids_run, RUN_EXTENSIONS};
pub use write::{
    default_task, ExportFormat, ExportOptions, ExportPlan, PlannedRun, RunData, RunSummary,
};

/// The BIDS version the exports follow.
pub const BIDS_VERSION: &str = "1.9.0";

pub use crate::error::BidsError;

/// The largest TSV or JSON sidecar read (bytes).
pub const MAX_SIDECAR_BYTES: u64 = 64 << 20;

/// Checks a BIDS label (`sub-<label>`, `ses-<label>`, `task-<label>`): letters and digits only.
pub fn check_label(entity: &'static str, value: &str) -> Result<(), BidsError> {
    if !value.is_empty() && value.bytes().all(|b| b.is_ascii_alphanumeric()) {
        Ok(())
    } else {
        Err(BidsError::Label {
            entity,
            value: crate::error::bounded(value),
        })
    }
}

/// The entities that name one run: `sub-S[_ses-T]_task-K[_run-N]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entities {
    pub subject: String,
    pub session: Option<String>,
    pub task: String,
    pub run: Option<u32>,
}

impl Entities {
    /// Checks every label.
    pub fn check(&self) -> Result<(), BidsError> {
        check_label("sub", &self.subject)?;
        if let Some(s) = &self.session {
            check_label("ses", s)?;
        }
        check_label("task", &self.task)
    }

    /// `sub-S[_ses-T]_task-K[_run-N]`, the start of every file name of the run.
    pub fn stem(&self) -> String {
        let mut s = format!("sub-{}", self.subject);
        if let Some(ses) = &self.session {
            s.push_str(&format!("_ses-{ses}"));
        }
        s.push_str(&format!("_task-{}", self.task));
        if let Some(r) = self.run {
            s.push_str(&format!("_run-{r}"));
        }
        s
    }

    /// `sub-S[/ses-T]/eeg`, relative to the data set's root.
    pub fn eeg_dir(&self) -> PathBuf {
        let mut p = PathBuf::from(format!("sub-{}", self.subject));
        if let Some(ses) = &self.session {
            p.push(format!("ses-{ses}"));
        }
        p.push("eeg");
        p
    }
}

/// The BIDS channel type of a channel name (`EEG` unless the name says otherwise: EOG, ECG/EKG,
/// EMG, TRIG/STIM/STATUS, AUX/ACC/MISC).
pub fn channel_type(name: &str) -> &'static str {
    let n = name.to_ascii_uppercase();
    let has = |k: &[&str]| k.iter().any(|k| n.contains(k));
    if has(&["EOG"]) {
        "EOG"
    } else if has(&["ECG", "EKG"]) {
        "ECG"
    } else if has(&["EMG"]) {
        "EMG"
    } else if has(&["TRIG", "STIM", "STATUS"]) {
        "TRIG"
    } else if has(&["AUX", "ACC", "MISC", "GYRO"]) {
        "MISC"
    } else {
        "EEG"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_and_names() {
        assert!(check_label("sub", "01").is_ok());
        assert!(check_label("sub", "").is_err());
        assert!(check_label("task", "p300_speller").is_err());
        assert!(check_label("ses", "a-b").is_err());
        let e = Entities {
            subject: "01".into(),
            session: Some("2".into()),
            task: "speller".into(),
            run: Some(3),
        };
        assert_eq!(e.stem(), "sub-01_ses-2_task-speller_run-3");
        assert_eq!(e.eeg_dir(), PathBuf::from("sub-01/ses-2/eeg"));
        assert_eq!(channel_type("Right AUX"), "MISC");
        assert_eq!(channel_type("Fz"), "EEG");
        assert_eq!(channel_type("HEOG"), "EOG");
    }
}
