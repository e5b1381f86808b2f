//! Block-Toeplitz shrinkage LDA (Sosulski & Tangermann 2022, *J. Neural Eng.* 19 066019), equal to
//! `toeplitzlda.classification.ToeplitzLDA(n_channels)` 0.4.0 by the method's authors.
//!
//! A shrinkage LDA on spatio-temporal features (one value per channel and time bin) whose covariance
//! assumes the background EEG is stationary over the epoch: the covariance between channel `a` at
//! time `t` and channel `b` at time `t + d` depends on `(a, b, d)` only. With 20 time bins that
//! pools 20 estimates of each lag-0 entry, and far fewer parameters are left to estimate from a
//! few hundred epochs.
//!
//! Fitting, as `toeplitzlda` does it:
//! * priors `π_k` = class frequencies; class means `μ_k`;
//! * every sample minus its class mean, pooled; those residuals standardised per feature
//!   (`StandardScaler`: population standard deviation; near-constant features keep scale 1);
//! * `S = Xᵀ X` of the (re-centred) standardised residuals `(n, p)`, target `T = ν I` with
//!   `ν = mean(diag S)`, Ledoit–Wolf weight (the BBCI toolbox's form)
//!   `γ = n·ΣV / ‖S − T‖²_F`, `V = (X²ᵀ X² − S∘S / n) / (n − 1)`, clipped to `[0, 1]`;
//!   `Σ = D·(γ T + (1 − γ) S)·D / (n − 1)` with `D` the scales;
//! * block-Toeplitz: every entry replaced by the mean of the entries with the same channel pair and
//!   the same time lag `d`, then multiplied by the linear taper `(n_times − |d|) / n_times`;
//! * `w_k = Σ⁻¹ μ_k`, `b_k = −½ μ_k·w_k + ln π_k`; binary `coef = w_target − w_nontarget`,
//!   `intercept = b_target − b_nontarget`.
//!
//! Features are oddball's channel-major layout: feature `ch · n_times + t` (an epoch
//! `(n_channels, n_times)` flattened row-major); `toeplitzlda` reads them time-major, which is the
//! same model with the features permuted.
//!
//! Written here: no Rust crate has it; checked against `toeplitzlda` 0.4.0 in
//! `tests/toeplitz_lda_golden.rs` (fixture from `tools/golden/decode_toeplitz/`).

use nalgebra::{DMatrix, DVector};
use ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::classifiers::lda::linear_decision;
use crate::linalg::{check_finite, check_labels, sigmoid, standardise_columns, to_array2};
use crate::traits::{FeatureView, FitClassifier, ProbabilisticClassifier};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of a block-Toeplitz LDA (it has none to choose: the shrinkage is Ledoit–Wolf's and the
/// taper linear, as the method's authors set them).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ToeplitzLdaParams {}

/// A fitted binary block-Toeplitz LDA.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToeplitzLda {
    coef: Array1<f64>,
    intercept: f64,
    n_channels: usize,
    n_times: usize,
    /// The Ledoit–Wolf weight used, in `[0, 1]`.
    shrinkage: f64,
    /// The block-Toeplitz, tapered covariance that was solved `(n_features, n_features)`; not
    /// saved (large and not needed to score).
    #[serde(skip)]
    covariance: Option<Array2<f64>>,
}

impl ToeplitzLdaParams {
    /// Fits on `x` `(n_samples, n_channels · n_times)` (channel-major) with labels `y` (`true` =
    /// target). Needs both classes, more than two samples, and finite values.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool], n_channels: usize) -> Result<ToeplitzLda> {
        let (n, p) = x.dim();
        check_labels(n, y)?;
        if n_channels == 0 || p == 0 || p % n_channels != 0 {
            return Err(DecodeError::ShapeMismatch {
                what: "block-Toeplitz LDA features".to_string(),
                expected: format!("a non-zero multiple of {n_channels} channels"),
                got: format!("{p} features"),
            });
        }
        if n <= 2 {
            return Err(DecodeError::TooFewSamples {
                what: format!("block-Toeplitz LDA needs more samples than classes, got {n}"),
            });
        }
        check_finite("block-Toeplitz LDA features", x.iter())?;
        let n_times = p / n_channels;

