//! Pipelines: transformers chained into a classifier, fit on epochs and labels, as a
//! scikit-learn `Pipeline`; named presets; and the saved [`Model`] with its pre-processing and
//! channel layout.
//!
//! A pipeline is `[channel selection] → features → [StandardScaler] → [PCA] → classifier`, where
//! the features are either a per-epoch map with nothing to learn (amplitudes; the paper's
//! amplitude + Hilbert–Huang + wavelet map) or learned xDAWN covariances, projected to the
//! Riemannian tangent space or kept as matrices (flattened row-major, for MDM). Every learned step
//! is fitted on the training epochs only. A fitted [`Pipeline`] keeps the [`PipelineParams`] it
//! was fitted with, so a saved model carries its settings (e.g. those chosen by
//! [`crate::tuning`]).

use ndarray::parallel::prelude::*;
use ndarray::{s, Array1, Array2, Array3, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::amplitude::{AmplitudeFeatures, PaperFeatures};
use crate::channel_select::{ChannelCount, ChannelSelection, ChannelSelectionParams};
use crate::ensemble::{MemberParams, ProbabilisticClassifier, SoftVote, SoftVoteParams};
use crate::knn::{Knn, KnnParams};
use crate::lda::{Lda, LdaParams};
use crate::logistic::{Logistic, LogisticParams};
use crate::pca::{Pca, PcaParams};
use crate::riemann::{Mdm, MdmParams, TangentSpace, TangentSpaceParams};
use crate::scaler::{StandardScaler, StandardScalerParams};
use crate::svm::{Calibration, Gamma, Kernel, Svm, SvmParams};
use crate::toeplitz_lda::{ToeplitzLda, ToeplitzLdaParams};
use crate::xdawn::{XdawnCovariances, XdawnCovariancesParams};
pub use crate::preprocess::{Preprocess, FLAT_UV};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

impl ProbabilisticClassifier for Lda {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Lda::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Lda::decision_function(self, x)
    }
}

/// MDM on xDAWN covariance matrices flattened row-major into rows of `(n_epochs, n·n)` (the
/// output of [`FeatureParams::XdawnCovariances`]); the score is
/// `d²(C, M_non-target) − d²(C, M_target)` (larger = closer to the target mean).
impl ProbabilisticClassifier for Mdm {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Ok(ProbabilisticClassifier::decision_function(self, x)?.mapv(crate::linalg::sigmoid))
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        let n = self.n_channels();
        if x.ncols() != n * n {
            return Err(DecodeError::ShapeMismatch {
                what: "MDM input (flattened matrices)".into(),
                expected: format!("{} columns ({n}×{n} matrices)", n * n),
                got: x.ncols().to_string(),
            });
        }
        // Matrices are independent: spread them over rayon's threads.
        let scores = x
            .axis_iter(Axis(0))
            .into_par_iter()
            .map(|row| {
                let m = row
                    .to_shape((n, n))
                    .map_err(|e| DecodeError::ShapeMismatch {
                        what: "MDM input row".into(),
                        expected: format!("{n}×{n}"),
                        got: e.to_string(),
                    })?;
                self.decision_one(m.view())
            })
            .collect::<Result<Vec<f64>>>()?;
        Ok(Array1::from(scores))
    }
}

/// Flattened `(n_epochs, n·n)` rows back to matrices `(n_epochs, n, n)`.
fn unflatten_square(x: ArrayView2<f64>) -> Result<Array3<f64>> {
    let (rows, cols) = x.dim();
    let n = (cols as f64).sqrt().round() as usize;
    if n == 0 || n * n != cols {
        return Err(DecodeError::ShapeMismatch {
            what: "MDM training input (flattened matrices)".into(),
            expected: "n·n columns for some n ≥ 1".into(),
            got: cols.to_string(),
        });
    }
    Ok(Array3::from_shape_fn((rows, n, n), |(e, i, j)| {
        x[[e, i * n + j]]
    }))
}

impl ProbabilisticClassifier for ToeplitzLda {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        ToeplitzLda::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        ToeplitzLda::decision_function(self, x)
    }
}

impl ProbabilisticClassifier for Logistic {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Logistic::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Logistic::decision_function(self, x)
    }
}

/// How an epoch becomes a feature vector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FeatureParams {
    /// Bin-averaged or decimated samples, flattened channel-major.
    Amplitude(AmplitudeFeatures),
    /// The paper's map: amplitudes + Hilbert–Huang (first IMF's instantaneous amplitude and
    /// frequency) + bior2.2 wavelet approximation and detail.
    Paper(PaperFeatures),
    /// Every `step`-th sample, then xDAWN covariances, then the Riemannian tangent space.
    XdawnTangent {
        step: usize,
        xdawn: XdawnCovariancesParams,
        tangent: TangentSpaceParams,
    },
    /// Every `step`-th sample, then xDAWN covariances `(n, n)` flattened row-major (`n·n`
    /// features) — the input of [`ClassifierParams::Mdm`].
    XdawnCovariances {
        step: usize,
        xdawn: XdawnCovariancesParams,
    },
}

/// Fitted features.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Features {
    Amplitude(AmplitudeFeatures),
    Paper(PaperFeatures),
    XdawnTangent(Box<XdawnTangent>),
    XdawnCovariances(Box<XdawnCovFeatures>),
}

/// Fitted xDAWN covariances on epochs decimated by `step`, flattened row-major.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct XdawnCovFeatures {
    pub step: usize,
    pub xdawn: XdawnCovariances,
}

/// Fitted xDAWN covariances and tangent space, on epochs decimated by `step`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct XdawnTangent {
    pub step: usize,
    pub xdawn: XdawnCovariances,
    pub tangent: TangentSpace,
}

