//! From per-flash scores to a choice: evidence accumulation, dynamic stopping and abstention.
//!
//! A pipeline scores each epoch (larger = more target-like). [`ScoreModelParams::fit`] models
//! those scores as two Gaussians with a pooled variance (target, non-target), fitted on
//! *out-of-sample* calibration scores, so each flash's score becomes a log-likelihood ratio
//! `llr(s) = log N(s; μ_t, σ) − log N(s; μ_n, σ)`. With flashes treated as independent, the
//! evidence for stimulus `k` after some rounds is the sum of the LLRs of its flashes and
//!
//! ```text
//! P(k | data)    ∝ (1 − π₀)/K · exp(E_k)
//! P(none | data) ∝ π₀
//! ```
//!
//! where `π₀` is the prior probability that the person attends no stimulus at all (the
//! "no-control" state). [`DecisionRule`] decides after a fixed number of rounds (the paper:
//! the stimulus with the most evidence, always), or dynamically: stop as soon as the best
//! stimulus's posterior reaches `threshold` (after at least `min_rounds`), and at `max_rounds`
//! choose it only if its posterior reaches `credible`, else abstain. This is the Bayesian
//! dynamic stopping of Throckmorton et al. (2013) and Schreuder et al. (2013) in its simplest
//! form; written here because no crate does it.

use serde::{Deserialize, Serialize};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of the score model (none yet beyond a variance floor).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreModelParams {
    /// The pooled standard deviation is at least this fraction of the class-mean distance,
    /// so a perfectly separated calibration set does not give infinite confidence.
    pub min_std_fraction: f64,
}

impl Default for ScoreModelParams {
    fn default() -> Self {
        Self {
            min_std_fraction: 0.1,
        }
    }
}

/// Two Gaussians with a pooled variance over classifier scores.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreModel {
    pub mean_target: f64,
    pub mean_nontarget: f64,
    /// Pooled within-class standard deviation.
    pub std: f64,
}

impl ScoreModelParams {
    /// Fits the model on scores of labelled epochs (use cross-validated scores).
    pub fn fit(&self, scores: &[f64], y: &[bool]) -> Result<ScoreModel> {
        if scores.len() != y.len() {
            return Err(DecodeError::LabelCount {
                n_samples: scores.len(),
                n_labels: y.len(),
            });
        }
        if let Some(i) = scores.iter().position(|s| !s.is_finite()) {
            return Err(DecodeError::NonFinite {
                what: format!("score {i}"),
            });
        }
        let (mut st, mut nt, mut sn, mut nn) = (0.0, 0usize, 0.0, 0usize);
        for (&s, &t) in scores.iter().zip(y) {
            if t {
                st += s;
                nt += 1;
            } else {
                sn += s;
                nn += 1;
            }
        }
        if nt < 2 || nn < 2 {
            return Err(DecodeError::NeedBothClasses {
                n_targets: nt,
                n_nontargets: nn,
            });
        }
        let (mt, mn) = (st / nt as f64, sn / nn as f64);
        let ss: f64 = scores
            .iter()
            .zip(y)
            .map(|(&s, &t)| (s - if t { mt } else { mn }).powi(2))
            .sum();
        let std = (ss / (scores.len() - 2) as f64).sqrt();
        let floor = self.min_std_fraction * (mt - mn).abs();
        let std = std.max(floor).max(f64::MIN_POSITIVE.sqrt());
        Ok(ScoreModel {
            mean_target: mt,
            mean_nontarget: mn,
            std,
        })
    }
}

