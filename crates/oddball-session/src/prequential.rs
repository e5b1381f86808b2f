//! How sure an uncalibrated session can be: evidence weighed by out-of-sample scores.
//!
//! The unsupervised EM decoder fits its LDA on the very trials it then judges. Its own
//! log-likelihood ratios are therefore in-sample: on a few trials it separates noise as well as
//! signal, and a posterior of 1.0 on the first trial says nothing (a seeded typical subject's
//! first fit was sure and wrong). Every online epoch, however, is scored as it arrives by the
//! model fitted on the trials *before* its own: a prequential score (Dawid 1984), never seen by
//! the model that made it. [`HonestParams::fit`] weighs those: it fits the labelled path's
//! two-Gaussian score model ([`ScoreModel`]) on the prequential scores of the trials decided so
//! far, each epoch counted as attended with the weight the latest fit gives it (its posterior:
//! soft labels, no label is ever used), and lowers the class separation by `z` of its standard
//! errors, so a model that has seen little is believed little. The stopping rule then weighs
//! the current trial's prequential scores with that score model exactly as a calibrated session
//! weighs its scores ([`oddball_decode::decision::DecisionModel`]).

use oddball_decode::decision::ScoreModel;
use serde::{Deserialize, Serialize};

use crate::SessionError;

/// Settings of the out-of-sample score model of an uncalibrated session.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HonestParams {
    /// The class separation (d′) is lowered by this many of its standard errors: a one-sided
    /// lower confidence bound (1.645: 95 %), so the evidence is what the scores so far make
    /// likely at least, not what they show at best.
    pub z: f64,
    /// Only the prequential scores of the last `window` decided trials count (older ones were
    /// made by older, weaker models and would understate a model that has learned).
    pub window: usize,
    /// Fewer scored trials than this: no score model yet (the trial runs its rounds).
    pub min_trials: usize,
}

impl Default for HonestParams {
    /// z = 1.645 (a 95 % lower bound), the last 10 trials, 2 scored trials at least (the window
    /// chosen on seeds 11–20 of the simulated typical subject, fast timing: windows of 3, 5, 10
    /// and 20 trials, z of 0, 1 and 1.645, all within 2.5 points of accuracy and 1.7 bits/min;
    /// 10 at 1.645 the most accurate on average).
    fn default() -> Self {
        Self {
            z: 1.645,
            window: 10,
            min_trials: 2,
        }
    }
}

impl HonestParams {
    pub(crate) fn check(&self) -> Result<(), SessionError> {
        if !(self.z >= 0.0 && self.z.is_finite()) {
            return Err(SessionError::InvalidParameter {
                name: "honest.z",
                value: self.z.to_string(),
                reason: "standard errors: finite and >= 0".into(),
            });
        }
        if self.window == 0 || self.min_trials == 0 || self.min_trials > self.window {
            return Err(SessionError::InvalidParameter {
                name: "honest.window/min_trials",
                value: format!("{}/{}", self.window, self.min_trials),
                reason: "need 1 <= min_trials <= window".into(),
            });
        }
        Ok(())
    }

    /// The score model of prequential `scores` (one per epoch; `None` where no model had
    /// scored it) with `attended`, each epoch's posterior of being the attended one, and
    /// `trials`, each epoch's trial (in order): the last `window` trials with a score count.
    /// `None` with fewer than `min_trials` such trials, or without spread in either class.
    pub fn fit(
        &self,
        scores: &[Option<f64>],
        attended: &[f64],
        trials: &[usize],
    ) -> Option<ScoreModel> {
        // The last `window` trials that have a score, newest first.
        let mut kept: Vec<usize> = Vec::new();
        for (s, &t) in scores.iter().zip(trials).rev() {
            if s.is_some() && !kept.contains(&t) {
                if kept.len() == self.window {
                    break;
                }
                kept.push(t);
            }
        }
        if kept.len() < self.min_trials {
            return None;
        }
        let oldest = *kept.last()?;
        let rows = scores
            .iter()
            .zip(attended)
            .zip(trials)
            .filter(|(_, &t)| t >= oldest)
            .filter_map(|((s, &r), _)| s.filter(|v| v.is_finite()).map(|s| (s, r.clamp(0.0, 1.0))));
        weighted_score_model(rows, self.z)
    }
}

