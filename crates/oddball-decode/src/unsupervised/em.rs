//! The EM itself, on feature rows: label-free statistics of the data ([`Prepared`]), one EM run
//! from an initial score per epoch ([`run`]) and the penalised log-likelihood it climbs.
//!
//! Notation (module doc of [`super`]): `x̃ᵢ` the centred feature rows, `S = X̃ᵀX̃ / N`, `D` its
//! diagonal, `B = (1 − λ)·S + λ·D` with `λ` the Ledoit–Wolf shrinkage of the standardised rows,
//! `c = λN / (1 − λ)` the strength of the covariance prior. Per iteration, with responsibilities
//! `rᵢ` (P(epoch i attended)), `N_t = Σ rᵢ`, `N_n = N − N_t`:
//!
//! ```text
//! a  = X̃ᵀr,  μ_t = a / (N_t + κ₀),  μ_n = −a / (N_n + κ₀)   (κ₀ pseudo-epochs at the mean)
//! Δμ = h a,  h = 1/(N_t + κ₀) + 1/(N_n + κ₀)
//! Σ  = B − g ΔμΔμᵀ,  g = 1 / (h (N + c))              (the exact M-step, see the module doc)
//! u  = B⁻¹Δμ,  a = Δμᵀu,  w = Σ⁻¹Δμ = u / (1 − g a)    (Sherman–Morrison)
//! LLRᵢ = wᵀ(x̃ᵢ − (μ_t + μ_n)/2)
//! ```
//!
//! so one iteration costs one triangular solve pair with the Cholesky factor of `B` (`p²`) and
//! two passes over the rows (`N·p`).
//!
//! [`held_out`] scores a trial `k` by that M-step without its epochs: the sums over the other
//! rows only (`a₋ₖ = a − Σ_{i∈k} rᵢx̃ᵢ`, `N₋ₖ`, `N_t,₋ₖ`, and `Σ_{i∉k} x̃ᵢ = −Σ_{i∈k} x̃ᵢ` for the
//! non-target mean), `B` kept (label-free, from every row), so each trial costs one solve pair.
//!
//! With [`Covariance::BlockToeplitz`], `Σ = σ²·B_T`: `B_T = T(B)` is fixed (label-free), `T` the
//! tapered block-Toeplitz map of `toeplitz-lda` (every channel pair and time lag averaged, lag `d`
//! tapered by `(n_t − |d|)/n_t`), and the M-step maximises the same objective over the scale only:
//!
//! ```text
//! τ  = tr(B_T⁻¹B)                         (once; B = (N·S + c·D)/(N + c))
//! σ² = ((N + c)·τ − a/h) / ((N + c)·p)     = tr(B_T⁻¹(c·D + W)) / ((N + c)·p),  a = ΔμᵀB_T⁻¹Δμ
//! w  = B_T⁻¹Δμ / σ²
//! ```
//!
//! (`W = N·S − ΔμΔμᵀ/h` the within-class scatter with the means' penalty, so `c·D + W` is
//! positive definite and `σ² > 0`; the means' maximiser does not depend on `Σ`). Both steps are
//! exact maximisations over that family, so the objective never decreases; it is the Ledoit–Wolf
//! model's objective, restricted to covariances of block-Toeplitz shape.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use ndarray::ArrayView2;

use super::error::{Result, UnsupervisedError};
use super::Covariance;
use crate::classifiers::toeplitz_lda::block_toeplitz_tapered;

/// Where each epoch sits in the paradigm's constraint: its slot (one trial's choice set, in
/// which exactly one choice is attended) and the choices of the slot that make it a target
/// (one where a code is a choice; its group under group flashes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Layout {
    /// `None` for a decoy: in no slot, a known non-target (responsibility 0).
    pub slot_of: Vec<Option<usize>>,
    /// Epoch i's choices are `choice_idx[choice_start[i]..choice_start[i + 1]]`.
    pub choice_start: Vec<usize>,
    pub choice_idx: Vec<usize>,
    /// Choices per slot.
    pub n_choices: Vec<usize>,
}

impl Layout {
    /// The choices of its slot that make epoch `i` a target.
    pub fn choices(&self, i: usize) -> &[usize] {
        &self.choice_idx[self.choice_start[i]..self.choice_start[i + 1]]
    }
}

