//! Binary shrinkage linear discriminant analysis, equal to scikit-learn's
//! `LinearDiscriminantAnalysis(solver="lsqr", shrinkage=...)`.
//!
//! Fitting, as scikit-learn 1.9 does it:
//! * priors `π_k` = class frequencies; class means `μ_k`;
//! * within-class covariance `Σ = Σ_k π_k Σ_k`, each `Σ_k` the class's own (centred, `/ n_k`)
//!   covariance, shrunk:
//!   * [`Shrinkage::Auto`]: the class's features are standardised (`StandardScaler`: centred, divided
//!     by their population standard deviation; near-constant features keep scale 1), Ledoit–Wolf
//!     shrunk ([`crate::riemann::covariance::ledoit_wolf`]), and scaled back `Σ_k = D·LW·D`;
//!   * [`Shrinkage::Fixed`]`(s)`: `(1 − s)·S_k + s·(tr S_k / p)·I`;
//! * `w_k = Σ⁺ μ_k` (least squares, singular values below `ε·σ_max` dropped, as `scipy.linalg.lstsq`),
//!   `b_k = −½ μ_k·w_k + ln π_k`; the binary model is `coef = w_target − w_nontarget`,
//!   `intercept = b_target − b_nontarget`.
//!
//! [`Lda::decision_function`] is the log-odds `x·coef + intercept` (nats; larger = more target-like)
//! and [`Lda::predict_proba`] its logistic sigmoid, P(target), as scikit-learn's binary `predict_proba`.
//!
//! Written here: no well-kept Rust crate has a shrinkage LDA matching scikit-learn's; checked against
//! scikit-learn 1.9.1 in `tests/linear_riemann_golden.rs`.

use nalgebra::{DMatrix, DVector};
use ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::riemann::covariance::{estimate_columns, shrink_in_place, CovEstimator};
use crate::linalg::{
    check_finite, check_labels, sigmoid, standardise_columns, sym_eigen, to_array2,
};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// How the class covariances are regularised.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum Shrinkage {
    /// Ledoit–Wolf shrinkage of the standardised features (scikit-learn's `shrinkage="auto"`).
    #[default]
    Auto,
    /// A fixed shrinkage weight in `[0, 1]` (0 = empirical covariance).
    Fixed(f64),
}

/// Settings of a shrinkage LDA.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LdaParams {
    pub shrinkage: Shrinkage,
}

/// A fitted binary shrinkage LDA.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Lda {
    coef: Array1<f64>,
    intercept: f64,
    /// `[P(non-target), P(target)]` from the training class frequencies.
    priors: [f64; 2],
    /// Class means `(2, n_features)`: row 0 non-target, row 1 target.
    means: Array2<f64>,
    /// Weighted within-class covariance `(n_features, n_features)`.
    covariance: Array2<f64>,
}

impl LdaParams {
    /// Fits on `x` `(n_samples, n_features)` with labels `y` (`true` = target). Needs both classes,
    /// more than two samples, and finite values.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<Lda> {
        if let Shrinkage::Fixed(s) = self.shrinkage {
            if !(0.0..=1.0).contains(&s) {
                return Err(DecodeError::InvalidParameter {
                    name: "shrinkage",
                    value: s.to_string(),
                    reason: "must be in [0, 1]".to_string(),
                });
            }
        }
        let (n, p) = x.dim();
        check_labels(n, y)?;
        if p == 0 {
            return Err(DecodeError::ShapeMismatch {
                what: "LDA features".to_string(),
                expected: "at least one feature".to_string(),
                got: "0".to_string(),
            });
        }
        if n <= 2 {
            return Err(DecodeError::TooFewSamples {
                what: format!("LDA needs more samples than classes, got {n}"),
            });
        }
        check_finite("LDA features", x.iter())?;

        let mut priors = [0.0; 2];
        let mut means = DMatrix::zeros(p, 2);
        let mut sigma = DMatrix::zeros(p, p);
        for (k, class) in [false, true].into_iter().enumerate() {
            let rows: Vec<usize> = (0..n).filter(|&i| y[i] == class).collect();
            let n_k = rows.len();
            priors[k] = n_k as f64 / n as f64;
            let data = DMatrix::from_fn(n_k, p, |r, j| x[[rows[r], j]]);
            for j in 0..p {
                means[(j, k)] = data.column(j).sum() / n_k as f64;
            }
            let cov = class_covariance(data, self.shrinkage);
            sigma += priors[k] * cov;
        }

        // Minimum-norm least squares Σ⁺ μ_k through the symmetric eigendecomposition of Σ.
        let eig = sym_eigen("LDA within-class covariance", sigma.clone())?;
        let l_max = eig.eigenvalues.amax();
        let cutoff = f64::EPSILON * l_max;
        let v = &eig.eigenvectors;
        let solve = |b: DVector<f64>| -> DVector<f64> {
            let mut t = v.tr_mul(&b);
            for (ti, &l) in t.iter_mut().zip(eig.eigenvalues.iter()) {
                *ti = if l > cutoff { *ti / l } else { 0.0 };
            }
            v * t
        };
        let mut w = [DVector::zeros(p), DVector::zeros(p)];
        let mut b = [0.0; 2];
        for k in 0..2 {
            let mu = means.column(k).into_owned();
            w[k] = solve(mu.clone());
            b[k] = -0.5 * mu.dot(&w[k]) + priors[k].ln();
        }
        let coef = &w[1] - &w[0];
        Ok(Lda {
            coef: Array1::from_iter(coef.iter().copied()),
            intercept: b[1] - b[0],
            priors,
            means: to_array2(&means.transpose()),
            covariance: to_array2(&sigma),
        })
    }
}

