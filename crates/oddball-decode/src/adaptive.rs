//! Online adaptation of a calibrated shrinkage LDA: after each decision the class means take in
//! the decision's epochs (labelled by the decision when the person does not correct it) through
//! incremental statistics, so the model follows slow drifts of the person's ERP without a refit.
//!
//! The covariance is the calibration's (shrunk, [`crate::classifiers::lda`]) and stays fixed: its inverse is
//! factorised once, and each epoch costs one product `Σ⁻¹x` (`p²`) and two running means:
//!
//! ```text
//! n_k ← n_k + 1,   μ_k ← μ_k + (x − μ_k)/n_k,   P_k ← P_k + (Σ⁻¹x − P_k)/n_k   (P_k = Σ⁻¹μ_k)
//! coef = P_t − P_n,   intercept = −½(μ_t·P_t − μ_n·P_n) + ln(π_t/π_n)
//! ```
//!
//! — exactly the LDA of the calibration's covariance and priors on the means of every epoch seen
//! (checked against that refit in the tests). A guard keeps a run of wrong decisions from
//! dragging the model away: an update that would turn the weights more than
//! [`AdaptiveLdaParams::min_cosine`] away from the calibrated weights is undone
//! ([`Update::Rejected`]). Written here: a few lines over [`crate::classifiers::lda`]; no crate adapts an LDA
//! this way.

use nalgebra::{DMatrix, DVector};
use ndarray::{Array1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::classifiers::lda::{Lda, LdaParams};
use crate::linalg::to_dmatrix;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of the adaptive LDA.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveLdaParams {
    /// The calibration's LDA.
    pub lda: LdaParams,
    /// Updates that leave the weights' cosine with the calibrated weights below this are undone.
    pub min_cosine: f64,
}

impl Default for AdaptiveLdaParams {
    fn default() -> Self {
        Self {
            lda: LdaParams::default(),
            min_cosine: 0.8,
        }
    }
}

/// What an update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Update {
    Accepted {
        cosine: f64,
    },
    /// Undone: the weights would have drifted to this cosine with the calibrated weights.
    Rejected {
        cosine: f64,
    },
}

/// A calibrated LDA whose class means follow the session; saved and restored whole (serde), so
/// a session's adapted model can be stored and picked up again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveLda {
    min_cosine: f64,
    /// `Σ⁻¹` of the calibration.
    precision: DMatrix<f64>,
    /// Per class (0 non-target, 1 target): count, mean, `Σ⁻¹·mean`.
    n: [f64; 2],
    mean: [DVector<f64>; 2],
    proj: [DVector<f64>; 2],
    log_prior_ratio: f64,
    calibrated: DVector<f64>,
    coef: DVector<f64>,
    intercept: f64,
}

impl AdaptiveLdaParams {
    /// Fits the LDA on calibration features `x` `(n_epochs, n_features)` with labels `y`.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<AdaptiveLda> {
        if !(-1.0..=1.0).contains(&self.min_cosine) {
            return Err(DecodeError::InvalidParameter {
                name: "min_cosine",
                value: self.min_cosine.to_string(),
                reason: "a cosine in [-1, 1]".into(),
            });
        }
        let lda = self.lda.fit(x, y)?;
        AdaptiveLda::from_lda(&lda, y, self.min_cosine)
    }
}

impl AdaptiveLda {
    /// Starts from a fitted LDA and the labels it was fitted on (for the class counts).
    pub fn from_lda(lda: &Lda, y: &[bool], min_cosine: f64) -> Result<Self> {
        let cov = to_dmatrix(lda.covariance());
        let chol = nalgebra::Cholesky::new(cov).ok_or(DecodeError::NotPositiveDefinite {
            what: "the LDA's covariance".into(),
        })?;
        let precision = chol.inverse();
        let n_t = y.iter().filter(|&&t| t).count() as f64;
        let n = [y.len() as f64 - n_t, n_t];
        let means = lda.means();
        let mean =
            [0, 1].map(|k| DVector::from_iterator(means.ncols(), means.row(k).iter().copied()));
        let proj = [0, 1].map(|k| &precision * &mean[k]);
        let [pn, pt] = lda.priors();
        let mut m = Self {
            min_cosine,
            precision,
            n,
            mean,
            proj,
            log_prior_ratio: (pt / pn).ln(),
            calibrated: DVector::zeros(0),
            coef: DVector::zeros(0),
            intercept: 0.0,
        };
        m.refresh();
        m.calibrated = m.coef.clone();
        Ok(m)
    }

