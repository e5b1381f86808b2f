//! Bayesian linear discriminant analysis (BLDA): Hoffmann, Vesin, Ebrahimi & Diserens 2008, "An
//! efficient P300-based brain–computer interface for disabled subjects", J. Neurosci. Methods
//! 167:115–125 — the classifier of the EPFL P300 benchmark — following the authors' MATLAB code
//! (`@bayeslda/train.m`, `classify.m`, EPFL 2006), which applies MacKay's (1992) evidence
//! framework to Fisher's discriminant written as a least-squares regression.
//!
//! Fitting, for `N` training rows, `N₁` targets and `N₂` non-targets:
//! * regression targets `t = N/N₁` for a target, `−N/N₂` for a non-target (their sum is 0);
//! * a constant feature 1 appended to every row (the bias), `X` `(N, p + 1)`;
//! * one symmetric eigendecomposition `XᵀX = V diag(d) Vᵀ`;
//! * a Gaussian prior on the weights with precision `α` and Gaussian noise of precision `β`, chosen
//!   by evidence maximisation with MacKay's fixed-point updates, from `α = 25`, `β = 1`:
//!   ```text
//!   m = β V ((β d + a)⁻¹ ∘ VᵀXᵀt)      a = (α, …, α, 10⁻⁸)
//!   γ = Σ β dᵢ / (β dᵢ + aᵢ)            (the number of well-determined parameters)
//!   α ← γ / (mᵀm),   β ← (N − γ) / ‖t − X m‖²
//!   ```
//!   until both `|Δα|` and `|Δβ|` are at most `10⁻⁴`, at most 499 updates. The near-flat prior
//!   `10⁻⁸` is placed, as the authors' code writes the prior in eigen coordinates, on the
//!   eigenvector of `XᵀX` with the largest eigenvalue — the bias direction when the features are
//!   small next to the constant, a feature direction otherwise; `mᵀm` includes the bias weight.
//! * The model is the last posterior mean `m` (computed with the `α`, `β` before the last update)
//!   and the last `α`, `β`, as the code returns them; no shrinkage grid or cross-validation.
//!
//! [`Blda::decision_function`] is the posterior mean's prediction `x·w + bias` (in units of the
//! regression targets; larger = more target-like). [`Blda::predict_proba`] maps it to P(target) by
//! a one-dimensional LDA on the training scores (equal-variance Gaussians per class, training class
//! frequencies as priors), since the regression output is not itself a probability.
//!
//! Written here: no well-kept Rust crate has BLDA (scikit-learn's `BayesianRidge` runs the same
//! MacKay updates but has neither the flat bias prior nor the discriminant targets). Checked against
//! a NumPy transcription of the authors' code, itself checked against scikit-learn's
//! `BayesianRidge`, in `tests/blda.rs` (`tools/golden/decode_blda/`).

use nalgebra::{DMatrix, DVector};
use ndarray::{Array1, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::classifiers::lda::linear_decision;
use crate::linalg::{check_finite, check_labels, sigmoid, sym_eigen};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of a Bayesian LDA; [`Default`] is the authors' code.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BldaParams {
    /// Initial precision `α` of the weights' Gaussian prior (25).
    pub alpha_init: f64,
    /// Initial precision `β` of the noise around the regression targets (1).
    pub beta_init: f64,
    /// Prior precision of the direction treated as the bias (10⁻⁸, near flat; ≥ 0).
    pub bias_precision: f64,
    /// The updates stop when `|Δα|` and `|Δβ|` are both at most this (10⁻⁴, absolute).
    pub tol: f64,
    /// Most updates of `α` and `β` (499: the code's `maxit = 500` with its loop counter starting
    /// at 1); a fit that has not met `tol` by then fails with [`DecodeError::NoConvergence`]. (The
    /// code also gives up when `tol` is first met on the very last update; this accepts it.)
    pub max_iter: usize,
}

impl Default for BldaParams {
    fn default() -> Self {
        BldaParams {
            alpha_init: 25.0,
            beta_init: 1.0,
            bias_precision: 1e-8,
            tol: 1e-4,
            max_iter: 499,
        }
    }
}

/// A fitted Bayesian LDA.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Blda {
    /// Posterior mean of the feature weights `(n_features,)`.
    weights: Array1<f64>,
    /// Posterior mean of the bias weight.
    bias: f64,
    /// Evidence-maximising prior precision of the weights.
    alpha: f64,
    /// Evidence-maximising noise precision.
    beta: f64,
    /// Log evidence at the returned `α`, `β` (the authors' formula).
    log_evidence: f64,
    /// Updates of `α`, `β` made.
    n_iter: usize,
    /// P(target) = sigmoid(`proba_slope`·score + `proba_offset`), from the training scores.
    proba_slope: f64,
    proba_offset: f64,
}

