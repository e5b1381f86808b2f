//! Binary support vector machines (linear or RBF kernel) with decision values and Platt-calibrated
//! probabilities, as scikit-learn's `SVC(kernel=..., C=..., gamma='scale')` wrapped in
//! `CalibratedClassifierCV(method='sigmoid', ensemble=False)`.
//!
//! * **Solver**: `linfa-svm` 0.8 (a port of libsvm's SMO with second-order working-set selection),
//!   stopping tolerance `tol` = libsvm's `eps` (scikit-learn's default 1e-3). Its shrinking heuristic
//!   is left off: in linfa-svm 0.8.1 it can index out of bounds and panic (it did on this crate's
//!   golden data set). Without shrinking the solution is the same optimum, reached in more steps.
//! * **Kernel**: RBF `exp(−γ‖x − x'‖²)` (linfa's Gaussian kernel with `eps = 1/γ`) with
//!   `γ = 'scale' = 1 / (n_features · Var(X))` (population variance of all training values; 1 when
//!   that is 0), `'auto' = 1 / n_features`, or a fixed value; or the linear kernel `x·x'`.
//! * **Decision value**: `Σ αᵢ yᵢ K(xᵢ, x) − ρ`, positive for targets, as scikit-learn's
//!   `decision_function` for classes `[False, True]`. Both solve the dual only to `tol`, so values
//!   agree with scikit-learn's to about that tolerance, not to round-off.
//! * **Probability**: Platt's sigmoid `P(target) = 1 / (1 + exp(a·f + b))` fitted by
//!   [`PlattSigmoid::fit`] with scikit-learn's `_sigmoid_calibration` semantics (targets
//!   `(N₊+1)/(N₊+2)` and `1/(N₋+2)`, decision values rescaled when |f| ≥ 30), solved by Newton's method
//!   to convergence. [`Calibration::CrossValidated`] fits it on out-of-fold decision values from
//!   `n_folds` folds made exactly as scikit-learn's `StratifiedKFold(n_folds)`, unshuffled
//!   ([`stratified_folds`](crate::model_selection::folds::stratified_folds)) or shuffled with
//!   `random_state=seed` ([`stratified_folds_shuffled`](crate::model_selection::folds::stratified_folds_shuffled),
//!   numpy's MT19937 stream reproduced), then refits the SVM on all data —
//!   `CalibratedClassifierCV(sigmoid, cv=StratifiedKFold(k, …), ensemble=False)`, the peer's
//!   twin with its seed 0 by default. (libsvm's own
//!   `probability=True` also uses internal CV but with its own RNG, and scikit-learn 1.9 deprecates
//!   it.) [`Calibration::TrainingSet`] fits the sigmoid on the training decision values (cheaper,
//!   overconfident); [`Calibration::None`] skips it and `predict_proba` is an error.

use linfa::prelude::*;
use ndarray::{Array1, Array2, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use crate::features::scaler::{check_finite, check_n_features};
use crate::linalg::check_labels;
use crate::model_selection::folds::stratified;
use crate::traits::{FeatureView, FitClassifier, ProbabilisticClassifier};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// RBF kernel width.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Gamma {
    /// `1 / (n_features · Var(X))` (scikit-learn's default).
    Scale,
    /// `1 / n_features`.
    Auto,
    /// A fixed γ > 0.
    Value(f64),
}

/// The most training epochs an SVM fits: linfa-svm's solver keeps the dense kernel matrix,
/// `8 n²` bytes (0.8 GB here; 27,000 epochs would need 5.8 GB and hours of SMO).
pub const MAX_KERNEL_EPOCHS: usize = 10_000;

/// Kernel of the SVM.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Kernel {
    /// `x · x'`.
    Linear,
    /// `exp(−γ ‖x − x'‖²)`.
    Rbf(Gamma),
}