    fn refresh(&mut self) {
        self.coef = &self.proj[1] - &self.proj[0];
        self.intercept = -0.5 * (self.mean[1].dot(&self.proj[1]) - self.mean[0].dot(&self.proj[0]))
            + self.log_prior_ratio;
    }

    /// Takes in labelled rows `x` `(n, n_features)`; undone when the guard rejects it.
    pub fn update(&mut self, x: ArrayView2<f64>, y: &[bool]) -> Result<Update> {
        if x.nrows() != y.len() {
            return Err(DecodeError::LabelCount {
                n_samples: x.nrows(),
                n_labels: y.len(),
            });
        }
        if x.ncols() != self.coef.len() {
            return Err(DecodeError::ShapeMismatch {
                what: "adaptive LDA update".into(),
                expected: format!("{} features", self.coef.len()),
                got: x.ncols().to_string(),
            });
        }
        crate::linalg::check_finite("adaptive LDA update", x.iter())?;
        let before = (self.n, self.mean.clone(), self.proj.clone());
        let mut xv = DVector::zeros(x.ncols());
        for (row, &t) in x.rows().into_iter().zip(y) {
            let k = usize::from(t);
            for (d, s) in xv.iter_mut().zip(row.iter()) {
                *d = *s;
            }
            let v = &self.precision * &xv;
            self.n[k] += 1.0;
            let inv = 1.0 / self.n[k];
            self.mean[k].axpy(inv, &xv, 1.0 - inv);
            self.proj[k].axpy(inv, &v, 1.0 - inv);
        }
        self.refresh();
        let cosine = self.cosine();
        if cosine < self.min_cosine {
            (self.n, self.mean, self.proj) = before;
            self.refresh();
            return Ok(Update::Rejected { cosine });
        }
        Ok(Update::Accepted { cosine })
    }

