//! Decoding without labels: expectation–maximisation over the paradigm's constraint
//! (Kindermans, Verstraeten & Schrauwen 2012, PLoS ONE 7(4):e33758), on a shrinkage LDA of the
//! `lda` preset's amplitude features.
//!
//! The paradigm says which labels are possible: in every trial exactly one code of each
//! [`Constraint`] set is attended — one of the four bulbs; one row and one column of a speller
//! character; or one choice, whose flashes are those of the groups showing it
//! ([`Constraint::groups`]); decoys are never attended. Which one is the latent variable. The
//! model is the LDA's own generative model: feature rows `xᵢ ~ N(μ_t, Σ)` for attended flashes and `N(μ_n, Σ)` for the others, with one
//! covariance, and a uniform prior over each slot's choices. Then
//!
//! * **E-step**: each slot's posterior over its codes is the softmax of the summed
//!   log-likelihood ratios `LLRᵢ = (μ_t − μ_n)ᵀΣ⁻¹(xᵢ − (μ_t + μ_n)/2)` of its epochs — the same
//!   evidence accumulation as a calibrated decision ([`crate::decision`]);
//! * **M-step**: with `rᵢ` = P(epoch i attended), the class means are the `r`-weighted means
//!   (shrunk towards the grand mean by `κ₀` pseudo-epochs, [`UnsupervisedParams::mean_prior`]:
//!   the penalty `−(κ₀/2)(μ_tᵀΣ⁻¹μ_t + μ_nᵀΣ⁻¹μ_n)` on centred means) and the covariance is the
//!   MAP estimate under an inverse-Wishart-type prior `−(c/2) ln|Σ| − ½ tr(c·D·Σ⁻¹)`:
//!   `Σ = (c·D + W) / (N + c)`, `W` the within-class scatter (with the means' penalty). Because
//!   the total scatter does not depend on the labels, `W = N·S − ΔμΔμᵀ / h` and
//!   `Σ = B − g·ΔμΔμᵀ` (`h = 1/(N_t + κ₀) + 1/(N_n + κ₀)`, `g = 1/(h(N + c))`), where `B = (1 − λ)·S + λ·D` is a Ledoit–Wolf shrunk total covariance
//!   (computed once, without labels; `D = diag S`, `λ` scikit-learn's Ledoit–Wolf shrinkage of the
//!   standardised rows, `c = λN/(1 − λ)`). This is a shrinkage LDA whose labels are soft, and one
//!   iteration needs only one solve with the Cholesky factor of `B` (Sherman–Morrison).
//!
//! [`Covariance::BlockToeplitz`] restricts the covariance to `Σ = σ²·B_T`, `B_T` the
//! block-Toeplitz, tapered form of `B` (the time-stationary structure of `toeplitz-lda`, on the
//! label-free total covariance, as the calibration-free spellers of Sosulski & Tangermann do),
//! fixed once; the M-step maximises the same penalised likelihood over the scale `σ²` (closed
//! form, always positive). The LLR's direction is then `B_T⁻¹Δμ` where the Ledoit–Wolf model's is
//! `B⁻¹Δμ` (its rank-one update changes only the scale).
//!
//! Both steps are exact, so the penalised log-likelihood (marginal over the unknown choices)
//! never decreases ([`Unsupervised::objective`]). EM finds a local maximum: a fit starts from
//! several initialisations (random projections of the standardised features, optionally a
//! previous model and a prior score per epoch such as the [`P300Template`]'s,
//! [`UnsupervisedParams::fit_features_from`]) and keeps the one of highest likelihood, or from
//! one given score per epoch only ([`UnsupervisedParams::fit_from_scores`]: another model's) —
//! no label is ever used, and the API takes none: epochs, stimulus codes and the trial of each
//! epoch only. [`replay`] decodes a recording as a live session would: each trial with the model
//! fitted on the trials so far, then every trial re-decoded by the final model.
//!
//! Written here: no Rust crate (nor scikit-learn, MNE or pyRiemann) has EM over such a
//! constraint. Checked against a dense numpy implementation that forms the means, scatter,
//! inverses and determinants directly and enumerates each trial's codes
//! (`tools/golden/unsupervised/`, objective per iteration, posteriors and LLRs to 1e-9), and by
//! property tests (posteriors sum to one; the objective never falls) in `tests/unsupervised.rs`.