/// How probabilities are calibrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Calibration {
    /// No sigmoid; `predict_proba` is an error.
    None,
    /// Sigmoid fitted on the training set's own decision values.
    TrainingSet,
    /// Sigmoid fitted on out-of-fold decision values of stratified folds: in blocks, or shuffled
    /// as scikit-learn's `StratifiedKFold(n_folds, shuffle=True, random_state=seed)` shuffles them
    /// ([`crate::model_selection::folds::stratified_folds_shuffled`]).
    CrossValidated {
        n_folds: usize,
        /// Absent in models saved before it existed: unshuffled folds.
        #[serde(default)]
        shuffle_seed: Option<u32>,
    },
}

/// Unfitted SVM settings. [`Default`] is the paper's `SVC(kernel='rbf', C=1, gamma='scale')` with
/// 5-fold sigmoid calibration on folds shuffled as the peer's `StratifiedKFold(5, shuffle=True,
/// random_state=0)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SvmParams {
    /// Penalty `C` > 0.
    pub c: f64,
    /// Kernel.
    pub kernel: Kernel,
    /// Stopping tolerance of the dual solver (libsvm `eps`; scikit-learn `tol`).
    pub tol: f64,
    /// Probability calibration.
    pub calibration: Calibration,
}

impl Default for SvmParams {
    fn default() -> Self {
        Self {
            c: 1.0,
            kernel: Kernel::Rbf(Gamma::Scale),
            tol: 1e-3,
            calibration: Calibration::CrossValidated {
                n_folds: 5,
                shuffle_seed: Some(0),
            },
        }
    }
}

/// Platt's sigmoid `P(target | f) = 1 / (1 + exp(a·f + b))` on decision values `f`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlattSigmoid {
    /// Slope (negative when larger f means target).
    pub a: f64,
    /// Offset.
    pub b: f64,
}

impl PlattSigmoid {
    /// Fits the sigmoid to decision values and labels, as scikit-learn's `_sigmoid_calibration`
    /// (Platt's prior-corrected targets; values rescaled by max |f| when that is ≥ 30), minimised by
    /// Newton's method with a backtracking line search (Lin, Lin & Weng 2007).
    pub fn fit(f: &[f64], y: &[bool]) -> Result<Self> {
        let (n_pos, n_neg) = check_labels(f.len(), y)?;
        if f.iter().any(|v| !v.is_finite()) {
            return Err(DecodeError::NonFinite {
                what: "decision values for Platt scaling".into(),
            });
        }
        let max_abs = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let scale = if max_abs >= 30.0 { max_abs } else { 1.0 };
        let (p1, p0) = (n_pos as f64, n_neg as f64);
        let hi = (p1 + 1.0) / (p1 + 2.0);
        let lo = 1.0 / (p0 + 2.0);
        let pts: Vec<(f64, f64)> = f
            .iter()
            .zip(y)
            .map(|(&v, &t)| (v / scale, if t { hi } else { lo }))
            .collect();
        // loss(z) = log(1 + e^z) − (1 − t) z with z = a·f + b (the negative log-likelihood)
        let loss = |a: f64, b: f64| -> f64 {
            pts.iter()
                .map(|&(fi, t)| {
                    let z = a * fi + b;
                    let log1pexp = if z > 0.0 {
                        z + (-z).exp().ln_1p()
                    } else {
                        z.exp().ln_1p()
                    };
                    log1pexp - (1.0 - t) * z
                })
                .sum()
        };
        let (mut a, mut b) = (0.0, ((p0 + 1.0) / (p1 + 1.0)).ln());
        let mut fval = loss(a, b);
        let n = pts.len() as f64;
        for _ in 0..200 {
            let (mut h11, mut h22, mut h21, mut g1, mut g2) = (1e-12, 1e-12, 0.0, 0.0, 0.0);
            for &(fi, t) in &pts {
                let z = a * fi + b;
                // p = P(target) = 1 / (1 + e^z), q = 1 − p
                let (p, q) = if z >= 0.0 {
                    let e = (-z).exp();
                    (e / (1.0 + e), 1.0 / (1.0 + e))
                } else {
                    let e = z.exp();
                    (1.0 / (1.0 + e), e / (1.0 + e))
                };
                let d2 = p * q;
                h11 += fi * fi * d2;
                h22 += d2;
                h21 += fi * d2;
                let d1 = t - p;
                g1 += fi * d1;
                g2 += d1;
            }
            if g1.abs().max(g2.abs()) < 1e-13 * n.max(1.0) {
                break;
            }
            let det = h11 * h22 - h21 * h21;
            let da = -(h22 * g1 - h21 * g2) / det;
            let db = -(-h21 * g1 + h11 * g2) / det;
            let gd = g1 * da + g2 * db;
            let mut step = 1.0;
            let mut moved = false;
            while step >= 1e-10 {
                let (na, nb) = (a + step * da, b + step * db);
                let nf = loss(na, nb);
                if nf < fval + 1e-4 * step * gd {
                    moved = na != a || nb != b;
                    a = na;
                    b = nb;
                    fval = nf;
                    break;
                }
                step /= 2.0;
            }
            if !moved {
                break;
            }
        }
        Ok(Self { a: a / scale, b })
    }

