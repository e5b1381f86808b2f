//! How sure an uncalibrated session can be: evidence weighed by out-of-sample scores.
//!
//! The unsupervised EM decoder fits its LDA on the very trials it then judges. Its own
//! log-likelihood ratios are therefore in-sample: on a few trials it separates noise as well as
//! signal, and a posterior of 1.0 on the first trial says nothing (a seeded typical subject's
//! first fit was sure and wrong). A trial in progress, however, is scored by the model fitted
//! on the trials *before* it: a prequential score (Dawid 1984), never seen by the model that
//! made it. How far such scores can be believed is measured on the trials decided so far, each
//! scored out of sample by the latest fit's own M-step without it
//! ([`oddball_decode::unsupervised::UnsupervisedParams::held_out_scores`]: leave one trial
//! out; [`HonestParams::held`] chooses the trials). [`HonestParams::fit`] fits the labelled
//! path's two-Gaussian score model ([`ScoreModel`]) to those scores, each epoch counted as
//! attended with the weight the latest fit gives it (its posterior: soft labels, no label is
//! ever used), and lowers the class separation by `z` of its standard errors, so a model that
//! has seen little is believed little. The stopping rule then weighs the current trial's
//! prequential scores with that score model exactly as a calibrated session weighs its scores
//! ([`oddball_decode::decision::DecisionModel`]).
//!
//! Leave-one-trial-out, not the prequential scores of past trials, because those were made by
//! older models fitted on fewer trials: they understate the model that scores the trial in
//! progress (on the simulated typical subject at the fast timing, 40 decisions, seeds 21–80,
//! never tuned on: 16.5 → 18.3 bits/min, 5 → 19 of 60 sessions at 20 bits/min or more; 90.9 →
//! 90.5 % right, fewer rounds also teach the decoder less; 1 in 40 early stops wrong on seeds
//! 11–20 at the 0.95 threshold, none of 109 before: the old model was more cautious than 0.95).

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
    /// The last `window` decided trials are scored out of sample ([`Self::held`]).
    pub window: usize,
    /// Fewer scored trials than this: no score model yet (the trial runs its rounds).
    pub min_trials: usize,
}

impl Default for HonestParams {
    /// z = 1.645 (a 95 % lower bound), the last 10 trials, 2 scored trials at least (chosen on
    /// seeds 11–20 of the simulated typical subject, fast timing, 40 decisions, mean % right /
    /// bits/min: windows of 10, 20 and 40 trials at z = 1.645 gave 91.5 / 19.0, 91.5 / 19.6,
    /// 90.3 / 18.6; z of 1.0 and 2.5 with 10 trials 90.3 / 18.4 and 91.8 / 17.8).
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

    /// The trials to score out of sample: the last `window` distinct numbers of `trials` (in
    /// order of arrival), newest first.
    pub fn held(&self, trials: &[usize]) -> Vec<usize> {
        let mut held: Vec<usize> = Vec::new();
        for &t in trials.iter().rev() {
            if held.len() == self.window {
                break;
            }
            if !held.contains(&t) {
                held.push(t);
            }
        }
        held
    }

    /// The score model of out-of-sample `scores` (one per epoch; `None` where an epoch was not
    /// scored) with `attended`, each epoch's posterior of being the attended one, and `trials`,
    /// each epoch's trial. `None` with fewer than `min_trials` scored trials, or without spread
    /// in either class.
    pub fn fit(
        &self,
        scores: &[Option<f64>],
        attended: &[f64],
        trials: &[usize],
    ) -> Option<ScoreModel> {
        let mut scored: Vec<usize> = Vec::new();
        for (s, &t) in scores.iter().zip(trials) {
            if s.is_some() && !scored.contains(&t) {
                scored.push(t);
            }
        }
        if scored.len() < self.min_trials {
            return None;
        }
        let rows = scores
            .iter()
            .zip(attended)
            .filter_map(|(s, &r)| s.filter(|v| v.is_finite()).map(|s| (s, r.clamp(0.0, 1.0))));
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
    fn the_score_model_waits_for_min_trials_and_holds_out_the_window() {
        let p = HonestParams {
            z: 0.0,
            window: 2,
            min_trials: 2,
        };
        assert_eq!(p.held(&[0, 0, 1, 1, 1, 2, 3, 3]), vec![3, 2]);
        assert_eq!(p.held(&[5, 5]), vec![5]);
        assert!(p.held(&[]).is_empty());
        // One scored trial is too few; two that separate give a positive separation; two
        // that contradict each other give none.
        let trials = [0, 0, 0, 0, 1, 1, 1, 1];
        let attended = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let good = [1.0, -1.0, -0.9, -1.1];
        let mut scores: Vec<Option<f64>> = good.iter().map(|&s| Some(s)).collect();
        scores.extend([None; 4]);
        assert!(p.fit(&scores, &attended, &trials).is_none());
        for (i, s) in good.iter().enumerate() {
            scores[4 + i] = Some(s + 0.1);
        }
        assert!(p.fit(&scores, &attended, &trials).unwrap().d_prime() > 1.0);
        for (i, s) in good.iter().enumerate() {
            scores[4 + i] = Some(-s);
        }
        assert_eq!(p.fit(&scores, &attended, &trials).unwrap().d_prime(), 0.0);
        assert!(HonestParams { window: 1, ..p }.check().is_err());
    }
}