mod constraint;
mod em;
mod error;
mod llp;
mod pooled;
mod replay;
mod template;

use std::collections::BTreeMap;

use ndarray::{Array1, ArrayView2, ArrayView3};
use serde::{Deserialize, Serialize};

use crate::features::amplitude::AmplitudeFeatures;
use crate::DecodeError;

pub use constraint::Constraint;
use error::Result;
pub use error::UnsupervisedError;
pub use llp::{ClassMeans, Llp, LlpParams, MeansLda, Mix};
pub use pooled::{
    feature_times, grid, is_placeholder, pooled_start, PooledPattern, PooledScorer, PooledStart,
    GRID_END_S, GRID_STEP_S, POOLED_VERSION,
};
pub use replay::{replay, replay_from, replay_starts, OnlineChoice, Replay, Start};
pub use template::{unit_spread, MatchedTemplate, P300Template};

/// What the label-free part `B` of the decoder's covariance `Σ = B − g·ΔμΔμᵀ` is (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Covariance {
    /// `B = (1 − λ)·S + λ·D`: the Ledoit–Wolf shrunk total covariance (the prior's scale `D`).
    #[default]
    LedoitWolf,
    /// `Σ = σ²·B_T`: `B_T` that matrix made block-Toeplitz over `n_channels` channels of the
    /// channel-major features (every channel pair and time lag averaged, lag `d` tapered by
    /// `(n_t − |d|)/n_t`: the time-stationary structure of `toeplitz-lda`, Sosulski & Tangermann
    /// 2022, on the total covariance, which needs no labels), fixed; the M-step chooses the scale
    /// `σ²` (the same objective, over covariances of that shape: still exact, never decreasing).
    BlockToeplitz {
        /// Channels of the features (each channel's points contiguous, the amplitude features'
        /// layout).
        n_channels: usize,
    },
}

/// Feature rows with their label-free statistics (centred rows, the shrunk total covariance
/// and its factor), from [`UnsupervisedParams::prepare`]: a refit and its held-out scores share
/// them instead of computing them twice.
#[derive(Debug)]
pub struct PreparedRows {
    prep: em::Prepared,
    covariance: Covariance,
}

impl PreparedRows {
    /// Epochs (rows).
    pub fn n_epochs(&self) -> usize {
        self.prep.n
    }
}

/// Settings of the unsupervised decoder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct UnsupervisedParams {
    /// The feature map (the `lda` preset's bin means by default).
    pub features: AmplitudeFeatures,
    /// Prior on each class mean, in pseudo-epochs at the grand mean (`κ₀`): keeps a fit on few
    /// trials from finding confident structure in noise; its weight fades as epochs accrue.
    pub mean_prior: f64,
    /// Random initialisations per fit (besides a warm start, if one is given).
    pub n_inits: usize,
    /// Most M-steps per initialisation.
    pub max_iter: usize,
    /// Stop when an iteration gains less than this (nats).
    pub tol: f64,
    /// Seed of the random initialisations.
    pub seed: u32,
    /// The label-free part of the covariance (Ledoit–Wolf by default, and in settings saved
    /// before this field existed).
    #[serde(default)]
    pub covariance: Covariance,
    /// With a warm start, random initialisations stop joining once there are this many epochs
    /// per feature: the last fit and the given starts carry on (`None`: they always join, as in
    /// settings saved before this field existed). The random starts find the likeliest optimum
    /// while the data are few; later they change nothing and cost nearly all of a refit.
    #[serde(default)]
    pub random_until: Option<f64>,
}