/// Every `step`-th sample of each epoch, as a view (no copy).
fn every_nth(epochs: ArrayView3<'_, f64>, step: usize) -> ArrayView3<'_, f64> {
    epochs.slice_move(s![.., .., ..;step])
}

fn check_step(step: usize) -> Result<()> {
    if step == 0 {
        return Err(DecodeError::InvalidParameter {
            name: "step",
            value: "0".into(),
            reason: "the decimation step must be at least 1".into(),
        });
    }
    Ok(())
}

impl FeatureParams {
    /// Whether the map learns nothing from the training data (so features of any epoch can be
    /// computed once, whatever the training split).
    pub fn is_stateless(&self) -> bool {
        matches!(self, FeatureParams::Amplitude(_) | FeatureParams::Paper(_))
    }

    fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Features> {
        Ok(match self {
            FeatureParams::Amplitude(a) => Features::Amplitude(*a),
            FeatureParams::Paper(p) => Features::Paper(*p),
            FeatureParams::XdawnCovariances { step, xdawn } => {
                check_step(*step)?;
                let x = every_nth(epochs, *step);
                Features::XdawnCovariances(Box::new(XdawnCovFeatures {
                    step: *step,
                    xdawn: xdawn.fit(x.view(), y)?,
                }))
            }
            FeatureParams::XdawnTangent {
                step,
                xdawn,
                tangent,
            } => {
                check_step(*step)?;
                let x = every_nth(epochs, *step);
                let xdawn = xdawn.fit(x.view(), y)?;
                let covs = xdawn.transform(x.view())?;
                let tangent = tangent.fit(covs.view())?;
                Features::XdawnTangent(Box::new(XdawnTangent {
                    step: *step,
                    xdawn,
                    tangent,
                }))
            }
        })
    }
}

impl Features {
    /// `(n_epochs, n_features)`.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        match self {
            Features::Amplitude(a) => a.transform(epochs),
            Features::Paper(p) => p.transform(epochs),
            Features::XdawnTangent(f) => {
                // Epochs are independent: spread them over rayon's threads.
                let x = every_nth(epochs, f.step);
                let n_features = f.tangent.n_features();
                let mut out = Array2::zeros((x.dim().0, n_features));
                // Each thread reuses its own buffers: no allocation per epoch.
                out.axis_iter_mut(Axis(0))
                    .into_par_iter()
                    .zip(x.axis_iter(Axis(0)).into_par_iter())
                    .try_for_each_init(
                        || {
                            (
                                crate::xdawn::Buffers::default(),
                                crate::riemann::Scratch::default(),
                            )
                        },
                        |(buf, scratch), (row, epoch)| -> Result<()> {
                            let cov = f.xdawn.covariance_of(epoch, buf)?;
                            f.tangent.vectorize_symmetric_into(cov, scratch, row)
                        },
                    )?;
                Ok(out)
            }
            Features::XdawnCovariances(f) => {
                let x = every_nth(epochs, f.step);
                let n = f.xdawn.size();
                let mut out = Array2::zeros((x.dim().0, n * n));
                out.axis_iter_mut(Axis(0))
                    .into_par_iter()
                    .zip(x.axis_iter(Axis(0)).into_par_iter())
                    .try_for_each_init(
                        crate::xdawn::Buffers::default,
                        |buf, (mut row, epoch)| -> Result<()> {
                            let cov = f.xdawn.covariance_of(epoch, buf)?;
                            // Row-major flattening of a symmetric matrix.
                            row.iter_mut().zip(cov.iter()).for_each(|(o, &v)| *o = v);
                            Ok(())
                        },
                    )?;
                Ok(out)
            }
        }
    }
}

/// The classifier at the end of a pipeline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ClassifierParams {
    Lda(LdaParams),
    /// Block-Toeplitz shrinkage LDA on channel-major spatio-temporal features (amplitudes); the
    /// channel count is the epochs' (after channel selection).
    ToeplitzLda(ToeplitzLdaParams),
    Logistic(LogisticParams),
    Svm(SvmParams),
    Knn(KnnParams),
    /// Soft vote of members' P(target) (the paper's multi-classifier).
    Vote(SoftVoteParams),
    /// Minimum distance to (Riemannian) mean on flattened SPD matrices
    /// ([`FeatureParams::XdawnCovariances`]).
    Mdm(MdmParams),
}

/// A fitted classifier.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Classifier {
    Lda(Lda),
    ToeplitzLda(ToeplitzLda),
    Logistic(Logistic),
    Svm(Svm),
    Knn(Knn),
    Vote(SoftVote),
    Mdm(Mdm),
}

/// scikit-learn's `gamma='scale'` of the features `x`: `1 / (n_features · Var(X))` (1 when the
/// variance is 0), as [`crate::svm`] resolves it.
fn gamma_scale(x: ArrayView2<f64>) -> f64 {
    let n = x.len() as f64;
    let mean = x.sum() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    if var > 0.0 {
        1.0 / (x.ncols() as f64 * var)
    } else {
        1.0
    }
}

impl ClassifierParams {
    /// The same settings with every RBF SVM's `γ = 'scale'` replaced by `factor ×` the scale
    /// γ of the training features `x` (unchanged when `factor` is 1).
    fn with_gamma_factor(&self, x: ArrayView2<f64>, factor: f64) -> Result<Self> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(DecodeError::InvalidParameter {
                name: "svm_gamma_scale",
                value: factor.to_string(),
                reason: "must be finite and > 0".into(),
            });
        }
        if factor == 1.0 || x.is_empty() {
            return Ok(self.clone());
        }
        let gamma = factor * gamma_scale(x);
        let resolve = |p: &SvmParams| SvmParams {
            kernel: match p.kernel {
                Kernel::Rbf(Gamma::Scale) => Kernel::Rbf(Gamma::Value(gamma)),
                k => k,
            },
            ..*p
        };
        Ok(match self {
            ClassifierParams::Svm(p) => ClassifierParams::Svm(resolve(p)),
            ClassifierParams::Vote(v) => ClassifierParams::Vote(SoftVoteParams {
                members: v
                    .members
                    .iter()
                    .map(|m| match m {
                        MemberParams::Svm(p) => MemberParams::Svm(resolve(p)),
                        other => *other,
                    })
                    .collect(),
                weights: v.weights.clone(),
            }),
            other => other.clone(),
        })
    }

    /// Fits on feature rows `x` of epochs with `n_channels` channels.
    fn fit(&self, x: ArrayView2<f64>, y: &[bool], n_channels: usize) -> Result<Classifier> {
        Ok(match self {
            ClassifierParams::Lda(p) => Classifier::Lda(p.fit(x, y)?),
            ClassifierParams::ToeplitzLda(p) => Classifier::ToeplitzLda(p.fit(x, y, n_channels)?),
            ClassifierParams::Logistic(p) => Classifier::Logistic(p.fit(x, y)?),
            ClassifierParams::Svm(p) => Classifier::Svm(p.fit(x, y)?),
            ClassifierParams::Knn(p) => Classifier::Knn(p.fit(x, y)?),
            ClassifierParams::Vote(p) => Classifier::Vote(p.fit(x, y)?),
            ClassifierParams::Mdm(p) => Classifier::Mdm(p.fit(unflatten_square(x)?.view(), y)?),
        })
    }
}