/// Label-free statistics of the feature rows an EM runs on.
#[derive(Debug)]
pub(crate) struct Prepared {
    pub n: usize,
    pub p: usize,
    /// Mean row `(p,)`.
    pub mean: DVector<f64>,
    /// Centred rows `(N, p)`.
    pub xc: DMatrix<f64>,
    /// `diag(S)` (floored, so `B` is positive definite).
    pub d: DVector<f64>,
    /// Ledoit–Wolf shrinkage `λ` of the standardised rows (clamped to `[1e-4, 0.99]`).
    pub shrinkage: f64,
    /// Prior strength `c = λN / (1 − λ)`.
    pub c: f64,
    /// Factor of `B`, or of `B_T` under [`Covariance::BlockToeplitz`].
    pub chol: Cholesky<f64, Dyn>,
    /// `ln |B|` (`ln |B_T|`).
    pub log_det_b: f64,
    /// `Some(τ = tr(B_T⁻¹B))` when `Σ = σ²·B_T` (block-Toeplitz); `None`: `Σ = B − g·ΔμΔμᵀ`.
    pub tau: Option<f64>,
}

impl Prepared {
    /// Centres `x` `(N, p)`, computes `S`, the shrinkage and the factor of `B` (of `B_T` and `τ`
    /// under [`Covariance::BlockToeplitz`]).
    pub fn new(x: ArrayView2<f64>, covariance: Covariance) -> Result<Self> {
        let (n, p) = x.dim();
        if n < 2 || p == 0 {
            return Err(UnsupervisedError::TooFewEpochs { n_epochs: n });
        }
        if let Some((i, _)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(UnsupervisedError::NonFinite {
                epoch: i / p,
                feature: i % p,
            });
        }
        let nf = n as f64;
        let mut xc = DMatrix::from_fn(n, p, |i, j| x[[i, j]]);
        let mut mean = DVector::zeros(p);
        for (j, mut col) in xc.column_iter_mut().enumerate() {
            let m = col.sum() / nf;
            mean[j] = m;
            col.add_scalar_mut(-m);
        }
        let s = xc.tr_mul(&xc) / nf;
        let mean_var = s.trace() / p as f64;
        let floor = (mean_var * 1e-12).max(f64::MIN_POSITIVE);
        let d = DVector::from_fn(p, |j, _| s[(j, j)].max(floor));
        let shrinkage = ledoit_wolf_standardised(&xc, &s, &d).clamp(1e-4, 0.99);
        let c = shrinkage * nf / (1.0 - shrinkage);
        let mut b = s * (1.0 - shrinkage);
        for j in 0..p {
            b[(j, j)] += shrinkage * d[j];
        }
        let not_pd = UnsupervisedError::NotPositiveDefinite {
            n_epochs: n,
            n_features: p,
        };
        let (chol, tau) = match covariance {
            Covariance::LedoitWolf => (Cholesky::new(b).ok_or(not_pd)?, None),
            Covariance::BlockToeplitz { n_channels } => {
                if n_channels == 0 || p % n_channels != 0 {
                    return Err(UnsupervisedError::InvalidParameter {
                        name: "covariance",
                        value: format!("block-Toeplitz over {n_channels} channels"),
                        reason: format!("{p} features are not a whole number per channel"),
                    });
                }
                let bt = block_toeplitz_tapered(b.clone(), n_channels, p / n_channels);
                let chol = Cholesky::new(bt).ok_or(not_pd)?;
                let tau = chol.solve(&b).trace();
                (chol, Some(tau))
            }
        };
        let log_det_b = 2.0
            * chol
                .l_dirty()
                .diagonal()
                .iter()
                .map(|v| v.ln())
                .sum::<f64>();
        Ok(Self {
            n,
            p,
            mean,
            xc,
            d,
            shrinkage,
            c,
            chol,
            log_det_b,
            tau,
        })
    }