impl UnsupervisedParams {
    /// The `lda` preset's features at `sfreq` (bins of round(sfreq / 25) samples), no prior on
    /// the means, 32 random initialisations, at most 200 iterations each, tolerance 1e-6 nats,
    /// the Ledoit–Wolf covariance. 32, not 8, by the evidence: on eeg3 with seeds 0–9 the online
    /// characters were 7, 8, 5, 8, 8, 8, 5, 5, 6, 5 of 8 with 8 starts and 8 of 8 with 32 on
    /// every seed (the first trials' likeliest optimum is found more often); IIb and the
    /// OpenViBE run were unchanged, the simulated subjects see `README.md`. Random starts stop
    /// joining a warm-started refit at 4 epochs per feature: eeg3 (8/8) and the OpenViBE run
    /// (5/5) online unchanged at 2, 4 and 8, IIb (17/18) at 4 (it never holds 4 epochs per
    /// feature); the simulated typical subject at the fast timing, seeds 11–20, 91.5 % right
    /// against 91.3 % with them always; a warm refit at a long 64-channel session's cap (6000
    /// epochs × 1024 features of noise, each EM to its iteration cap) takes 7.0 s, against
    /// 31.3 s with them (`benches/adaptive.rs`).
    pub fn for_sfreq(sfreq: f64) -> std::result::Result<Self, DecodeError> {
        Ok(Self {
            features: AmplitudeFeatures::for_sfreq(sfreq)?,
            mean_prior: 0.0,
            n_inits: 32,
            max_iter: 200,
            tol: 1e-6,
            seed: 0,
            covariance: Covariance::LedoitWolf,
            random_until: Some(4.0),
        })
    }

    fn validate(&self) -> Result<()> {
        if self.n_inits == 0 || self.max_iter == 0 {
            return Err(UnsupervisedError::InvalidParameter {
                name: "n_inits/max_iter",
                value: format!("{}/{}", self.n_inits, self.max_iter),
                reason: "at least one initialisation and one iteration".into(),
            });
        }
        if !(self.mean_prior >= 0.0 && self.mean_prior.is_finite()) {
            return Err(UnsupervisedError::InvalidParameter {
                name: "mean_prior",
                value: self.mean_prior.to_string(),
                reason: "pseudo-epochs: finite and >= 0".into(),
            });
        }
        if let Some(r) = self.random_until {
            if !(r >= 0.0 && r.is_finite()) {
                return Err(UnsupervisedError::InvalidParameter {
                    name: "random_until",
                    value: r.to_string(),
                    reason: "epochs per feature: finite and >= 0".into(),
                });
            }
        }
        if self.tol.is_nan() || self.tol < 0.0 {
            return Err(UnsupervisedError::InvalidParameter {
                name: "tol",
                value: self.tol.to_string(),
                reason: "must be >= 0".into(),
            });
        }
        Ok(())
    }

    /// Fits on `epochs` `(n_epochs, n_channels, n_times)` with each epoch's stimulus `codes` and
    /// `trials` (any numbers: epochs with the same number form one trial).
    pub fn fit(
        &self,
        epochs: ArrayView3<f64>,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
    ) -> Result<Unsupervised> {
        let x = self.features.transform(epochs)?;
        self.fit_features(x.view(), codes, trials, constraint, None)
    }

    /// Fits on feature rows `x` `(n_epochs, n_features)`; `warm` (a previous model of the same
    /// features) is one more initialisation.
    pub fn fit_features(
        &self,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        warm: Option<&Unsupervised>,
    ) -> Result<Unsupervised> {
        self.fit_features_from(x, codes, trials, constraint, warm, None)
    }

    /// [`Self::fit_features`] with `prior`, a score per epoch (e.g. the [`P300Template`]'s), as
    /// one more initialisation (at [`unit_spread`]). With a prior, the random initialisations
    /// join only once there are at least as many epochs as features: before that the likeliest
    /// fit is as often noise as not, and the prior is what the decoder has to go on.
    pub fn fit_features_from(
        &self,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        warm: Option<&Unsupervised>,
        prior: Option<&[f64]>,
    ) -> Result<Unsupervised> {
        let starts: Vec<&[f64]> = prior.into_iter().collect();
        self.fit_features_starts(x, codes, trials, constraint, warm, &starts)
    }

