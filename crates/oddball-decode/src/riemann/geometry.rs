//! Matrix functions of SPD matrices and the affine-invariant distance.

use nalgebra::DMatrix;
use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::linalg::{
    congruence_into, eigen_function, generalized_eigenvalues, spd_eigen, sym_eigen,
    sym_eigenvalues, symmetric_from, to_array2,
};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// The Riemannian metric used for means, maps and distances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Metric {
    /// The affine-invariant metric.
    #[default]
    Riemann,
}

/// Square root of an SPD matrix.
pub fn sqrtm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("sqrtm input", c, f64::sqrt)
}

/// Inverse square root of an SPD matrix.
pub fn invsqrtm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("invsqrtm input", c, |l| 1.0 / l.sqrt())
}

/// Principal logarithm of an SPD matrix (a symmetric matrix).
pub fn logm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("logm input", c, f64::ln)
}

/// Exponential of a symmetric matrix (an SPD matrix).
pub fn expm(s: ArrayView2<f64>) -> Result<Array2<f64>> {
    let m = symmetric_from("expm input", s)?;
    let eig = sym_eigen("expm input", m)?;
    Ok(to_array2(&eigen_function(&eig, f64::exp)))
}

pub(crate) fn spd_function(
    what: &str,
    c: ArrayView2<f64>,
    f: impl Fn(f64) -> f64,
) -> Result<Array2<f64>> {
    let m = symmetric_from(what, c)?;
    let eig = spd_eigen(what, m)?;
    Ok(to_array2(&eigen_function(&eig, f)))
}

/// Affine-invariant Riemannian distance between two SPD matrices (dimensionless).
pub fn distance_riemann(a: ArrayView2<f64>, b: ArrayView2<f64>) -> Result<f64> {
    let a = symmetric_from("distance: first matrix", a)?;
    let b = symmetric_from("distance: second matrix", b)?;
    if a.nrows() != b.nrows() {
        return Err(DecodeError::ShapeMismatch {
            what: "distance: second matrix".to_string(),
            expected: format!("{n}×{n}", n = a.nrows()),
            got: format!("{n}×{n}", n = b.nrows()),
        });
    }
    // λ: generalized eigenvalues of (A, B), all positive iff A is SPD (B being SPD).
    let l = generalized_eigenvalues("distance", &a, &b)?;
    if l.iter().all(|&v| v > 0.0) {
        Ok(l.iter().map(|v| v.ln().powi(2)).sum::<f64>().sqrt())
    } else {
        Err(DecodeError::NotPositiveDefinite {
            what: "distance: first matrix".to_string(),
        })
    }
}

/// `d²(C, R)` from `R^{-1/2}`: the eigenvalues of `R^{-1/2} C R^{-1/2}`.
pub(crate) fn squared_distance_whitened(
    r_invsqrt: &DMatrix<f64>,
    c: &DMatrix<f64>,
    tmp: &mut DMatrix<f64>,
    w: &mut DMatrix<f64>,
) -> Result<f64> {
    congruence_into(r_invsqrt, c, tmp, w);
    let l = sym_eigenvalues("whitened matrix", w)?;
    if l.iter().all(|&v| v > 0.0) {
        Ok(l.iter().map(|v| v.ln().powi(2)).sum())
    } else {
        Err(DecodeError::NotPositiveDefinite {
            what: format!("matrix in distance (whitened eigenvalue {:e})", l.min()),
        })
    }
}
