//! What a listener says (decisions, stops, the in-stream calibration, as the JSON a stimulus
//! program reads) and what it counts of the markers it could not use.

use serde::Serialize;

/// What the listener says.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Output {
    /// Trial `trial` is decided before its flashes ran out: the program may end it.
    Stop {
        trial: usize,
    },
    Decision(ListenerDecision),
    /// The in-stream calibration is fitted; decisions follow.
    Calibrated {
        trials: usize,
        epochs: usize,
        targets: usize,
        cv_auc: f64,
    },
}

impl Output {
    /// The message as it goes out to a stimulus program: JSON text with the choices' labels and
    /// `time_s`, when it was sent (`{"type":"decision","trial":3,"choice":"M","posterior":{…},
    /// "flashes":96,…}`, `{"type":"stop","trial":3,…}`).
    pub fn to_json(&self, labels: &[String], time_s: f64) -> String {
        let v = match self {
            Output::Decision(d) => {
                let posterior: serde_json::Map<String, serde_json::Value> = labels
                    .iter()
                    .zip(&d.posterior)
                    .map(|(l, p)| (l.clone(), serde_json::json!(p)))
                    .collect();
                serde_json::json!({
                    "type": "decision",
                    "trial": d.trial,
                    "choice": d.choice.map(|c| labels[c].clone()),
                    "best": labels[d.best].clone(),
                    "posterior": posterior,
                    "p_none": d.p_none,
                    "flashes": d.flashes,
                    "flashes_shown": d.flashes_shown,
                    "early": d.early,
                    "time": time_s,
                })
            }
            other => {
                let mut v = serde_json::to_value(other).expect("outputs serialise");
                v["time"] = serde_json::json!(time_s);
                v
            }
        };
        v.to_string()
    }
}

/// One trial decided.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ListenerDecision {
    /// 1, 2, … in the order trials started.
    pub trial: usize,
    /// The chosen choice's index; `None`: abstention (no choice credible).
    pub choice: Option<usize>,
    /// The most probable choice (chosen or not).
    pub best: usize,
    /// Posterior of each choice.
    pub posterior: Vec<f64>,
    /// Posterior that no choice was attended (dynamic stopping's no-control prior).
    pub p_none: f64,
    /// Flashes whose epochs were scored.
    pub flashes: usize,
    /// Flashes the trial announced until the decision.
    pub flashes_shown: usize,
    /// Decided before the trial's end (dynamic stopping).
    pub early: bool,
    /// The sample (index in the stream) that completed the last epoch the decision used.
    pub completed_at: u64,
}

/// Markers the listener could not use, by reason, and what it read.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct MarkerCounts {
    pub markers: u64,
    pub flashes: u64,
    /// Texts no pattern of the paradigm reads (or a code it has no choice for).
    pub unknown: u64,
    /// Flashes whose epoch started before the samples still kept (far in the past).
    pub too_old: u64,
    /// Flashes stamped more than [`super::MAX_AHEAD_S`] past the newest sample.
    pub future: u64,
    /// Flashes stamped before the previous flash.
    pub out_of_order: u64,
    /// The same flash twice.
    pub duplicate: u64,
    /// Target / non-target flags with no flash at their timestamp.
    pub orphan_flags: u64,
    /// Flashes outside a trial, which opened one.
    pub implicit_trials: u64,
    /// Trials a new trial start cut short (no end marker).
    pub unended_trials: u64,
    /// Trial ends with no trial open.
    pub stray_ends: u64,
    /// Calibration flashes with neither a flag nor a cue.
    pub unlabelled: u64,
    /// Epochs of flashes after their trial was decided (dynamic stopping) or given up.
    pub after_decision: u64,
    /// Epochs the rejection rule dropped.
    pub rejected: u64,
    /// Markers dropped because too many waited for the first EEG sample.
    pub held_overflow: u64,
    /// Trials given up because too many were open.
    pub abandoned_trials: u64,
    /// Trials that ended with no flash.
    pub empty_trials: u64,
}