    /// The part of the objective that does not depend on the parameters:
    /// `−(Np/2) ln 2π − ((N + c)/2)(ln|B| + p)` (from `N tr(B⁻¹S) + c tr(B⁻¹D) = (N + c) p`);
    /// block-Toeplitz: `−(Np/2) ln 2π − ((N + c)/2) ln|B_T|` (the trace depends on `σ²`).
    fn constant(&self) -> f64 {
        let (nf, pf) = (self.n as f64, self.p as f64);
        let trace = if self.tau.is_some() { 0.0 } else { pf };
        -0.5 * nf * pf * (2.0 * std::f64::consts::PI).ln()
            - 0.5 * (nf + self.c) * (self.log_det_b + trace)
    }
}

/// scikit-learn's `ledoit_wolf_shrinkage` of the standardised rows `zᵢⱼ = x̃ᵢⱼ / √dⱼ`, from the
/// centred rows and their covariance (the formula of `crate::riemann::covariance`, on the correlation
/// matrix).
pub(crate) fn ledoit_wolf_standardised(
    xc: &DMatrix<f64>,
    s: &DMatrix<f64>,
    d: &DVector<f64>,
) -> f64 {
    let (n, p) = xc.shape();
    let (nf, pf) = (n as f64, p as f64);
    let inv_sd: Vec<f64> = d.iter().map(|v| 1.0 / v.sqrt()).collect();
    let mut row_sq = vec![0.0; n];
    for (j, col) in xc.column_iter().enumerate() {
        let k = inv_sd[j] * inv_sd[j];
        for (acc, v) in row_sq.iter_mut().zip(col.iter()) {
            *acc += v * v * k;
        }
    }
    let beta_: f64 = row_sq.iter().map(|r| r * r).sum();
    let mut delta_ = 0.0;
    let mut trace = 0.0;
    for j in 0..p {
        for i in 0..p {
            let r = s[(i, j)] * inv_sd[i] * inv_sd[j];
            delta_ += r * r;
        }
        trace += s[(j, j)] * inv_sd[j] * inv_sd[j];
    }
    let mu = trace / pf;
    let beta = (beta_ / nf - delta_) / (pf * nf);
    let delta = (delta_ - 2.0 * mu * trace + pf * mu * mu) / pf;
    let beta = beta.min(delta);
    if beta <= 0.0 || delta <= 0.0 {
        0.0
    } else {
        beta / delta
    }
}

/// The parameters after an M-step, as a linear log-likelihood ratio on centred rows.
#[derive(Debug, Clone)]
pub(crate) struct Linear {
    /// `w = Σ⁻¹Δμ` `(p,)`.
    pub w: DVector<f64>,
    /// `LLR = wᵀx̃ + offset`.
    pub offset: f64,
}

/// One EM run's result.
#[derive(Debug, Clone)]
pub(crate) struct Run {
    /// The penalised log-likelihood of each M-step's parameters, in order (non-decreasing).
    pub objective: Vec<f64>,
    /// The final parameters.
    pub linear: Linear,
    /// Posterior per slot over its choices, under the final parameters.
    pub posterior: Vec<Vec<f64>>,
}

/// E-step: the posterior of each slot's choices from per-epoch LLRs (uniform prior), and
/// `Σ_slots ln Σ_c (1/K) exp(E_c)`.
pub(crate) fn e_step(layout: &Layout, llr: &[f64]) -> (Vec<Vec<f64>>, f64) {
    let mut evidence: Vec<Vec<f64>> = layout.n_choices.iter().map(|&k| vec![0.0; k]).collect();
    for (i, &l) in llr.iter().enumerate() {
        if let Some(slot) = layout.slot_of[i] {
            for &c in layout.choices(i) {
                evidence[slot][c] += l;
            }
        }
    }
    let mut total = 0.0;
    for e in &mut evidence {
        let m = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = e.iter().map(|v| (v - m).exp()).sum();
        total += m + z.ln() - (e.len() as f64).ln();
        for v in e.iter_mut() {
            *v = (*v - m).exp() / z;
        }
    }
    (evidence, total)
}

