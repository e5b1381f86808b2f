//! The saved model: a fitted [`Pipeline`] with the pre-processing and channel layout that feed
//! it, its format versions, and its JSON form (`PipelineRepr`, `ParamsRepr`: the layout
//! every version so far wrote, kept apart from the in-memory types so those can say what the
//! file cannot, e.g. that fusions do not nest).

use serde::{Deserialize, Serialize};

use crate::classifiers::{Classifier, ClassifierParams};
use crate::features::channel_select::{ChannelSelection, ChannelSelectionParams};
use crate::features::pca::{Pca, PcaParams};
use crate::features::scaler::{StandardScaler, StandardScalerParams};
use crate::features::{FeatureParams, Features};
use crate::pipeline::{
    FusedMember, Fusion, FusionTerm, Pipeline, PipelineParams, Single, SingleParams,
};
use crate::preprocess::Preprocess;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Version of the saved-model format written; a file of a version not in
/// [`READABLE_MODEL_VERSIONS`] is refused at load. Version 2 added score fusion (a model of
/// version 1 reads the same under 2; a binary that knows only 1 refuses a fused model rather
/// than scoring half of it). Version 3 added stacked fusion (weights, centres, intercept) and the
/// block-Toeplitz LDA; older files read the same under 3. Version 4: a model trained offline
/// (`oddball train`) carries its decision model too, fitted on cross-validated training scores,
/// so it runs in a session; older files read the same under 4 (one without a decision model is
/// refused by a session with [`NO_DECISION_MODEL`]).
pub const MODEL_FORMAT_VERSION: u32 = 4;

/// Saved-model versions this build reads.
pub const READABLE_MODEL_VERSIONS: [u32; 4] = [1, 2, 3, 4];

