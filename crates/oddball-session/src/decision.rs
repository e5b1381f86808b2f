//! The records at the bottom of a session: what was shown ([`ShownFlash`]), how each trial ran
//! ([`TrialRecord`], the engine's log, saved in session files), what a calibration measured
//! ([`CalibrationReport`]), and [`Decision`], the one record of a decision that the tasks, the
//! replayed recordings and the reports all use.
//!
//! Nothing here imports another file of the crate but [`crate::paradigm`] and the error.

use oddball_arm::Command;
use serde::{Deserialize, Serialize};

use crate::paradigm::FourBulbParams;

/// Calibration or online control.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Calibration,
    Online,
}

/// One flash as shown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShownFlash {
    /// Onset, samples from the start of the session.
    pub onset: u64,
    pub code: u32,
    /// Index of its trial in [`SessionLog::trials`].
    pub trial: usize,
    pub round: usize,
    pub attended: bool,
    /// The pipeline's score (online, accepted epochs only).
    pub score: Option<f64>,
    /// The epoch passed the amplitude rejection (`None` until its epoch completed).
    pub accepted: Option<bool>,
}

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum TrialOutcome {
    /// A calibration trial: nothing decided.
    Labelled,
    Chosen {
        code: u32,
    },
    Abstained,
}

impl TrialOutcome {
    /// A decision rule's verdict as an outcome and its posterior per bulb (`None` when the rule
    /// would go on flashing: there is no posterior to report).
    pub fn of(verdict: oddball_decode::decision::Verdict) -> (TrialOutcome, Option<Vec<f64>>) {
        use oddball_decode::decision::Verdict;
        match verdict {
            Verdict::Choose { index, posterior } => (
                TrialOutcome::Chosen {
                    code: index as u32 + 1,
                },
                Some(posterior.p),
            ),
            Verdict::Abstain { posterior } => (TrialOutcome::Abstained, Some(posterior.p)),
            Verdict::Continue => (TrialOutcome::Abstained, None),
        }
    }

    /// The decision's confidence given the posterior per bulb (`posterior[code − 1]`): the
    /// posterior of the chosen bulb, or, abstaining, of the best one (0 with none).
    pub fn confidence(&self, posterior: &[f64]) -> f64 {
        match *self {
            TrialOutcome::Chosen { code } => posterior[code as usize - 1],
            _ => posterior.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// One trial (a calibration decision or an online decision).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    pub phase: Phase,
    /// First sample of the countdown.
    pub start: u64,
    /// The sample at which the trial ended (exclusive): the decision was made once the samples
    /// before it had arrived.
    pub end: u64,
    /// Code of the attended bulb (`None`: attending nothing).
    pub intended: Option<u32>,
    pub outcome: TrialOutcome,
    /// Complete rounds the decision used.
    pub rounds: usize,
    /// Posterior per bulb at the decision (empty for calibration), and of "attending nothing".
    pub posterior: Vec<f64>,
    pub p_none: f64,
    /// The arm refused the command (it would leave the board): the reason.
    pub arm_refusal: Option<String>,
    /// Pen position (x, z) in metres when the decision was made, before its command.
    pub pen_m: Option<[f64; 2]>,
}

impl TrialRecord {
    /// The decided code, if any.
    pub fn decided(&self) -> Option<u32> {
        match self.outcome {
            TrialOutcome::Chosen { code } => Some(code),
            _ => None,
        }
    }

    /// Confidence: the posterior of the decided (or, abstaining, the best) bulb.
    pub fn confidence(&self) -> f64 {
        self.outcome.confidence(&self.posterior)
    }
}

/// How far a calibration is, after each of its trials ([`crate::engine::Session::start`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CalibrationProgress {
    /// Calibration trials done, of `total`.
    pub done: usize,
    pub total: usize,
    /// Seconds of EEG the calibration has taken so far.
    pub eeg_seconds: f64,
    /// Seconds of EEG the remaining trials should take at this pace.
    pub seconds_left: f64,
}

/// What calibration measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    pub n_trials: usize,
    pub n_epochs: usize,
    pub n_targets: usize,
    pub n_rejected: usize,
    /// Epoch ROC-AUC of the cross-validated scores.
    pub cv_auc: f64,
    /// Separation of the cross-validated target and non-target scores, in pooled SDs.
    pub d_prime: f64,
    pub fit_seconds: f64,
}

