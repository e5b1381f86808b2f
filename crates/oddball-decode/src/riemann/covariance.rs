//! Covariance estimators for one multichannel signal `(n_channels, n_times)` → SPD
//! `(n_channels, n_channels)`, in µV² when the signal is in µV.
//!
//! * [`CovEstimator::Scm`]: the sample covariance, centred, divided by `n_times` (the maximum-likelihood
//!   estimate; pyRiemann's `covariance_scm`, scikit-learn's `empirical_covariance`).
//! * [`CovEstimator::LedoitWolf`]: scikit-learn's `ledoit_wolf` exactly — the data are centred, the
//!   shrinkage is `ledoit_wolf_shrinkage`'s `β/δ` (with `β = min(β, δ)`), and the estimate is
//!   `(1 − s)·S + s·(tr S / n)·I`.
//! * [`CovEstimator::Oas`]: scikit-learn's `oas` exactly (1.9: `s = min((α + μ²) / ((n_times + 1)(α − μ²/p)), 1)`
//!   with `α = mean(S²)`, `μ = tr S / p`), on centred data.
//!
//! With one channel both shrinkage estimators return the variance and shrinkage 0, as scikit-learn does.
//! pyRiemann's `covariances(X, estimator="oas" | "lwf" | "scm")` applies exactly these per epoch (on the
//! transposed epoch, i.e. time samples as observations), so [`CovEstimator::estimate_epochs`] equals it.
//!
//! Written here: no well-kept Rust crate implements Ledoit–Wolf or OAS shrinkage with scikit-learn's
//! exact formulas; checked against scikit-learn 1.9.1 / pyRiemann 0.12 in `tests/linear_riemann_golden.rs`.

use nalgebra::DMatrix;
use ndarray::{Array2, Array3, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::linalg::{check_finite, copy_transposed_into, dot, to_array2};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Which covariance estimator to use (see the module documentation for the exact formulas).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum CovEstimator {
    /// Sample covariance, centred, divided by `n_times`.
    #[default]
    Scm,
    /// Ledoit–Wolf shrinkage towards `(tr S / p)·I`, as scikit-learn's `ledoit_wolf`.
    LedoitWolf,
    /// Oracle approximating shrinkage towards `(tr S / p)·I`, as scikit-learn's `oas`.
    Oas,
}

/// A covariance estimate with the shrinkage coefficient used (0 for [`CovEstimator::Scm`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShrunkCovariance {
    /// `(n_channels, n_channels)`, in the signal's unit squared (µV²).
    pub covariance: Array2<f64>,
    /// Convex weight of the scaled identity, in `[0, 1]`.
    pub shrinkage: f64,
}

impl CovEstimator {
    /// Covariance of `x` `(n_channels, n_times)`: channels are the variables, time samples the
    /// observations. Needs at least 2 time samples and finite values.
    pub fn estimate(self, x: ArrayView2<f64>) -> Result<Array2<f64>> {
        Ok(self.estimate_with_shrinkage(x)?.covariance)
    }

    /// As [`estimate`](Self::estimate), also returning the shrinkage coefficient.
    pub fn estimate_with_shrinkage(self, x: ArrayView2<f64>) -> Result<ShrunkCovariance> {
        check_finite("covariance input", x.iter())?;
        check_dims(x.nrows(), x.ncols())?;
        let mut data = DMatrix::zeros(0, 0);
        copy_transposed_into(x, &mut data);
        let mut cov = DMatrix::zeros(0, 0);
        let shrinkage = estimate_columns(self, &mut data, &mut cov);
        Ok(ShrunkCovariance {
            covariance: to_array2(&cov),
            shrinkage,
        })
    }