impl Classifier {
    fn inner(&self) -> &dyn ProbabilisticClassifier {
        match self {
            Classifier::Lda(m) => m,
            Classifier::ToeplitzLda(m) => m,
            Classifier::Logistic(m) => m,
            Classifier::Svm(m) => m,
            Classifier::Knn(m) => m,
            Classifier::Vote(m) => m,
            Classifier::Mdm(m) => m,
        }
    }
}

/// Unfitted pipeline settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PipelineParams {
    /// A name for reports (the preset's name, or any).
    pub name: String,
    pub channel_selection: Option<ChannelSelectionParams>,
    pub features: FeatureParams,
    pub scaler: Option<StandardScalerParams>,
    pub pca: Option<PcaParams>,
    pub classifier: ClassifierParams,
    /// Score fusion: further pipelines fitted on the same epochs, whose scores are combined with
    /// this one's as [`fusion`](Self::fusion) says. Empty for one pipeline.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fused: Vec<PipelineParams>,
    /// How the scores of a fusion are combined (ignored without [`fused`](Self::fused)).
    #[serde(default, skip_serializing_if = "Fusion::is_standardised")]
    pub fusion: Fusion,
    /// Multiplies the RBF SVMs' `γ = 'scale'`: 1 is scikit-learn's `'scale'`; otherwise the
    /// γ is resolved once on the training features (the Platt-calibration folds inside share it).
    #[serde(default = "one")]
    pub svm_gamma_scale: f64,
}

fn one() -> f64 {
    1.0
}

/// How a score fusion combines its pipelines' decision values `s_i`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Fusion {
    /// `Σ s_i / σ_i`, `σ_i` the standard deviation of `s_i` over the training epochs: each
    /// pipeline counts equally, nothing is fitted.
    #[default]
    Standardised,
    /// Stacking (scikit-learn's `StackingClassifier` with `cv`, a logistic-regression final
    /// estimator on standardised scores): each pipeline is fitted on the training part of
    /// `n_folds` inner folds ([`crate::tuning::cv_folds`]: speller characters kept whole when the
    /// fit is given groups, otherwise stratified) and scores the held-out part; a logistic
    /// regression (`C = 1`) on those out-of-fold scores, each standardised by its mean and
    /// standard deviation, learns the weights. The pipelines are then fitted on all the epochs,
    /// and the fused score is `b + Σ w_i (s_i − m_i) / σ_i` (log-odds of target).
    Stacked { n_folds: usize },
}

impl Fusion {
    fn is_standardised(&self) -> bool {
        *self == Fusion::Standardised
    }
}

/// The names [`PipelineParams::preset`] knows.
pub const PRESETS: [&str; 9] = [
    "lda",
    "toeplitz-lda",
    "riemann",
    "lda+riemann",
    "stack",
    "mdm",
    "paper",
    "paper-svm",
    "paper-knn",
];

impl PipelineParams {
    /// A named preset for epochs sampled at `sfreq` Hz:
    /// * `lda`: shrinkage LDA on bin-averaged amplitudes (bins of round(sfreq/25) samples);
    /// * `riemann`: every round(sfreq/64)-th sample → XdawnCovariances(4 filters, OAS) →
    ///   tangent space → logistic regression (pyRiemann's ERP pipeline);
    /// * `mdm`: the same XdawnCovariances → minimum distance to (Riemannian) mean (pyRiemann's
    ///   `MDM`), scored `d²(C, M_non-target) − d²(C, M_target)`;
    /// * `paper`: the paper's amplitude + HHT + wavelet features → StandardScaler → PCA (95 %
    ///   variance) → soft vote of an RBF SVM and a 3-NN;
    /// * `paper-svm`, `paper-knn`: the same features with one of the two members alone;
    /// * `lda+riemann`: score fusion of `lda` and `riemann` (each pipeline's decision value
    ///   divided by its standard deviation on the training epochs, then summed; no weights to
    ///   tune).
    /// * `toeplitz-lda`: block-Toeplitz shrinkage LDA ([`crate::toeplitz_lda`]) on the `lda`
    ///   preset's amplitudes;
    /// * `stack`: `toeplitz-lda`, `riemann` and `mdm` stacked ([`Fusion::Stacked`], 5 inner
    ///   folds): a logistic regression learns their weights from out-of-fold scores on the
    ///   training epochs.
    pub fn preset(name: &str, sfreq: f64) -> Result<Self> {
        let paper_front = |classifier| -> Result<Self> {
            Ok(Self {
                name: name.to_string(),
                channel_selection: None,
                features: FeatureParams::Paper(PaperFeatures::for_sfreq(sfreq)?),
                scaler: Some(StandardScalerParams::default()),
                pca: Some(PcaParams::variance_fraction(0.95)),
                classifier,
                svm_gamma_scale: 1.0,
                fused: Vec::new(),
                fusion: Fusion::Standardised,
            })
        };
        let xdawn_step = crate::amplitude::samples_per(sfreq, 64.0);
        match name {
            "lda" => Ok(Self {
                name: name.to_string(),
                channel_selection: None,
                features: FeatureParams::Amplitude(AmplitudeFeatures::for_sfreq(sfreq)?),
                scaler: None,
                pca: None,
                classifier: ClassifierParams::Lda(LdaParams::default()),
                svm_gamma_scale: 1.0,
                fused: Vec::new(),
                fusion: Fusion::Standardised,
            }),
            "riemann" => Ok(Self {
                name: name.to_string(),
                channel_selection: None,
                features: FeatureParams::XdawnTangent {
                    step: xdawn_step,
                    xdawn: XdawnCovariancesParams::default(),
                    tangent: TangentSpaceParams::default(),
                },
                scaler: None,
                pca: None,
                classifier: ClassifierParams::Logistic(LogisticParams::default()),
                svm_gamma_scale: 1.0,
                fused: Vec::new(),
                fusion: Fusion::Standardised,
            }),
            "mdm" => Ok(Self {
                name: name.to_string(),
                channel_selection: None,
                features: FeatureParams::XdawnCovariances {
                    step: xdawn_step,
                    xdawn: XdawnCovariancesParams::default(),
                },
                scaler: None,
                pca: None,
                classifier: ClassifierParams::Mdm(MdmParams::default()),
                svm_gamma_scale: 1.0,
                fused: Vec::new(),
                fusion: Fusion::Standardised,
            }),
            "paper" => paper_front(ClassifierParams::Vote(SoftVoteParams::paper())),
            // Alone, the SVM's decision value is the score: no probability calibration needed.
            "paper-svm" => paper_front(ClassifierParams::Svm(SvmParams {
                calibration: Calibration::None,
                ..SvmParams::default()
            })),
            "paper-knn" => paper_front(ClassifierParams::Knn(KnnParams::default())),
            "lda+riemann" => {
                let mut p = Self::preset("lda", sfreq)?;
                p.name = name.to_string();
                p.fused = vec![Self::preset("riemann", sfreq)?];
                Ok(p)
            }
            "toeplitz-lda" => {
                let mut p = Self::preset("lda", sfreq)?;
                p.name = name.to_string();
                p.classifier = ClassifierParams::ToeplitzLda(ToeplitzLdaParams::default());
                Ok(p)
            }
            "stack" => {
                let mut p = Self::preset("toeplitz-lda", sfreq)?;
                p.name = name.to_string();
                p.fused = vec![Self::preset("riemann", sfreq)?, Self::preset("mdm", sfreq)?];
                p.fusion = Fusion::Stacked { n_folds: 5 };
                Ok(p)
            }
            other => Err(DecodeError::InvalidParameter {
                name: "pipeline",
                value: other.to_string(),
                reason: format!("unknown preset; known: {}", PRESETS.join(", ")),
            }),
        }
    }

