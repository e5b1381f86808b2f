//! The paradigm's timing where it meets the bit rate: the stopping rule chosen for a person
//! from their calibration and the paradigm's seconds per round ([`choose_stopping`]), and where
//! a session's decision time went ([`time_report`]: cue, flashing, decoding).
//!
//! The seconds of a decision come from one place, [`FourBulbParams::time_split`]: the cue, the
//! flashing up to one flash period after the last onset, and the wait for the last epoch.

use oddball_decode::decision::{DecisionRule, ScoreModel};
use oddball_decode::pipeline::Preprocess;
use oddball_decode::stopping::{Expected, StoppingSearch};
use serde::Serialize;

use crate::decision::Decision;
use crate::paradigm::{FourBulbParams, TimeSplit};
use crate::SessionError;

/// The stopping rule that maximises `search`'s objective for a person whose cross-validated
/// calibration scores are `oof` (labels `y`), on `paradigm` with epochs ending at
/// `preprocess.tmax`.
pub fn choose_stopping(
    search: &StoppingSearch,
    scores: &ScoreModel,
    oof: &[f64],
    y: &[bool],
    paradigm: &FourBulbParams,
    preprocess: &Preprocess,
) -> Result<Expected, SessionError> {
    let of_class = |class: bool| -> Vec<f64> {
        oof.iter()
            .zip(y)
            .filter(|(_, &t)| t == class)
            .map(|(&s, _)| s)
            .collect()
    };
    let (target, nontarget) = (of_class(true), of_class(false));
    Ok(search.choose(scores, &target, &nontarget, 4, |rounds| {
        paradigm.time_split(rounds, preprocess.tmax).total_s()
    })?)
}

/// `stopping chosen from calibration: dynamic stopping (p >= 0.9, at most 7 rounds); expected
/// accuracy 96.0 %, 2.1 rounds, 2.93 s/decision, 33.1 bits/min (Wolpaw), 30.2 (utility)`.
pub fn stopping_text(e: &Expected) -> String {
    format!(
        "stopping chosen from calibration: {}; expected accuracy {:.1} % ({:.1} % abstained), {:.2} rounds, {:.2} s/decision, {:.1} bits/min (Wolpaw), {:.1} bits/min (utility)",
        rule_name(&e.rule),
        100.0 * e.accuracy,
        100.0 * e.abstained,
        e.mean_rounds,
        e.seconds_per_decision,
        e.wolpaw_bits_per_min,
        e.utility_bits_per_min
    )
}

/// The stopping rule in words (`fixed 10 rounds`, `dynamic stopping (p >= …, at most … rounds)`).
pub fn rule_name(rule: &DecisionRule) -> String {
    match rule {
        DecisionRule::Fixed { rounds } => format!("fixed {rounds} rounds"),
        DecisionRule::Dynamic {
            threshold,
            max_rounds,
            ..
        } => format!("dynamic stopping (p >= {threshold}, at most {max_rounds} rounds)"),
    }
}

/// Where a session's decision time went, mean seconds per decision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimeReport {
    /// The cue (countdown) before the first flash.
    pub cue_s: f64,
    /// Flashing: the rounds the decisions used, to one flash period after the last onset.
    pub flashing_s: f64,
    /// The rest, as measured: waiting for the last epoch, scoring, and the stream's chunking.
    pub decoding_s: f64,
    /// The measured mean seconds per decision.
    pub total_s: f64,
}

/// The mean split of `rows`' decisions: cue and flashing from the schedule of the rounds each
/// used, decoding the measured remainder.
pub fn time_report(rows: &[Decision], paradigm: &FourBulbParams) -> TimeReport {
    let n = rows.len().max(1) as f64;
    let mut r = TimeReport {
        cue_s: 0.0,
        flashing_s: 0.0,
        decoding_s: 0.0,
        total_s: 0.0,
    };
    for row in rows {
        let TimeSplit {
            cue_s, flashing_s, ..
        } = paradigm.time_split(row.rounds.max(1), 0.0);
        r.cue_s += cue_s / n;
        r.flashing_s += flashing_s / n;
        r.decoding_s += (row.seconds - cue_s - flashing_s).max(0.0) / n;
        r.total_s += row.seconds / n;
    }
    r
}

/// `time per decision 2.93 s = cue 1.00 + flashing 1.47 + decoding 0.46 s (fast: 100 ms on, …)`.
pub fn time_text(t: &TimeReport, paradigm: &FourBulbParams) -> String {
    format!(
        "time per decision {:.2} s = cue {:.2} + flashing {:.2} + decoding {:.2} s ({})",
        t.total_s,
        t.cue_s,
        t.flashing_s,
        t.decoding_s,
        paradigm.describe()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use oddball_arm::Command;

    #[test]
    fn the_split_adds_up_to_the_measured_time() {
        let p = FourBulbParams::fast();
        let row = |rounds, seconds| Decision {
            intended: Command::Up,
            decided: Some(Command::Up),
            abstained: false,
            rounds,
            confidence: 1.0,
            seconds,
            ended_s: None,
            arm_refusal: None,
            pen_m: None,
        };
        // 1 round: cue 1 s, flashing 0.7 s; 2 rounds: flashing 1.4 s.
        let t = time_report(&[row(1, 2.2), row(2, 2.9)], &p);
        assert!((t.cue_s - 1.0).abs() < 1e-12);
        assert!((t.flashing_s - 1.05).abs() < 1e-12);
        assert!((t.decoding_s - 0.5).abs() < 1e-12);
        assert!((t.total_s - 2.55).abs() < 1e-12);
        assert!(time_text(&t, &p).starts_with("time per decision 2.55 s = cue 1.00"));
    }
}