impl BldaParams {
    fn check(&self) -> Result<()> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(DecodeError::InvalidParameter {
                name,
                value,
                reason: reason.to_string(),
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.alpha_init) {
            return bad("alpha_init", self.alpha_init.to_string(), "must be > 0");
        }
        if !positive(self.beta_init) {
            return bad("beta_init", self.beta_init.to_string(), "must be > 0");
        }
        if !(self.bias_precision.is_finite() && self.bias_precision >= 0.0) {
            let v = self.bias_precision.to_string();
            return bad("bias_precision", v, "must be finite and ≥ 0");
        }
        if !positive(self.tol) {
            return bad("tol", self.tol.to_string(), "must be > 0");
        }
        if self.max_iter == 0 {
            return bad("max_iter", "0".to_string(), "must be at least 1");
        }
        Ok(())
    }

    /// Fits on `x` `(n_samples, n_features)` with labels `y` (`true` = target). Needs both
    /// classes, at least one feature and finite values.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<Blda> {
        self.check()?;
        let (n, p) = x.dim();
        let (n_pos, n_neg) = check_labels(n, y)?;
        if p == 0 {
            return Err(DecodeError::ShapeMismatch {
                what: "BLDA features".to_string(),
                expected: "at least one feature".to_string(),
                got: "0".to_string(),
            });
        }
        check_finite("BLDA features", x.iter())?;

        let nf = n as f64;
        let t = DVector::from_iterator(
            n,
            y.iter().map(|&c| {
                if c {
                    nf / n_pos as f64
                } else {
                    -nf / n_neg as f64
                }
            }),
        );
        // Rows with the constant feature last.
        let xa = DMatrix::from_fn(n, p + 1, |i, j| if j < p { x[[i, j]] } else { 1.0 });
        let eig = sym_eigen("BLDA XᵀX", xa.tr_mul(&xa))?;
        let (d, v) = (&eig.eigenvalues, &eig.eigenvectors);
        let vxy = v.tr_mul(&xa.tr_mul(&t));
        // The prior precision per eigen direction: α everywhere but the largest eigenvalue's.
        let top = d.imax();
        let prior = |alpha: f64| {
            DVector::from_fn(
                p + 1,
                |k, _| {
                    if k == top {
                        self.bias_precision
                    } else {
                        alpha
                    }
                },
            )
        };

        let (mut alpha, mut beta) = (self.alpha_init, self.beta_init);
        let mut updates = 0;
        let (m, err) = loop {
            let a = prior(alpha);
            let scaled = DVector::from_fn(p + 1, |k, _| vxy[k] / (beta * d[k] + a[k]));
            let m = beta * (v * scaled);
            let err = (&t - &xa * &m).norm_squared();
            let gamma: f64 = (0..=p).map(|k| beta * d[k] / (beta * d[k] + a[k])).sum();
            let (alpha_old, beta_old) = (alpha, beta);
            alpha = gamma / m.norm_squared();
            beta = (nf - gamma) / err;
            updates += 1;
            if !(alpha.is_finite() && beta.is_finite() && alpha > 0.0 && beta > 0.0) {
                return Err(DecodeError::NonFinite {
                    what: format!(
                        "BLDA evidence maximisation (α = {alpha}, β = {beta} after {updates} \
                         updates: the features carry no linear information about the classes, \
                         or fit them exactly)"
                    ),
                });
            }
            if (alpha - alpha_old).abs() <= self.tol && (beta - beta_old).abs() <= self.tol {
                break (m, err);
            }
            if updates == self.max_iter {
                return Err(DecodeError::NoConvergence {
                    what: "BLDA evidence maximisation (α, β)".to_string(),
                    iterations: updates,
                });
            }
        };

        let a = prior(alpha);
        let log_det: f64 = (0..=p).map(|k| (beta * d[k] + a[k]).ln()).sum();
        let log_evidence = 0.5 * (p + 1) as f64 * alpha.ln() + 0.5 * nf * beta.ln()
            - 0.5 * beta * err
            - 0.5 * alpha * m.norm_squared()
            - 0.5 * log_det
            - 0.5 * nf * (2.0 * std::f64::consts::PI).ln();

        let weights = Array1::from_iter(m.iter().take(p).copied());
        let bias = m[p];
        let scores = x.dot(&weights) + bias;
        let (proba_slope, proba_offset) = score_lda(scores.view(), y, n_pos, n_neg)?;
        Ok(Blda {
            weights,
            bias,
            alpha,
            beta,
            log_evidence,
            n_iter: updates,
            proba_slope,
            proba_offset,
        })
    }
}