impl ScoreModel {
    /// Refuses a score model that cannot weigh evidence: non-finite means, or a spread that is
    /// not finite and positive (zero spread makes every log-likelihood ratio infinite).
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("mean_target", self.mean_target),
            ("mean_nontarget", self.mean_nontarget),
        ] {
            if !v.is_finite() {
                return Err(DecodeError::InvalidParameter {
                    name,
                    value: v.to_string(),
                    reason: "a finite score".into(),
                });
            }
        }
        if !(self.std.is_finite() && self.std > 0.0) {
            return Err(DecodeError::InvalidParameter {
                name: "std",
                value: self.std.to_string(),
                reason: "a finite spread > 0".into(),
            });
        }
        // Finite but absurd statistics (means of 1e308, a spread of 1e-320) overflow the
        // log-likelihood ratio, and the posterior becomes NaN: the ratio of every score within
        // ten spreads of either mean, summed over the most rounds a decision may take, must stay
        // finite.
        let d = self.mean_target - self.mean_nontarget;
        let slope = d / (self.std * self.std);
        let reach = slope.abs() * (0.5 * d.abs() + 10.0 * self.std) * MAX_ROUNDS as f64;
        if !reach.is_finite() {
            return Err(DecodeError::InvalidParameter {
                name: "std",
                value: format!(
                    "{} (means {} and {})",
                    self.std, self.mean_target, self.mean_nontarget
                ),
                reason: "statistics that give finite posteriors: these overflow the \
                         log-likelihood ratio"
                    .into(),
            });
        }
        Ok(())
    }

    /// Log-likelihood ratio (target vs non-target) of one score.
    pub fn llr(&self, score: f64) -> f64 {
        let d = self.mean_target - self.mean_nontarget;
        let mid = 0.5 * (self.mean_target + self.mean_nontarget);
        d / (self.std * self.std) * (score - mid)
    }

    /// How far apart the classes are, in standard deviations (d′).
    pub fn d_prime(&self) -> f64 {
        (self.mean_target - self.mean_nontarget) / self.std
    }
}

/// Posterior probabilities after some evidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Posterior {
    /// P(stimulus k attended), one per stimulus.
    pub p: Vec<f64>,
    /// P(no stimulus attended).
    pub p_none: f64,
}

impl Posterior {
    /// The posterior from summed log-likelihood ratios per stimulus and the no-control prior.
    pub fn from_evidence(evidence: &[f64], p_no_control: f64) -> Self {
        let k = evidence.len().max(1) as f64;
        let log_prior = ((1.0 - p_no_control) / k).ln();
        let mut logs: Vec<f64> = evidence.iter().map(|e| log_prior + e).collect();
        let log_none = if p_no_control > 0.0 {
            p_no_control.ln()
        } else {
            f64::NEG_INFINITY
        };
        logs.push(log_none);
        let m = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = logs.iter().map(|l| (l - m).exp()).sum();
        let mut p: Vec<f64> = logs.iter().map(|l| (l - m).exp() / z).collect();
        let p_none = p.pop().unwrap_or(0.0);
        Self { p, p_none }
    }

    /// The stimulus with the largest posterior (lowest index on ties) and its probability.
    pub fn best(&self) -> (usize, f64) {
        let mut best = (0, f64::NEG_INFINITY);
        for (i, &p) in self.p.iter().enumerate() {
            if p > best.1 {
                best = (i, p);
            }
        }
        best
    }
}

/// The most rounds of flashes one decision may take (a hundred rounds of four bulbs is well over
/// a minute and a half per decision; 10⁸ rounds kept a session busy for ever).
pub const MAX_ROUNDS: usize = 100;

/// When to stop flashing and what to decide.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DecisionRule {
    /// Always `rounds` rounds, then the stimulus with the most evidence (the paper).
    Fixed { rounds: usize },
    /// Stop when a stimulus is probable enough; abstain if none is credible at `max_rounds`.
    Dynamic {
        /// Stop once the best posterior reaches this.
        threshold: f64,
        min_rounds: usize,
        max_rounds: usize,
        /// At `max_rounds`, choose only if the best posterior reaches this; else abstain.
        credible: f64,
        /// Prior probability that no stimulus is attended.
        p_no_control: f64,
    },
}

impl DecisionRule {
    /// Dynamic stopping with the defaults: threshold 0.95, 1..=`max_rounds` rounds, abstain
    /// below 0.5, no-control prior 0.2.
    pub fn dynamic(max_rounds: usize) -> Self {
        Self::dynamic_at(0.95, max_rounds)
    }

    /// Dynamic stopping at `threshold`, the other settings [`DecisionRule::dynamic`]'s.
    pub fn dynamic_at(threshold: f64, max_rounds: usize) -> Self {
        DecisionRule::Dynamic {
            threshold,
            min_rounds: 1,
            max_rounds,
            credible: 0.5,
            p_no_control: 0.2,
        }
    }