/// Why a model without a decision model cannot run a session, and what fixes it (one home for
/// every command that says it).
pub const NO_DECISION_MODEL: &str = "the model has no decision model (score → posterior), which \
     models saved before format version 4 lack: train it again with `oddball train` (which fits \
     one from cross-validated training scores), or calibrate in the session (--calibrate)";

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
    /// How scores become choices in a session: fitted on cross-validated scores of the
    /// training epochs (a session's calibration, or `oddball train` from format version 4 on).
    #[serde(default)]
    pub decision: Option<crate::decision::DecisionModel>,
    /// How the pipeline's settings were chosen by cross-validation on the training data
    /// (`oddball train --tune`); absent when the preset's defaults were used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tuning: Option<crate::model_selection::tuning::TuningReport>,
    /// What a session runs when this model's band-pass is zero-phase (`oddball train`, from
    /// format version 4): the same settings fitted on the same files' epochs band-passed
    /// causally, as a session cuts them, with its own decision model. A session cannot filter
    /// backward in time, and a model fitted on zero-phase epochs but fed causal ones loses
    /// accuracy (phase shifts), so both fits travel in one file. See [`Model::for_session`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub live: Option<Box<Model>>,
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
            live: None,
        }
    }

    /// The model a session runs: this one when its band-pass is causal, else its
    /// [`Model::live`] fit; a zero-phase model without one runs its own band causally
    /// ([`crate::pipeline::Preprocess::as_causal`]; its epochs then differ from its training's).
    pub fn for_session(self) -> Model {
        if self.preprocess.causal {
            return self;
        }
        match self.live {
            Some(live) => *live,
            None => Model {
                preprocess: self.preprocess.as_causal(),
                ..self
            },
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
            /// Present in an unsupervised fit ([`crate::unsupervised::Unsupervised`]), which an
            /// uncalibrated session saves as its `model.json`.
            constraint: Option<serde::de::IgnoredAny>,
        }
        let v: Version = serde_json::from_str(text).map_err(|e| DecodeError::ModelFormat {
            reason: e.to_string(),
        })?;
        if v.format_version.is_none() && v.constraint.is_some() {
            return Err(DecodeError::ModelFormat {
                reason: "this is an uncalibrated session's unsupervised fit, not a pipeline model \
                         (a labelled session's model.json or a trained model is one)"
                    .into(),
            });
        }
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
        model.check()?;
        Ok(model)
    }

    /// The checks a model passes before it scores anything (linfa's `ParamGuard` idea: a value
    /// from outside becomes a checked one once, where it enters): a plausible sampling rate,
    /// unique channel names as many as the pipeline's channels, a bounded epoch window and a
    /// band below Nyquist at that rate, fusion terms that can be used, and a decision model that
    /// can decide. [`Model::from_json`] runs it.
    pub fn check(&self) -> Result<()> {
        let bad = |reason: String| DecodeError::ModelFormat { reason };
        oddball_signal::check_sfreq(self.sfreq).map_err(|e| bad(e.to_string()))?;
        oddball_signal::check_unique_names(&self.ch_names).map_err(|e| bad(e.to_string()))?;
        let (n_channels, _) = self.pipeline.epoch_shape();
        if self.ch_names.len() != n_channels {
            return Err(bad(format!(
                "{} channel names for a pipeline of {n_channels} channels",
                self.ch_names.len()
            )));
        }
        let params = self.preprocess.params();
        params
            .epochs
            .validate(self.sfreq)
            .map_err(|e| bad(format!("epoch window: {e}")))?;
        params
            .band
            .design(self.sfreq)
            .map_err(|e| bad(format!("band-pass: {e}")))?;
        self.pipeline.check_fusion()?;
        if let Some(d) = &self.decision {
            d.validate()?;
        }
        if let Some(live) = &self.live {
            let why = if !live.preprocess.causal {
                Some("its band-pass is not causal")
            } else if live.live.is_some() {
                Some("it holds a live fit of its own")
            } else if live.ch_names != self.ch_names || live.sfreq != self.sfreq {
                Some("its channels or rate differ from the model's")
            } else if live.decision.is_none() {
                Some("it has no decision model")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(bad(format!("live fit: {why}")));
            }
            live.check().map_err(|e| bad(format!("live fit: {e}")))?;
        }
        Ok(())
    }

    /// Checks that a recording's channels and rate are the ones the model was trained on, in
    /// its order. See [`Model::channel_order`] for matching a recording's channels by name.
    pub fn check_layout(&self, ch_names: &[String], sfreq: f64) -> Result<()> {
        if ch_names != self.ch_names.as_slice()
            || !oddball_signal::rate::same_sfreq(sfreq, self.sfreq)
        {
            return Err(DecodeError::LayoutMismatch {
                expected: format!("{} Hz, channels {:?}", self.sfreq, self.ch_names),
                got: format!("{sfreq} Hz, channels {ch_names:?}"),
            });
        }
        Ok(())
    }

    /// Where each of the model's channels is in a recording with `ch_names` at `sfreq` Hz,
    /// matched by name: `order[k]` is the recording's row of the model's channel `k` (the
    /// recording may hold more channels, in any order). A missing channel or another rate is
    /// [`DecodeError::LayoutMismatch`] naming it.
    pub fn channel_order(&self, ch_names: &[String], sfreq: f64) -> Result<Vec<usize>> {
        if !oddball_signal::rate::same_sfreq(sfreq, self.sfreq) {
            return Err(DecodeError::LayoutMismatch {
                expected: format!("{} Hz", self.sfreq),
                got: format!("{sfreq} Hz"),
            });
        }
        match_channels(&self.ch_names, ch_names)
    }
}