    /// The same pipeline with the paper's channel selection (drop the `n_drop` channels whose
    /// target responses correlate least with the others) in front.
    pub fn with_channel_drop(mut self, n_drop: usize) -> Self {
        self.channel_selection = Some(ChannelSelectionParams {
            count: ChannelCount::Drop(n_drop),
        });
        self
    }

    /// Fits every step on training `epochs` `(n_epochs, n_channels, n_times)` with labels `y`.
    /// A stacked fusion's inner folds are stratified by label ([`fit_grouped`](Self::fit_grouped)
    /// keeps groups whole).
    pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Pipeline> {
        self.fit_grouped(epochs, y, None)
    }

    /// [`fit`](Self::fit) where epochs belong to `groups` (one id per epoch, e.g. the speller
    /// character): a stacked fusion's inner folds keep each group whole, as
    /// [`crate::tuning::cv_folds`] does. Only a stacked fusion reads the groups.
    pub fn fit_grouped(
        &self,
        epochs: ArrayView3<f64>,
        y: &[bool],
        groups: Option<&[usize]>,
    ) -> Result<Pipeline> {
        let mut pipeline = self.fit_single(epochs, y)?;
        if self.fused.is_empty() {
            return Ok(pipeline);
        }
        let mut members = Vec::with_capacity(self.fused.len());
        for p in &self.fused {
            members.push(p.fit_single(epochs, y)?);
        }
        match self.fusion {
            Fusion::Standardised => {
                pipeline.score_scale = training_score_sd(&pipeline, epochs)?;
                for m in &mut members {
                    m.score_scale = training_score_sd(m, epochs)?;
                }
            }
            Fusion::Stacked { n_folds } => {
                let stack = self.fit_stacker(epochs, y, groups, n_folds)?;
                for (k, m) in std::iter::once(&mut pipeline)
                    .chain(members.iter_mut())
                    .enumerate()
                {
                    m.score_center = stack.center[k];
                    m.score_scale = stack.scale[k];
                    m.score_weight = stack.weight[k];
                }
                pipeline.fusion_intercept = stack.intercept;
            }
        }
        pipeline.fused = members;
        Ok(pipeline)
    }

    /// This pipeline and its fused ones, each alone (without fusion).
    fn members(&self) -> Vec<PipelineParams> {
        let mut head = self.clone();
        head.fused = Vec::new();
        std::iter::once(head)
            .chain(self.fused.iter().cloned())
            .collect()
    }

