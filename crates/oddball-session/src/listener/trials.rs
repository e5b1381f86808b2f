//! What the listener keeps of each flash, trial and the in-stream calibration while it waits for
//! their epochs.

use std::collections::BTreeMap;

use ndarray::Array2;

#[derive(Debug, Clone, Copy)]
pub(super) struct Flash {
    pub(super) trial: usize,
    pub(super) code: u32,
    pub(super) time: f64,
    pub(super) target: Option<bool>,
}

#[derive(Debug)]
pub(super) struct Trial {
    pub(super) number: usize,
    /// Opened by a flash with no trial open: a start marker that arrives late adopts it.
    pub(super) implicit: bool,
    /// The earliest flash's time.
    pub(super) first_time: f64,
    /// The start marker's time: a flash stamped before it is not this trial's.
    pub(super) start_time: Option<f64>,
    /// The trial end marker's time: flashes stamped up to it are this trial's, in whatever
    /// order they arrive; the trial is decided once the EEG has passed its last epoch.
    pub(super) end_time: Option<f64>,
    pub(super) cue: Option<usize>,
    pub(super) announced: usize,
    pub(super) completed: usize,
    pub(super) ended: bool,
    pub(super) decided: bool,
    pub(super) calibration: bool,
    pub(super) evidence: Vec<f64>,
    pub(super) per_code: BTreeMap<u32, usize>,
    pub(super) scored: usize,
    pub(super) last_sample: u64,
}

/// Labelled calibration epochs of the first trials.
#[derive(Debug, Default)]
pub(super) struct CalibrationSet {
    pub(super) epochs: Vec<Array2<f64>>,
    pub(super) labels: Vec<bool>,
    pub(super) trials: Vec<usize>,
    pub(super) done: usize,
}

impl Trial {
    /// Trial `number`, just opened: no flash yet, evidence zero for each of `n_choices`.
    pub(super) fn new(
        number: usize,
        cue: Option<usize>,
        calibration: bool,
        n_choices: usize,
    ) -> Self {
        Self {
            number,
            implicit: false,
            first_time: f64::INFINITY,
            start_time: None,
            end_time: None,
            cue,
            announced: 0,
            completed: 0,
            ended: false,
            decided: false,
            calibration,
            evidence: vec![0.0; n_choices],
            per_code: BTreeMap::new(),
            scored: 0,
            last_sample: 0,
        }
    }
}