    /// P(target) for one decision value.
    pub fn probability(&self, f: f64) -> f64 {
        let z = self.a * f + self.b;
        if z >= 0.0 {
            let e = (-z).exp();
            e / (1.0 + e)
        } else {
            1.0 / (1.0 + z.exp())
        }
    }
}

/// A fitted SVM: its support vectors and dual coefficients (the linfa model is not kept, so saved
/// models don't depend on linfa's serde format), or the weight vector for the linear kernel.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Svm {
    kernel: Kernel,
    n_features: usize,
    dual: Dual,
    platt: Option<PlattSigmoid>,
}

/// The dual solution as support vectors, coefficients and intercept.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Dual {
    /// Support vectors `(n_support, n_features)`.
    support_vectors: Array2<f64>,
    /// `yᵢ αᵢ` per support vector.
    dual_coef: Array1<f64>,
    /// `Σ yᵢ αᵢ xᵢ` for the linear kernel.
    weights: Option<Array1<f64>>,
    /// −ρ.
    intercept: f64,
    /// γ of the RBF kernel.
    gamma: Option<f64>,
    /// `‖svᵢ‖²` per support vector, computed on first use (not saved).
    #[serde(skip)]
    sv_sq: std::sync::OnceLock<Array1<f64>>,
}

fn fit_dual(p: &SvmParams, x: ArrayView2<f64>, y: &[bool]) -> Result<Dual> {
    let n_features = x.ncols();
    let ds = linfa::Dataset::new(x.to_owned(), Array1::from(y.to_vec()));
    let base = linfa_svm::Svm::<f64, bool>::params()
        .pos_neg_weights(p.c, p.c)
        .eps(p.tol)
        .shrinking(false);
    let (params, gamma) = match p.kernel {
        Kernel::Linear => (base.linear_kernel(), None),
        Kernel::Rbf(g) => {
            let gamma = match g {
                Gamma::Value(v) => v,
                Gamma::Auto => 1.0 / n_features as f64,
                Gamma::Scale => {
                    let n = x.len() as f64;
                    let mean = x.sum() / n;
                    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
                    if var > 0.0 {
                        1.0 / (n_features as f64 * var)
                    } else {
                        1.0
                    }
                }
            };
            (base.gaussian_kernel(1.0 / gamma), Some(gamma))
        }
    };
    let model: linfa_svm::Svm<f64, bool> = params
        .fit(&ds)
        .map_err(|e| DecodeError::Linfa(e.to_string()))?;
    // linfa's `alpha` is yᵢαᵢ in training order; it counts |yᵢαᵢ| > 100ε as support (`nsupport`)
    let keep: Vec<usize> = (0..x.nrows())
        .filter(|&i| model.alpha[i].abs() > 100.0 * f64::EPSILON)
        .collect();
    let support_vectors = x.select(Axis(0), &keep);
    let dual_coef: Array1<f64> = keep.iter().map(|&i| model.alpha[i]).collect();
    let weights = match p.kernel {
        Kernel::Linear => Some(support_vectors.t().dot(&dual_coef)),
        Kernel::Rbf(_) => None,
    };
    Ok(Dual {
        support_vectors,
        dual_coef,
        weights,
        intercept: -model.rho,
        gamma,
        sv_sq: Default::default(),
    })
}