    /// Stacking weights from out-of-fold scores (see [`Fusion::Stacked`]).
    fn fit_stacker(
        &self,
        epochs: ArrayView3<f64>,
        y: &[bool],
        groups: Option<&[usize]>,
        n_folds: usize,
    ) -> Result<Stacker> {
        let folds = crate::tuning::cv_folds(y, groups, n_folds)?;
        let members = self.members();
        let n = y.len();
        let per_fold = (0..folds.n_folds())
            .into_par_iter()
            .map(|f| {
                let (tr, te) = folds.split(f);
                let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
                let etr = epochs.select(Axis(0), &tr);
                let ete = epochs.select(Axis(0), &te);
                let scores = members
                    .iter()
                    .map(|p| {
                        p.fit_single(etr.view(), &ytr)?
                            .own_decision_function(ete.view())
                    })
                    .collect::<Result<Vec<Array1<f64>>>>()?;
                Ok((te, scores))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut oof = Array2::zeros((n, members.len()));
        for (te, scores) in per_fold {
            for (k, s) in scores.iter().enumerate() {
                for (&i, &v) in te.iter().zip(s) {
                    oof[[i, k]] = v;
                }
            }
        }
        let scaler = StandardScalerParams::default().fit(oof.view())?;
        let z = scaler.transform(oof.view())?;
        let lr = LogisticParams::default().fit(z.view(), y)?;
        Ok(Stacker {
            center: scaler.mean.to_vec(),
            scale: scaler.scale.to_vec(),
            weight: lr.coef().to_vec(),
            intercept: lr.intercept(),
        })
    }

    /// Fits this pipeline's own steps (its fusion left out).
    fn fit_single(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Pipeline> {
        let (n_epochs, n_channels, n_times) = epochs.dim();
        if y.len() != n_epochs {
            return Err(DecodeError::LabelCount {
                n_samples: n_epochs,
                n_labels: y.len(),
            });
        }
        let n_targets = y.iter().filter(|&&t| t).count();
        if n_targets == 0 || n_targets == n_epochs {
            return Err(DecodeError::NeedBothClasses {
                n_targets,
                n_nontargets: n_epochs - n_targets,
            });
        }
        let (front, x) = self.fit_front(epochs, y)?;
        let n_front = front.n_channels(n_channels);
        let Front { channels, features } = front;
        let Head {
            scaler,
            pca,
            classifier,
        } = self.fit_head(x, y, n_front)?;
        Ok(Pipeline {
            name: self.name.clone(),
            n_channels,
            n_times,
            channels,
            features,
            scaler,
            pca,
            classifier,
            params: Some(self.clone()),
            fused: Vec::new(),
            score_scale: 1.0,
            score_center: 0.0,
            score_weight: 1.0,
            fusion_intercept: 0.0,
        })
    }

    /// Fits the channel selection and the features on `epochs`; returns them with the features
    /// of `epochs`.
    pub(crate) fn fit_front(
        &self,
        epochs: ArrayView3<f64>,
        y: &[bool],
    ) -> Result<(Front, Array2<f64>)> {
        let channels = self
            .channel_selection
            .map(|p| p.fit(epochs, y))
            .transpose()?;
        let selected;
        let epochs = match &channels {
            Some(c) => {
                selected = c.transform(epochs)?;
                selected.view()
            }
            None => epochs.view(),
        };
        let features = self.features.fit(epochs, y)?;
        let x = features.transform(epochs)?;
        Ok((Front { channels, features }, x))
    }

    /// Whether `other` has the same channel selection and features (so one fitted front
    /// serves both).
    pub(crate) fn same_front(&self, other: &Self) -> bool {
        self.channel_selection == other.channel_selection && self.features == other.features
    }

    /// Fits the steps after the features (scaler, PCA, classifier) on feature rows `x` of epochs
    /// with `n_channels` channels (after channel selection).
    pub(crate) fn fit_head(
        &self,
        mut x: Array2<f64>,
        y: &[bool],
        n_channels: usize,
    ) -> Result<Head> {
        let scaler = match &self.scaler {
            Some(p) => {
                let s = p.fit(x.view())?;
                x = s.transform(x.view())?;
                Some(s)
            }
            None => None,
        };
        let pca = match &self.pca {
            Some(p) => {
                let m = p.fit(x.view())?;
                x = m.transform(x.view())?;
                Some(m)
            }
            None => None,
        };
        let classifier = self
            .classifier
            .with_gamma_factor(x.view(), self.svm_gamma_scale)?
            .fit(x.view(), y, n_channels)?;
        Ok(Head {
            scaler,
            pca,
            classifier,
        })
    }

    /// Features of `epochs` when the front learns nothing (no channel selection, a stateless
    /// feature map): the same rows whatever the training split. `None` otherwise.
    pub(crate) fn stateless_features(
        &self,
        epochs: ArrayView3<f64>,
    ) -> Option<Result<Array2<f64>>> {
        if self.channel_selection.is_some() || !self.features.is_stateless() {
            return None;
        }
        Some(
            self.features
                .fit(epochs, &[])
                .and_then(|f| f.transform(epochs)),
        )
    }
}

/// Standard deviation of `pipeline`'s own decision values on its training `epochs` (its unit in
/// a score fusion).
fn training_score_sd(pipeline: &Pipeline, epochs: ArrayView3<f64>) -> Result<f64> {
    let scores = pipeline.own_decision_function(epochs)?;
    let sd = scores.std(0.0);
    if sd.is_finite() && sd > 0.0 {
        Ok(sd)
    } else {
        Err(DecodeError::InvalidParameter {
            name: "fused",
            value: pipeline.name.clone(),
            reason: format!(
                "its training scores have no spread (standard deviation {sd}): nothing to fuse"
            ),
        })
    }
}

/// A stacked fusion's learned combination, one entry per pipeline (this one first).
struct Stacker {
    center: Vec<f64>,
    scale: Vec<f64>,
    weight: Vec<f64>,
    intercept: f64,
}

/// The fitted channel selection and features.
#[derive(Debug)]
pub(crate) struct Front {
    channels: Option<ChannelSelection>,
    features: Features,
}

impl Front {
    /// Channels the features see, of `n_channels` given.
    pub(crate) fn n_channels(&self, n_channels: usize) -> usize {
        self.channels
            .as_ref()
            .map_or(n_channels, |c| c.selected.len())
    }

    /// Features `(n_epochs, n_features)` of `epochs`.
    pub(crate) fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        match &self.channels {
            Some(c) => self.features.transform(c.transform(epochs)?.view()),
            None => self.features.transform(epochs),
        }
    }
}

/// The fitted steps after the features.
#[derive(Debug)]
pub(crate) struct Head {
    scaler: Option<StandardScaler>,
    pca: Option<Pca>,
    classifier: Classifier,
}

impl Head {
    /// Scores of feature rows `x`.
    pub(crate) fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        let mut x = x.to_owned();
        if let Some(s) = &self.scaler {
            x = s.transform(x.view())?;
        }
        if let Some(p) = &self.pca {
            x = p.transform(x.view())?;
        }
        self.classifier.inner().decision_function(x.view())
    }
}

/// A fitted pipeline.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Pipeline {
    name: String,
    n_channels: usize,
    n_times: usize,
    channels: Option<ChannelSelection>,
    features: Features,
    scaler: Option<StandardScaler>,
    pca: Option<Pca>,
    classifier: Classifier,
    /// The settings it was fitted with (absent in models saved before they were kept).
    #[serde(default)]
    params: Option<PipelineParams>,
    /// Score fusion: the further pipelines whose scores are added (see
    /// [`PipelineParams::fused`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    fused: Vec<Pipeline>,
    /// In a fusion, this pipeline adds `score_weight · (s − score_center) / score_scale` to the
    /// fused score (see [`Fusion`]). Standardised: the standard deviation of the decision values
    /// on the training epochs, centre 0, weight 1; stacked: the out-of-fold scores' mean and
    /// standard deviation and the logistic regression's weight.
    #[serde(default = "unit_scale")]
    score_scale: f64,
    #[serde(default)]
    score_center: f64,
    #[serde(default = "unit_scale")]
    score_weight: f64,
    /// The fused score's offset (the stacking regression's intercept; 0 when standardised).
    #[serde(default)]
    fusion_intercept: f64,
}

fn unit_scale() -> f64 {
    1.0
}

impl Pipeline {
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The settings it was fitted with, if the model recorded them.
    pub fn params(&self) -> Option<&PipelineParams> {
        self.params.as_ref()
    }

    /// Channels and samples per epoch it was fitted on.
    pub fn epoch_shape(&self) -> (usize, usize) {
        (self.n_channels, self.n_times)
    }

    /// Indices of the channels kept by channel selection (all when there is none).
    pub fn selected_channels(&self) -> Vec<usize> {
        match &self.channels {
            Some(c) => c.selected.clone(),
            None => (0..self.n_channels).collect(),
        }
    }

    /// The fitted classifier.
    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    /// The fitted PCA, if the pipeline has one.
    pub fn pca(&self) -> Option<&Pca> {
        self.pca.as_ref()
    }

    /// The classifier's input `(n_epochs, n_features)` for `epochs`.
    pub fn features(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (_, n_channels, n_times) = epochs.dim();
        if (n_channels, n_times) != (self.n_channels, self.n_times) {
            return Err(DecodeError::ShapeMismatch {
                what: "epochs (n_channels, n_times)".into(),
                expected: format!("({}, {})", self.n_channels, self.n_times),
                got: format!("({n_channels}, {n_times})"),
            });
        }
        let selected;
        let epochs = match &self.channels {
            Some(c) => {
                selected = c.transform(epochs)?;
                selected.view()
            }
            None => epochs.view(),
        };
        let mut x = self.features.transform(epochs)?;
        if let Some(s) = &self.scaler {
            x = s.transform(x.view())?;
        }
        if let Some(p) = &self.pca {
            x = p.transform(x.view())?;
        }
        Ok(x)
    }

