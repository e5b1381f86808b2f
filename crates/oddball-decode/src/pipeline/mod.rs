//! Pipelines: transformers chained into a classifier, fit on epochs and labels, as a
//! scikit-learn `Pipeline`; and score fusions of single pipelines.
//!
//! A single pipeline ([`SingleParams`] → [`Single`]) is `[channel selection] → features →
//! [StandardScaler] → [PCA] → classifier`, where the features are either a per-epoch map with
//! nothing to learn (amplitudes; the paper's amplitude + Hilbert–Huang + wavelet map) or learned
//! xDAWN covariances, projected to the Riemannian tangent space (rows) or kept as SPD matrices
//! `(n_epochs, n, n)` (for MDM). The feature maps and classifiers are the registries of
//! [`crate::features`] and [`crate::classifiers`], each step fitted through the traits of
//! [`crate::traits`]. Every learned step is fitted on the training epochs only.
//!
//! A [`PipelineParams`] is one single pipeline plus, optionally, further single pipelines fused
//! with it ([`fusion`]); a member of a fusion is a single pipeline by its type, so fusions do not
//! nest. A fitted [`Pipeline`] keeps the [`PipelineParams`] it was fitted with, so a saved model
//! carries its settings (e.g. those chosen by [`crate::model_selection::tuning`]). Named settings are
//! [`crate::preset::Preset`]s; the saved form is [`crate::model`]'s.

mod cache;
pub mod fusion;
mod single;
mod source;

use ndarray::{Array1, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

pub use crate::classifiers::{Classifier, ClassifierParams};
use crate::features::channel_select::{ChannelCount, ChannelSelectionParams};
use crate::features::pca::Pca;
pub use crate::features::{FeatureParams, Features};
pub use crate::model::{Model, MODEL_FORMAT_VERSION, READABLE_MODEL_VERSIONS};
pub use crate::preprocess::{Preprocess, FLAT_UV};
pub use crate::riemann::{XdawnCovFeatures, XdawnTangent};
use crate::traits::FeatureData;
use crate::DecodeError;
pub use cache::{CachedScores, FrontCache};
pub use fusion::{FusedMember, Fusion, FusionTerm};
pub(crate) use single::Necked;
pub use single::{Single, SingleParams};
pub use source::EpochSource;

type Result<T> = std::result::Result<T, DecodeError>;

/// Unfitted pipeline settings: a single pipeline, and the single pipelines fused with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    try_from = "crate::model::ParamsRepr",
    into = "crate::model::ParamsRepr"
)]
pub struct PipelineParams {
    pub main: SingleParams,
    /// Score fusion: further pipelines fitted on the same epochs, whose scores are combined with
    /// this one's as [`fusion`](Self::fusion) says. Empty for one pipeline.
    pub fused: Vec<SingleParams>,
    /// How the scores of a fusion are combined (ignored without [`fused`](Self::fused)).
    pub fusion: Fusion,
}

impl From<SingleParams> for PipelineParams {
    fn from(main: SingleParams) -> Self {
        Self {
            main,
            fused: Vec::new(),
            fusion: Fusion::Standardised,
        }
    }
}

impl PipelineParams {
    /// The name for reports.
    pub fn name(&self) -> &str {
        &self.main.name
    }