        // Class means and the pooled residuals (each sample minus its class mean).
        let mut priors = [0.0; 2];
        let mut means = DMatrix::zeros(p, 2);
        let mut resid = DMatrix::zeros(n, p);
        let mut row = 0;
        for (k, class) in [false, true].into_iter().enumerate() {
            let rows: Vec<usize> = (0..n).filter(|&i| y[i] == class).collect();
            priors[k] = rows.len() as f64 / n as f64;
            for j in 0..p {
                means[(j, k)] = rows.iter().map(|&i| x[[i, j]]).sum::<f64>() / rows.len() as f64;
            }
            for &i in &rows {
                for j in 0..p {
                    resid[(row, j)] = x[[i, j]] - means[(j, k)];
                }
                row += 1;
            }
        }

        let (cov, shrinkage) = standardised_ledoit_wolf(resid);
        let cov = block_toeplitz_tapered(cov, n_channels, n_times);

        let rhs = means.clone();
        let w =
            match cov.clone().cholesky() {
                Some(c) => c.solve(&rhs),
                None => cov.clone().lu().solve(&rhs).ok_or_else(|| {
                    DecodeError::NotPositiveDefinite {
                        what: "block-Toeplitz LDA covariance (singular)".to_string(),
                    }
                })?,
            };
        check_finite("block-Toeplitz LDA weights", w.iter())?;
        let mut b = [0.0; 2];
        for (k, bk) in b.iter_mut().enumerate() {
            *bk = -0.5 * means.column(k).dot(&w.column(k)) + priors[k].ln();
        }
        let coef: DVector<f64> = w.column(1) - w.column(0);
        Ok(ToeplitzLda {
            coef: Array1::from_iter(coef.iter().copied()),
            intercept: b[1] - b[0],
            n_channels,
            n_times,
            shrinkage,
            covariance: Some(to_array2(&cov)),
        })
    }
}

/// `toeplitzlda`'s `shrinkage(X, standardize=True)` on residuals `x` `(n, p)`: the shrunk covariance
/// (scaled back to feature units) and the Ledoit–Wolf weight.
fn standardised_ledoit_wolf(mut x: DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let (n, p) = x.shape();
    let nf = n as f64;
    let scale = standardise_columns(&mut x);
    // `shrinkage` centres the standardised rows once more.
    for mut col in x.column_iter_mut() {
        let mean = col.sum() / nf;
        col.apply(|v| *v -= mean);
    }
    let s = x.tr_mul(&x);
    let nu = s.diagonal().sum() / p as f64;
    // ΣV = (Σ_k (Σ_i x_ki²)² − Σ S_ij² / n) / (n − 1): the p×p product X²ᵀX² is never formed.
    let sum_sq_rows: f64 = x
        .row_iter()
        .map(|r| r.iter().map(|v| v * v).sum::<f64>().powi(2))
        .sum();
    let sum_s2: f64 = s.iter().map(|v| v * v).sum();
    let sum_v = (sum_sq_rows - sum_s2 / nf) / (nf - 1.0);
    let mut dist = 0.0;
    for j in 0..p {
        for i in 0..p {
            let d = s[(i, j)] - if i == j { nu } else { 0.0 };
            dist += d * d;
        }
    }
    let gamma = if dist > 0.0 {
        (nf * sum_v / dist).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let mut cov = s * ((1.0 - gamma) / (nf - 1.0));
    for i in 0..p {
        cov[(i, i)] += gamma * nu / (nf - 1.0);
    }
    for j in 0..p {
        for i in 0..p {
            cov[(i, j)] *= scale[i] * scale[j];
        }
    }
    (cov, gamma)
}

/// Averages `cov` (channel-major, `n_channels · n_times` square) over every (channel pair, time
/// lag) diagonal and tapers lag `d` by `(n_times − |d|) / n_times`. Linear in `cov`, and the
/// result of a positive semi-definite `cov` is positive semi-definite (each entry is the biased
/// cross-correlogram `(1/n_times) Σ_t cov[(a, t), (b, t + d)]`); the unsupervised decoder's
/// structured covariance is this map too.
pub(crate) fn block_toeplitz_tapered(
    mut cov: DMatrix<f64>,
    n_channels: usize,
    n_times: usize,
) -> DMatrix<f64> {
    let nt = n_times as isize;
    for a in 0..n_channels {
        for b in 0..n_channels {
            for d in -(nt - 1)..nt {
                let ts = (0.max(-d))..(nt.min(nt - d));
                let at = |t: isize| (a * n_times + t as usize, b * n_times + (t + d) as usize);
                let mean = ts.clone().map(|t| cov[at(t)]).sum::<f64>() / ts.len() as f64;
                let taper = (nt - d.abs()) as f64 / nt as f64;
                for t in ts {
                    cov[at(t)] = mean * taper;
                }
            }
        }
    }
    cov
}

impl ToeplitzLda {
    /// `(n_features,)`: weights of the score, channel-major.
    pub fn coef(&self) -> ArrayView1<'_, f64> {
        self.coef.view()
    }

    /// Score offset (nats).
    pub fn intercept(&self) -> f64 {
        self.intercept
    }

    /// The Ledoit–Wolf weight used, in `[0, 1]`.
    pub fn shrinkage(&self) -> f64 {
        self.shrinkage
    }

    /// `(n_channels, n_times)` of the feature layout it was fitted on.
    pub fn layout(&self) -> (usize, usize) {
        (self.n_channels, self.n_times)
    }

    /// The block-Toeplitz, tapered covariance that was solved, as fitted (`None` after a model
    /// was loaded: it is not saved).
    pub fn covariance(&self) -> Option<ArrayView2<'_, f64>> {
        self.covariance.as_ref().map(|c| c.view())
    }

    /// Number of features the model was fitted on.
    pub fn n_features(&self) -> usize {
        self.coef.len()
    }

    /// `x·coef + intercept` per row of `x` `(n_samples, n_features)`: larger = more target-like.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        linear_decision(
            "block-Toeplitz LDA input",
            x,
            self.coef.view(),
            self.intercept,
        )
    }

    /// The logistic sigmoid of [`decision_function`](Self::decision_function).
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Ok(self.decision_function(x)?.mapv(sigmoid))
    }
}