    /// [`Self::fit_features`] with several `starts`, a score per epoch each (e.g. the
    /// [`P300Template`]'s and a [`PooledStart`]'s), each one more initialisation (at
    /// [`unit_spread`]; [`Init::Given`] the first, [`Init::Start`]`(k)` the k-th after it). With
    /// any start, the random initialisations join only once there are at least as many epochs
    /// as features: before that the likeliest fit is as often noise as not, and the starts are
    /// what the decoder has to go on; with `warm`, they stop joining at
    /// [`UnsupervisedParams::random_until`] epochs per feature. Whichever initialisation ends
    /// likeliest is kept: a start only chooses where EM begins.
    pub fn fit_features_starts(
        &self,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        warm: Option<&Unsupervised>,
        starts: &[&[f64]],
    ) -> Result<Unsupervised> {
        let rows = self.prepare(x)?;
        self.fit_prepared_starts(&rows, codes, trials, constraint, warm, starts)
    }

    /// The label-free statistics of feature rows `x` `(n_epochs, n_features)` under this
    /// covariance: computed once, shared by a fit ([`Self::fit_prepared_starts`],
    /// [`Self::fit_prepared_from_scores`]) and its held-out scores ([`Self::held_out_scores`]).
    pub fn prepare(&self, x: ArrayView2<f64>) -> Result<PreparedRows> {
        Ok(PreparedRows {
            prep: em::Prepared::new(x, self.covariance)?,
            covariance: self.covariance,
        })
    }