/// Decision values `Σ yᵢαᵢ K(svᵢ, x) + intercept` of the rows of `x`. For the RBF kernel the squared
/// distances come from `‖x‖² + ‖sv‖² − 2 x·sv` through one matrix product (as libsvm's and
/// scikit-learn's kernels do), in blocks of rows.
fn decision_values(d: &Dual, x: ArrayView2<f64>) -> Array1<f64> {
    if let Some(w) = &d.weights {
        return x.dot(w) + d.intercept;
    }
    let sv = &d.support_vectors;
    let sv_sq = d
        .sv_sq
        .get_or_init(|| crate::linalg::row_sq_norms(sv.view()));
    let mut out = Array1::zeros(x.nrows());
    const BLOCK: usize = 256;
    for (xb, mut ob) in x
        .axis_chunks_iter(Axis(0), BLOCK)
        .zip(out.axis_chunks_iter_mut(Axis(0), BLOCK))
    {
        let d2 = crate::linalg::sq_distances(xb, sv.view(), sv_sq); // (block, n_sv)
        ob.assign(&rbf_decision(d, d2));
    }
    out
}

/// `Σ yᵢαᵢ exp(−γ d²ᵢ) + intercept` per row of the squared distances `d2` `(n, n_sv)` to the
/// support vectors.
fn rbf_decision(d: &Dual, mut d2: Array2<f64>) -> Array1<f64> {
    let gamma = d.gamma.unwrap_or(1.0);
    d2.mapv_inplace(|v| (-gamma * v).exp());
    d2.dot(&d.dual_coef) + d.intercept
}

impl SvmParams {
    fn validate(&self) -> Result<()> {
        let bad = |name, v: f64, reason: &str| DecodeError::InvalidParameter {
            name,
            value: v.to_string(),
            reason: reason.into(),
        };
        if !(self.c.is_finite() && self.c > 0.0) {
            return Err(bad("c", self.c, "must be finite and > 0"));
        }
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(bad("tol", self.tol, "must be finite and > 0"));
        }
        if let Kernel::Rbf(Gamma::Value(g)) = self.kernel {
            if !(g.is_finite() && g > 0.0) {
                return Err(bad("gamma", g, "must be finite and > 0"));
            }
        }
        Ok(())
    }

    /// Trains on `x` `(n_samples, n_features)` with labels `y` (both classes needed), then calibrates.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<Svm> {
        self.validate()?;
        check_labels(x.nrows(), y)?;
        if x.nrows() > MAX_KERNEL_EPOCHS {
            return Err(DecodeError::TooManySamples {
                what: "the SVM",
                n: x.nrows(),
                max: MAX_KERNEL_EPOCHS,
                reason: format!(
                    "its solver holds the n × n kernel matrix: {:.1} GB at {MAX_KERNEL_EPOCHS}",
                    (MAX_KERNEL_EPOCHS * MAX_KERNEL_EPOCHS * 8) as f64 / 1e9
                ),
            });
        }
        check_finite(x, "SVM training features")?;
        if x.ncols() == 0 {
            return Err(DecodeError::TooFewSamples {
                what: "SVM needs at least one feature".into(),
            });
        }
        let cv_platt = match self.calibration {
            Calibration::None | Calibration::TrainingSet => None,
            Calibration::CrossValidated {
                n_folds,
                shuffle_seed,
            } => {
                let folds = stratified(y, n_folds, shuffle_seed)?;
                let mut oof = vec![0.0; y.len()];
                for f in 0..n_folds {
                    let train: Vec<usize> = (0..y.len()).filter(|&i| folds[i] != f).collect();
                    let test: Vec<usize> = (0..y.len()).filter(|&i| folds[i] == f).collect();
                    let xtr = x.select(Axis(0), &train);
                    let ytr: Vec<bool> = train.iter().map(|&i| y[i]).collect();
                    let m = fit_dual(self, xtr.view(), &ytr)?;
                    let d = decision_values(&m, x.select(Axis(0), &test).view());
                    for (&i, v) in test.iter().zip(d) {
                        oof[i] = v;
                    }
                }
                Some(PlattSigmoid::fit(&oof, y)?)
            }
        };
        let dual = fit_dual(self, x, y)?;
        let platt = match self.calibration {
            Calibration::TrainingSet => {
                let d = decision_values(&dual, x);
                Some(PlattSigmoid::fit(&d.to_vec(), y)?)
            }
            _ => cv_platt,
        };
        Ok(Svm {
            kernel: self.kernel,
            n_features: x.ncols(),
            dual,
            platt,
        })
    }
}