/// Where each of `wanted` is among `present`, by name: `order[k]` is the index in `present` of
/// `wanted[k]`; the exact name, else the one name equal to it but for ASCII case (EEG labels
/// are written both ways: `PO7`, `Po7`), as `Raw::channel_index` finds. Every missing name is
/// listed in the [`DecodeError::LayoutMismatch`].
pub fn match_channels(wanted: &[String], present: &[String]) -> Result<Vec<usize>> {
    let mut order = Vec::with_capacity(wanted.len());
    let mut missing = Vec::new();
    let find = |w: &String| {
        present.iter().position(|p| p == w).or_else(|| {
            let mut same = present
                .iter()
                .enumerate()
                .filter(|(_, p)| p.eq_ignore_ascii_case(w));
            match (same.next(), same.next()) {
                (Some((i, _)), None) => Some(i),
                _ => None,
            }
        })
    };
    for w in wanted {
        match find(w) {
            Some(i) => order.push(i),
            None => missing.push(w.as_str()),
        }
    }
    if !missing.is_empty() {
        return Err(DecodeError::LayoutMismatch {
            expected: format!("channels {wanted:?}"),
            got: format!("channels {present:?}, without {missing:?}"),
        });
    }
    Ok(order)
}

/// The saved form of a [`Pipeline`], as every format so far wrote it: the main pipeline's
/// steps and settings, its fused pipelines in the same form (their own fusion fields empty),
/// and the fusion terms. A fused pipeline that fuses again is refused: fusions do not nest.
#[derive(Serialize, Deserialize)]
pub(crate) struct PipelineRepr {
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
    params: Option<ParamsRepr>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    fused: Vec<PipelineRepr>,
    /// This pipeline's [`FusionTerm`].
    #[serde(default = "unit")]
    score_scale: f64,
    #[serde(default)]
    score_center: f64,
    #[serde(default = "unit")]
    score_weight: f64,
    /// The fused score's offset (0 for a fused member).
    #[serde(default)]
    fusion_intercept: f64,
}

/// The saved form of [`PipelineParams`] (a fused member's: no `fused`, standardised `fusion`).
#[derive(Serialize, Deserialize)]
pub(crate) struct ParamsRepr {
    name: String,
    channel_selection: Option<ChannelSelectionParams>,
    features: FeatureParams,
    scaler: Option<StandardScalerParams>,
    pca: Option<PcaParams>,
    classifier: ClassifierParams,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    fused: Vec<ParamsRepr>,
    #[serde(default, skip_serializing_if = "Fusion::is_standardised")]
    fusion: Fusion,
    #[serde(default = "unit")]
    svm_gamma_scale: f64,
}

fn unit() -> f64 {
    1.0
}

fn nested(name: &str) -> DecodeError {
    DecodeError::ModelFormat {
        reason: format!("fused pipeline {name} fuses further pipelines: fusions do not nest"),
    }
}

impl ParamsRepr {
    fn split(self) -> (SingleParams, Vec<ParamsRepr>, Fusion) {
        let single = SingleParams {
            name: self.name,
            channel_selection: self.channel_selection,
            features: self.features,
            scaler: self.scaler,
            pca: self.pca,
            classifier: self.classifier,
            svm_gamma_scale: self.svm_gamma_scale,
        };
        (single, self.fused, self.fusion)
    }
}

impl From<SingleParams> for ParamsRepr {
    fn from(p: SingleParams) -> Self {
        Self {
            name: p.name,
            channel_selection: p.channel_selection,
            features: p.features,
            scaler: p.scaler,
            pca: p.pca,
            classifier: p.classifier,
            fused: Vec::new(),
            fusion: Fusion::Standardised,
            svm_gamma_scale: p.svm_gamma_scale,
        }
    }
}

impl TryFrom<ParamsRepr> for SingleParams {
    type Error = DecodeError;
    fn try_from(r: ParamsRepr) -> Result<Self> {
        let (single, fused, fusion) = r.split();
        if !fused.is_empty() || !fusion.is_standardised() {
            return Err(nested(&single.name));
        }
        Ok(single)
    }
}

impl From<PipelineParams> for ParamsRepr {
    fn from(p: PipelineParams) -> Self {
        Self {
            fused: p.fused.into_iter().map(Into::into).collect(),
            fusion: p.fusion,
            ..p.main.into()
        }
    }
}

impl TryFrom<ParamsRepr> for PipelineParams {
    type Error = DecodeError;
    fn try_from(r: ParamsRepr) -> Result<Self> {
        let (main, fused, fusion) = r.split();
        Ok(Self {
            main,
            fused: fused
                .into_iter()
                .map(SingleParams::try_from)
                .collect::<Result<_>>()?,
            fusion,
        })
    }
}

