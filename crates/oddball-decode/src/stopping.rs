//! Stopping chosen for bit rate: the dynamic-stopping threshold and round limit that maximise
//! the expected Wolpaw information transfer rate (or the utility rate) of a person, estimated
//! from their calibration alone.
//!
//! [`StoppingSearch::choose`] replays `n_decisions` simulated decisions per candidate
//! (threshold × round limit) with the *cross-validated* calibration scores: each flash of the
//! attended stimulus draws a score from the calibration's out-of-fold target scores, each other
//! flash from the non-target ones (with replacement, independently: a bootstrap of the
//! empirical score distributions, which keeps their tails and any bias the Gaussian score model
//! misses). The scores become evidence through the fitted [`ScoreModel`] and the candidate's
//! [`DecisionRule::Dynamic`] decides, continues or abstains exactly as online. Every candidate
//! sees the same simulated flashes (common random numbers), so they are compared on the same
//! luck. A decision's seconds come from the caller (the paradigm's cue, flashing and decoding
//! time for a number of rounds), so the search knows what a round costs.
//!
//! Objectives: Wolpaw's ITR with every abstention counted as a miss (as the session reports
//! it), or the utility rate of Dal Seno et al. (2010): `(correct − wrong) · log2(N − 1)` bits per
//! total time — what a person actually gets done when each error costs one more selection to
//! undo it; abstentions cost only their time. Written here: no crate does Monte-Carlo stopping
//! design over a BCI's own scores.

use rand_mt::Mt64;
use serde::{Deserialize, Serialize};

use crate::decision::{DecisionModel, DecisionRule, ScoreModel, Verdict};
use crate::metrics::wolpaw_bits;
use crate::DecodeError;

/// What the search maximises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Objective {
    /// Wolpaw bits per minute, accuracy over every decision (abstentions are misses).
    Wolpaw,
    /// Utility bits per minute (Dal Seno et al. 2010): `(correct − wrong) · log2(N − 1)` per
    /// minute, 0 when errors are as many as hits.
    Utility,
}

/// Settings of the search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoppingSearch {
    /// Candidate posterior thresholds.
    pub thresholds: Vec<f64>,
    /// Round limits tried: 1..=`max_rounds`.
    pub max_rounds: usize,
    /// At the round limit, choose only with at least this posterior (else abstain).
    pub credible: f64,
    /// Prior of "attending nothing" (kept so abstention works as online).
    pub p_no_control: f64,
    pub objective: Objective,
    /// Only candidates expected to be right at least this often compete on the objective (the
    /// most accurate wins when none is); 0 for no floor.
    #[serde(default)]
    pub min_accuracy: f64,
    /// Simulated decisions per candidate.
    pub n_decisions: usize,
    pub seed: u64,
}

impl Default for StoppingSearch {
    /// Thresholds 0.70–0.999, 1..=12 rounds, abstain below 0.5, no-control prior 0.2 (the
    /// defaults of [`DecisionRule::dynamic`]), Wolpaw, 4000 decisions.
    fn default() -> Self {
        Self {
            thresholds: vec![
                0.7, 0.8, 0.85, 0.9, 0.925, 0.95, 0.97, 0.98, 0.99, 0.995, 0.999,
            ],
            max_rounds: 12,
            credible: 0.5,
            p_no_control: 0.2,
            objective: Objective::Wolpaw,
            min_accuracy: 0.0,
            n_decisions: 4000,
            seed: 0,
        }
    }
}

/// The expected performance of one rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Expected {
    pub rule: DecisionRule,
    /// Right decisions over all decisions.
    pub accuracy: f64,
    pub abstained: f64,
    pub mean_rounds: f64,
    pub seconds_per_decision: f64,
    pub wolpaw_bits_per_min: f64,
    pub utility_bits_per_min: f64,
}

impl Expected {
    fn value(&self, objective: Objective) -> f64 {
        match objective {
            Objective::Wolpaw => self.wolpaw_bits_per_min,
            Objective::Utility => self.utility_bits_per_min,
        }
    }
}

