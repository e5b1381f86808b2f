//! Learning from label proportions (LLP) and its mixture with the EM (MIX): class means without
//! labels where the paradigm fixes the share of targets in groups of flashes.
//!
//! **LLP** (Hübner et al. 2017, "Learning from label proportions in brain-computer interfaces",
//! PLoS ONE 12(4):e0175856). The flashes come in groups (sequence types) whose target proportion `π_g` is
//! known from the paradigm, though not which flash was the target. Under the LDA's model every
//! group's mean is `m_g = π_g μ_t + (1 − π_g) μ_n`, so with at least two groups of different `π`
//! the class means are the least-squares solution of `A [μ_t; μ_n] = M` (`A`'s rows
//! `[π_g, 1 − π_g]`, `M`'s rows the group means; two groups: the closed form
//! `μ_t = ((1 − π₂)m₁ − (1 − π₁)m₂)/(π₁ − π₂)`, `μ_n = (π₁m₂ − π₂m₁)/(π₁ − π₂)`). The estimate is
//! unbiased and needs no iteration nor initialisation; it is noisier than a supervised mean by
//! the factors of `(AᵀA)⁻¹Aᵀ`, large when the proportions are close.
//!
//! **When the paradigm allows it.** Only when groups of flashes differ in their target share:
//! Hübner et al. added symbols that are never targets to a speller, so that sequences of type 1
//! have `π₁ = 3/8` and of type 2 `π₂ = 2/18`. The standard row/column speller does not: every row
//! or column flash set holds the target once, so every sequence has the same share (two of twelve
//! flashes on a 6 × 6 matrix) and the means are not identified — [`LlpParams::fit`] refuses
//! groups of one proportion ([`UnsupervisedError::NotIdentified`]). Neither does the four-bulb
//! panel as run here (one attended bulb among four in every trial). Use the EM
//! ([`super::UnsupervisedParams`]) there. Where a paradigm does have such groups, its file says
//! so (`[groups]`, `decoys`) and the EM's constraint holds every flash's membership
//! ([`super::Constraint::groups`], [`super::Constraint::with_decoys`]), which is more than the
//! proportions: a live session decodes with that; this estimator and [`Mix`] stay for replays
//! that know only the proportions.
//!
//! **The classifier** is the EM's shrinkage LDA with its labels at the known proportions: `B` the
//! Ledoit–Wolf shrunk total covariance of the rows (the EM's own `Prepared` statistics,
//! label-free), the within-class covariance `Σ = B − q·ΔμΔμᵀ` with `q = π̄(1 − π̄)·N/(N + c)`
//! (`π̄` the epochs' overall target share, `c` the covariance prior of the EM: the EM's M-step
//! with every responsibility at `π̄`), `w = Σ⁻¹Δμ = B⁻¹Δμ / (1 − q·ΔμᵀB⁻¹Δμ)` (Sherman–Morrison)
//! and the LLR `wᵀx − wᵀ(μ_t + μ_n)/2`.
//!
//! **MIX** (Hübner et al. 2018, "Unsupervised learning for brain-computer interfaces based on
//! event-related potentials", IEEE Computational Intelligence Magazine 13(2)): per class, the convex combination `γ·μ_EM + (1 − γ)·μ_LLP` of the two
//! estimates, `γ` minimising the variance of the combination. The paper estimates each
//! estimator's variance; what is done here (simple, stated): each mean's sampling variance is
//! summarised by its trace (the sum over features), and
//!
//! * LLP: `μ_k = Σ_g C_kg m_g` (`C = (AᵀA)⁻¹Aᵀ`), the group means independent, so
//!   `v_k = Σ_g C_kg² tr(S_g)/n_g`, `S_g` group g's (maximum-likelihood) covariance;
//! * EM: the means of its M-step, `μ_t = (Σ rᵢxᵢ + κ₀m̄)/(N_t + κ₀)` from the responsibilities
//!   `rᵢ` (and `1 − rᵢ` for `μ_n`), so `v_t = tr(S_w)·Σ rᵢ²/(N_t + κ₀)²`, `S_w` the
//!   `r`-weighted within-class covariance — as if the responsibilities were fixed weights;
//! * `γ_k = v_LLP,k / (v_EM,k + v_LLP,k)` (the minimiser for uncorrelated estimators).
//!
//! What this leaves out: the two estimates come from the same epochs and are correlated; the
//! EM's variance ignores the uncertainty of its labels beyond their softness and its bias at a
//! wrong local optimum (where the LLP, unbiased, is what the mixture should lean on), so `γ` is
//! optimistic for the EM when it is unsure. The mixed means are decoded by the same LDA as the
//! LLP's.
//!
//! Written here: no Rust crate (nor scikit-learn, MNE or pyRiemann) estimates from label
//! proportions. Checked against numpy's `lstsq` on the group means and a dense LDA
//! (`tools/golden/unsupervised/make_llp.py`, to 1e-9) and by a consistency test (the error to the
//! true means falls with the number of epochs) in `tests/llp.rs`.