    /// One covariance per epoch: `epochs` `(n_epochs, n_channels, n_times)` →
    /// `(n_epochs, n_channels, n_channels)`.
    pub fn estimate_epochs(self, epochs: ArrayView3<f64>) -> Result<Array3<f64>> {
        check_finite("epochs", epochs.iter())?;
        let (n_epochs, n_channels, n_times) = epochs.dim();
        check_dims(n_channels, n_times)?;
        let mut out = Array3::zeros((n_epochs, n_channels, n_channels));
        let mut data = DMatrix::zeros(0, 0);
        let mut cov = DMatrix::zeros(0, 0);
        for (epoch, mut dst) in epochs.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            copy_transposed_into(epoch, &mut data);
            estimate_columns(self, &mut data, &mut cov);
            dst.indexed_iter_mut()
                .for_each(|((i, j), v)| *v = cov[(i, j)]);
        }
        Ok(out)
    }
}

/// Sample covariance (centred, `/ n_times`) of `x` `(n_channels, n_times)`.
pub fn sample_covariance(x: ArrayView2<f64>) -> Result<Array2<f64>> {
    CovEstimator::Scm.estimate(x)
}

/// scikit-learn's `ledoit_wolf(x.T)`: covariance and shrinkage of `x` `(n_channels, n_times)`.
pub fn ledoit_wolf(x: ArrayView2<f64>) -> Result<ShrunkCovariance> {
    CovEstimator::LedoitWolf.estimate_with_shrinkage(x)
}

/// scikit-learn's `oas(x.T)`: covariance and shrinkage of `x` `(n_channels, n_times)`.
pub fn oas(x: ArrayView2<f64>) -> Result<ShrunkCovariance> {
    CovEstimator::Oas.estimate_with_shrinkage(x)
}

fn check_dims(n_vars: usize, n_obs: usize) -> Result<()> {
    if n_vars == 0 {
        return Err(DecodeError::ShapeMismatch {
            what: "covariance input".to_string(),
            expected: "at least one channel".to_string(),
            got: "0 channels".to_string(),
        });
    }
    if n_obs < 2 {
        return Err(DecodeError::TooFewSamples {
            what: format!("a covariance needs at least 2 time samples, got {n_obs}"),
        });
    }
    Ok(())
}