impl ProbabilisticClassifier for ToeplitzLda {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        ToeplitzLda::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        ToeplitzLda::decision_function(self, x)
    }
}

impl FitClassifier for ToeplitzLdaParams {
    type Fitted = ToeplitzLda;
    fn fit_classifier(
        &self,
        x: FeatureView<'_>,
        y: &[bool],
        n_channels: usize,
    ) -> Result<ToeplitzLda> {
        self.fit(x.rows("block-Toeplitz LDA")?, y, n_channels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform noise in [−1, 1) (an LCG, deterministic in `seed`) plus a unit bump at times 2..5 on
    /// targets (every 4th sample).
    fn data(n: usize, n_ch: usize, nt: usize, seed: u64) -> (Array2<f64>, Vec<bool>) {
        let mut state = seed;
        let y: Vec<bool> = (0..n).map(|i| i % 4 == 0).collect();
        let x = Array2::from_shape_fn((n, n_ch * nt), |(i, j)| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            let bump = if y[i] && (2..5).contains(&(j % nt)) {
                1.0
            } else {
                0.0
            };
            bump + u
        });
        (x, y)
    }

    #[test]
    fn separates_and_the_covariance_is_block_toeplitz_and_tapered() {
        let (n_ch, nt) = (3, 8);
        let (x, y) = data(200, n_ch, nt, 3);
        let m = ToeplitzLdaParams::default()
            .fit(x.view(), &y, n_ch)
            .unwrap();
        assert!((0.0..=1.0).contains(&m.shrinkage()));
        let d = m.decision_function(x.view()).unwrap();
        let auc = crate::metrics::roc_auc(&d.to_vec(), &y).unwrap();
        assert!(auc > 0.9, "training AUC {auc}");
        let c = m.covariance().unwrap();
        for a in 0..n_ch {
            for b in 0..n_ch {
                for dl in -(nt as isize - 1)..nt as isize {
                    let vals: Vec<f64> = (0..nt as isize)
                        .filter(|t| (0..nt as isize).contains(&(t + dl)))
                        .map(|t| c[[a * nt + t as usize, b * nt + (t + dl) as usize]])
                        .collect();
                    assert!(vals
                        .iter()
                        .all(|v| (v - vals[0]).abs() <= 1e-12 * vals[0].abs()));
                }
            }
        }
        assert!(c.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn errors_name_the_fault() {
        let (x, y) = data(40, 2, 5, 1);
        assert!(matches!(
            ToeplitzLdaParams::default().fit(x.view(), &y, 3),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        assert!(matches!(
            ToeplitzLdaParams::default().fit(x.view(), &y[..5], 2),
            Err(DecodeError::LabelCount { .. })
        ));
        assert!(matches!(
            ToeplitzLdaParams::default().fit(x.view(), &[false; 40], 2),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        let m = ToeplitzLdaParams::default().fit(x.view(), &y, 2).unwrap();
        assert!(matches!(
            m.decision_function(Array2::zeros((1, 3)).view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
    }
}
