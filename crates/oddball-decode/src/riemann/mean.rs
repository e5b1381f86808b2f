//! The Riemannian (Karcher) mean of SPD matrices, as pyRiemann's `mean_riemann`.

use nalgebra::DMatrix;
use ndarray::{Array2, ArrayView3};
use serde::{Deserialize, Serialize};

use crate::linalg::{
    congruence_into, eigen_function, eigen_function_into, spd_eigen, spd_eigen4, sym_eigen,
    symmetric_from, to_array2,
};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of the Karcher-mean gradient descent (pyRiemann's defaults).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanRiemannParams {
    /// Stop when the Frobenius norm of the Riemannian gradient, or the step size, is ≤ `tol`.
    pub tol: f64,
    /// Maximum number of iterations.
    pub max_iter: usize,
}

impl Default for MeanRiemannParams {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            max_iter: 50,
        }
    }
}

/// Result of [`mean_riemann`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RiemannMean {
    /// The mean, SPD `(n, n)`.
    pub mean: Array2<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Whether a stopping criterion was met within `max_iter` iterations.
    pub converged: bool,
}

/// Riemannian (Karcher) mean of SPD matrices `covs` `(n_matrices, n, n)` with equal weights.
pub fn mean_riemann(covs: ArrayView3<f64>, params: &MeanRiemannParams) -> Result<RiemannMean> {
    let mats = spd_matrices("mean_riemann input", covs)?;
    let refs: Vec<&DMatrix<f64>> = mats.iter().collect();
    let (mean, iterations, converged) = mean_riemann_dm(&refs, params)?;
    Ok(RiemannMean {
        mean: to_array2(&mean),
        iterations,
        converged,
    })
}

/// Converts `(n_matrices, n, n)` to checked symmetric matrices; each is verified SPD.
pub(crate) fn spd_matrices(what: &str, covs: ArrayView3<f64>) -> Result<Vec<DMatrix<f64>>> {
    let (k, r, c) = covs.dim();
    if k == 0 || r != c || r == 0 {
        return Err(DecodeError::ShapeMismatch {
            what: what.to_string(),
            expected: "(n_matrices ≥ 1, n, n) with n ≥ 1".to_string(),
            got: format!("({k}, {r}, {c})"),
        });
    }
    covs.outer_iter()
        .enumerate()
        .map(|(i, m)| {
            let m = symmetric_from(&format!("{what} matrix {i}"), m)?;
            if nalgebra::Cholesky::new(m.clone()).is_none() {
                return Err(DecodeError::NotPositiveDefinite {
                    what: format!("{what} matrix {i}"),
                });
            }
            Ok(m)
        })
        .collect()
}

pub(crate) fn mean_riemann_dm(
    mats: &[&DMatrix<f64>],
    params: &MeanRiemannParams,
) -> Result<(DMatrix<f64>, usize, bool)> {
    if !(params.tol >= 0.0 && params.tol.is_finite()) {
        return Err(DecodeError::InvalidParameter {
            name: "tol",
            value: params.tol.to_string(),
            reason: "must be finite and ≥ 0".to_string(),
        });
    }
    let n = mats[0].nrows();
    let w = 1.0 / mats.len() as f64;
    let mut m = DMatrix::zeros(n, n);
    for c in mats {
        m += *c * w;
    }
    let mut nu = 1.0;
    let mut tau = f64::MAX;
    let mut j = DMatrix::zeros(n, n);
    let (mut tmp, mut white, mut log) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
    );
    let mut pool: [DMatrix<f64>; 4] = Default::default();
    for iter in 1..=params.max_iter {
        let eig = spd_eigen("Riemannian mean iterate", m.clone())?;
        let m12 = eigen_function(&eig, f64::sqrt);
        let mm12 = eigen_function(&eig, |l| 1.0 / l.sqrt());
        j.fill(0.0);
        // Four whitened matrices decomposed at once (the same numbers as one by one), added to
        // the gradient in order.
        let mut fours = mats.chunks_exact(4);
        for four in &mut fours {
            let whites: [DMatrix<f64>; 4] = std::array::from_fn(|k| {
                let mut out = std::mem::take(&mut pool[k]);
                congruence_into(&mm12, four[k], &mut tmp, &mut out);
                out
            });
            let eigs = spd_eigen4("whitened matrix in Riemannian mean", whites)?;
            for (e, slot) in eigs.into_iter().zip(pool.iter_mut()) {
                eigen_function_into(&e, f64::ln, &mut log);
                j.zip_apply(&log, |a, l| *a += w * l);
                // The eigenvectors' storage serves the next whitened matrices.
                *slot = e.eigenvectors;
            }
        }
        for c in fours.remainder() {
            congruence_into(&mm12, c, &mut tmp, &mut white);
            let e = spd_eigen(
                "whitened matrix in Riemannian mean",
                std::mem::take(&mut white),
            )?;
            eigen_function_into(&e, f64::ln, &mut log);
            j.zip_apply(&log, |a, l| *a += w * l);
            // The eigenvectors' storage serves the next whitened matrix.
            white = e.eigenvectors;
        }
        let je = sym_eigen("Riemannian mean gradient", j.clone())?;
        let step = eigen_function(&je, |l| (nu * l).exp());
        congruence_into(&m12, &step, &mut tmp, &mut m);
        let crit = j.norm();
        let h = nu * crit;
        if h < tau {
            nu *= 0.95;
            tau = h;
        } else {
            nu *= 0.5;
        }
        if crit <= params.tol || nu <= params.tol {
            return Ok((m, iter, true));
        }
    }
    Ok((m, params.max_iter, false))
}