/// Two Gaussians with a pooled variance over `(score, weight of the target class)` pairs, the
/// separation lowered by `z` standard errors (never below zero: no evidence either way).
pub(crate) fn weighted_score_model(
    rows: impl Iterator<Item = (f64, f64)>,
    z: f64,
) -> Option<ScoreModel> {
    let rows: Vec<(f64, f64)> = rows.collect();
    let n_t: f64 = rows.iter().map(|(_, r)| r).sum();
    let n = rows.len() as f64;
    let n_n = n - n_t;
    if !(n_t >= 1.0 && n_n >= 1.0 && n > 2.0) {
        return None;
    }
    let mt = rows.iter().map(|(s, r)| s * r).sum::<f64>() / n_t;
    let mn = rows.iter().map(|(s, r)| s * (1.0 - r)).sum::<f64>() / n_n;
    let ss: f64 = rows
        .iter()
        .map(|(s, r)| r * (s - mt).powi(2) + (1.0 - r) * (s - mn).powi(2))
        .sum();
    let std = (ss / (n - 2.0)).sqrt();
    if !(std.is_finite() && std > 0.0) {
        return None;
    }
    let d = (mt - mn) / std;
    // The standard error of a two-sample d′ (Hedges & Olkin 1985, eq. 5.14).
    let se = (1.0 / n_t + 1.0 / n_n + d * d / (2.0 * (n - 2.0))).sqrt();
    let lowered = (d - z * se).max(0.0);
    let mid = 0.5 * (mt + mn);
    Some(ScoreModel {
        mean_target: mid + 0.5 * lowered * std,
        mean_nontarget: mid - 0.5 * lowered * std,
        std,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separation_is_lowered_by_its_standard_error_and_never_reversed() {
        // 10 targets at 1 ± 0.5, 30 non-targets at -1 ± 0.5 (alternating): d′ = 4 at best.
        let rows: Vec<(f64, f64)> = (0..40)
            .map(|i| {
                let sign = if i % 2 == 0 { 0.5 } else { -0.5 };
                if i < 10 {
                    (1.0 + sign, 1.0)
                } else {
                    (-1.0 + sign, 0.0)
                }
            })
            .collect();
        let plain = weighted_score_model(rows.iter().copied(), 0.0).unwrap();
        let lowered = weighted_score_model(rows.iter().copied(), 1.645).unwrap();
        assert!((plain.d_prime() - 2.0 / plain.std).abs() < 1e-12);
        assert!(lowered.d_prime() < plain.d_prime() - 0.5, "{lowered:?}");
        assert!(lowered.d_prime() > 0.0);
        // Classes that do not separate give no evidence, never evidence the other way.
        let flat: Vec<(f64, f64)> = rows.iter().map(|&(s, r)| (s, 1.0 - r)).collect();
        let none = weighted_score_model(flat.into_iter(), 1.645).unwrap();
        assert_eq!(none.d_prime(), 0.0);
        assert_eq!(none.llr(5.0), 0.0);
    }

    #[test]
    fn the_score_model_waits_for_min_trials_and_keeps_the_window() {
        let p = HonestParams {
            z: 0.0,
            window: 2,
            min_trials: 2,
        };
        // Trial 0 unscored; trials 1–3 scored, trial 1 reversed (an early, bad model).
        let mut scores = vec![None; 4];
        let mut attended = vec![1.0, 0.0, 0.0, 0.0];
        let mut trials = vec![0; 4];
        assert!(p.fit(&scores, &attended, &trials).is_none());
        for t in 1..4usize {
            let good = t > 1;
            for k in 0..4 {
                let target = k == 0;
                let s = if target == good { 1.0 } else { -1.0 } + 0.1 * k as f64;
                scores.push(Some(s));
                attended.push(if target { 1.0 } else { 0.0 });
                trials.push(t);
            }
            let m = p.fit(&scores, &attended, &trials);
            match t {
                1 => assert!(m.is_none(), "one scored trial"),
                // Trials 1 (reversed) and 2 (good) cancel: no evidence either way.
                2 => assert_eq!(m.unwrap().d_prime(), 0.0, "{m:?}"),
                // The window holds trials 2 and 3 only: good scores, a positive separation.
                _ => assert!(m.unwrap().d_prime() > 1.0, "after trial {t}: {m:?}"),
            }
        }
        assert!(HonestParams { window: 1, ..p }.check().is_err());
    }
}