    /// Refuses thresholds outside (0, 1], zero rounds and min > max.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(DecodeError::InvalidParameter {
                name,
                value,
                reason: reason.to_string(),
            })
        };
        match *self {
            DecisionRule::Fixed { rounds } if !(1..=MAX_ROUNDS).contains(&rounds) => bad(
                "rounds",
                rounds.to_string(),
                &format!("1 to {MAX_ROUNDS} rounds"),
            ),
            DecisionRule::Fixed { .. } => Ok(()),
            DecisionRule::Dynamic {
                threshold,
                min_rounds,
                max_rounds,
                credible,
                p_no_control,
            } => {
                for (name, v) in [("threshold", threshold), ("credible", credible)] {
                    if !(v > 0.0 && v <= 1.0) {
                        return bad(name, v.to_string(), "a probability in (0, 1]");
                    }
                }
                if !(0.0..1.0).contains(&p_no_control) {
                    return bad(
                        "p_no_control",
                        p_no_control.to_string(),
                        "a probability in [0, 1)",
                    );
                }
                if max_rounds == 0
                    || min_rounds == 0
                    || min_rounds > max_rounds
                    || max_rounds > MAX_ROUNDS
                {
                    return bad(
                        "min_rounds/max_rounds",
                        format!("{min_rounds}/{max_rounds}"),
                        &format!("need 1 <= min_rounds <= max_rounds <= {MAX_ROUNDS}"),
                    );
                }
                Ok(())
            }
        }
    }

    /// The most rounds a decision can take.
    pub fn max_rounds(&self) -> usize {
        match *self {
            DecisionRule::Fixed { rounds } => rounds,
            DecisionRule::Dynamic { max_rounds, .. } => max_rounds,
        }
    }

    fn p_no_control(&self) -> f64 {
        match *self {
            DecisionRule::Fixed { .. } => 0.0,
            DecisionRule::Dynamic { p_no_control, .. } => p_no_control,
        }
    }

    /// What to do after `rounds_done` complete rounds with the summed evidence per stimulus. A
    /// posterior that is not finite (infinite or NaN evidence) never chooses: the rule abstains
    /// where it would have chosen, so NaN never moves the arm.
    pub fn check(&self, rounds_done: usize, evidence: &[f64]) -> Verdict {
        match self.check_finite(rounds_done, evidence) {
            Verdict::Choose { posterior, .. }
                if !(posterior.p.iter().all(|p| p.is_finite()) && posterior.p_none.is_finite()) =>
            {
                Verdict::Abstain { posterior }
            }
            v => v,
        }
    }

    fn check_finite(&self, rounds_done: usize, evidence: &[f64]) -> Verdict {
        let posterior = Posterior::from_evidence(evidence, self.p_no_control());
        let (best, p) = posterior.best();
        match *self {
            DecisionRule::Fixed { rounds } => {
                if rounds_done >= rounds {
                    Verdict::Choose {
                        index: best,
                        posterior,
                    }
                } else {
                    Verdict::Continue
                }
            }
            DecisionRule::Dynamic {
                threshold,
                min_rounds,
                max_rounds,
                credible,
                ..
            } => {
                if rounds_done >= min_rounds && p >= threshold {
                    Verdict::Choose {
                        index: best,
                        posterior,
                    }
                } else if rounds_done >= max_rounds {
                    if p >= credible {
                        Verdict::Choose {
                            index: best,
                            posterior,
                        }
                    } else {
                        Verdict::Abstain { posterior }
                    }
                } else {
                    Verdict::Continue
                }
            }
        }
    }
}

/// The outcome of [`DecisionRule::check`].
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Keep flashing.
    Continue,
    /// Stimulus `index` (0-based) is chosen.
    Choose { index: usize, posterior: Posterior },
    /// No stimulus is credible: no command.
    Abstain { posterior: Posterior },
}

/// What a session needs to turn scores into decisions: the score model and the rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DecisionModel {
    pub scores: ScoreModel,
    pub rule: DecisionRule,
}