/// Slope and offset of the log-odds of a one-dimensional LDA on the training scores: class means
/// `μ₁`, `μ₀`, pooled within-class variance `σ²` (divided by `N`), priors `N₁/N`, `N₀/N`.
fn score_lda(
    scores: ArrayView1<f64>,
    y: &[bool],
    n_pos: usize,
    n_neg: usize,
) -> Result<(f64, f64)> {
    let mean = |class: bool, count: usize| {
        scores
            .iter()
            .zip(y)
            .filter(|(_, &c)| c == class)
            .map(|(s, _)| s)
            .sum::<f64>()
            / count as f64
    };
    let (mu1, mu0) = (mean(true, n_pos), mean(false, n_neg));
    let var = scores
        .iter()
        .zip(y)
        .map(|(s, &c)| (s - if c { mu1 } else { mu0 }).powi(2))
        .sum::<f64>()
        / scores.len() as f64;
    if !(var > 0.0 && var.is_finite()) {
        return Err(DecodeError::NotPositiveDefinite {
            what: "BLDA within-class variance of the training scores".to_string(),
        });
    }
    let slope = (mu1 - mu0) / var;
    let offset = -slope * 0.5 * (mu1 + mu0) + (n_pos as f64 / n_neg as f64).ln();
    Ok((slope, offset))
}

impl Blda {
    /// Posterior mean of the feature weights `(n_features,)`, per feature unit⁻¹.
    pub fn weights(&self) -> ArrayView1<'_, f64> {
        self.weights.view()
    }

    /// Posterior mean of the bias weight.
    pub fn bias(&self) -> f64 {
        self.bias
    }

    /// The evidence-maximising prior precision of the weights.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// The evidence-maximising noise precision (per squared target unit).
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// Log evidence at [`Self::alpha`], [`Self::beta`] (the authors' formula, nats).
    pub fn log_evidence(&self) -> f64 {
        self.log_evidence
    }

    /// Updates of `α` and `β` the fit made.
    pub fn n_iter(&self) -> usize {
        self.n_iter
    }

    /// Number of features the model was fitted on.
    pub fn n_features(&self) -> usize {
        self.weights.len()
    }

    /// The posterior mean's prediction `x·w + bias` per row of `x` `(n_samples, n_features)`.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        linear_decision("BLDA input", x, self.weights.view(), self.bias)
    }

    /// P(target) per row: the training scores' one-dimensional LDA applied to
    /// [`decision_function`](Self::decision_function).
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Ok(self
            .decision_function(x)?
            .mapv(|s| sigmoid(self.proba_slope * s + self.proba_offset)))
    }
}

crate::traits::rows_classifier!(BldaParams => Blda, "BLDA");

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{array, Array2};

    fn toy() -> (Array2<f64>, Vec<bool>) {
        let x = array![
            [1.0, 2.0],
            [1.5, 1.8],
            [0.8, 2.4],
            [1.2, 2.1],
            [0.9, 1.7],
            [3.0, 0.5],
            [3.3, 0.9],
            [2.7, 0.2],
        ];
        (x, vec![false, false, false, false, false, true, true, true])
    }

    #[test]
    fn separates_toy_data_and_probabilities_follow_scores() {
        let (x, y) = toy();
        let blda = BldaParams::default().fit(x.view(), &y).unwrap();
        let s = blda.decision_function(x.view()).unwrap();
        let p = blda.predict_proba(x.view()).unwrap();
        for i in 0..y.len() {
            assert_eq!(p[i] > 0.5, y[i], "sample {i}: score {} P {}", s[i], p[i]);
        }
        for i in 1..y.len() {
            assert_eq!(s[i] > s[0], p[i] > p[0]);
        }
        assert!(blda.alpha() > 0.0 && blda.beta() > 0.0 && blda.n_iter() >= 1);
        assert!(blda.log_evidence().is_finite());
    }

    #[test]
    fn errors() {
        let (x, y) = toy();
        let fit = |p: BldaParams| p.fit(x.view(), &y);
        for bad in [
            BldaParams {
                alpha_init: 0.0,
                ..Default::default()
            },
            BldaParams {
                beta_init: f64::NAN,
                ..Default::default()
            },
            BldaParams {
                bias_precision: -1.0,
                ..Default::default()
            },
            BldaParams {
                tol: 0.0,
                ..Default::default()
            },
            BldaParams {
                max_iter: 0,
                ..Default::default()
            },
        ] {
            assert!(
                matches!(fit(bad), Err(DecodeError::InvalidParameter { .. })),
                "{bad:?}"
            );
        }
        assert!(matches!(
            fit(BldaParams {
                max_iter: 1,
                ..Default::default()
            }),
            Err(DecodeError::NoConvergence { iterations: 1, .. })
        ));
        assert!(matches!(
            BldaParams::default().fit(x.view(), &[false; 8]),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        assert!(matches!(
            BldaParams::default().fit(x.view(), &y[..3]),
            Err(DecodeError::LabelCount { .. })
        ));
        let blda = BldaParams::default().fit(x.view(), &y).unwrap();
        assert!(matches!(
            blda.decision_function(array![[1.0, 2.0, 3.0]].view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
    }
}
