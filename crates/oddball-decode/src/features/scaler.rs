//! Feature standardisation with scikit-learn's `StandardScaler` semantics, and the input checks the
//! paper's feature and classifier modules share.
//!
//! Fitting computes each feature's mean and its population variance (`/ n`) with scikit-learn's
//! two-pass, compensated formula (`Σ(x − m)² − (Σ(x − m))² / n`); `scale = √var`, except that a
//! feature whose variance is within round-off of zero (`var ≤ n·ε·var + (n·|mean|·ε)²`, scikit-learn's
//! `_is_constant_feature`) keeps scale 1. `transform` is `(x − mean) / scale`. Written here: it is a
//! dozen lines, and `linfa-preprocessing` pulls in a BLAS-backed linear-algebra stack.

use ndarray::{Array1, Array2, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Unfitted settings: which of centring and scaling to do (both by default, as scikit-learn).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct StandardScalerParams {
    /// Subtract the mean.
    pub with_mean: bool,
    /// Divide by the standard deviation.
    pub with_std: bool,
}

impl Default for StandardScalerParams {
    fn default() -> Self {
        Self {
            with_mean: true,
            with_std: true,
        }
    }
}

/// A fitted scaler.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StandardScaler {
    /// Per-feature mean (zeros when `with_mean` is off).
    pub mean: Array1<f64>,
    /// Per-feature population variance.
    pub var: Array1<f64>,
    /// Per-feature divisor (ones when `with_std` is off; 1 for constant features).
    pub scale: Array1<f64>,
}

impl StandardScalerParams {
    /// Learns means and scales from `x` `(n_samples, n_features)`.
    pub fn fit(&self, x: ArrayView2<f64>) -> Result<StandardScaler> {
        let (n, p) = x.dim();
        if n == 0 {
            return Err(DecodeError::TooFewSamples {
                what: "StandardScaler needs at least one sample".into(),
            });
        }
        check_finite(x, "StandardScaler input")?;
        let nf = n as f64;
        let mut mean = Array1::<f64>::zeros(p);
        for row in x.outer_iter() {
            mean += &row;
        }
        mean /= nf;
        let mut var = Array1::<f64>::zeros(p);
        let mut correction = Array1::<f64>::zeros(p);
        for row in x.outer_iter() {
            for j in 0..p {
                let d = row[j] - mean[j];
                correction[j] += d;
                var[j] += d * d;
            }
        }
        for j in 0..p {
            var[j] = (var[j] - correction[j] * correction[j] / nf) / nf;
        }
        let eps = f64::EPSILON;
        let scale = if self.with_std {
            Array1::from_shape_fn(p, |j| {
                let constant = var[j] <= nf * eps * var[j] + (nf * mean[j] * eps).powi(2);
                if constant {
                    1.0
                } else {
                    var[j].sqrt()
                }
            })
        } else {
            Array1::ones(p)
        };
        if !self.with_mean {
            mean.fill(0.0);
        }
        Ok(StandardScaler { mean, var, scale })
    }
}

impl StandardScaler {
    /// Number of features seen in fitting.
    pub fn n_features(&self) -> usize {
        self.mean.len()
    }

    /// `(x − mean) / scale`.
    pub fn transform(&self, x: ArrayView2<f64>) -> Result<Array2<f64>> {
        check_n_features("StandardScaler input", self.n_features(), x.ncols())?;
        let mut out = x.to_owned();
        for mut row in out.axis_iter_mut(Axis(0)) {
            for ((v, m), s) in row.iter_mut().zip(&self.mean).zip(&self.scale) {
                *v = (*v - m) / s;
            }
        }
        Ok(out)
    }

    /// `x · scale + mean`.
    pub fn inverse_transform(&self, x: ArrayView2<f64>) -> Result<Array2<f64>> {
        check_n_features("StandardScaler input", self.n_features(), x.ncols())?;
        let mut out = x.to_owned();
        for mut row in out.axis_iter_mut(Axis(0)) {
            for ((v, m), s) in row.iter_mut().zip(&self.mean).zip(&self.scale) {
                *v = *v * s + m;
            }
        }
        Ok(out)
    }
}

// ---------------------------------------------------------------- checks shared by the paper modules

/// Every value of `x` is finite.
pub(crate) fn check_finite(x: ArrayView2<f64>, what: &str) -> Result<()> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(DecodeError::NonFinite { what: what.into() })
    }
}

/// `got` columns where `expected` were fitted.
pub(crate) fn check_n_features(what: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(DecodeError::ShapeMismatch {
            what: what.into(),
            expected: format!("{expected} features"),
            got: format!("{got} features"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn standardises_and_inverts() {
        let x = array![
            [1.0, 10.0, 5.0],
            [2.0, 20.0, 5.0],
            [3.0, 60.0, 5.0],
            [6.0, 10.0, 5.0]
        ];
        let s = StandardScalerParams::default().fit(x.view()).unwrap();
        assert_eq!(s.scale[2], 1.0, "constant feature keeps scale 1");
        let z = s.transform(x.view()).unwrap();
        for j in 0..2 {
            let col = z.column(j);
            assert!(col.mean().unwrap().abs() < 1e-12);
            assert!((col.mapv(|v| v * v).mean().unwrap() - 1.0).abs() < 1e-12);
        }
        assert!(z.column(2).iter().all(|&v| v == 0.0));
        let back = s.inverse_transform(z.view()).unwrap();
        assert!(back
            .iter()
            .zip(x.iter())
            .all(|(a, b)| (a - b).abs() < 1e-12));
        assert!(s.transform(array![[1.0, 2.0]].view()).is_err());
    }

    #[test]
    fn options_and_errors() {
        let x = array![[1.0, 3.0], [3.0, 7.0]];
        let p = StandardScalerParams {
            with_mean: false,
            with_std: true,
        };
        let s = p.fit(x.view()).unwrap();
        assert_eq!(s.mean, array![0.0, 0.0]);
        assert_eq!(s.scale, array![1.0, 2.0]);
        assert!(StandardScalerParams::default()
            .fit(Array2::<f64>::zeros((0, 2)).view())
            .is_err());
        assert!(StandardScalerParams::default()
            .fit(array![[f64::NAN]].view())
            .is_err());
    }
}