impl DecisionModel {
    /// Refuses a score model or rule that cannot decide (see [`ScoreModel::validate`],
    /// [`DecisionRule::validate`]).
    pub fn validate(&self) -> Result<()> {
        self.scores.validate()?;
        self.rule.validate()
    }

    /// Runs the rule over complete rounds: `rounds[r][k]` is the score of stimulus `k` in round
    /// `r` (`None` for a rejected epoch: no evidence). Returns the verdict and the rounds used;
    /// `Continue` only if the rounds run out first.
    pub fn decide(&self, rounds: &[Vec<Option<f64>>]) -> (Verdict, usize) {
        let n = rounds.first().map_or(0, Vec::len);
        let mut evidence = vec![0.0; n];
        for (r, round) in rounds.iter().enumerate() {
            for (e, s) in evidence.iter_mut().zip(round) {
                if let Some(s) = s {
                    *e += self.scores.llr(*s);
                }
            }
            let v = match self.rule.check(r + 1, &evidence) {
                // No epoch scored at all (none drawn, all rejected): a choice would be blind.
                Verdict::Choose { posterior, .. }
                    if rounds[..=r].iter().flatten().all(Option::is_none) =>
                {
                    Verdict::Abstain { posterior }
                }
                v => v,
            };
            if v != Verdict::Continue {
                return (v, r + 1);
            }
        }
        (Verdict::Continue, rounds.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue #30: finite but absurd statistics (the probe's model: `mean_target` 1e308, `std`
    /// 1e-320) gave NaN posteriors, and every decision moved the arm "up". They are refused; a
    /// posterior that is not finite anyway abstains instead of choosing the first bulb.
    #[test]
    fn absurd_statistics_are_refused_and_a_nan_posterior_abstains() {
        let absurd = ScoreModel {
            mean_target: 1e308,
            mean_nontarget: 0.0,
            std: 1e-320,
        };
        let e = absurd.validate().unwrap_err();
        assert!(e.to_string().contains("finite posteriors"), "{e}");
        let tiny = ScoreModel {
            mean_target: 1.0,
            mean_nontarget: 0.0,
            std: 1e-160,
        };
        assert!(tiny.validate().is_err());
        let fine = ScoreModel {
            mean_target: 1.5,
            mean_nontarget: -0.3,
            std: 1.0,
        };
        fine.validate().unwrap();
        for rule in [DecisionRule::Fixed { rounds: 1 }, DecisionRule::dynamic(1)] {
            for evidence in [
                [f64::NAN, 0.0, 0.0, 0.0],
                [f64::INFINITY, f64::INFINITY, 0.0, 0.0],
                [f64::INFINITY, 0.0, 0.0, 0.0],
            ] {
                let v = rule.check(1, &evidence);
                assert!(
                    matches!(v, Verdict::Abstain { .. } | Verdict::Choose { .. }),
                    "{v:?}"
                );
                if let Verdict::Choose { posterior, .. } = &v {
                    assert!(posterior.p.iter().all(|p| p.is_finite()), "{v:?}");
                }
            }
            assert!(matches!(
                rule.check(1, &[f64::NAN, 0.0, 0.0, 0.0]),
                Verdict::Abstain { .. }
            ));
        }
    }

    #[test]
    fn no_scored_epoch_abstains_under_any_rule() {
        let scores = ScoreModelParams::default()
            .fit(&[2.0, 4.0, 0.0, -2.0], &[true, true, false, false])
            .unwrap();
        for rule in [DecisionRule::Fixed { rounds: 2 }, DecisionRule::dynamic(2)] {
            let m = DecisionModel { scores, rule };
            let (v, used) = m.decide(&[vec![None; 4], vec![None; 4]]);
            assert!(matches!(v, Verdict::Abstain { .. }), "{rule:?}: {v:?}");
            assert_eq!(used, 2);
            // One scored epoch is evidence: the fixed rule chooses.
            let (v, _) = m.decide(&[vec![Some(4.0), None, None, None], vec![None; 4]]);
            if matches!(rule, DecisionRule::Fixed { .. }) {
                assert!(matches!(v, Verdict::Choose { index: 0, .. }), "{v:?}");
            }
        }
    }

    #[test]
    fn score_model_matches_a_hand_computation() {
        let s = [2.0, 4.0, 0.0, -2.0, 1.0, -1.0];
        let y = [true, true, false, false, false, false];
        let m = ScoreModelParams::default().fit(&s, &y).unwrap();
        assert_eq!(m.mean_target, 3.0);
        assert_eq!(m.mean_nontarget, -0.5);
        // Within-class squares: 1 + 1 + 0.25 + 2.25 + 2.25 + 0.25 = 7, over n − 2 = 4.
        assert!((m.std - (7.0f64 / 4.0).sqrt()).abs() < 1e-15);
        // LLR equals the log ratio of the two Gaussian densities.
        let pdf = |x: f64, mu: f64| (-(x - mu).powi(2) / (2.0 * m.std * m.std)).exp();
        for x in [-3.0, 0.0, 1.25, 5.0] {
            let direct = (pdf(x, 3.0) / pdf(x, -0.5)).ln();
            assert!((m.llr(x) - direct).abs() < 1e-12);
        }
        assert!(ScoreModelParams::default()
            .fit(&[1.0, f64::NAN], &[true, false])
            .is_err());
        assert!(ScoreModelParams::default()
            .fit(&[1.0, 2.0, 3.0], &[true, false, false])
            .is_err());
    }

    #[test]
    fn posterior_sums_to_one_and_ranks_evidence() {
        let p = Posterior::from_evidence(&[0.0, 3.0, -1.0, 0.5], 0.2);
        let total: f64 = p.p.iter().sum::<f64>() + p.p_none;
        assert!((total - 1.0).abs() < 1e-12);
        assert_eq!(p.best().0, 1);
        // No evidence: the priors come back.
        let p = Posterior::from_evidence(&[0.0; 4], 0.2);
        assert!((p.p_none - 0.2).abs() < 1e-12);
        assert!(p.p.iter().all(|&x| (x - 0.2).abs() < 1e-12));
        // Huge evidence does not overflow.
        let p = Posterior::from_evidence(&[1e4, 0.0, 0.0, 0.0], 0.2);
        assert!((p.p[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn fixed_rule_waits_for_every_round_and_dynamic_stops_or_abstains() {
        let m = ScoreModel {
            mean_target: 1.0,
            mean_nontarget: -1.0,
            std: 1.0,
        };
        let strong = vec![vec![Some(3.0), Some(-1.0), None, Some(-1.0)]; 5];
        let fixed = DecisionModel {
            scores: m,
            rule: DecisionRule::Fixed { rounds: 5 },
        };
        let (v, used) = fixed.decide(&strong);
        assert_eq!(used, 5);
        assert!(matches!(v, Verdict::Choose { index: 0, .. }));
        let dynamic = DecisionModel {
            scores: m,
            rule: DecisionRule::dynamic(5),
        };
        let (v, used) = dynamic.decide(&strong);
        assert!(used < 5, "strong evidence stops early, used {used}");
        assert!(matches!(v, Verdict::Choose { index: 0, .. }));
        // Nobody attends: every score looks like a non-target → abstain at max rounds.
        let idle = vec![vec![Some(-1.0), Some(-1.2), Some(-0.8), Some(-1.0)]; 5];
        let (v, used) = dynamic.decide(&idle);
        assert_eq!(used, 5);
        assert!(matches!(v, Verdict::Abstain { .. }), "{v:?}");
        // Too few rounds given: Continue.
        let (v, used) = fixed.decide(&strong[..2]);
        assert_eq!((v, used), (Verdict::Continue, 2));
    }

    #[test]
    fn rules_are_validated() {
        assert!(DecisionRule::Fixed { rounds: 0 }.validate().is_err());
        assert!(DecisionRule::dynamic(5).validate().is_ok());
        let mut r = DecisionRule::dynamic(5);
        if let DecisionRule::Dynamic { threshold, .. } = &mut r {
            *threshold = 1.5;
        }
        assert!(r.validate().is_err());
        let r = DecisionRule::Dynamic {
            threshold: 0.9,
            min_rounds: 3,
            max_rounds: 2,
            credible: 0.5,
            p_no_control: 0.2,
        };
        assert!(r.validate().is_err());
    }
}
