//! What an EEGLAB recording holds besides the samples ([`EeglabInfo`]).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::mat::MatHeader;

/// An `EEG.event(k).type`: EEGLAB allows text or a number.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum EeglabEventType {
    Text(String),
    Number(f64),
}

/// One element of `EEG.event`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EeglabEvent {
    pub kind: EeglabEventType,
    /// `EEG.event(k).latency`: 1-based, in samples, possibly fractional; NaN when empty.
    pub latency: f64,
    /// The 0-based sample of the event it became (`latency − 1` rounded half to even, as MNE
    /// rounds), `None` when it lies outside the recording or has no latency.
    pub onset: Option<usize>,
    /// Its code (also given to events outside the recording).
    pub code: u32,
}

/// What an EEGLAB recording held besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EeglabInfo {
    /// The `.set` file's MAT header.
    pub header: MatHeader,
    /// The fields are those of a struct variable `EEG` (older EEGLAB) rather than top-level
    /// variables (EEGLAB ≥ 2019, eeglabio).
    pub in_eeg_struct: bool,
    /// `EEG.setname`, when it is text.
    pub setname: Option<String>,
    /// The `.fdt` file the samples were read from; `None` when they are in the `.set`.
    pub data_file: Option<PathBuf>,
    /// `EEG.data` names this file, but it is not there: the `.fdt` with the `.set`'s own name
    /// was read instead (a renamed recording; MNE does the same).
    pub stale_data_name: Option<String>,
    /// Every element of `EEG.event`, in order (those outside the recording included).
    pub events: Vec<EeglabEvent>,
    /// The code given to each event type text that is not a number.
    pub label_codes: BTreeMap<String, u32>,
    /// `EEG.ref`, when it is text (`common`, `average`, channel names).
    pub reference: Option<String>,
}