/// One class's (shrunk) covariance from its data `(n_k, p)`.
fn class_covariance(mut data: DMatrix<f64>, shrinkage: Shrinkage) -> DMatrix<f64> {
    let p = data.ncols();
    let mut cov = DMatrix::zeros(p, p);
    match shrinkage {
        Shrinkage::Fixed(s) => {
            estimate_columns(CovEstimator::Scm, &mut data, &mut cov);
            shrink_in_place(&mut cov, s);
        }
        Shrinkage::Auto => {
            let scale = standardise_columns(&mut data);
            estimate_columns(CovEstimator::LedoitWolf, &mut data, &mut cov);
            for j in 0..p {
                for i in 0..p {
                    cov[(i, j)] *= scale[i] * scale[j];
                }
            }
        }
    }
    cov
}

impl Lda {
    /// `(n_features,)`: weights of the log-odds, per feature unit⁻¹.
    pub fn coef(&self) -> ArrayView1<'_, f64> {
        self.coef.view()
    }

    /// Log-odds offset (nats).
    pub fn intercept(&self) -> f64 {
        self.intercept
    }

    /// `[P(non-target), P(target)]` from the training class frequencies.
    pub fn priors(&self) -> [f64; 2] {
        self.priors
    }

    /// Class means `(2, n_features)`: row 0 non-target, row 1 target.
    pub fn means(&self) -> ArrayView2<'_, f64> {
        self.means.view()
    }

    /// Weighted within-class covariance `(n_features, n_features)`.
    pub fn covariance(&self) -> ArrayView2<'_, f64> {
        self.covariance.view()
    }

    /// Number of features the model was fitted on.
    pub fn n_features(&self) -> usize {
        self.coef.len()
    }

    /// Log-odds of target `x·coef + intercept` per row of `x` `(n_samples, n_features)`.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        linear_decision("LDA input", x, self.coef.view(), self.intercept)
    }

    /// P(target) per row: the logistic sigmoid of [`decision_function`](Self::decision_function).
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Ok(self.decision_function(x)?.mapv(sigmoid))
    }
}

/// `x·coef + intercept` with shape and finiteness checks (shared with logistic regression).
pub(crate) fn linear_decision(
    what: &str,
    x: ArrayView2<f64>,
    coef: ArrayView1<f64>,
    intercept: f64,
) -> Result<Array1<f64>> {
    if x.ncols() != coef.len() {
        return Err(DecodeError::ShapeMismatch {
            what: what.to_string(),
            expected: format!("{} features", coef.len()),
            got: format!("{}", x.ncols()),
        });
    }
    check_finite(what, x.iter())?;
    Ok(x.dot(&coef) + intercept)
}

crate::traits::rows_classifier!(LdaParams => Lda, "LDA");

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    fn toy() -> (Array2<f64>, Vec<bool>) {
        let x = array![
            [1.0, 2.0],
            [1.5, 1.8],
            [0.8, 2.4],
            [1.2, 2.1],
            [3.0, 0.5],
            [3.3, 0.9],
            [2.7, 0.2],
        ];
        (x, vec![false, false, false, false, true, true, true])
    }

    #[test]
    fn separates_toy_data_and_probabilities_follow_decision() {
        let (x, y) = toy();
        for shrinkage in [
            Shrinkage::Auto,
            Shrinkage::Fixed(0.0),
            Shrinkage::Fixed(0.5),
        ] {
            let lda = LdaParams { shrinkage }.fit(x.view(), &y).unwrap();
            let d = lda.decision_function(x.view()).unwrap();
            let p = lda.predict_proba(x.view()).unwrap();
            for i in 0..y.len() {
                assert_eq!(d[i] > 0.0, y[i], "{shrinkage:?} sample {i}: {}", d[i]);
                assert!((p[i] - 1.0 / (1.0 + (-d[i]).exp())).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn fixed_zero_is_plain_lda() {
        // With Σ the pooled covariance, coef = Σ⁻¹ (μ1 − μ0).
        let (x, y) = toy();
        let lda = LdaParams {
            shrinkage: Shrinkage::Fixed(0.0),
        }
        .fit(x.view(), &y)
        .unwrap();
        let s = crate::linalg::to_dmatrix(lda.covariance());
        let m = lda.means();
        let dmu = DVector::from_vec(vec![m[[1, 0]] - m[[0, 0]], m[[1, 1]] - m[[0, 1]]]);
        let expect = s.try_inverse().unwrap() * dmu;
        for j in 0..2 {
            assert!((lda.coef()[j] - expect[j]).abs() < 1e-10 * expect.amax());
        }
    }

    #[test]
    fn errors() {
        let (x, y) = toy();
        assert!(matches!(
            LdaParams::default().fit(x.view(), &y[..3]),
            Err(DecodeError::LabelCount { .. })
        ));
        assert!(matches!(
            LdaParams::default().fit(x.view(), &[false; 7]),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        assert!(matches!(
            LdaParams {
                shrinkage: Shrinkage::Fixed(1.5)
            }
            .fit(x.view(), &y),
            Err(DecodeError::InvalidParameter { .. })
        ));
        let lda = LdaParams::default().fit(x.view(), &y).unwrap();
        assert!(matches!(
            lda.decision_function(array![[1.0, 2.0, 3.0]].view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
    }
}