    /// The pipelines fused with this one (empty for a single pipeline).
    pub fn fused(&self) -> &[Pipeline] {
        &self.fused
    }

    /// Continuous target evidence per epoch (larger = more target-like). For a score fusion,
    /// the fused score (see [`Fusion`]).
    pub fn decision_function(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let own = self.own_decision_function(epochs)?;
        if self.fused.is_empty() {
            return Ok(own);
        }
        let mut total = self.fusion_term(own);
        for m in &self.fused {
            total += &m.fusion_term(m.own_decision_function(epochs)?);
        }
        Ok(total + self.fusion_intercept)
    }

    /// This pipeline's share `w · (s − c) / σ` of a fused score (`s / σ` when standardised).
    fn fusion_term(&self, s: Array1<f64>) -> Array1<f64> {
        let (c, sd, w) = (self.score_center, self.score_scale, self.score_weight);
        s.mapv_into(|v| w * ((v - c) / sd))
    }

    /// A fusion's score scales are finite and positive (a file could say anything).
    fn check_fusion(&self) -> Result<()> {
        if self.fused.is_empty() {
            return Ok(());
        }
        if !self.fusion_intercept.is_finite() {
            return Err(DecodeError::ModelFormat {
                reason: format!("fusion intercept {} must be finite", self.fusion_intercept),
            });
        }
        for p in std::iter::once(self).chain(&self.fused) {
            let nested = !std::ptr::eq(p, self) && !p.fused.is_empty();
            if !(p.score_scale.is_finite() && p.score_scale > 0.0) || nested {
                return Err(DecodeError::ModelFormat {
                    reason: format!(
                        "fused pipeline {}: score scale {} (must be finite and > 0, one level of fusion)",
                        p.name, p.score_scale
                    ),
                });
            }
            if !(p.score_center.is_finite() && p.score_weight.is_finite()) {
                return Err(DecodeError::ModelFormat {
                    reason: format!(
                        "fused pipeline {}: score centre {} and weight {} must be finite",
                        p.name, p.score_center, p.score_weight
                    ),
                });
            }
            if p.epoch_shape() != self.epoch_shape() {
                return Err(DecodeError::ModelFormat {
                    reason: format!(
                        "fused pipeline {} expects epochs {:?}, the model {:?}",
                        p.name,
                        p.epoch_shape(),
                        self.epoch_shape()
                    ),
                });
            }
        }
        Ok(())
    }

    /// This pipeline's decision values, without the pipelines fused with it.
    fn own_decision_function(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let x = self.features(epochs)?;
        self.classifier.inner().decision_function(x.view())
    }

    /// P(target) per epoch. A score fusion has no calibrated probability: the logistic of its
    /// fused score.
    pub fn predict_proba(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        if !self.fused.is_empty() {
            return Ok(self.decision_function(epochs)?.mapv(crate::linalg::sigmoid));
        }
        let x = self.features(epochs)?;
        self.classifier.inner().predict_proba(x.view())
    }

    /// Target evidence of one epoch `(n_channels, n_times)`, for online use.
    pub fn score_epoch(&self, epoch: ArrayView2<f64>) -> Result<f64> {
        let one = epoch.insert_axis(Axis(0));
        Ok(self.decision_function(one)?[0])
    }
}

/// Version of the saved-model format written; a file of a version not in
/// [`READABLE_MODEL_VERSIONS`] is refused at load. Version 2 added score fusion (a model of
/// version 1 reads the same under 2; a binary that knows only 1 refuses a fused model rather
/// than scoring half of it). Version 3 added stacked fusion (weights, centres, intercept) and the
/// block-Toeplitz LDA; older files read the same under 3.
pub const MODEL_FORMAT_VERSION: u32 = 3;

/// Saved-model versions this build reads.
pub const READABLE_MODEL_VERSIONS: [u32; 3] = [1, 2, 3];

/// A trained model as saved to disk: the pipeline plus everything needed to feed it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Model {
    pub format_version: u32,
    pub preprocess: Preprocess,
    /// Sampling rate of the training data, Hz.
    pub sfreq: f64,
    /// Channel names, in the order the pipeline expects.
    pub ch_names: Vec<String>,
    pub pipeline: Pipeline,
    /// How scores become choices in a session (absent for models trained offline).
    #[serde(default)]
    pub decision: Option<crate::decision::DecisionModel>,
    /// How the pipeline's settings were chosen by cross-validation on the training data
    /// (`oddball train --tune`); absent when the preset's defaults were used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tuning: Option<crate::tuning::TuningReport>,
}

impl Model {
    pub fn new(
        preprocess: Preprocess,
        sfreq: f64,
        ch_names: Vec<String>,
        pipeline: Pipeline,
    ) -> Self {
        Self {
            format_version: MODEL_FORMAT_VERSION,
            preprocess,
            sfreq,
            ch_names,
            pipeline,
            decision: None,
            tuning: None,
        }
    }