    /// Log-odds of target per row of `x` `(n, n_features)`.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        let coef = Array1::from_iter(self.coef.iter().copied());
        crate::classifiers::lda::linear_decision(
            "adaptive LDA input",
            x,
            coef.view(),
            self.intercept,
        )
    }

    /// P(target) per row of `x` (the log-odds' logistic).
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Ok(self.decision_function(x)?.mapv(crate::linalg::sigmoid))
    }

    /// Epochs per class taken in so far (calibration included): `[non-target, target]`.
    pub fn counts(&self) -> [f64; 2] {
        self.n
    }

    /// The current weights (`Σ⁻¹(μ_t − μ_n)`).
    pub fn coef(&self) -> Array1<f64> {
        Array1::from_iter(self.coef.iter().copied())
    }

    /// The current intercept.
    pub fn intercept(&self) -> f64 {
        self.intercept
    }

    /// The current class means `(2, n_features)`: non-target, target.
    pub fn means(&self) -> ndarray::Array2<f64> {
        let p = self.coef.len();
        ndarray::Array2::from_shape_fn((2, p), |(k, j)| self.mean[k][j])
    }

    /// The weights' cosine with the calibrated weights (1 before any update).
    pub fn cosine(&self) -> f64 {
        self.coef.dot(&self.calibrated)
            / (self.coef.norm() * self.calibrated.norm()).max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    fn data(n: usize, seed: u64) -> (Array2<f64>, Vec<bool>) {
        let mut s = seed;
        let mut u = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let y: Vec<bool> = (0..n).map(|i| i % 4 == 1).collect();
        let x = Array2::from_shape_fn((n, 6), |(i, j)| {
            u() + if y[i] { 0.3 * j as f64 } else { 0.0 }
        });
        (x, y)
    }

    #[test]
    fn an_update_is_the_lda_of_all_epochs_with_the_calibration_covariance() {
        let (x1, y1) = data(80, 1);
        let (x2, y2) = data(40, 2);
        let params = AdaptiveLdaParams {
            min_cosine: -1.0,
            ..Default::default()
        };
        let mut m = params.fit(x1.view(), &y1).unwrap();
        let lda = params.lda.fit(x1.view(), &y1).unwrap();
        // Before any update: the calibration's LDA.
        let (a, b) = (
            m.decision_function(x2.view()).unwrap(),
            lda.decision_function(x2.view()).unwrap(),
        );
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "{a} vs {b}");
        }
        assert!(matches!(
            m.update(x2.view(), &y2).unwrap(),
            Update::Accepted { .. }
        ));
        // Naive: class means of all 120 epochs, Σ of the calibration, dense inverse.
        let sigma = to_dmatrix(lda.covariance()).try_inverse().unwrap();
        let mean = |k: bool| {
            let rows: Vec<usize> = (0..120)
                .filter(|&i| (if i < 80 { y1[i] } else { y2[i - 80] }) == k)
                .collect();
            DVector::from_fn(6, |j, _| {
                rows.iter()
                    .map(|&i| if i < 80 { x1[[i, j]] } else { x2[[i - 80, j]] })
                    .sum::<f64>()
                    / rows.len() as f64
            })
        };
        let (mt, mn) = (mean(true), mean(false));
        let w = &sigma * (&mt - &mn);
        let [pn, pt] = lda.priors();
        let b = -0.5 * (mt.dot(&(&sigma * &mt)) - mn.dot(&(&sigma * &mn))) + (pt / pn).ln();
        let got = m.decision_function(x2.view()).unwrap();
        for i in 0..40 {
            let want = w.iter().zip(x2.row(i)).map(|(a, b)| a * b).sum::<f64>() + b;
            assert!(
                (got[i] - want).abs() < 1e-9 * (1.0 + want.abs()),
                "{} vs {want}",
                got[i]
            );
        }
        assert_eq!(m.counts(), [90.0, 30.0]);
    }

    #[test]
    fn a_saved_model_adapts_on_as_the_original() {
        let (x1, y1) = data(80, 1);
        let (x2, y2) = data(40, 2);
        let mut m = AdaptiveLdaParams::default().fit(x1.view(), &y1).unwrap();
        m.update(x2.slice(ndarray::s![..20, ..]), &y2[..20])
            .unwrap();
        let mut back: AdaptiveLda =
            serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
        let rest = (x2.slice(ndarray::s![20.., ..]), &y2[20..]);
        assert_eq!(
            back.update(rest.0, rest.1).unwrap(),
            m.update(rest.0, rest.1).unwrap()
        );
        assert_eq!(
            back.decision_function(x1.view()).unwrap(),
            m.decision_function(x1.view()).unwrap()
        );
    }

    #[test]
    fn the_guard_undoes_an_update_that_turns_the_weights_away() {
        let (x1, y1) = data(80, 1);
        let mut m = AdaptiveLdaParams::default().fit(x1.view(), &y1).unwrap();
        let before = m.decision_function(x1.view()).unwrap();
        // Every label flipped, many times over: the means would swap.
        let (x2, y2) = data(400, 3);
        let flipped: Vec<bool> = y2.iter().map(|t| !t).collect();
        let r = m.update(x2.view(), &flipped).unwrap();
        assert!(
            matches!(r, Update::Rejected { cosine } if cosine < 0.8),
            "{r:?}"
        );
        assert_eq!(m.decision_function(x1.view()).unwrap(), before);
        assert_eq!(m.counts(), [60.0, 20.0]);
        assert!(m.update(x2.view(), &flipped[..3]).is_err());
    }
}