    fn prepared<'a>(&self, rows: &'a PreparedRows) -> Result<&'a em::Prepared> {
        self.validate()?;
        if rows.covariance != self.covariance {
            return Err(UnsupervisedError::InvalidParameter {
                name: "covariance",
                value: format!("{:?}", self.covariance),
                reason: format!("the rows were prepared for {:?}", rows.covariance),
            });
        }
        Ok(&rows.prep)
    }

    /// [`Self::fit_features_starts`] on prepared rows.
    pub fn fit_prepared_starts(
        &self,
        rows: &PreparedRows,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        warm: Option<&Unsupervised>,
        starts: &[&[f64]],
    ) -> Result<Unsupervised> {
        let prep = self.prepared(rows)?;
        let mut inits: Vec<(Init, Vec<f64>)> = Vec::new();
        for (k, s) in starts.iter().enumerate() {
            if s.len() != prep.n {
                return Err(UnsupervisedError::InitLength {
                    n_epochs: prep.n,
                    n_scores: s.len(),
                });
            }
            let init = if k == 0 { Init::Given } else { Init::Start(k) };
            inits.push((init, unit_spread(s)));
        }
        if let Some(w) = warm {
            inits.push((Init::Warm, w.decision_function_prepared(prep)?));
        }
        let mut rng = rand_mt::Mt::new(self.seed);
        let settled = warm.is_some()
            && self
                .random_until
                .is_some_and(|r| prep.n as f64 >= r * prep.p as f64);
        let n_random = if (starts.is_empty() || prep.n >= prep.p) && !settled {
            self.n_inits
        } else {
            0
        };
        for k in 0..n_random {
            inits.push((Init::Random(k), random_projection(prep, &mut rng)));
        }
        self.fit_prepared(prep, codes, trials, constraint, inits)
    }

    /// Leave-one-trial-out scores of prepared feature rows under `attended`, each epoch's
    /// responsibility (P(attended), e.g. a fit's posterior of its code): every trial of `held`
    /// scored by this model's M-step on all other epochs' responsibilities, as though that
    /// trial had not been seen (the label-free covariance part `B` is of all rows; it holds no
    /// label). `None` for epochs of other trials. Out-of-sample scores of the model family a fit
    /// belongs to, for judging how far its own scores can be believed; unlike a fit's
    /// posteriors, a trial's held-out score cannot have been pulled towards that trial's noise.
    pub fn held_out_scores(
        &self,
        rows: &PreparedRows,
        attended: &[f64],
        trials: &[usize],
        held: &[usize],
    ) -> Result<Vec<Option<f64>>> {
        let prep = self.prepared(rows)?;
        for (what, got) in [
            ("responsibilities", attended.len()),
            ("trial numbers", trials.len()),
        ] {
            if got != prep.n {
                return Err(UnsupervisedError::EpochCount {
                    what,
                    n_epochs: prep.n,
                    got,
                });
            }
        }
        // Probabilities, up to the rounding of a sum of posteriors.
        if let Some(&r) = attended.iter().find(|r| !(-1e-9..=1.0 + 1e-9).contains(*r)) {
            return Err(UnsupervisedError::InvalidParameter {
                name: "attended",
                value: r.to_string(),
                reason: "responsibilities are probabilities in [0, 1]".into(),
            });
        }
        let r: Vec<f64> = attended.iter().map(|r| r.clamp(0.0, 1.0)).collect();
        Ok(em::held_out(prep, &r, trials, held, self.mean_prior))
    }

    /// One EM run on feature rows `x` from `init`, a score per epoch taken as the first E-step's
    /// log-likelihood ratios (e.g. another model's scores); no random initialisations.
    pub fn fit_from_scores(
        &self,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        init: &[f64],
    ) -> Result<Unsupervised> {
        let rows = self.prepare(x)?;
        self.fit_prepared_from_scores(&rows, codes, trials, constraint, init)
    }

    /// [`Self::fit_from_scores`] on prepared rows.
    pub fn fit_prepared_from_scores(
        &self,
        rows: &PreparedRows,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        init: &[f64],
    ) -> Result<Unsupervised> {
        let prep = self.prepared(rows)?;
        if init.len() != prep.n {
            return Err(UnsupervisedError::InitLength {
                n_epochs: prep.n,
                n_scores: init.len(),
            });
        }
        self.fit_prepared(
            prep,
            codes,
            trials,
            constraint,
            vec![(Init::Given, init.to_vec())],
        )
    }

    fn fit_prepared(
        &self,
        prep: &em::Prepared,
        codes: &[u32],
        trials: &[usize],
        constraint: &Constraint,
        inits: Vec<(Init, Vec<f64>)>,
    ) -> Result<Unsupervised> {
        let (layout, trial_ids) = layout(prep.n, codes, trials, constraint)?;
        let mut best: Option<(Init, em::Run)> = None;
        let mut init_objectives = Vec::with_capacity(inits.len());
        let mut posteriors = Vec::with_capacity(inits.len());
        for (init, s) in inits {
            let run = em::run(prep, &layout, &s, self.mean_prior, self.max_iter, self.tol)?;
            let j = *run.objective.last().expect("one M-step at least");
            init_objectives.push((init, j));
            posteriors.push((j, run.posterior.clone()));
            if best
                .as_ref()
                .is_none_or(|(_, b)| j > *b.objective.last().expect("one M-step"))
            {
                best = Some((init, run));
            }
        }
        let (init, run) = best.expect("at least one initialisation");
        // Every initialisation's posterior, weighted by its likelihood relative to the best.
        let j_max = posteriors
            .iter()
            .map(|(j, _)| *j)
            .fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = posteriors.iter().map(|(j, _)| (j - j_max).exp()).sum();
        let mut averaged: Vec<Vec<f64>> =
            run.posterior.iter().map(|p| vec![0.0; p.len()]).collect();
        for (j, post) in &posteriors {
            let wgt = (j - j_max).exp() / z;
            for (a, p) in averaged.iter_mut().zip(post) {
                for (x, y) in a.iter_mut().zip(p) {
                    *x += wgt * y;
                }
            }
        }
        let n_sets = constraint.sets().len();
        let averaged = to_trials(&averaged, &trial_ids, n_sets);
        let intercept = run.linear.offset - run.linear.w.dot(&prep.mean);
        let trials_out = to_trials(&run.posterior, &trial_ids, n_sets);
        Ok(Unsupervised {
            features: self.features,
            coef: Array1::from_iter(run.linear.w.iter().copied()),
            intercept,
            constraint: constraint.clone(),
            trials: trials_out,
            averaged,
            objective: run.objective,
            init,
            init_objectives,
            shrinkage: prep.shrinkage,
            covariance: self.covariance,
        })
    }
}