/// The estimator on a data matrix `(n_obs, n_vars)` (observations as rows, variables as columns, the
/// memory layout of a row-major `(n_vars, n_obs)` signal). Centres `data` in place, writes the
/// `(n_vars, n_vars)` estimate into `out` and returns the shrinkage. The caller guarantees finite
/// values, `n_vars ≥ 1` and `n_obs ≥ 2`.
pub(crate) fn estimate_columns(
    estimator: CovEstimator,
    data: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> f64 {
    let (n, p) = data.shape();
    let nf = n as f64;
    for mut col in data.column_iter_mut() {
        let mean = col.sum() / nf;
        col.add_scalar_mut(-mean);
    }
    if out.nrows() != p || out.ncols() != p {
        *out = DMatrix::zeros(p, p);
    }
    // S = XᵀX / n, upper triangle by column dot products, mirrored (exactly symmetric).
    let cols = data.as_slice();
    for j in 0..p {
        let cj = &cols[j * n..(j + 1) * n];
        for i in 0..=j {
            let v = dot(&cols[i * n..(i + 1) * n], cj) / nf;
            out[(i, j)] = v;
            out[(j, i)] = v;
        }
    }
    let shrinkage = match estimator {
        CovEstimator::Scm => return 0.0,
        _ if p == 1 => return 0.0,
        CovEstimator::LedoitWolf => ledoit_wolf_shrinkage(data, out),
        CovEstimator::Oas => oas_shrinkage(n, out),
    };
    shrink_in_place(out, shrinkage);
    shrinkage
}

/// `(1 − s)·S + s·(tr S / p)·I` in place.
pub(crate) fn shrink_in_place(s: &mut DMatrix<f64>, shrinkage: f64) {
    let p = s.nrows();
    let mu = s.trace() / p as f64;
    *s *= 1.0 - shrinkage;
    for i in 0..p {
        s[(i, i)] += shrinkage * mu;
    }
}

/// scikit-learn's `ledoit_wolf_shrinkage` for centred `x` `(n, p)` with empirical covariance `s`.
fn ledoit_wolf_shrinkage(x: &DMatrix<f64>, s: &DMatrix<f64>) -> f64 {
    let (n, p) = x.shape();
    let (nf, pf) = (n as f64, p as f64);
    // beta_ = sum(X2ᵀ X2) = Σ_k (Σ_j x_kj²)²; delta_ = sum((XᵀX)²) / n² = ‖S‖_F².
    let mut row_sq = vec![0.0; n];
    for col in x.column_iter() {
        for (acc, v) in row_sq.iter_mut().zip(col.iter()) {
            *acc += v * v;
        }
    }
    let beta_: f64 = row_sq.iter().map(|r| r * r).sum();
    let delta_: f64 = s.iter().map(|v| v * v).sum();
    let trace = s.trace();
    let mu = trace / pf;
    let beta = (beta_ / nf - delta_) / (pf * nf);
    let delta = (delta_ - 2.0 * mu * trace + pf * mu * mu) / pf;
    let beta = beta.min(delta);
    if beta == 0.0 || delta == 0.0 {
        // delta == 0: S is already a multiple of the identity and any shrinkage gives the same matrix.
        0.0
    } else {
        beta / delta
    }
}

/// scikit-learn 1.9's OAS shrinkage from the empirical covariance `s` of `n` observations.
fn oas_shrinkage(n: usize, s: &DMatrix<f64>) -> f64 {
    let p = s.nrows() as f64;
    let alpha = s.iter().map(|v| v * v).sum::<f64>() / (p * p);
    let mu = s.trace() / p;
    let mu2 = mu * mu;
    let num = alpha + mu2;
    let den = (n as f64 + 1.0) * (alpha - mu2 / p);
    if den == 0.0 {
        1.0
    } else {
        (num / den).min(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn scm_is_centred_and_divided_by_n() {
        let x = array![[1.0, 2.0, 3.0, 6.0], [0.0, 1.0, 0.0, 3.0]];
        let c = sample_covariance(x.view()).unwrap();
        // means 3 and 1; deviations (-2,-1,0,3) and (-1,0,-1,2)
        assert!((c[[0, 0]] - 14.0 / 4.0).abs() < 1e-15);
        assert!((c[[1, 1]] - 6.0 / 4.0).abs() < 1e-15);
        assert!((c[[0, 1]] - 8.0 / 4.0).abs() < 1e-15);
        assert_eq!(c[[0, 1]], c[[1, 0]]);
    }

    #[test]
    fn one_channel_gives_variance_and_no_shrinkage() {
        let x = array![[1.0, 2.0, 4.0]];
        for est in [CovEstimator::LedoitWolf, CovEstimator::Oas] {
            let r = est.estimate_with_shrinkage(x.view()).unwrap();
            assert_eq!(r.shrinkage, 0.0);
            // mean 7/3, deviations (-4/3, -1/3, 5/3)
            let var = (16.0 + 1.0 + 25.0) / 9.0 / 3.0;
            assert!((r.covariance[[0, 0]] - var).abs() < 1e-14);
        }
    }

    #[test]
    fn shrinkage_within_unit_interval_and_trace_preserved() {
        let x = Array2::from_shape_fn((5, 12), |(i, j)| {
            ((i * 7 + j * 3) % 11) as f64 - 0.3 * j as f64
        });
        let scm = sample_covariance(x.view()).unwrap();
        for est in [CovEstimator::LedoitWolf, CovEstimator::Oas] {
            let r = est.estimate_with_shrinkage(x.view()).unwrap();
            assert!(
                (0.0..=1.0).contains(&r.shrinkage),
                "{est:?} {}",
                r.shrinkage
            );
            assert!((r.covariance.diag().sum() - scm.diag().sum()).abs() < 1e-12);
        }
    }

    #[test]
    fn errors() {
        let x = array![[1.0], [2.0]];
        assert!(matches!(
            CovEstimator::Oas.estimate(x.view()),
            Err(DecodeError::TooFewSamples { .. })
        ));
        let x = array![[1.0, f64::INFINITY], [2.0, 3.0]];
        assert!(matches!(
            CovEstimator::Scm.estimate(x.view()),
            Err(DecodeError::NonFinite { .. })
        ));
    }
}