impl Svm {
    /// Features expected.
    pub fn n_features(&self) -> usize {
        self.n_features
    }

    /// The kernel's γ as resolved on the training data (`None` for the linear kernel).
    pub fn gamma(&self) -> Option<f64> {
        self.dual.gamma
    }

    /// The kernel.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Number of support vectors (non-zero dual coefficients).
    pub fn n_support(&self) -> usize {
        self.dual.dual_coef.len()
    }

    /// The support vectors `(n_support, n_features)`.
    pub fn support_vectors(&self) -> ArrayView2<'_, f64> {
        self.dual.support_vectors.view()
    }

    /// `yᵢαᵢ` of each support vector (scikit-learn's `dual_coef_`).
    pub fn dual_coef(&self) -> &Array1<f64> {
        &self.dual.dual_coef
    }

    /// Offset of the decision function (scikit-learn's `intercept_` = −ρ).
    pub fn intercept(&self) -> f64 {
        self.dual.intercept
    }

    /// The fitted sigmoid, if calibrated.
    pub fn platt(&self) -> Option<PlattSigmoid> {
        self.platt
    }

    /// Signed distance-like score per row, positive for targets.
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        check_n_features("SVM input", self.n_features, x.ncols())?;
        check_finite(x, "SVM input")?;
        Ok(decision_values(&self.dual, x))
    }

    /// P(target) per row from the Platt sigmoid.
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        let platt = self.calibration()?;
        Ok(self.decision_function(x)?.mapv(|f| platt.probability(f)))
    }

    /// The Platt sigmoid, or the error of an SVM fitted without one.
    fn calibration(&self) -> Result<PlattSigmoid> {
        self.platt.ok_or_else(|| DecodeError::InvalidParameter {
            name: "calibration",
            value: "None".into(),
            reason: "this SVM was fitted without probability calibration".into(),
        })
    }

    /// The support vectors of an RBF SVM, which [`crate::classifiers::ensemble::SoftVote`] may measure queries
    /// against once for several members (`None` for the linear kernel).
    pub fn rbf_support_vectors(&self) -> Option<ArrayView2<'_, f64>> {
        self.dual
            .weights
            .is_none()
            .then(|| self.dual.support_vectors.view())
    }

    /// [`Self::predict_proba`] of an RBF SVM from squared distances `(n_queries, n_support)` to its
    /// support vectors.
    pub fn predict_proba_from_sq_distances(&self, d2: Array2<f64>) -> Result<Array1<f64>> {
        let platt = self.calibration()?;
        if self.rbf_support_vectors().is_none() {
            return Err(DecodeError::InvalidParameter {
                name: "kernel",
                value: "linear".into(),
                reason: "a linear SVM scores inner products, not distances".into(),
            });
        }
        check_n_features("SVM distances", self.n_support(), d2.ncols())?;
        Ok(rbf_decision(&self.dual, d2).mapv(|f| platt.probability(f)))
    }

    /// Target where the decision value is positive.
    pub fn predict(&self, x: ArrayView2<f64>) -> Result<Vec<bool>> {
        Ok(self
            .decision_function(x)?
            .iter()
            .map(|&f| f > 0.0)
            .collect())
    }
}

impl ProbabilisticClassifier for Svm {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Svm::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Svm::decision_function(self, x)
    }
    fn distance_rows(&self) -> Option<ArrayView2<'_, f64>> {
        self.rbf_support_vectors()
    }
    fn predict_proba_from_sq_distances(&self, d2: Array2<f64>) -> Result<Array1<f64>> {
        Svm::predict_proba_from_sq_distances(self, d2)
    }
}