/// Scores of a random projection of the standardised features, scaled to unit spread.
fn random_projection(prep: &em::Prepared, rng: &mut rand_mt::Mt) -> Vec<f64> {
    let v = nalgebra::DVector::from_fn(prep.p, |j, _| normal(rng) / prep.d[j].sqrt());
    let s = &prep.xc * v;
    let sd = (s.norm_squared() / prep.n as f64)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    s.iter().map(|x| x / sd).collect()
}

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut rand_mt::Mt) -> f64 {
    let u = |rng: &mut rand_mt::Mt| ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let (u1, u2) = (u(rng), u(rng));
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// The slots of the epochs (trial in order of first appearance × set) and the trial numbers in
/// that order.
fn layout(
    n_epochs: usize,
    codes: &[u32],
    trials: &[usize],
    constraint: &Constraint,
) -> Result<(em::Layout, Vec<usize>)> {
    if codes.len() != n_epochs || trials.len() != n_epochs {
        return Err(UnsupervisedError::Length {
            n_epochs,
            n_codes: codes.len(),
            n_trials: trials.len(),
        });
    }
    let n_sets = constraint.sets().len();
    let mut dense: BTreeMap<usize, usize> = BTreeMap::new();
    let mut ids = Vec::new();
    let mut slot_of = Vec::with_capacity(n_epochs);
    let mut choice_start = Vec::with_capacity(n_epochs + 1);
    let mut choice_idx = Vec::with_capacity(n_epochs);
    choice_start.push(0);
    for (index, (&code, &trial)) in codes.iter().zip(trials).enumerate() {
        let located = match constraint.targets_of(code) {
            Some(at) => Some(at),
            None if constraint.is_decoy(code) => None,
            None => {
                return Err(UnsupervisedError::UnknownCode {
                    index,
                    code,
                    sets: constraint.sets().to_vec(),
                })
            }
        };
        let t = *dense.entry(trial).or_insert_with(|| {
            ids.push(trial);
            ids.len() - 1
        });
        // A decoy is in no slot: a known non-target.
        slot_of.push(located.as_ref().map(|(set, _)| t * n_sets + set));
        if let Some((_, choices)) = located {
            choice_idx.extend(choices);
        }
        choice_start.push(choice_idx.len());
    }
    let n_choices = (0..ids.len())
        .flat_map(|_| constraint.sets().iter().map(Vec::len))
        .collect();
    Ok((
        em::Layout {
            slot_of,
            choice_start,
            choice_idx,
            n_choices,
        },
        ids,
    ))
}

/// Where a fit started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Init {
    /// From the model given as the warm start.
    Warm,
    /// From the k-th random projection.
    Random(usize),
    /// From scores given to [`UnsupervisedParams::fit_from_scores`], or the first start given
    /// to [`UnsupervisedParams::fit_features_starts`].
    Given,
    /// From the k-th start (k ≥ 1) given to [`UnsupervisedParams::fit_features_starts`].
    Start(usize),
}

/// One trial's posterior: per constraint set, P(code attended) in the set's order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialPosterior {
    /// The trial's number as given.
    pub trial: usize,
    pub sets: Vec<Vec<f64>>,
}

/// A fitted unsupervised decoder: a linear log-likelihood ratio per epoch and the posterior of
/// every trial it was fitted on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Unsupervised {
    features: AmplitudeFeatures,
    coef: Array1<f64>,
    intercept: f64,
    constraint: Constraint,
    trials: Vec<TrialPosterior>,
    averaged: Vec<TrialPosterior>,
    objective: Vec<f64>,
    init: Init,
    init_objectives: Vec<(Init, f64)>,
    shrinkage: f64,
    #[serde(default)]
    covariance: Covariance,
}

impl Unsupervised {
    /// LLR (target vs non-target, nats) per epoch `(n_epochs, n_channels, n_times)`.
    pub fn decision_function(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let x = self.features.transform(epochs)?;
        self.decision_function_features(x.view())
    }

    /// LLR per feature row.
    pub fn decision_function_features(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.check_width(x.ncols())?;
        Ok(x.dot(&self.coef) + self.intercept)
    }

    /// Rows of `n_features` features are this model's input.
    fn check_width(&self, n_features: usize) -> Result<()> {
        if n_features != self.coef.len() {
            return Err(DecodeError::ShapeMismatch {
                what: "unsupervised decoder input".into(),
                expected: format!("{} features", self.coef.len()),
                got: n_features.to_string(),
            }
            .into());
        }
        Ok(())
    }