impl CalibrationReport {
    /// A session that did not calibrate (no trials; AUC and d′ unknown: NaN).
    pub fn none() -> Self {
        Self {
            n_trials: 0,
            n_epochs: 0,
            n_targets: 0,
            n_rejected: 0,
            cv_auc: f64::NAN,
            d_prime: f64::NAN,
            fit_seconds: 0.0,
        }
    }
}

/// Everything a session showed, recorded and decided.
#[derive(Debug)]
pub struct SessionLog {
    pub sfreq: f64,
    pub ch_names: Vec<String>,
    /// Raw samples as received, `(n_channels, n_times)`, µV, on disk (read a block at a time,
    /// or whole with [`oddball_io::SpilledSamples::to_array`]); `None` when the session kept
    /// none ([`crate::engine::Session::discard_samples`]).
    pub samples: Option<oddball_io::SpilledSamples>,
    /// Samples the session took.
    pub n_times: usize,
    pub flashes: Vec<ShownFlash>,
    pub trials: Vec<TrialRecord>,
}

/// The scores of a trial's complete rounds, in order, stopping at the first incomplete one:
/// `rounds[r][code − 1]`, `None` for a rejected epoch. A round is complete when all four of its
/// flashes have their epoch.
pub fn complete_rounds(flashes: &[ShownFlash]) -> Vec<Vec<Option<f64>>> {
    let mut rounds: Vec<Vec<Option<f64>>> = Vec::new();
    let mut seen: Vec<usize> = Vec::new();
    for f in flashes {
        if f.round >= rounds.len() {
            rounds.resize(f.round + 1, vec![None; 4]);
            seen.resize(f.round + 1, 0);
        }
        if f.accepted.is_some() && (1..=4).contains(&f.code) {
            rounds[f.round][f.code as usize - 1] = f.score;
            seen[f.round] += 1;
        }
    }
    let n_complete = seen.iter().take_while(|&&n| n == 4).count();
    rounds.truncate(n_complete);
    rounds
}

/// One decision as a task, a replayed recording and the reports see it: what was intended and
/// decided, how sure and how long it took, and what the arm made of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Decision {
    pub intended: Command,
    pub decided: Option<Command>,
    pub abstained: bool,
    pub rounds: usize,
    pub confidence: f64,
    /// Seconds the decision took (countdown included).
    pub seconds: f64,
    /// Seconds from the session's first sample (its calibration included) to the decision; a
    /// live or simulated session's only (`None` in a replay, which has no session clock).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ended_s: Option<f64>,
    /// The arm refused the decided command (it would leave the board).
    pub arm_refusal: Option<String>,
    /// Pen (x, z) in metres when the decision was made, before its command (written only by
    /// the report's rows, [`crate::report::numbered`]).
    #[serde(skip)]
    pub pen_m: Option<[f64; 2]>,
}

impl Decision {
    /// An online trial of a session as a decision: `intended` the command the person attended,
    /// the trial's seconds at `sfreq`.
    pub fn of_trial(
        t: &TrialRecord,
        intended: Command,
        paradigm: &FourBulbParams,
        sfreq: f64,
    ) -> Self {
        Self {
            intended,
            decided: t.decided().and_then(|c| paradigm.command_of(c)),
            abstained: t.outcome == TrialOutcome::Abstained,
            rounds: t.rounds,
            confidence: t.confidence(),
            seconds: (t.end - t.start) as f64 / sfreq,
            ended_s: Some(t.end as f64 / sfreq),
            arm_refusal: t.arm_refusal.clone(),
            pen_m: t.pen_m,
        }
    }

    pub fn correct(&self) -> bool {
        self.decided == Some(self.intended)
    }
}