/// Utility bits per selection of Dal Seno et al. (2010): `(p_correct − p_wrong) · log2(N − 1)`,
/// at least 0 (abstentions move nothing).
pub fn utility_bits(n_choices: usize, p_correct: f64, p_wrong: f64) -> f64 {
    if n_choices < 2 {
        return 0.0;
    }
    ((p_correct - p_wrong) * ((n_choices - 1) as f64).log2()).max(0.0)
}

impl StoppingSearch {
    pub fn validate(&self) -> Result<(), DecodeError> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(DecodeError::InvalidParameter {
                name,
                value,
                reason: reason.to_string(),
            })
        };
        if self.thresholds.is_empty() || self.thresholds.iter().any(|t| !(*t > 0.0 && *t <= 1.0)) {
            return bad(
                "thresholds",
                format!("{:?}", self.thresholds),
                "one or more probabilities in (0, 1]",
            );
        }
        if self.max_rounds == 0 {
            return bad("max_rounds", "0".into(), "at least one round");
        }
        if !(0.0..=1.0).contains(&self.min_accuracy) {
            return bad(
                "min_accuracy",
                self.min_accuracy.to_string(),
                "a probability in [0, 1]",
            );
        }
        if self.n_decisions == 0 {
            return bad("n_decisions", "0".into(), "at least one decision");
        }
        DecisionRule::Dynamic {
            threshold: self.thresholds[0],
            min_rounds: 1,
            max_rounds: self.max_rounds,
            credible: self.credible,
            p_no_control: self.p_no_control,
        }
        .validate()
    }

    /// Every candidate's expected performance, best first (ties: fewer rounds, then lower
    /// threshold). `target` and `nontarget` are out-of-fold calibration scores, `scores` the
    /// score model fitted on them, `n_choices` the stimuli per decision, `seconds(r)` the length
    /// of a decision that used `r` rounds.
    pub fn rank(
        &self,
        scores: &ScoreModel,
        target: &[f64],
        nontarget: &[f64],
        n_choices: usize,
        seconds: impl Fn(usize) -> f64,
    ) -> Result<Vec<Expected>, DecodeError> {
        self.validate()?;
        if target.is_empty() || nontarget.is_empty() || n_choices < 2 {
            return Err(DecodeError::NeedBothClasses {
                n_targets: target.len(),
                n_nontargets: nontarget.len(),
            });
        }
        if let Some(s) = target.iter().chain(nontarget).find(|s| !s.is_finite()) {
            return Err(DecodeError::NonFinite {
                what: format!("calibration score {s}"),
            });
        }
        // The simulated flashes: per decision, max_rounds rounds of one score per stimulus;
        // stimulus 0 is attended (the rule is symmetric in the stimuli; a posterior tie goes
        // to the lowest index, which continuous scores make improbable).
        let mut rng = Mt64::new(self.seed);
        let mut pick = |from: &[f64]| from[(rng.next_u64() % from.len() as u64) as usize];
        let trials: Vec<Vec<Vec<Option<f64>>>> = (0..self.n_decisions)
            .map(|_| {
                (0..self.max_rounds)
                    .map(|_| {
                        (0..n_choices)
                            .map(|k| Some(pick(if k == 0 { target } else { nontarget })))
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let mut out = Vec::new();
        for max_rounds in 1..=self.max_rounds {
            for &threshold in &self.thresholds {
                let rule = DecisionRule::Dynamic {
                    threshold,
                    min_rounds: 1,
                    max_rounds,
                    credible: self.credible,
                    p_no_control: self.p_no_control,
                };
                let model = DecisionModel {
                    scores: *scores,
                    rule,
                };
                let (mut right, mut wrong, mut abstained, mut rounds, mut time) =
                    (0usize, 0usize, 0usize, 0usize, 0.0);
                for t in &trials {
                    let (verdict, used) = model.decide(&t[..max_rounds]);
                    rounds += used;
                    time += seconds(used);
                    match verdict {
                        Verdict::Choose { index: 0, .. } => right += 1,
                        Verdict::Choose { .. } => wrong += 1,
                        _ => abstained += 1,
                    }
                }
                let n = self.n_decisions as f64;
                let per_decision = time / n;
                let per_min = |bits: f64| {
                    if per_decision > 0.0 {
                        bits * 60.0 / per_decision
                    } else {
                        0.0
                    }
                };
                let accuracy = right as f64 / n;
                out.push(Expected {
                    rule,
                    accuracy,
                    abstained: abstained as f64 / n,
                    mean_rounds: rounds as f64 / n,
                    seconds_per_decision: per_decision,
                    wolpaw_bits_per_min: per_min(wolpaw_bits(n_choices, accuracy)),
                    utility_bits_per_min: per_min(utility_bits(
                        n_choices,
                        accuracy,
                        wrong as f64 / n,
                    )),
                });
            }
        }
        let (objective, floor) = (self.objective, self.min_accuracy);
        // Candidates over the accuracy floor first, by the objective; the rest by accuracy.
        let key = |e: &Expected| {
            if e.accuracy >= floor {
                (1, e.value(objective))
            } else {
                (0, e.accuracy)
            }
        };
        out.sort_by(|a, b| {
            let (ka, kb) = (key(a), key(b));
            kb.0.cmp(&ka.0)
                .then(kb.1.total_cmp(&ka.1))
                .then(a.rule.max_rounds().cmp(&b.rule.max_rounds()))
        });
        Ok(out)
    }

    /// The candidate with the largest expected objective (see [`Self::rank`]).
    pub fn choose(
        &self,
        scores: &ScoreModel,
        target: &[f64],
        nontarget: &[f64],
        n_choices: usize,
        seconds: impl Fn(usize) -> f64,
    ) -> Result<Expected, DecodeError> {
        Ok(self.rank(scores, target, nontarget, n_choices, seconds)?[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decision::ScoreModelParams;

    /// Scores of a detector with separation `d` (unit variance), evenly spread quantiles.
    fn scores(d: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        // Normal quantiles by inverting the CDF with bisection on erf (libm).
        let q = |p: f64| {
            let (mut lo, mut hi) = (-10.0, 10.0);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if 0.5 * (1.0 + libm::erf(mid / std::f64::consts::SQRT_2)) < p {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        let z: Vec<f64> = (0..n).map(|i| q((i as f64 + 0.5) / n as f64)).collect();
        (z.iter().map(|v| v + d).collect(), z)
    }

    fn fit(t: &[f64], n: &[f64]) -> ScoreModel {
        let s: Vec<f64> = t.iter().chain(n).copied().collect();
        let y: Vec<bool> = t
            .iter()
            .map(|_| true)
            .chain(n.iter().map(|_| false))
            .collect();
        ScoreModelParams::default().fit(&s, &y).unwrap()
    }

    #[test]
    fn one_round_fixed_accuracy_matches_the_closed_form() {
        // One round and a credible level of 1e-9: always the best of the four after one round.
        // P(correct) for 4 unit Gaussians with separation d is ∫ φ(x − d) Φ(x)³ dx.
        let d = 1.5;
        let (t, n) = scores(d, 400);
        let model = fit(&t, &n);
        let search = StoppingSearch {
            thresholds: vec![1.0],
            max_rounds: 1,
            credible: 1e-9,
            p_no_control: 0.0,
            n_decisions: 20000,
            ..Default::default()
        };
        let e = search.choose(&model, &t, &n, 4, |r| r as f64).unwrap();
        let phi = |x: f64| (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let cdf = |x: f64| 0.5 * (1.0 + libm::erf(x / std::f64::consts::SQRT_2));
        let (a, b, m) = (-8.0, 12.0, 20000);
        let h = (b - a) / m as f64;
        let exact: f64 = (0..m)
            .map(|i| {
                let x = a + (i as f64 + 0.5) * h;
                phi(x - d) * cdf(x).powi(3) * h
            })
            .sum();
        assert!(
            (e.accuracy - exact).abs() < 0.015,
            "{} vs {exact}",
            e.accuracy
        );
        assert_eq!(e.mean_rounds, 1.0);
        assert_eq!(e.abstained, 0.0);
        assert!(
            (e.wolpaw_bits_per_min - 60.0 * wolpaw_bits(4, e.accuracy)).abs() < 1e-9,
            "one second per decision"
        );
    }

    #[test]
    fn weak_users_get_more_rounds_and_strong_users_fewer() {
        let secs = |r: usize| 1.0 + 0.7 * r as f64 + 0.4;
        let search = StoppingSearch::default();
        let (ts, ns) = scores(2.5, 300);
        let strong = search.choose(&fit(&ts, &ns), &ts, &ns, 4, secs).unwrap();
        let (tw, nw) = scores(0.6, 300);
        let weak = search.choose(&fit(&tw, &nw), &tw, &nw, 4, secs).unwrap();
        assert!(weak.rule.max_rounds() > 5, "{weak:?}");
        assert!(weak.mean_rounds > strong.mean_rounds, "{weak:?} {strong:?}");
        assert!(strong.wolpaw_bits_per_min > weak.wolpaw_bits_per_min);
        // The chosen rule is at least as good as every candidate, and as 5 fixed-ish rounds.
        let all = search.rank(&fit(&tw, &nw), &tw, &nw, 4, secs).unwrap();
        assert_eq!(all[0], weak);
        assert!(all
            .iter()
            .all(|e| e.wolpaw_bits_per_min <= weak.wolpaw_bits_per_min));
        assert_eq!(all.len(), 12 * search.thresholds.len());
    }

    #[test]
    fn an_accuracy_floor_buys_accuracy_with_time() {
        let secs = |r: usize| 1.0 + 0.7 * r as f64 + 0.4;
        let (t, n) = scores(1.2, 300);
        let m = fit(&t, &n);
        let free = StoppingSearch::default()
            .choose(&m, &t, &n, 4, secs)
            .unwrap();
        let floored = StoppingSearch {
            min_accuracy: 0.95,
            ..Default::default()
        };
        let sure = floored.choose(&m, &t, &n, 4, secs).unwrap();
        assert!(free.accuracy < 0.95, "{free:?}");
        assert!(sure.accuracy >= 0.95, "{sure:?}");
        assert!(sure.mean_rounds > free.mean_rounds);
        assert!(sure.wolpaw_bits_per_min <= free.wolpaw_bits_per_min);
        // Out of reach: the most accurate candidate.
        let out_of_reach = StoppingSearch {
            min_accuracy: 1.0,
            max_rounds: 2,
            ..Default::default()
        };
        let all = out_of_reach.rank(&m, &t, &n, 4, secs).unwrap();
        assert!(all.iter().all(|e| e.accuracy <= all[0].accuracy));
    }

    #[test]
    fn utility_charges_for_errors() {
        assert_eq!(utility_bits(4, 1.0, 0.0), 3f64.log2());
        assert_eq!(utility_bits(4, 0.5, 0.5), 0.0);
        assert_eq!(utility_bits(4, 0.3, 0.6), 0.0);
        assert!((utility_bits(4, 0.9, 0.05) - 0.85 * 3f64.log2()).abs() < 1e-12);
        let (t, n) = scores(1.0, 200);
        let search = StoppingSearch {
            objective: Objective::Utility,
            n_decisions: 500,
            ..Default::default()
        };
        let best = search
            .choose(&fit(&t, &n), &t, &n, 4, |r| r as f64)
            .unwrap();
        assert!(best.utility_bits_per_min > 0.0);
    }

    #[test]
    fn bad_settings_and_scores_are_refused() {
        let (t, n) = scores(1.0, 20);
        let m = fit(&t, &n);
        let s = StoppingSearch {
            max_rounds: 0,
            ..Default::default()
        };
        assert!(s.choose(&m, &t, &n, 4, |r| r as f64).is_err());
        let s = StoppingSearch {
            thresholds: vec![1.5],
            ..Default::default()
        };
        assert!(s.choose(&m, &t, &n, 4, |r| r as f64).is_err());
        let s = StoppingSearch::default();
        assert!(s.choose(&m, &[], &n, 4, |r| r as f64).is_err());
        assert!(s.choose(&m, &[f64::NAN], &n, 4, |r| r as f64).is_err());
    }
}