/// M-step from responsibilities `r` with `kappa0` pseudo-epochs of prior on each class mean:
/// the new parameters and the parameter-dependent part of the objective (everything but the
/// E-step's log-sum-exp and [`Prepared::constant`]).
fn m_step(prep: &Prepared, r: &[f64], kappa0: f64) -> Result<(Linear, f64)> {
    let nf = prep.n as f64;
    let n_t: f64 = r.iter().sum();
    let n_n = nf - n_t;
    if !(n_t > 0.0 && n_n > 0.0) {
        return Err(UnsupervisedError::Degenerate {
            what: format!("expected targets {n_t} of {nf} epochs"),
        });
    }
    // a = Σ rᵢ x̃ᵢ; μ_t = a / (N_t + κ₀), μ_n = −a / (N_n + κ₀) (Σ x̃ᵢ = 0).
    let rv = DVector::from_column_slice(r);
    let h = 1.0 / (n_t + kappa0) + 1.0 / (n_n + kappa0);
    let dmu = prep.xc.tr_mul(&rv) * h;
    // μ_t = β_t Δμ, μ_n = β_n Δμ.
    let (beta_t, beta_n) = (1.0 / (h * (n_t + kappa0)), -1.0 / (h * (n_n + kappa0)));
    let u = prep.chol.solve(&dmu);
    let a = dmu.dot(&u);
    if let Some(tau) = prep.tau {
        return Ok(m_step_scaled(prep, tau, &u, a, h, [beta_t, beta_n], kappa0));
    }
    let g = 1.0 / (h * (nf + prep.c));
    let one_minus = 1.0 - g * a;
    if !(one_minus > 0.0 && one_minus.is_finite()) {
        return Err(UnsupervisedError::Degenerate {
            what: format!("within-class covariance lost definiteness (1 − g·a = {one_minus})"),
        });
    }
    let kappa = g / one_minus;
    let w = &u / one_minus;
    // Δμᵀ Σ⁻¹ Δμ.
    let m = a / one_minus;
    let offset = -0.5 * (beta_t + beta_n) * m;
    let xu = &prep.xc * &u;
    let u_s_u = xu.norm_squared() / nf;
    let u_d_u: f64 = u
        .iter()
        .zip(prep.d.iter())
        .map(|(ui, di)| ui * ui * di)
        .sum();
    let rest = -0.5 * (nf + prep.c) * one_minus.ln()
        - 0.5 * nf * (kappa * u_s_u + beta_n * beta_n * m)
        - 0.5 * prep.c * kappa * u_d_u
        - 0.5 * kappa0 * (beta_t * beta_t + beta_n * beta_n) * m;
    Ok((Linear { w, offset }, rest))
}

/// The M-step of `Σ = σ²·B_T` (module doc) from `u = B_T⁻¹Δμ`, `a = Δμᵀu`, `h` and the means'
/// factors `[β_t, β_n]` (`μ = β·Δμ`): `σ² > 0` always, since `c·D + W` is positive definite.
fn m_step_scaled(
    prep: &Prepared,
    tau: f64,
    u: &DVector<f64>,
    a: f64,
    h: f64,
    [beta_t, beta_n]: [f64; 2],
    kappa0: f64,
) -> (Linear, f64) {
    let (nf, pf) = (prep.n as f64, prep.p as f64);
    let nc = nf + prep.c;
    // Floored only against rounding: (N + c)·τ − a/h = tr(B_T⁻¹(c·D + W)) > 0.
    let s2 = ((nc * tau - a / h) / (nc * pf)).max(f64::MIN_POSITIVE);
    let w = u / s2;
    // Δμᵀ Σ⁻¹ Δμ.
    let m = a / s2;
    let offset = -0.5 * (beta_t + beta_n) * m;
    let rest = -0.5 * nc * pf * s2.ln()
        - 0.5 * nc * tau / s2
        - 0.5 * nf * beta_n * beta_n * m
        - 0.5 * kappa0 * (beta_t * beta_t + beta_n * beta_n) * m;
    (Linear { w, offset }, rest)
}

/// LLR per epoch of the centred rows.
pub(crate) fn scores(prep: &Prepared, lin: &Linear) -> Vec<f64> {
    let s = &prep.xc * &lin.w;
    s.iter().map(|v| v + lin.offset).collect()
}

/// Responsibilities of each epoch from the slot posteriors.
fn responsibilities(layout: &Layout, post: &[Vec<f64>]) -> Vec<f64> {
    (0..layout.slot_of.len())
        .map(|i| {
            layout.slot_of[i].map_or(0.0, |s| layout.choices(i).iter().map(|&c| post[s][c]).sum())
        })
        .collect()
}