use nalgebra::{DMatrix, DVector};
use ndarray::{Array1, ArrayView2};
use serde::{Deserialize, Serialize};

use super::em::Prepared;
use super::error::{Result, UnsupervisedError};
use super::{Covariance, Unsupervised};
use crate::DecodeError;

/// Estimated class means and the estimated sampling variance (its trace: summed over features)
/// of each.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClassMeans {
    pub target: Array1<f64>,
    pub non_target: Array1<f64>,
    /// `[target, non-target]`: the trace of each mean's estimated sampling covariance.
    pub variance: [f64; 2],
}

impl ClassMeans {
    /// The EM's M-step means from responsibilities `r` (P(epoch attended), one per row of `x`)
    /// with `mean_prior` pseudo-epochs at the grand mean on each class
    /// ([`super::UnsupervisedParams::mean_prior`]), and their variances as if `r` were fixed
    /// weights (module doc).
    pub fn from_responsibilities(x: ArrayView2<f64>, r: &[f64], mean_prior: f64) -> Result<Self> {
        let (n, p) = x.dim();
        check_finite(x)?;
        if r.len() != n {
            return Err(UnsupervisedError::EpochCount {
                what: "responsibilities",
                n_epochs: n,
                got: r.len(),
            });
        }
        if !(mean_prior >= 0.0 && mean_prior.is_finite()) {
            return Err(UnsupervisedError::InvalidParameter {
                name: "mean_prior",
                value: mean_prior.to_string(),
                reason: "pseudo-epochs: finite and >= 0".into(),
            });
        }
        if let Some(&v) = r.iter().find(|v| !(0.0..=1.0).contains(*v)) {
            return Err(UnsupervisedError::InvalidParameter {
                name: "responsibility",
                value: v.to_string(),
                reason: "a probability, in [0, 1]".into(),
            });
        }
        let grand = x
            .mean_axis(ndarray::Axis(0))
            .ok_or(UnsupervisedError::TooFewEpochs { n_epochs: n })?;
        let n_t: f64 = r.iter().sum();
        let n_n = n as f64 - n_t;
        let (z_t, z_n) = (n_t + mean_prior, n_n + mean_prior);
        if !(z_t > 0.0 && z_n > 0.0) {
            return Err(UnsupervisedError::Degenerate {
                what: format!("expected targets {n_t} of {n} epochs"),
            });
        }
        let mut target = &grand * mean_prior;
        let mut non_target = &grand * mean_prior;
        for (row, &ri) in x.outer_iter().zip(r) {
            target.scaled_add(ri, &row);
            non_target.scaled_add(1.0 - ri, &row);
        }
        target /= z_t;
        non_target /= z_n;
        let mut scatter = 0.0;
        for (row, &ri) in x.outer_iter().zip(r) {
            for j in 0..p {
                let (dt, dn) = (row[j] - target[j], row[j] - non_target[j]);
                scatter += ri * dt * dt + (1.0 - ri) * dn * dn;
            }
        }
        let tr_w = scatter / n as f64;
        let (sq_t, sq_n) = r.iter().fold((0.0, 0.0), |(a, b), &ri| {
            (a + ri * ri, b + (1.0 - ri) * (1.0 - ri))
        });
        Ok(Self {
            target,
            non_target,
            variance: [tr_w * sq_t / (z_t * z_t), tr_w * sq_n / (z_n * z_n)],
        })
    }

    /// [`Self::from_responsibilities`] with the responsibilities of `model`'s posterior on the
    /// feature rows `x` with their stimulus `codes` and `trials` (the epochs it was fitted on):
    /// the means of one more M-step, which at convergence are the fit's own.
    pub fn from_em(
        model: &Unsupervised,
        x: ArrayView2<f64>,
        codes: &[u32],
        trials: &[usize],
        mean_prior: f64,
    ) -> Result<Self> {
        let post = model.posteriors_features(x, codes, trials)?;
        let constraint = model.constraint();
        let r: Vec<f64> = codes
            .iter()
            .zip(trials)
            .map(|(&code, trial)| {
                let t = post
                    .iter()
                    .find(|t| t.trial == *trial)
                    .expect("every trial has a posterior");
                // 0 for a decoy (never attended; checked by the E-step).
                constraint.attended_weight(code, &t.sets)
            })
            .collect();
        Self::from_responsibilities(x, &r, mean_prior)
    }
}