impl PipelineRepr {
    fn new(single: Single, term: FusionTerm, params: Option<ParamsRepr>) -> Self {
        Self {
            name: single.name,
            n_channels: single.n_channels,
            n_times: single.n_times,
            channels: single.channels,
            features: single.features,
            scaler: single.scaler,
            pca: single.pca,
            classifier: single.classifier,
            params,
            fused: Vec::new(),
            score_scale: term.scale,
            score_center: term.center,
            score_weight: term.weight,
            fusion_intercept: 0.0,
        }
    }

    /// The single pipeline, its fusion term, and the rest.
    #[allow(clippy::type_complexity)]
    fn split(
        self,
    ) -> (
        Single,
        FusionTerm,
        Option<ParamsRepr>,
        Vec<PipelineRepr>,
        f64,
    ) {
        let single = Single {
            name: self.name,
            n_channels: self.n_channels,
            n_times: self.n_times,
            channels: self.channels,
            features: self.features,
            scaler: self.scaler,
            pca: self.pca,
            classifier: self.classifier,
        };
        let term = FusionTerm {
            scale: self.score_scale,
            center: self.score_center,
            weight: self.score_weight,
        };
        (single, term, self.params, self.fused, self.fusion_intercept)
    }
}

impl From<Pipeline> for PipelineRepr {
    fn from(p: Pipeline) -> Self {
        let mut repr = PipelineRepr::new(p.main, p.term, p.params.map(Into::into));
        repr.fused = p
            .fused
            .into_iter()
            .map(|m| PipelineRepr::new(m.single, m.term, m.params.map(Into::into)))
            .collect();
        repr.fusion_intercept = p.fusion_intercept;
        repr
    }
}

/// A fitted single pipeline holds every step its settings name (a file with a step cut out
/// would load and score worse without a word).
fn check_complete(single: &Single, params: &SingleParams) -> Result<()> {
    for (step, wanted, present) in [
        (
            "channel selection",
            params.channel_selection.is_some(),
            single.channels.is_some(),
        ),
        ("scaler", params.scaler.is_some(), single.scaler.is_some()),
        ("PCA", params.pca.is_some(), single.pca.is_some()),
    ] {
        if wanted != present {
            return Err(DecodeError::ModelFormat {
                reason: format!(
                    "pipeline {}: its settings {} a {step}, the fitted steps {}",
                    single.name,
                    if wanted { "have" } else { "have no" },
                    if present { "have one" } else { "have none" },
                ),
            });
        }
    }
    Ok(())
}

impl TryFrom<PipelineRepr> for Pipeline {
    type Error = DecodeError;
    fn try_from(r: PipelineRepr) -> Result<Self> {
        let (main, term, params, fused, fusion_intercept) = r.split();
        if let Some(p) = &params {
            if p.fused.len() != fused.len() {
                return Err(DecodeError::ModelFormat {
                    reason: format!(
                        "pipeline {}: its settings fuse {} pipelines, the file holds {}",
                        main.name,
                        p.fused.len(),
                        fused.len()
                    ),
                });
            }
        }
        let fused = fused
            .into_iter()
            .map(|m| {
                // A member's own fusion intercept was always written as 0 and never read.
                let (single, term, params, further, _) = m.split();
                if !further.is_empty() {
                    return Err(nested(&single.name));
                }
                let params = params.map(SingleParams::try_from).transpose()?;
                if let Some(p) = &params {
                    check_complete(&single, p)?;
                }
                Ok(FusedMember {
                    single,
                    params,
                    term,
                })
            })
            .collect::<Result<_>>()?;
        let params = params.map(PipelineParams::try_from).transpose()?;
        if let Some(p) = &params {
            check_complete(&main, &p.main)?;
        }
        Ok(Self {
            main,
            params,
            term,
            fused,
            fusion_intercept,
        })
    }
}