impl FitClassifier for SvmParams {
    type Fitted = Svm;
    fn fit_classifier(&self, x: FeatureView<'_>, y: &[bool], _: usize) -> Result<Svm> {
        self.fit(x.rows("SVM")?, y)
    }
    fn with_scale_gamma(&self, gamma: f64) -> Self {
        SvmParams {
            kernel: match self.kernel {
                Kernel::Rbf(Gamma::Scale) => Kernel::Rbf(Gamma::Value(gamma)),
                k => k,
            },
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    fn blobs() -> (Array2<f64>, Vec<bool>) {
        let mut x = Array2::zeros((40, 2));
        let mut y = Vec::new();
        for i in 0..40 {
            let t = i % 2 == 0;
            let a = i as f64 * 0.7;
            let c = if t { 1.5 } else { -1.5 };
            x[[i, 0]] = c + a.sin();
            x[[i, 1]] = c + (1.3 * a).cos();
            y.push(t);
        }
        (x, y)
    }

    #[test]
    fn separates_blobs_and_calibrates() {
        let (x, y) = blobs();
        for kernel in [Kernel::Linear, Kernel::Rbf(Gamma::Scale)] {
            let m = SvmParams {
                kernel,
                ..SvmParams::default()
            }
            .fit(x.view(), &y)
            .unwrap();
            assert_eq!(m.predict(x.view()).unwrap(), y);
            let p = m
                .predict_proba(array![[2.0, 2.0], [-2.0, -2.0]].view())
                .unwrap();
            assert!(p[0] > 0.8 && p[1] < 0.2, "{p}");
            assert!(m.n_support() >= 2);
        }
    }

    #[test]
    fn platt_recovers_a_known_sigmoid() {
        // labels drawn deterministically from P = 1/(1+exp(-2f + 0.5)) on a fine grid
        let mut f = Vec::new();
        let mut y = Vec::new();
        for i in 0..2000 {
            let v = -3.0 + 6.0 * (i as f64 + 0.5) / 2000.0;
            let p = 1.0 / (1.0 + (-2.0 * v + 0.5f64).exp());
            // low-discrepancy thresholding keeps the empirical rate close to p
            let u = ((i as f64) * 0.618_033_988_749_895).fract();
            f.push(v);
            y.push(u < p);
        }
        let s = PlattSigmoid::fit(&f, &y).unwrap();
        assert!(
            (s.a + 2.0).abs() < 0.15 && (s.b - 0.5).abs() < 0.15,
            "{s:?}"
        );
        assert!(s.probability(10.0) > 0.99 && s.probability(-10.0) < 0.01);
    }

    #[test]
    fn rejects_bad_settings_and_uncalibrated_proba() {
        let (x, y) = blobs();
        let bad = SvmParams {
            c: 0.0,
            ..SvmParams::default()
        };
        assert!(bad.fit(x.view(), &y).is_err());
        let m = SvmParams {
            calibration: Calibration::None,
            ..SvmParams::default()
        }
        .fit(x.view(), &y)
        .unwrap();
        assert!(m.predict_proba(x.view()).is_err());
        assert!(m.decision_function(array![[1.0]].view()).is_err());
        assert!(SvmParams::default().fit(x.view(), &y[..10]).is_err());
    }
}

#[cfg(test)]
mod size_tests {
    use super::*;

    #[test]
    fn more_epochs_than_a_dense_kernel_holds_are_refused_before_any_work() {
        let n = MAX_KERNEL_EPOCHS + 1;
        let x = Array2::<f64>::zeros((n, 1));
        let y: Vec<bool> = (0..n).map(|i| i % 2 == 0).collect();
        match SvmParams::default().fit(x.view(), &y) {
            Err(DecodeError::TooManySamples { n: got, max, .. }) => {
                assert_eq!((got, max), (n, MAX_KERNEL_EPOCHS))
            }
            other => panic!("{other:?}"),
        }
    }
}