/// A shrinkage LDA on given class means: `LLR(x) = coef·x + intercept`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeansLda {
    means: ClassMeans,
    coef: Array1<f64>,
    intercept: f64,
    shrinkage: f64,
    target_share: f64,
}

impl MeansLda {
    /// The LDA of `means` on the rows of `prep` with overall target share `share` (module doc).
    fn new(prep: &Prepared, means: ClassMeans, share: f64) -> Result<Self> {
        let p = prep.p;
        let dmu = DVector::from_fn(p, |j, _| means.target[j] - means.non_target[j]);
        let u = prep.chol.solve(&dmu);
        let a = dmu.dot(&u);
        let nf = prep.n as f64;
        let q = share * (1.0 - share) * nf / (nf + prep.c);
        let one_minus = 1.0 - q * a;
        if !(one_minus > 0.0 && one_minus.is_finite()) {
            return Err(UnsupervisedError::Degenerate {
                what: format!("within-class covariance lost definiteness (1 − q·a = {one_minus})"),
            });
        }
        let coef = Array1::from_iter(u.iter().map(|v| v / one_minus));
        let mid = (&means.target + &means.non_target) * 0.5;
        let intercept = -coef.dot(&mid);
        Ok(Self {
            means,
            coef,
            intercept,
            shrinkage: prep.shrinkage,
            target_share: share,
        })
    }

    /// LLR (target vs non-target) per feature row.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        if x.ncols() != self.coef.len() {
            return Err(DecodeError::ShapeMismatch {
                what: "label-proportion decoder input".into(),
                expected: format!("{} features", self.coef.len()),
                got: x.ncols().to_string(),
            }
            .into());
        }
        Ok(x.dot(&self.coef) + self.intercept)
    }

    pub fn means(&self) -> &ClassMeans {
        &self.means
    }

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

    /// The overall target share `π̄` the within-class covariance was formed with.
    pub fn target_share(&self) -> f64 {
        self.target_share
    }
}

/// Settings of learning from label proportions: the target proportion of each group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LlpParams {
    /// `π_g` per group (sequence type), in `[0, 1]`: the share of targets among its flashes.
    pub groups: Vec<f64>,
}

impl LlpParams {
    fn validate(&self) -> Result<()> {
        if let Some(&pi) = self
            .groups
            .iter()
            .find(|p| !(p.is_finite() && (0.0..=1.0).contains(*p)))
        {
            return Err(UnsupervisedError::InvalidParameter {
                name: "groups",
                value: pi.to_string(),
                reason: "a target proportion, in [0, 1]".into(),
            });
        }
        let first = self.groups.first().copied().unwrap_or(0.0);
        if self.groups.iter().all(|&p| p == first) {
            return Err(UnsupervisedError::NotIdentified {
                proportions: self.groups.clone(),
            });
        }
        Ok(())
    }

    /// Fits on feature rows `x` `(n_epochs, n_features)`, epoch i in group `group_of_epoch[i]`
    /// (an index into [`Self::groups`]); every group needs an epoch.
    pub fn fit(&self, x: ArrayView2<f64>, group_of_epoch: &[usize]) -> Result<Llp> {
        self.validate()?;
        let (n, p) = x.dim();
        if group_of_epoch.len() != n {
            return Err(UnsupervisedError::EpochCount {
                what: "group numbers",
                n_epochs: n,
                got: group_of_epoch.len(),
            });
        }
        let n_groups = self.groups.len();
        if let Some((index, &group)) = group_of_epoch
            .iter()
            .enumerate()
            .find(|(_, &g)| g >= n_groups)
        {
            return Err(UnsupervisedError::UnknownGroup {
                index,
                group,
                n_groups,
            });
        }
        let prep = Prepared::new(x, Covariance::LedoitWolf)?;
        // Group sizes, means and covariance traces.
        let mut count = vec![0usize; n_groups];
        let mut sums = DMatrix::<f64>::zeros(n_groups, p);
        for (row, &g) in x.outer_iter().zip(group_of_epoch) {
            count[g] += 1;
            for j in 0..p {
                sums[(g, j)] += row[j];
            }
        }
        if let Some(group) = count.iter().position(|&c| c == 0) {
            return Err(UnsupervisedError::EmptyGroup { group });
        }
        let means = DMatrix::from_fn(n_groups, p, |g, j| sums[(g, j)] / count[g] as f64);
        let mut trace = vec![0.0; n_groups];
        for (row, &g) in x.outer_iter().zip(group_of_epoch) {
            trace[g] += (0..p)
                .map(|j| (row[j] - means[(g, j)]).powi(2))
                .sum::<f64>();
        }
        // C = (AᵀA)⁻¹Aᵀ, A's rows [π_g, 1 − π_g]; AᵀA is invertible iff the π differ.
        let a = DMatrix::from_fn(n_groups, 2, |g, k| {
            if k == 0 {
                self.groups[g]
            } else {
                1.0 - self.groups[g]
            }
        });
        let ata = a.tr_mul(&a);
        let c = ata
            .try_inverse()
            .ok_or_else(|| UnsupervisedError::NotIdentified {
                proportions: self.groups.clone(),
            })?
            * a.transpose();
        let class = &c * &means;
        let mut variance = [0.0; 2];
        for (k, v) in variance.iter_mut().enumerate() {
            *v = (0..n_groups)
                .map(|g| c[(k, g)].powi(2) * trace[g] / (count[g] as f64).powi(2))
                .sum();
        }
        let means_out = ClassMeans {
            target: Array1::from_iter(class.row(0).iter().copied()),
            non_target: Array1::from_iter(class.row(1).iter().copied()),
            variance,
        };
        let share = count
            .iter()
            .zip(&self.groups)
            .map(|(&c, &pi)| c as f64 * pi)
            .sum::<f64>()
            / n as f64;
        let lda = MeansLda::new(&prep, means_out, share)?;
        Ok(Llp {
            groups: self.groups.clone(),
            group_sizes: count,
            lda,
        })
    }
}