    /// The score of every prepared row (`coefᵀx + intercept`, with `x` the centred row plus the
    /// rows' mean).
    fn decision_function_prepared(&self, prep: &em::Prepared) -> Result<Vec<f64>> {
        self.check_width(prep.p)?;
        let coef = nalgebra::DVector::from_iterator(self.coef.len(), self.coef.iter().copied());
        let offset = coef.dot(&prep.mean) + self.intercept;
        Ok((&prep.xc * &coef).iter().map(|v| v + offset).collect())
    }

    /// LLR of one epoch `(n_channels, n_times)`.
    pub fn score_epoch(&self, epoch: ndarray::ArrayView2<f64>) -> Result<f64> {
        let e = epoch.insert_axis(ndarray::Axis(0));
        Ok(self.decision_function(e)?[0])
    }

    /// The fitted trials' posteriors, in order of first appearance.
    pub fn trials(&self) -> &[TrialPosterior] {
        &self.trials
    }

    /// The fitted trials' posteriors averaged over every initialisation's local optimum, each
    /// weighted by its likelihood relative to the best (`exp(J_k − J_max)`): where optima of
    /// similar likelihood disagree about a trial, its posterior is spread between them.
    pub fn averaged_trials(&self) -> &[TrialPosterior] {
        &self.averaged
    }

    /// Per fitted trial, the most probable code of each set.
    pub fn choices(&self) -> Vec<Vec<u32>> {
        self.choices_of(&self.trials)
    }

    /// Per trial of `posteriors`, the most probable code of each set.
    pub fn choices_of(&self, posteriors: &[TrialPosterior]) -> Vec<Vec<u32>> {
        posteriors
            .iter()
            .map(|t| {
                t.sets
                    .iter()
                    .zip(self.constraint.sets())
                    .map(|(p, codes)| codes[argmax(p)])
                    .collect()
            })
            .collect()
    }

    /// Each trial's posterior over its choices under this model (the E-step, uniform prior), for
    /// feature rows `x` with their stimulus `codes` and `trials` — epochs it was not fitted on.
    pub fn posteriors_features(
        &self,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
    ) -> Result<Vec<TrialPosterior>> {
        let llr = self.decision_function_features(x)?;
        let (layout, ids) = layout(x.nrows(), codes, trials, &self.constraint)?;
        let (post, _) = em::e_step(&layout, llr.as_slice().expect("a new array is contiguous"));
        Ok(to_trials(&post, &ids, self.constraint.sets().len()))
    }

    /// The penalised log-likelihood after each iteration of the chosen initialisation
    /// (non-decreasing).
    pub fn objective(&self) -> &[f64] {
        &self.objective
    }

    /// Where the chosen run started, and every initialisation's final objective.
    pub fn init(&self) -> (Init, &[(Init, f64)]) {
        (self.init, &self.init_objectives)
    }

    pub fn constraint(&self) -> &Constraint {
        &self.constraint
    }

    pub fn features(&self) -> AmplitudeFeatures {
        self.features
    }

    /// Weights of the LLR per feature.
    pub fn coef(&self) -> ndarray::ArrayView1<'_, f64> {
        self.coef.view()
    }

    pub fn intercept(&self) -> f64 {
        self.intercept
    }

    /// The Ledoit–Wolf shrinkage of the total covariance.
    pub fn shrinkage(&self) -> f64 {
        self.shrinkage
    }

    /// The covariance structure it was fitted with.
    pub fn covariance(&self) -> Covariance {
        self.covariance
    }
}

/// Slot posteriors (trial in order × set) as one [`TrialPosterior`] per trial `ids[t]`.
fn to_trials(post: &[Vec<f64>], ids: &[usize], n_sets: usize) -> Vec<TrialPosterior> {
    ids.iter()
        .enumerate()
        .map(|(t, &id)| TrialPosterior {
            trial: id,
            sets: post[t * n_sets..(t + 1) * n_sets].to_vec(),
        })
        .collect()
}

/// Index of the largest value (first on ties).
pub(crate) fn argmax(p: &[f64]) -> usize {
    let mut best = 0;
    for (i, &v) in p.iter().enumerate() {
        if v > p[best] {
            best = i;
        }
    }
    best
}