/// One EM run from `init` (a score per epoch, used as the first E-step's LLRs): iterates until
/// the objective gains less than `tol` (nats) or `max_iter` M-steps were made.
pub(crate) fn run(
    prep: &Prepared,
    layout: &Layout,
    init: &[f64],
    kappa0: f64,
    max_iter: usize,
    tol: f64,
) -> Result<Run> {
    let (mut post, _) = e_step(layout, init);
    let constant = prep.constant();
    let mut objective = Vec::new();
    let mut linear = None;
    for _ in 0..max_iter.max(1) {
        let (lin, rest) = m_step(prep, &responsibilities(layout, &post), kappa0)?;
        let llr = scores(prep, &lin);
        let (p, lse) = e_step(layout, &llr);
        post = p;
        let j = lse + rest + constant;
        let done = objective
            .last()
            .is_some_and(|&last: &f64| (j - last).abs() <= tol);
        objective.push(j);
        linear = Some(lin);
        if done {
            break;
        }
    }
    Ok(Run {
        objective,
        linear: linear.expect("at least one M-step"),
        posterior: post,
    })
}

/// Leave-one-trial-out scores: each trial of `held` scored by the M-step of responsibilities
/// `r` on every other epoch (module doc; `B` of all rows kept, it holds no label), its LLR
/// `wᵀ(x̃ᵢ − (μ_t + μ_n)/2)` on the held trial's epochs; `None` for every other epoch, and for a
/// held trial whose rest leaves a class empty or the covariance indefinite.
pub(crate) fn held_out(
    prep: &Prepared,
    r: &[f64],
    trials: &[usize],
    held: &[usize],
    kappa0: f64,
) -> Vec<Option<f64>> {
    let mut out = vec![None; prep.n];
    let a_all = prep.xc.tr_mul(&DVector::from_column_slice(r));
    let n_t_all: f64 = r.iter().sum();
    for &k in held {
        let rows: Vec<usize> = (0..prep.n).filter(|&i| trials[i] == k).collect();
        let (mut a_k, mut sum_k, mut n_t_k) = (DVector::zeros(prep.p), DVector::zeros(prep.p), 0.0);
        for &i in &rows {
            let x = prep.xc.row(i).transpose();
            a_k.axpy(r[i], &x, 1.0);
            sum_k += &x;
            n_t_k += r[i];
        }
        let nf = (prep.n - rows.len()) as f64;
        let n_t = n_t_all - n_t_k;
        let n_n = nf - n_t;
        if rows.is_empty() || !(n_t > 0.0 && n_n > 0.0) {
            continue;
        }
        let a = &a_all - &a_k;
        let mu_t = &a / (n_t + kappa0);
        let mu_n = -(&sum_k + &a) / (n_n + kappa0);
        let dmu = &mu_t - &mu_n;
        let mid = (&mu_t + &mu_n) * 0.5;
        let h = 1.0 / (n_t + kappa0) + 1.0 / (n_n + kappa0);
        let u = prep.chol.solve(&dmu);
        let ua = dmu.dot(&u);
        let w = match prep.tau {
            Some(tau) => {
                let nc = nf + prep.c;
                let s2 = ((nc * tau - ua / h) / (nc * prep.p as f64)).max(f64::MIN_POSITIVE);
                u / s2
            }
            None => {
                let one_minus = 1.0 - ua / (h * (nf + prep.c));
                if !(one_minus > 0.0 && one_minus.is_finite()) {
                    continue;
                }
                u / one_minus
            }
        };
        for &i in &rows {
            out[i] = Some(w.dot(&(prep.xc.row(i).transpose() - &mid)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    /// 6 trials of 8 epochs, 6 features (2 channels × 3 times), a shifted mean on every fourth
    /// epoch, and responsibilities that are not labels (soft, some wrong).
    fn toy() -> (Array2<f64>, Vec<f64>, Vec<usize>) {
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let (n, p) = (48, 6);
        let x = Array2::from_shape_fn((n, p), |(i, j)| {
            next() + if i % 4 == 0 { 0.3 * j as f64 } else { 0.0 }
        });
        let r: Vec<f64> = (0..n)
            .map(|i| {
                if i % 4 == 0 {
                    0.8
                } else {
                    0.1 + 0.2 * next().abs()
                }
            })
            .collect();
        let trials = (0..n).map(|i| i / 8).collect();
        (x, r, trials)
    }

    /// The documented model, formed densely: means of the rows outside the trial, `Σ = B −
    /// g·ΔμΔμᵀ` (or `σ²·B_T`) inverted, the LLR at the midpoint.
    fn naive(
        prep: &Prepared,
        x: &Array2<f64>,
        r: &[f64],
        trials: &[usize],
        k: usize,
        bt: Option<&DMatrix<f64>>,
    ) -> Vec<f64> {
        let (n, p) = x.dim();
        let mean = DVector::from_fn(p, |j, _| x.column(j).sum() / n as f64);
        let row = |i: usize| DVector::from_fn(p, |j, _| x[[i, j]]) - &mean;
        let rest: Vec<usize> = (0..n).filter(|&i| trials[i] != k).collect();
        let n_t: f64 = rest.iter().map(|&i| r[i]).sum();
        let n_n = rest.len() as f64 - n_t;
        let mut mu_t = DVector::zeros(p);
        let mut mu_n = DVector::zeros(p);
        for &i in &rest {
            mu_t += row(i) * r[i];
            mu_n += row(i) * (1.0 - r[i]);
        }
        mu_t /= n_t;
        mu_n /= n_n;
        let dmu = &mu_t - &mu_n;
        let s = prep.xc.tr_mul(&prep.xc) / n as f64;
        let lam = prep.shrinkage;
        let b = &s * (1.0 - lam) + DMatrix::from_diagonal(&prep.d) * lam;
        let h = 1.0 / n_t + 1.0 / n_n;
        let nc = rest.len() as f64 + prep.c;
        let sigma = match bt {
            None => &b - &dmu * dmu.transpose() / (h * nc),
            Some(bt) => {
                let inv = bt.clone().try_inverse().unwrap();
                let s2 = (&inv * (&b * nc - &dmu * dmu.transpose() / h)).trace() / (nc * p as f64);
                bt * s2
            }
        };
        let w = sigma.try_inverse().unwrap() * &dmu;
        let mid = (&mu_t + &mu_n) * 0.5;
        (0..n)
            .filter(|&i| trials[i] == k)
            .map(|i| w.dot(&(row(i) - &mid)))
            .collect()
    }

    #[test]
    fn held_out_scores_are_the_dense_model_without_the_trial() {
        let (x, r, trials) = toy();
        for covariance in [
            Covariance::LedoitWolf,
            Covariance::BlockToeplitz { n_channels: 2 },
        ] {
            let prep = Prepared::new(x.view(), covariance).unwrap();
            let bt = matches!(covariance, Covariance::BlockToeplitz { .. }).then(|| {
                let s = prep.xc.tr_mul(&prep.xc) / prep.n as f64;
                let b =
                    &s * (1.0 - prep.shrinkage) + DMatrix::from_diagonal(&prep.d) * prep.shrinkage;
                block_toeplitz_tapered(b, 2, 3)
            });
            let got = held_out(&prep, &r, &trials, &[1, 4], 0.0);
            for (i, g) in got.iter().enumerate() {
                assert_eq!(g.is_some(), trials[i] == 1 || trials[i] == 4, "epoch {i}");
            }
            for k in [1, 4] {
                let want = naive(&prep, &x, &r, &trials, k, bt.as_ref());
                let have: Vec<f64> = (0..prep.n)
                    .filter(|&i| trials[i] == k)
                    .map(|i| got[i].unwrap())
                    .collect();
                for (h, w) in have.iter().zip(&want) {
                    assert!(
                        (h - w).abs() < 1e-9 * w.abs().max(1.0),
                        "{covariance:?} trial {k}: {h} vs {w}"
                    );
                }
            }
            // The held trial's own responsibilities do not enter its scores.
            let mut flipped = r.clone();
            for i in (0..prep.n).filter(|&i| trials[i] == 1) {
                flipped[i] = 1.0 - flipped[i];
            }
            let again = held_out(&prep, &flipped, &trials, &[1], 0.0);
            for i in (0..prep.n).filter(|&i| trials[i] == 1) {
                assert!((again[i].unwrap() - got[i].unwrap()).abs() < 1e-12);
            }
        }
    }
}