/// A fitted label-proportion decoder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Llp {
    groups: Vec<f64>,
    group_sizes: Vec<usize>,
    lda: MeansLda,
}

impl Llp {
    /// LLR (target vs non-target) per feature row.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.lda.decision_function(x)
    }

    /// The class means from the group means, and their variances (module doc).
    pub fn means(&self) -> &ClassMeans {
        self.lda.means()
    }

    /// The LDA on the LLP's means.
    pub fn lda(&self) -> &MeansLda {
        &self.lda
    }

    /// The target proportion of each group.
    pub fn groups(&self) -> &[f64] {
        &self.groups
    }

    /// Epochs per group in the fit.
    pub fn group_sizes(&self) -> &[usize] {
        &self.group_sizes
    }

    /// MIX: per class `γ·em + (1 − γ)·LLP`, `γ = v_LLP / (v_EM + v_LLP)` (module doc), decoded by
    /// the LDA on the rows `x` this was fitted on, at this fit's target share.
    pub fn mix(&self, x: ArrayView2<f64>, em: &ClassMeans) -> Result<Mix> {
        let llp = self.means();
        let p = llp.target.len();
        if em.target.len() != p || em.non_target.len() != p || x.ncols() != p {
            return Err(DecodeError::ShapeMismatch {
                what: "MIX: the EM's means and rows".into(),
                expected: format!("{p} features"),
                got: format!(
                    "{}, {} and {}",
                    em.target.len(),
                    em.non_target.len(),
                    x.ncols()
                ),
            }
            .into());
        }
        let mut gamma = [0.5; 2];
        let mut variance = [0.0; 2];
        for k in 0..2 {
            let (ve, vl) = (em.variance[k], llp.variance[k]);
            if ve + vl > 0.0 {
                gamma[k] = vl / (ve + vl);
            }
            variance[k] = gamma[k].powi(2) * ve + (1.0 - gamma[k]).powi(2) * vl;
        }
        let mixed = ClassMeans {
            target: &em.target * gamma[0] + &llp.target * (1.0 - gamma[0]),
            non_target: &em.non_target * gamma[1] + &llp.non_target * (1.0 - gamma[1]),
            variance,
        };
        let prep = Prepared::new(x, Covariance::LedoitWolf)?;
        let lda = MeansLda::new(&prep, mixed, self.lda.target_share)?;
        Ok(Mix { gamma, lda })
    }
}

/// The MIX decoder: the EM's and LLP's means combined per class.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mix {
    gamma: [f64; 2],
    lda: MeansLda,
}

impl Mix {
    /// LLR (target vs non-target) per feature row.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.lda.decision_function(x)
    }

    /// `[γ_target, γ_non-target]`: the EM's weight in each class mean.
    pub fn gamma(&self) -> [f64; 2] {
        self.gamma
    }

    /// The mixed means and the variance of each combination.
    pub fn means(&self) -> &ClassMeans {
        self.lda.means()
    }

    /// The LDA on the mixed means.
    pub fn lda(&self) -> &MeansLda {
        &self.lda
    }
}

fn check_finite(x: ArrayView2<f64>) -> Result<()> {
    let p = x.ncols().max(1);
    if let Some((i, _)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(UnsupervisedError::NonFinite {
            epoch: i / p,
            feature: i % p,
        });
    }
    Ok(())
}