    /// JSON text of the model.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a model serialises")
    }

    /// Reads a model, refusing other format versions before decoding the rest.
    pub fn from_json(text: &str) -> Result<Self> {
        #[derive(Deserialize)]
        struct Version {
            format_version: Option<u32>,
        }
        let v: Version = serde_json::from_str(text).map_err(|e| DecodeError::ModelFormat {
            reason: e.to_string(),
        })?;
        match v.format_version {
            Some(found) if READABLE_MODEL_VERSIONS.contains(&found) => {}
            found => {
                return Err(DecodeError::ModelVersion {
                    found,
                    expected: MODEL_FORMAT_VERSION,
                })
            }
        }
        let model: Self = serde_json::from_str(text).map_err(|e| DecodeError::ModelFormat {
            reason: e.to_string(),
        })?;
        model.pipeline.check_fusion()?;
        Ok(model)
    }

    /// Checks that a recording's channels and rate are the ones the model was trained on.
    pub fn check_layout(&self, ch_names: &[String], sfreq: f64) -> Result<()> {
        if ch_names != self.ch_names.as_slice() || (sfreq - self.sfreq).abs() > 1e-9 * self.sfreq {
            return Err(DecodeError::LayoutMismatch {
                expected: format!("{} Hz, channels {:?}", self.sfreq, self.ch_names),
                got: format!("{sfreq} Hz, channels {ch_names:?}"),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Synthetic epochs: targets (every 5th) carry a positive bump at 300 ms on the later channels.
    fn synthetic(n_epochs: usize, seed: u64) -> (Array3<f64>, Vec<bool>) {
        crate::testutil::synthetic_p300(n_epochs, seed, 5, 0, 4.0, 3.0)
    }

    #[test]
    fn presets_learn_a_separable_p300_and_round_trip_through_json() {
        let (xtr, ytr) = synthetic(200, 1);
        let (xte, yte) = synthetic(100, 2);
        for name in ["lda", "riemann", "lda+riemann", "mdm", "paper-svm"] {
            let p = PipelineParams::preset(name, 64.0).unwrap();
            let m = p.fit(xtr.view(), &ytr).unwrap();
            let scores = m.decision_function(xte.view()).unwrap();
            let auc = crate::metrics::roc_auc(scores.as_slice().unwrap(), &yte).unwrap();
            assert!(auc > 0.9, "{name}: AUC {auc}");
            let model = Model::new(Preprocess::peer(), 64.0, vec!["a".into(); 4], m);
            let back = Model::from_json(&model.to_json()).unwrap();
            let again = back.pipeline.decision_function(xte.view()).unwrap();
            assert_eq!(again, scores, "{name}: a loaded model scores the same");
            let one = back
                .pipeline
                .score_epoch(xte.index_axis(Axis(0), 3))
                .unwrap();
            assert!((one - scores[3]).abs() < 1e-12);
        }
    }

    #[test]
    fn a_score_fusion_adds_its_members_scores_in_units_of_their_training_spread() {
        let (xtr, ytr) = synthetic(200, 6);
        let (xte, _) = synthetic(30, 7);
        let fused = PipelineParams::preset("lda+riemann", 64.0)
            .unwrap()
            .fit(xtr.view(), &ytr)
            .unwrap();
        assert_eq!(fused.fused().len(), 1);
        // Independently: each preset alone, scaled by the spread of its own training scores.
        let part = |name: &str| {
            let m = PipelineParams::preset(name, 64.0)
                .unwrap()
                .fit(xtr.view(), &ytr)
                .unwrap();
            let train = m.decision_function(xtr.view()).unwrap();
            let n = train.len() as f64;
            let mean = train.sum() / n;
            let sd = (train.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
            m.decision_function(xte.view()).unwrap() / sd
        };
        let expected = part("lda") + part("riemann");
        let got = fused.decision_function(xte.view()).unwrap();
        for (g, e) in got.iter().zip(expected.iter()) {
            assert!((g - e).abs() < 1e-9 * e.abs().max(1.0), "{g} vs {e}");
        }
        // The probability is the logistic of the fused score.
        let p = fused.predict_proba(xte.view()).unwrap();
        assert!((p[0] - 1.0 / (1.0 + (-got[0]).exp())).abs() < 1e-12);
        // A model of the older format (version 1, no fusion) still loads.
        let single = PipelineParams::preset("lda", 64.0)
            .unwrap()
            .fit(xtr.view(), &ytr)
            .unwrap();
        let v1 = Model::new(Preprocess::peer(), 64.0, vec!["a".into(); 4], single)
            .to_json()
            .replace(
                &format!("\"format_version\":{MODEL_FORMAT_VERSION}"),
                "\"format_version\":1",
            );
        assert!(v1.contains("\"format_version\":1"));
        assert!(Model::from_json(&v1).is_ok());
        // A fused model whose score scale is not a positive number is refused at load.
        let text = Model::new(Preprocess::peer(), 64.0, vec!["a".into(); 4], fused).to_json();
        assert!(Model::from_json(&text).is_ok());
        let scale = format!("\"score_scale\":{}", {
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            v["pipeline"]["score_scale"].clone()
        });
        assert!(text.contains(&scale), "{scale}");
        for bad in ["0.0", "-1.0"] {
            let broken = text.replacen(&scale, &format!("\"score_scale\":{bad}"), 1);
            assert!(
                matches!(
                    Model::from_json(&broken),
                    Err(DecodeError::ModelFormat { .. })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn a_stacked_fusion_is_a_logistic_regression_on_out_of_fold_scores() {
        let (xtr, ytr) = synthetic(200, 6);
        let (xte, _) = synthetic(30, 7);
        let groups: Vec<usize> = (0..200).map(|i| i / 25).collect();
        let stack = PipelineParams::preset("stack", 64.0).unwrap();
        assert_eq!(stack.fusion, Fusion::Stacked { n_folds: 5 });
        let fused = stack.fit_grouped(xtr.view(), &ytr, Some(&groups)).unwrap();
        assert_eq!(fused.fused().len(), 2);
        // Independently: the three presets alone, scored out of fold on folds keeping the
        // groups whole, then scikit-learn's recipe (StandardScaler → LogisticRegression).
        let names = ["toeplitz-lda", "riemann", "mdm"];
        let folds = crate::tuning::cv_folds(&ytr, Some(&groups), 5).unwrap();
        assert!(folds.grouped());
        let fold_of = folds.fold_of();
        assert!((0..200).all(|i| fold_of[i] == fold_of[25 * groups[i]]));
        let mut oof = Array2::<f64>::zeros((200, 3));
        for f in 0..folds.n_folds() {
            let (tr, te) = folds.split(f);
            let y: Vec<bool> = tr.iter().map(|&i| ytr[i]).collect();
            for (k, name) in names.iter().enumerate() {
                let m = PipelineParams::preset(name, 64.0)
                    .unwrap()
                    .fit(xtr.select(Axis(0), &tr).view(), &y)
                    .unwrap();
                let s = m
                    .decision_function(xtr.select(Axis(0), &te).view())
                    .unwrap();
                for (&i, &v) in te.iter().zip(&s) {
                    oof[[i, k]] = v;
                }
            }
        }
        let scaler = StandardScalerParams::default().fit(oof.view()).unwrap();
        let lr = LogisticParams::default()
            .fit(scaler.transform(oof.view()).unwrap().view(), &ytr)
            .unwrap();
        let mut expected = Array1::from_elem(30, lr.intercept());
        for (k, name) in names.iter().enumerate() {
            let m = PipelineParams::preset(name, 64.0)
                .unwrap()
                .fit(xtr.view(), &ytr)
                .unwrap();
            let s = m.decision_function(xte.view()).unwrap();
            expected += &s.mapv(|v| lr.coef()[k] * (v - scaler.mean[k]) / scaler.scale[k]);
        }
        let got = fused.decision_function(xte.view()).unwrap();
        for (g, e) in got.iter().zip(expected.iter()) {
            assert!((g - e).abs() < 1e-9 * e.abs().max(1.0), "{g} vs {e}");
        }
        // The learned combination survives saving; a non-finite weight is refused at load.
        let text = Model::new(Preprocess::peer(), 64.0, vec!["a".into(); 4], fused).to_json();
        let back = Model::from_json(&text).unwrap();
        assert_eq!(back.pipeline.decision_function(xte.view()).unwrap(), got);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let w = format!("\"score_weight\":{}", v["pipeline"]["score_weight"]);
        assert!(text.contains(&w), "{w}");
        let broken = text.replacen(&w, "\"score_weight\":1e999", 1);
        assert!(Model::from_json(&broken).is_err());
        // Without groups the inner folds are stratified: a different, still valid, fit.
        let plain = stack.fit(xtr.view(), &ytr).unwrap();
        assert!(plain
            .decision_function(xte.view())
            .unwrap()
            .iter()
            .all(|v| v.is_finite()));
    }

    #[test]
    fn mdm_scores_are_distance_differences_to_the_class_means() {
        let (xtr, ytr) = synthetic(200, 4);
        let (xte, _) = synthetic(20, 5);
        let m = PipelineParams::preset("mdm", 64.0)
            .unwrap()
            .fit(xtr.view(), &ytr)
            .unwrap();
        let Classifier::Mdm(mdm) = m.classifier() else {
            panic!("mdm ends in an MDM classifier")
        };
        // Features are the xDAWN covariances, flattened row-major: 4 filters × 2 classes → 16×16
        // super-trial covariances (4 channels: 4 filters per class).
        let x = m.features(xte.view()).unwrap();
        let n = mdm.n_channels();
        assert_eq!((n, x.ncols()), (16, 256));
        let covs = x.to_shape((20, n, n)).unwrap().to_owned();
        let d = mdm.distances(covs.view()).unwrap();
        let s = m.decision_function(xte.view()).unwrap();
        for e in 0..20 {
            let want = d[[e, 0]].powi(2) - d[[e, 1]].powi(2);
            assert!(
                (s[e] - want).abs() < 1e-9 * (1.0 + want.abs()),
                "{} vs {want}",
                s[e]
            );
        }
        let p = m.predict_proba(xte.view()).unwrap();
        assert!(p
            .iter()
            .zip(s.iter())
            .all(|(p, s)| (*p > 0.5) == (*s > 0.0)));
        // The fitted pipeline keeps its settings.
        assert_eq!(
            m.params(),
            Some(&PipelineParams::preset("mdm", 64.0).unwrap())
        );
    }

    #[test]
    fn svm_gamma_factor_scales_the_resolved_gamma() {
        let (x, y) = synthetic(120, 6);
        let gamma = |factor: f64| {
            let mut p = PipelineParams::preset("paper-svm", 64.0).unwrap();
            p.svm_gamma_scale = factor;
            match p.fit(x.view(), &y).unwrap().classifier() {
                Classifier::Svm(s) => s.gamma().unwrap(),
                _ => unreachable!(),
            }
        };
        let (g1, g05) = (gamma(1.0), gamma(0.5));
        assert!((g05 - 0.5 * g1).abs() < 1e-12 * g1, "{g05} vs {g1}");
        let mut p = PipelineParams::preset("paper-svm", 64.0).unwrap();
        p.svm_gamma_scale = 0.0;
        assert!(p.fit(x.view(), &y).is_err());
        // Settings saved without the field read as the plain 'scale'.
        let text = serde_json::to_string(&p)
            .unwrap()
            .replace(",\"svm_gamma_scale\":0.0", "");
        assert!(!text.contains("svm_gamma_scale"));
        let back: PipelineParams = serde_json::from_str(&text).unwrap();
        assert_eq!(back.svm_gamma_scale, 1.0);
    }

    #[test]
    fn the_peer_window_and_steps_follow_numpy_and_python() {
        // numpy's x[onset : onset + round(0.8·sfreq)]: 205 samples at 256 Hz, 128 at 160 Hz
        let peer = Preprocess::peer();
        assert_eq!(peer.window(256.0), (0, 205));
        assert_eq!(peer.window(160.0), (0, 128));
        // MNE's both-ends-included window online: 0–0.6 s at 500 Hz is 301 samples
        assert_eq!(Preprocess::online().window(500.0), (0, 301));
        for (pre, sfreq) in [(peer, 256.0), (peer, 160.0), (Preprocess::online(), 500.0)] {
            let (first, n) = pre.window(sfreq);
            let (a, b) = pre.epochs_params().offsets(sfreq).unwrap();
            assert_eq!((a, b - a + 1), (first, n as i64));
        }
        // a model saved before `end_exclusive` existed reads as both ends included
        let old: Preprocess = serde_json::from_str(
            r#"{"band":{"order":4,"band":{"Bandpass":{"l_freq":0.5,"h_freq":20.0}}},"tmin":0.0,"tmax":0.8}"#,
        )
        .unwrap();
        assert_eq!(old.window(256.0), (0, 206));
        // Python's round(160 / 64) = round(2.5) = 2 (ties to even), not 3
        let step =
            |name: &str, sfreq: f64| match PipelineParams::preset(name, sfreq).unwrap().features {
                FeatureParams::XdawnTangent { step, .. }
                | FeatureParams::XdawnCovariances { step, .. } => step,
                _ => unreachable!("an xDAWN preset"),
            };
        assert_eq!((step("riemann", 160.0), step("mdm", 160.0)), (2, 2));
        assert_eq!((step("riemann", 256.0), step("riemann", 96.0)), (4, 2));
    }

    #[test]
    fn wrong_version_and_layout_are_clear_errors() {
        let (x, y) = synthetic(60, 3);
        let m = PipelineParams::preset("lda", 64.0)
            .unwrap()
            .fit(x.view(), &y)
            .unwrap();
        let model = Model::new(Preprocess::peer(), 64.0, vec!["Cz".into(); 4], m);
        let text = model.to_json().replace(
            &format!("\"format_version\":{MODEL_FORMAT_VERSION}"),
            "\"format_version\":99",
        );
        assert!(matches!(
            Model::from_json(&text),
            Err(DecodeError::ModelVersion {
                found: Some(99),
                expected: MODEL_FORMAT_VERSION
            })
        ));
        assert!(matches!(
            model.check_layout(&vec!["Cz".to_string(); 3], 64.0),
            Err(DecodeError::LayoutMismatch { .. })
        ));
        let wrong = Array3::zeros((2, 3, 64));
        assert!(matches!(
            model.pipeline.decision_function(wrong.view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        assert!(PipelineParams::preset("nope", 64.0).is_err());
    }
}