    /// The same pipeline with the paper's channel selection (drop the `n_drop` channels whose
    /// target responses correlate least with the others) in front.
    pub fn with_channel_drop(mut self, n_drop: usize) -> Self {
        self.main.channel_selection = Some(ChannelSelectionParams {
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
    /// [`crate::model_selection::tuning::cv_folds`] does. Only a stacked fusion reads the groups.
    pub fn fit_grouped(
        &self,
        epochs: ArrayView3<f64>,
        y: &[bool],
        groups: Option<&[usize]>,
    ) -> Result<Pipeline> {
        self.fit_source(EpochSource::Array(epochs), y, groups)
    }

    /// [`Self::fit_grouped`] on an [`EpochSource`]: on windows, each single pipeline reads
    /// them as [`SingleParams::fit_source`] does, the stack's inner folds as they read a
    /// fold's epochs; the result is the same.
    pub fn fit_source(
        &self,
        epochs: EpochSource<'_>,
        y: &[bool],
        groups: Option<&[usize]>,
    ) -> Result<Pipeline> {
        let mut pipeline = self.unfused(self.main.fit_source(epochs, y)?);
        if self.fused.is_empty() {
            return Ok(pipeline);
        }
        let mut members = Vec::with_capacity(self.fused.len());
        for p in &self.fused {
            members.push(FusedMember {
                single: p.fit_source(epochs, y)?,
                params: Some(p.clone()),
                term: FusionTerm::UNIT,
            });
        }
        pipeline.fused = members;
        let singles: Vec<&SingleParams> = self.singles().collect();
        let fitted: Vec<&Single> = std::iter::once(&pipeline.main)
            .chain(pipeline.fused.iter().map(|m| &m.single))
            .collect();
        let (terms, intercept) =
            fusion::fit_terms(self.fusion, &singles, &fitted, epochs, y, groups)?;
        pipeline.term = terms[0];
        for (m, &t) in pipeline.fused.iter_mut().zip(&terms[1..]) {
            m.term = t;
        }
        pipeline.fusion_intercept = intercept;
        Ok(pipeline)
    }

    /// The fitted pipeline of `main` (fitted with these settings) before any fusion.
    fn unfused(&self, main: Single) -> Pipeline {
        Pipeline {
            main,
            params: Some(self.clone()),
            term: FusionTerm::UNIT,
            fused: Vec::new(),
            fusion_intercept: 0.0,
        }
    }

    /// This pipeline and its fused ones, each alone.
    fn singles(&self) -> impl Iterator<Item = &SingleParams> {
        std::iter::once(&self.main).chain(&self.fused)
    }
}

/// A fitted pipeline: a single pipeline and, in a score fusion, the single pipelines fused with
/// it. Saved as [`crate::model`] describes.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(
    try_from = "crate::model::PipelineRepr",
    into = "crate::model::PipelineRepr"
)]
pub struct Pipeline {
    pub(crate) main: Single,
    /// The settings it was fitted with (absent in models saved before they were kept).
    pub(crate) params: Option<PipelineParams>,
    /// The main pipeline's share of a fused score.
    pub(crate) term: FusionTerm,
    /// Score fusion: the further pipelines whose scores are added (see
    /// [`PipelineParams::fused`]).
    pub(crate) fused: Vec<FusedMember>,
    /// The fused score's offset (the stacking regression's intercept; 0 when standardised).
    pub(crate) fusion_intercept: f64,
}

impl Pipeline {
    pub fn name(&self) -> &str {
        &self.main.name
    }

    /// The settings it was fitted with, if the model recorded them.
    pub fn params(&self) -> Option<&PipelineParams> {
        self.params.as_ref()
    }

    /// A fusion's score scales are finite and positive, its members take the same epochs (a
    /// file could say anything).
    pub(crate) fn check_fusion(&self) -> Result<()> {
        fusion::check_terms(&self.main, &self.term, &self.fused, self.fusion_intercept)
    }

    /// Channels and samples per epoch it was fitted on.
    pub fn epoch_shape(&self) -> (usize, usize) {
        self.main.epoch_shape()
    }

    /// Indices of the channels kept by channel selection (all when there is none).
    pub fn selected_channels(&self) -> Vec<usize> {
        match &self.main.channels {
            Some(c) => c.selected.clone(),
            None => (0..self.main.n_channels).collect(),
        }
    }

    /// The fitted classifier.
    pub fn classifier(&self) -> &Classifier {
        &self.main.classifier
    }

    /// The fitted PCA, if the pipeline has one.
    pub fn pca(&self) -> Option<&Pca> {
        self.main.pca.as_ref()
    }

    /// The classifier's input for `epochs` (of the main pipeline of a fusion).
    pub fn features(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        self.main.features(epochs)
    }

    /// The pipelines fused with this one (empty for a single pipeline).
    pub fn fused(&self) -> &[FusedMember] {
        &self.fused
    }

    /// Continuous target evidence per epoch (larger = more target-like). For a score fusion,
    /// the fused score (see [`Fusion`]).
    pub fn decision_function(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let own = self.main.decision_function(epochs)?;
        if self.fused.is_empty() {
            return Ok(own);
        }
        let mut total = self.term.apply(own);
        for m in &self.fused {
            total += &m.term.apply(m.single.decision_function(epochs)?);
        }
        Ok(total + self.fusion_intercept)
    }

    /// [`Self::decision_function`] of an [`EpochSource`] (e.g. `(&epochs).into()`): of their
    /// array when preloaded, otherwise of [`oddball_signal::EPOCH_CHUNK`] epochs at a time (each epoch's score
    /// depends on that epoch alone, so the scores are the same).
    pub fn decision_function_source(&self, epochs: EpochSource<'_>) -> Result<Array1<f64>> {
        epochs.map_scores(|chunk| self.decision_function(chunk))
    }

    /// P(target) per epoch. A score fusion has no calibrated probability: the logistic of its
    /// fused score.
    pub fn predict_proba(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        if !self.fused.is_empty() {
            return Ok(self.decision_function(epochs)?.mapv(crate::linalg::sigmoid));
        }
        let x = self.main.features(epochs)?;
        self.main.classifier.scorer().predict_proba(x.view())
    }

    /// Target evidence of one epoch `(n_channels, n_times)`, for online use.
    pub fn score_epoch(&self, epoch: ArrayView2<f64>) -> Result<f64> {
        let one = epoch.insert_axis(Axis(0));
        Ok(self.decision_function(one)?[0])
    }
}

#[cfg(test)]
mod tests;
