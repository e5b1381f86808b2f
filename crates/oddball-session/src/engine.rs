//! The session engine: calibration, training, and online control of the arm.
//!
//! A [`Session`] drives a [`Subject`] (an EEG stream, a stimulus presenter and an observer in
//! one, see [`crate::roles`]: the simulated subject here, a live source in `oddball_live`)
//! through the four-bulb paradigm. It runs on the EEG's sample clock, as fast as the stream
//! delivers; pacing by the wall clock is the live sources' job:
//!
//! 1. **Calibration**: `calibration_per_bulb` labelled decisions per bulb, in seeded random
//!    order, each with the paradigm's full rounds. Every epoch comes from the same causal
//!    [`OnlineEpocher`] the online phase uses.
//! 2. **Training**: the chosen preset is fitted on the accepted calibration epochs. Its scores
//!    are turned into log-likelihood ratios by a [`ScoreModelParams`] fitted on
//!    *cross-validated* scores (folds by decision), so the evidence is not over-confident.
//!    With [`SessionParams::stopping`] the stopping rule is then chosen from those same
//!    cross-validated scores for the most expected bits per minute ([`crate::timing`]).
//! 3. **Online**: per decision, a countdown, then rounds of four flashes. Flashes are shown (to
//!    the subject and the epocher) when the stream reaches their onset; each epoch is scored as
//!    soon as its last sample (600 ms after onset) has arrived; after each complete round the
//!    [`DecisionRule`] decides, continues or abstains. A decision issues the bulb's command to the
//!    arm, which runs on the same clock as the EEG, one chunk at a time.
//!
//! Before every trial the presenter may hold the session ([`Presenter::hold`]: an operator's
//! pause): the EEG and the arm run on, no trial starts. After every trial the observer hears
//! each channel's rejected epochs ([`Observer::channel_faults`]).
//!
//! Everything shown and decided is kept ([`SessionLog`]) so a session can be saved and
//! re-evaluated offline to the same decisions ([`crate::record`]).

use ndarray::{Array2, Array3, Axis};
use oddball_arm::{ArmSim, Command};
use oddball_decode::adaptive::{AdaptiveLda, Update};
use oddball_decode::classifiers::Classifier;
use oddball_decode::decision::{DecisionModel, DecisionRule, ScoreModelParams, Verdict};
use oddball_decode::metrics::roc_auc;
use oddball_decode::pipeline::{EpochSource, FrontCache, Model, PipelineParams, Preprocess};
use oddball_decode::stopping::{Expected, StoppingSearch};
use oddball_decode::unsupervised::{
    Constraint, MatchedTemplate, P300Template, Unsupervised, UnsupervisedParams,
};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::online::{Marker, OnlineEpocher};
use crate::paradigm::FourBulbParams;
pub use crate::roles::{Drawn, EegStream, Observer, Presenter, Subject};
use crate::SessionError;

/// A flash's measured onset (a page's stamp) further than this from its planned onset, seconds,
/// is refused: no display draws a frame a second off its schedule, and the epoch of an onset far
/// in the future would keep its trial waiting for ever.
pub const MAX_ONSET_SHIFT_S: f64 = 1.0;

/// The most calibration decisions per bulb (a thousand is hours of flashing).
pub const MAX_CALIBRATION_PER_BULB: usize = 1000;

/// Settings of a session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionParams {
    pub paradigm: FourBulbParams,
    pub preprocess: Preprocess,
    /// Pipeline preset name (see `oddball_decode::pipeline::PRESETS`).
    pub pipeline: String,
    /// Calibration decisions per bulb.
    pub calibration_per_bulb: usize,
    /// The online decision rule (fixed rounds, or dynamic stopping).
    pub rule: DecisionRule,
    /// Samples per streamed chunk.
    pub chunk: usize,
    /// Cross-validation folds for the score model.
    pub cv_folds: usize,
    /// Seed of the flash orders and the calibration order.
    pub seed: u64,
    /// Choose the stopping rule from the calibration to maximise the expected bit rate
    /// (replacing `rule`); `None` keeps `rule`.
    #[serde(default)]
    pub stopping: Option<StoppingSearch>,
}

impl SessionParams {
    /// The paper's session: four bulbs, 5 rounds, causal 1–15 Hz, 10 calibration decisions
    /// per bulb, 20-sample chunks.
    pub fn paper(pipeline: &str) -> Self {
        let paradigm = FourBulbParams::paper();
        Self {
            paradigm,
            preprocess: Preprocess::online(),
            pipeline: pipeline.to_string(),
            calibration_per_bulb: 10,
            rule: DecisionRule::Fixed {
                rounds: paradigm.n_rounds,
            },
            chunk: 20,
            cv_folds: 5,
            seed: 0,
            stopping: None,
        }
    }

    pub fn validate(&self) -> Result<(), SessionError> {
        self.paradigm.validate()?;
        self.rule.validate()?;
        if let Some(s) = &self.stopping {
            s.validate()?;
        }
        let bad = |name: &'static str, value: usize, reason: &str| {
            Err(SessionError::InvalidParameter {
                name,
                value: value.to_string(),
                reason: reason.into(),
            })
        };
        if self.chunk == 0 {
            return bad("chunk", 0, "at least one sample per chunk");
        }
        if self.cv_folds < 2 {
            return bad("cv_folds", self.cv_folds, "at least 2 folds");
        }
        if self.calibration_per_bulb > MAX_CALIBRATION_PER_BULB {
            return bad(
                "calibration_per_bulb",
                self.calibration_per_bulb,
                &format!("at most {MAX_CALIBRATION_PER_BULB} calibration decisions per bulb"),
            );
        }
        if self.calibration_per_bulb < self.cv_folds.div_ceil(4).max(1) {
            return bad(
                "calibration_per_bulb",
                self.calibration_per_bulb,
                "too few calibration decisions for the folds",
            );
        }
        Ok(())
    }

    /// How many labelled calibration decisions [`Session::calibrate`] runs:
    /// `calibration_per_bulb` for each of the four bulbs.
    pub fn calibration_trials(&self) -> usize {
        CALIBRATION_CODES.len() * self.calibration_per_bulb
    }
}

/// The bulb codes calibration cues, each `calibration_per_bulb` times.
const CALIBRATION_CODES: [u32; 4] = [1, 2, 3, 4];

/// Calibration or online control.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Calibration,
    Online,
}

/// One flash as shown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShownFlash {
    /// Onset, samples from the start of the session.
    pub onset: u64,
    pub code: u32,
    /// Index of its trial in [`SessionLog::trials`].
    pub trial: usize,
    pub round: usize,
    pub attended: bool,
    /// The pipeline's score (online, accepted epochs only).
    pub score: Option<f64>,
    /// The epoch passed the amplitude rejection (`None` until its epoch completed).
    pub accepted: Option<bool>,
}

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum TrialOutcome {
    /// A calibration trial: nothing decided.
    Labelled,
    Chosen {
        code: u32,
    },
    Abstained,
}

impl TrialOutcome {
    /// The decision's confidence given the posterior per bulb (`posterior[code − 1]`): the
    /// posterior of the chosen bulb, or, abstaining, of the best one (0 with none).
    pub fn confidence(&self, posterior: &[f64]) -> f64 {
        match *self {
            TrialOutcome::Chosen { code } => posterior[code as usize - 1],
            _ => posterior.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// One trial (a calibration decision or an online decision).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    pub phase: Phase,
    /// First sample of the countdown.
    pub start: u64,
    /// The sample at which the trial ended (exclusive): the decision was made once the samples
    /// before it had arrived.
    pub end: u64,
    /// Code of the attended bulb (`None`: attending nothing).
    pub intended: Option<u32>,
    pub outcome: TrialOutcome,
    /// Complete rounds the decision used.
    pub rounds: usize,
    /// Posterior per bulb at the decision (empty for calibration), and of "attending nothing".
    pub posterior: Vec<f64>,
    pub p_none: f64,
    /// The arm refused the command (it would leave the board): the reason.
    pub arm_refusal: Option<String>,
    /// Pen position (x, z) in metres when the decision was made, before its command.
    pub pen_m: Option<[f64; 2]>,
}

impl TrialRecord {
    /// The decided code, if any.
    pub fn decided(&self) -> Option<u32> {
        match self.outcome {
            TrialOutcome::Chosen { code } => Some(code),
            _ => None,
        }
    }

    /// Confidence: the posterior of the decided (or, abstaining, the best) bulb.
    pub fn confidence(&self) -> f64 {
        self.outcome.confidence(&self.posterior)
    }
}

/// How far a calibration is, after each of its trials ([`Session::calibrate_with`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CalibrationProgress {
    /// Calibration trials done, of `total`.
    pub done: usize,
    pub total: usize,
    /// Seconds of EEG the calibration has taken so far.
    pub eeg_seconds: f64,
    /// Seconds of EEG the remaining trials should take at this pace.
    pub seconds_left: f64,
}

/// What calibration measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationReport {
    pub n_trials: usize,
    pub n_epochs: usize,
    pub n_targets: usize,
    pub n_rejected: usize,
    /// Epoch ROC-AUC of the cross-validated scores.
    pub cv_auc: f64,
    /// Separation of the cross-validated target and non-target scores, in pooled SDs.
    pub d_prime: f64,
    pub fit_seconds: f64,
}

impl CalibrationReport {
    /// A session that did not calibrate (no trials; AUC and d′ unknown: NaN).
    pub fn none() -> Self {
        Self {
            n_trials: 0,
            n_epochs: 0,
            n_targets: 0,
            n_rejected: 0,
            cv_auc: f64::NAN,
            d_prime: f64::NAN,
            fit_seconds: 0.0,
        }
    }
}

/// Everything a session showed, recorded and decided.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionLog {
    pub sfreq: f64,
    pub ch_names: Vec<String>,
    /// Raw samples as received, `(n_channels, n_times)`, µV.
    pub raw: Array2<f64>,
    pub flashes: Vec<ShownFlash>,
    pub trials: Vec<TrialRecord>,
}

/// Calibration epochs kept for training.
#[derive(Debug, Default)]
struct Calibration {
    epochs: Vec<Array2<f64>>,
    labels: Vec<bool>,
    trials: Vec<usize>,
    /// Index of each epoch's flash.
    flashes: Vec<usize>,
    rejected: usize,
}

/// A running session.
#[derive(Debug)]
pub struct Session<S: Subject> {
    params: SessionParams,
    subject: S,
    epocher: OnlineEpocher,
    rng: ChaCha8Rng,
    raw: Vec<Vec<f64>>,
    flashes: Vec<ShownFlash>,
    trials: Vec<TrialRecord>,
    calibration: Calibration,
    model: Option<Model>,
    arm: Option<ArmSim>,
    /// The arm runs from the first online decision on (it holds still during calibration).
    arm_running: bool,
    /// Drawn onsets refused (see [`Session::refused_onsets`]).
    refused_onsets: u64,
    /// Control without calibration ([`Session::start_uncalibrated`]).
    unlabelled: Option<Unlabelled>,
    /// Online adaptation after a labelled calibration ([`Session::start_adaptation`]).
    adaptation: Option<Adaptation>,
    /// The stopping rule chosen from the calibration, with its expected performance.
    stopping: Option<Expected>,
    /// Rows of the subject's channels the epocher takes, in the model's order (a model set
    /// with other or reordered channels, see [`Session::set_model`]); `None`: all, as they are.
    pick: Option<Vec<usize>>,
    /// The channels' names: the subject's, or a montage's ([`Session::name_channels`]).
    ch_names: Vec<String>,
}

/// A calibrated LDA adapting to the session: the feature rows of the current trial's epochs.
#[derive(Debug)]
struct Adaptation {
    model: AdaptiveLda,
    rows: Vec<f64>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    min_confidence: f64,
    report: AdaptationReport,
}

/// What online adaptation did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AdaptationReport {
    /// Decisions whose epochs the model took in.
    pub accepted: usize,
    /// Updates the drift guard undid.
    pub rejected: usize,
    /// Decisions left out as too unsure.
    pub unsure: usize,
}

impl Adaptation {
    /// Features per row.
    fn model_features(&self) -> usize {
        self.rows.len() / self.codes.len().max(1)
    }
}

/// Settings of a session without calibration: the unsupervised decoder, refitted after every
/// decision on every epoch so far, and how sure it must be to move the arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct UncalibratedParams {
    pub decoder: UnsupervisedParams,
    /// A decision whose best bulb has a smaller posterior abstains (the arm stays still).
    pub abstain_below: f64,
}

impl UncalibratedParams {
    /// The `lda` preset's features at `sfreq`, abstaining below a posterior of 0.9.
    pub fn for_sfreq(sfreq: f64) -> Result<Self, SessionError> {
        Ok(Self {
            decoder: UnsupervisedParams::for_sfreq(sfreq)?,
            abstain_below: 0.9,
        })
    }
}

/// What an uncalibrated session has seen: the feature row, code and trial of every accepted
/// online epoch, and the latest EM fit.
#[derive(Debug)]
struct Unlabelled {
    params: UncalibratedParams,
    constraint: Constraint,
    rows: Vec<f64>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    model: Option<Unsupervised>,
    /// A model from other recordings ([`Session::start_transfer`]) and its score of every epoch.
    transfer: Option<Model>,
    /// Each epoch's score by `transfer`, or (without one) by the [`P300Template`] as this
    /// session's band-pass shows it: where every refit's EM starts.
    start_scores: Vec<f64>,
    template: MatchedTemplate,
}

impl<S: Subject> Session<S> {
    /// A session with `subject`, optionally driving `arm`.
    pub fn new(
        params: SessionParams,
        subject: S,
        arm: Option<ArmSim>,
    ) -> Result<Self, SessionError> {
        params.validate()?;
        let epocher = OnlineEpocher::new(
            &params.preprocess,
            subject.sfreq(),
            subject.ch_names().len(),
        )?;
        let ch_names = subject.ch_names().to_vec();
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(params.seed),
            raw: vec![Vec::new(); subject.ch_names().len()],
            params,
            subject,
            epocher,
            flashes: Vec::new(),
            trials: Vec::new(),
            calibration: Calibration::default(),
            model: None,
            arm,
            arm_running: false,
            refused_onsets: 0,
            unlabelled: None,
            adaptation: None,
            stopping: None,
            pick: None,
            ch_names,
        })
    }

    /// Controls without calibration: the first decision comes from the first trial's epochs,
    /// and after every decision the unsupervised decoder is refitted (EM over "one bulb per
    /// trial", started from the [`P300Template`]'s score of every epoch, the last fit and, once
    /// there are as many epochs as features, random starts) on all online epochs so far — no
    /// label is used.
    pub fn start_uncalibrated(&mut self, params: UncalibratedParams) -> Result<(), SessionError> {
        if !(params.abstain_below > 0.0 && params.abstain_below <= 1.0) {
            return Err(SessionError::InvalidParameter {
                name: "abstain_below",
                value: params.abstain_below.to_string(),
                reason: "a probability in (0, 1]".into(),
            });
        }
        let codes: Vec<u32> = (1..=self.params.paradigm.bulbs.len() as u32).collect();
        self.unlabelled = Some(Unlabelled {
            params,
            constraint: Constraint::one_of(&codes)?,
            rows: Vec::new(),
            codes: Vec::new(),
            trials: Vec::new(),
            model: None,
            transfer: None,
            start_scores: Vec::new(),
            template: P300Template::default()
                .matched(&self.params.preprocess, self.subject.sfreq())?,
        });
        Ok(())
    }

    /// As [`Session::start_uncalibrated`], starting from `model`, fitted on other recordings
    /// (other people, other sessions): its scores of the session's epochs start the EM, which
    /// from then on follows its own last fit only (no random initialisations), so the session
    /// adapts the transferred model instead of searching from scratch.
    pub fn start_transfer(
        &mut self,
        params: UncalibratedParams,
        model: Model,
    ) -> Result<(), SessionError> {
        model.check_layout(&self.ch_names, self.subject.sfreq())?;
        if model.preprocess != self.params.preprocess {
            return Err(SessionError::InvalidParameter {
                name: "transfer model preprocess",
                value: format!("{:?}", model.preprocess),
                reason: "differs from the session's pre-processing".into(),
            });
        }
        self.start_uncalibrated(params)?;
        if let Some(u) = &mut self.unlabelled {
            u.transfer = Some(model);
        }
        Ok(())
    }

    /// After a labelled calibration of the `lda` pipeline: the model adapts online — after each
    /// decision its class means take in the decision's epochs, labelled by the decision (the
    /// person corrects nothing), through incremental statistics ([`AdaptiveLda`]); an update
    /// that turns the weights below a cosine of `min_cosine` with the calibrated ones is undone.
    ///
    /// Only decisions whose posterior reaches `min_confidence` are taken in (a unsure decision
    /// is more often wrong, and a wrong label pulls the means the wrong way).
    pub fn start_adaptation(
        &mut self,
        min_cosine: f64,
        min_confidence: f64,
    ) -> Result<(), SessionError> {
        let model = self.model.as_ref().ok_or(SessionError::NotCalibrated)?;
        let not_lda = || SessionError::InvalidParameter {
            name: "adaptation",
            value: model.pipeline.name().to_string(),
            reason: "online adaptation needs the lda pipeline, calibrated in this session".into(),
        };
        let Classifier::Lda(lda) = model.pipeline.classifier() else {
            return Err(not_lda());
        };
        let y = &self.calibration.labels;
        if !model.pipeline.fused().is_empty() || model.pipeline.pca().is_some() || y.is_empty() {
            return Err(not_lda());
        }
        self.adaptation = Some(Adaptation {
            model: AdaptiveLda::from_lda(lda, y, min_cosine)?,
            rows: Vec::new(),
            codes: Vec::new(),
            trials: Vec::new(),
            min_confidence,
            report: AdaptationReport::default(),
        });
        Ok(())
    }

    /// What online adaptation did so far (`None` without it).
    pub fn adaptation(&self) -> Option<AdaptationReport> {
        self.adaptation.as_ref().map(|a| a.report)
    }

    /// Takes a decided trial's epochs into the adaptive model, labelled by the decision.
    fn adapt(&mut self, trial: usize) -> Result<(), SessionError> {
        let Some(a) = &mut self.adaptation else {
            return Ok(());
        };
        let decided = self.trials[trial].decided();
        let sure = self.trials[trial].confidence() >= a.min_confidence;
        let keep: Vec<usize> = (0..a.trials.len())
            .filter(|&i| a.trials[i] == trial)
            .collect();
        if decided.is_some() && !keep.is_empty() && !sure {
            a.report.unsure += 1;
        }
        if let (Some(code), false, true) = (decided, keep.is_empty(), sure) {
            let p = a.model_features();
            let x =
                ndarray::Array2::from_shape_fn((keep.len(), p), |(r, j)| a.rows[keep[r] * p + j]);
            let y: Vec<bool> = keep.iter().map(|&i| a.codes[i] == code).collect();
            match a.model.update(x.view(), &y)? {
                Update::Accepted { .. } => a.report.accepted += 1,
                Update::Rejected { .. } => a.report.rejected += 1,
            }
        }
        a.rows.clear();
        a.codes.clear();
        a.trials.clear();
        Ok(())
    }

    /// The latest unsupervised fit of an uncalibrated session.
    pub fn unsupervised(&self) -> Option<&Unsupervised> {
        self.unlabelled.as_ref().and_then(|u| u.model.as_ref())
    }

    /// Every online decision of an uncalibrated session re-decided by the latest fit ("post
    /// hoc"): per online trial (index into [`Session::trials`]), the bulb code of highest
    /// posterior and that posterior.
    pub fn redecided(&self) -> Vec<(usize, u32, f64)> {
        let Some(m) = self.unsupervised() else {
            return Vec::new();
        };
        m.trials()
            .iter()
            .map(|t| {
                let p = &t.sets[0];
                let (k, best) = p
                    .iter()
                    .enumerate()
                    .fold(
                        (0, f64::NEG_INFINITY),
                        |b, (i, &v)| if v > b.1 { (i, v) } else { b },
                    );
                (t.trial, k as u32 + 1, best)
            })
            .collect()
    }

    /// Measured onsets refused: a flash reported drawn before the oldest buffered sample (its
    /// epoch could no longer be cut) or more than [`MAX_ONSET_SHIFT_S`] from its planned onset
    /// (its epoch would never complete). The flash loses its epoch like an undrawn one; the
    /// session goes on.
    pub fn refused_onsets(&self) -> u64 {
        self.refused_onsets
    }

    pub fn params(&self) -> &SessionParams {
        &self.params
    }

    /// The stopping rule calibration chose ([`SessionParams::stopping`]) and what it expects.
    pub fn stopping(&self) -> Option<&Expected> {
        self.stopping.as_ref()
    }

    pub fn model(&self) -> Option<&Model> {
        self.model.as_ref()
    }

    /// Names the subject's channels in order (a montage: the stream's own names are not the
    /// model's), before the session's first sample: models are matched to these names,
    /// calibration fits and the session's log carry them.
    pub fn name_channels(&mut self, names: Vec<String>) -> Result<(), SessionError> {
        let taken = self.raw.first().map_or(0, Vec::len);
        if taken > 0 {
            return Err(SessionError::TooLate {
                what: "a montage",
                n_times: taken,
            });
        }
        if names.len() != self.ch_names.len() {
            return Err(SessionError::InvalidParameter {
                name: "montage",
                value: format!("{} names", names.len()),
                reason: format!(
                    "the EEG has {} channels ({:?})",
                    self.ch_names.len(),
                    self.ch_names
                ),
            });
        }
        oddball_signal::check_unique_names(&names)?;
        self.ch_names = names;
        Ok(())
    }

    /// Uses a model trained elsewhere, before the session's first sample: a session's, or one
    /// `oddball train` fitted offline (it must carry a decision model, as format 4 on does).
    /// Its channels are matched by name (the subject may have more, in any order: the session
    /// epochs only the model's, in the model's order). A model trained offline (zero-phase
    /// band-pass) runs its causal fit ([`Model::for_session`]); the model kept, and saved, is
    /// the one that ran, so re-evaluating the session reproduces its decisions.
    pub fn set_model(&mut self, model: Model) -> Result<(), SessionError> {
        let model = model.for_session();
        if model.decision.is_none() {
            return Err(SessionError::NoDecisionModel {
                pipeline: model.pipeline.name().to_string(),
            });
        }
        let sfreq = self.subject.sfreq();
        if (sfreq - model.sfreq).abs() > 1e-9 * model.sfreq {
            return Err(SessionError::ModelRate {
                model_sfreq: model.sfreq,
                stream_sfreq: sfreq,
            });
        }
        let order = model.channel_order(&self.ch_names, sfreq).map_err(|_| {
            SessionError::ModelChannels {
                missing: model
                    .ch_names
                    .iter()
                    .filter(|w| !self.ch_names.iter().any(|h| h.eq_ignore_ascii_case(w)))
                    .cloned()
                    .collect(),
                have: self.ch_names.clone(),
            }
        })?;
        let taken = self.raw.first().map_or(0, Vec::len);
        if taken > 0 {
            return Err(SessionError::TooLate {
                what: "a model",
                n_times: taken,
            });
        }
        self.epocher = OnlineEpocher::new(&model.preprocess, self.subject.sfreq(), order.len())?;
        self.params.preprocess = model.preprocess;
        let identity =
            order.len() == self.ch_names.len() && order.iter().enumerate().all(|(i, &o)| i == o);
        self.pick = (!identity).then_some(order);
        self.model = Some(model);
        Ok(())
    }

    pub fn subject(&self) -> &S {
        &self.subject
    }

    /// Per channel: epochs rejected because of it (NaN, flat or saturated, over threshold).
    pub fn channel_faults(&self) -> &[crate::online::ChannelFaults] {
        self.epocher.channel_faults()
    }

    /// Channels that cost epochs, as text (`P3: 12 flat`), or `None` when all were clean.
    pub fn channel_report(&self) -> Option<String> {
        let names = &self.ch_names;
        let parts: Vec<String> = self
            .channel_faults()
            .iter()
            .zip(names)
            .filter(|(f, _)| f.total() > 0)
            .map(|(f, name)| {
                let mut why = Vec::new();
                for (n, what) in [
                    (f.non_finite, "NaN/inf"),
                    (f.flat, "flat or saturated"),
                    (f.over_threshold, "over threshold"),
                ] {
                    if n > 0 {
                        why.push(format!("{n} {what}"));
                    }
                }
                format!("{name}: {}", why.join(", "))
            })
            .collect();
        (!parts.is_empty()).then(|| format!("epochs rejected by channel: {}", parts.join("; ")))
    }

    pub fn subject_mut(&mut self) -> &mut S {
        &mut self.subject
    }

    pub fn arm(&self) -> Option<&ArmSim> {
        self.arm.as_ref()
    }

    pub fn trials(&self) -> &[TrialRecord] {
        &self.trials
    }

    /// Every flash shown so far, in order.
    pub fn flashes(&self) -> &[ShownFlash] {
        &self.flashes
    }

    /// The accepted calibration epochs (band-passed, as the model saw them), events flagged.
    pub fn calibration_epochs(&self) -> Result<oddball_signal::Epochs, SessionError> {
        let cal = &self.calibration;
        let (n_ch, n_t) = cal.epochs.first().map_or((self.raw.len(), 0), |e| e.dim());
        let mut x = Array3::zeros((cal.epochs.len(), n_ch, n_t));
        for (i, e) in cal.epochs.iter().enumerate() {
            x.index_axis_mut(Axis(0), i).assign(e);
        }
        let events = cal
            .flashes
            .iter()
            .map(|&k| {
                let f = &self.flashes[k];
                oddball_signal::Event::new(f.onset as usize, f.code).with_target(f.attended)
            })
            .collect();
        Ok(oddball_signal::Epochs::new(
            x,
            self.subject.sfreq(),
            self.params.preprocess.tmin,
            self.ch_names.clone(),
            events,
        )?)
    }

    /// Sampling rate of the subject's EEG, Hz.
    pub fn sfreq(&self) -> f64 {
        self.subject.sfreq()
    }

    /// Seconds of EEG so far.
    pub fn time_s(&self) -> f64 {
        self.subject.position() as f64 / self.subject.sfreq()
    }

    /// Passes over a recorded calibration of `n_trials` trials ending at sample `until` (a
    /// replayed session recording, with a model set): its samples are filtered but no flash is
    /// shown and nothing decided, and the flash orders are drawn as the calibration drew them,
    /// so with the recording's seed every later flash falls where the recorded session's did.
    pub fn pass_calibration(&mut self, n_trials: usize, until: u64) -> Result<(), SessionError> {
        if n_trials % 4 != 0 {
            return Err(SessionError::InvalidParameter {
                name: "recorded calibration trials",
                value: n_trials.to_string(),
                reason: "a calibration has as many trials for each of the four bulbs".into(),
            });
        }
        let mut intended: Vec<u32> = (1..=4)
            .flat_map(|c| std::iter::repeat_n(c, n_trials / 4))
            .collect();
        intended.shuffle(&mut self.rng);
        for _ in &intended {
            self.params
                .paradigm
                .trial(&mut self.rng, self.params.paradigm.n_rounds);
        }
        while self.subject.position() < until {
            let n = (until - self.subject.position()).min(self.params.chunk as u64);
            self.advance(n as usize)?;
        }
        Ok(())
    }

    /// Runs the calibration trials and trains the model.
    pub fn calibrate(&mut self) -> Result<CalibrationReport, SessionError> {
        self.calibrate_with(&mut |_| {})
    }

    /// [`Self::calibrate`], telling `progress` after each calibration trial how far it is (for
    /// a live or real-time calibration, which takes minutes).
    pub fn calibrate_with(
        &mut self,
        progress: &mut dyn FnMut(CalibrationProgress),
    ) -> Result<CalibrationReport, SessionError> {
        let mut intended: Vec<u32> = CALIBRATION_CODES
            .into_iter()
            .flat_map(|c| std::iter::repeat_n(c, self.params.calibration_per_bulb))
            .collect();
        intended.shuffle(&mut self.rng);
        let first = self.trials.len();
        let total = intended.len();
        let t0 = self.time_s();
        for (k, code) in intended.into_iter().enumerate() {
            self.run_trial(Phase::Calibration, Some(code))?;
            let eeg_seconds = self.time_s() - t0;
            progress(CalibrationProgress {
                done: k + 1,
                total,
                eeg_seconds,
                seconds_left: eeg_seconds / (k + 1) as f64 * (total - k - 1) as f64,
            });
        }
        self.train(first)
    }

    /// Fits the preset on the calibration epochs, the score model on cross-validated scores.
    fn train(&mut self, first_trial: usize) -> Result<CalibrationReport, SessionError> {
        let t0 = std::time::Instant::now();
        let cal = &self.calibration;
        let n = cal.epochs.len();
        let (n_ch, n_t) = cal.epochs.first().map_or((0, 0), |e| e.dim());
        let mut x = Array3::zeros((n, n_ch, n_t));
        for (i, e) in cal.epochs.iter().enumerate() {
            x.index_axis_mut(Axis(0), i).assign(e);
        }
        let y = &cal.labels;
        let sfreq = self.subject.sfreq();
        let groups: Vec<usize> = cal.trials.iter().map(|&t| t - first_trial).collect();
        let (mut model, cv_auc, d_prime, oof) = fit_session_model_oof(
            &self.params.pipeline,
            self.params.preprocess,
            self.params.rule,
            self.params.cv_folds,
            sfreq,
            &self.ch_names,
            x.view().into(),
            y,
            &groups,
        )?;
        if let (Some(search), Some(decision)) = (&self.params.stopping, &mut model.decision) {
            let chosen = crate::timing::choose_stopping(
                search,
                &decision.scores,
                &oof,
                y,
                &self.params.paradigm,
                &self.params.preprocess,
            )?;
            decision.rule = chosen.rule;
            self.params.rule = chosen.rule;
            self.stopping = Some(chosen);
        }
        self.model = Some(model);
        Ok(CalibrationReport {
            n_trials: self.trials.len() - first_trial,
            n_epochs: n,
            n_targets: y.iter().filter(|&&t| t).count(),
            n_rejected: cal.rejected,
            cv_auc,
            d_prime,
            fit_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// One online decision while the person attends `intended` (`None`: attends nothing).
    pub fn decide(&mut self, intended: Option<Command>) -> Result<TrialRecord, SessionError> {
        if self.model.is_none() && self.unlabelled.is_none() {
            return Err(SessionError::NotCalibrated);
        }
        let code = intended.map(|c| self.params.paradigm.code_of(c));
        self.arm_running = true;
        let i = self.run_trial(Phase::Online, code)?;
        Ok(self.trials[i].clone())
    }

    /// Lets the arm finish its last movement: runs `seconds` more of EEG and arm.
    pub fn idle(&mut self, seconds: f64) -> Result<(), SessionError> {
        let n = (seconds * self.subject.sfreq()).round() as usize;
        let mut done = 0;
        while done < n {
            let c = self.params.chunk.min(n - done);
            self.advance(c)?;
            done += c;
        }
        Ok(())
    }

    /// Ends the session and hands back its subject (a live one closes its recording).
    pub fn into_subject(self) -> S {
        self.subject
    }

    /// Ends the session, returning its log, the model and the arm.
    pub fn finish(self) -> (SessionLog, Option<Model>, Option<ArmSim>) {
        let n_ch = self.raw.len();
        let n_t = self.raw.first().map_or(0, Vec::len);
        let mut raw = Array2::zeros((n_ch, n_t));
        for (c, r) in self.raw.iter().enumerate() {
            raw.row_mut(c)
                .assign(&ndarray::ArrayView1::from(r.as_slice()));
        }
        (
            SessionLog {
                sfreq: self.subject.sfreq(),
                ch_names: self.ch_names,
                raw,
                flashes: self.flashes,
                trials: self.trials,
            },
            self.model,
            self.arm,
        )
    }

    /// Renders one chunk, feeds the epocher, records, runs the arm; handles completed epochs.
    fn advance(&mut self, n: usize) -> Result<(), SessionError> {
        let data = self.subject.render(n)?;
        for (r, row) in self.raw.iter_mut().zip(data.rows()) {
            r.extend(row.iter());
        }
        for d in self.subject.drawn() {
            self.retime(d)?;
        }
        let ready = match &self.pick {
            Some(rows) => self
                .epocher
                .push_samples(data.select(Axis(0), rows).view())?,
            None => self.epocher.push_samples(data.view())?,
        };
        if let (Some(arm), true) = (&mut self.arm, self.arm_running) {
            arm.run_for(n as f64 / self.subject.sfreq())?;
            self.subject.arm_state(self.subject.position(), arm)?;
        }
        for e in ready {
            let f = &mut self.flashes[e.marker.tag];
            f.accepted = Some(e.accepted);
            match self.trials[f.trial].phase {
                Phase::Calibration => {
                    if e.accepted {
                        self.calibration.epochs.push(e.data);
                        self.calibration.labels.push(f.attended);
                        self.calibration.trials.push(f.trial);
                        self.calibration.flashes.push(e.marker.tag);
                    } else {
                        self.calibration.rejected += 1;
                    }
                }
                Phase::Online => {
                    if let (true, Some(u)) = (e.accepted, &mut self.unlabelled) {
                        let row = u
                            .params
                            .decoder
                            .features
                            .transform(e.data.view().insert_axis(Axis(0)))?;
                        if let Some(t) = &u.transfer {
                            let score = t.pipeline.score_epoch(e.data.view())?;
                            u.start_scores.push(score);
                            f.score = Some(score);
                        } else {
                            u.start_scores.push(u.template.score(e.data.view())?);
                        }
                        if let Some(m) = &u.model {
                            f.score = Some(m.decision_function_features(row.view())?[0]);
                        }
                        u.rows.extend(row.iter());
                        u.codes.push(f.code);
                        u.trials.push(f.trial);
                    } else if let (true, Some(a)) = (e.accepted, &mut self.adaptation) {
                        let model = self.model.as_ref().ok_or(SessionError::NotCalibrated)?;
                        let row = model
                            .pipeline
                            .features(e.data.view().insert_axis(Axis(0)))?
                            .into_rows("adaptive LDA")?;
                        f.score = Some(a.model.decision_function(row.view())?[0]);
                        a.rows.extend(row.iter());
                        a.codes.push(f.code);
                        a.trials.push(f.trial);
                    } else if e.accepted {
                        let model = self.model.as_ref().ok_or(SessionError::NotCalibrated)?;
                        f.score = Some(model.pipeline.score_epoch(e.data.view())?);
                    }
                }
            }
        }
        Ok(())
    }

    /// Moves a flash's marker to its measured onset, or voids its epoch when it was never drawn
    /// or its measured onset is refused (see [`Session::refused_onsets`]).
    fn retime(&mut self, d: Drawn) -> Result<(), SessionError> {
        let Some(k) = self
            .flashes
            .iter()
            .rposition(|f| f.onset == d.planned && f.code == d.code && f.accepted.is_none())
        else {
            return Ok(());
        };
        let max_shift = (MAX_ONSET_SHIFT_S * self.subject.sfreq()).ceil() as u64;
        match d.onset {
            Some(onset) if onset.abs_diff(d.planned) > max_shift => {
                self.refused_onsets += 1;
                if self.epocher.cancel(k) {
                    self.flashes[k].accepted = Some(false);
                }
            }
            Some(onset) if onset != d.planned => match self.epocher.retime(k, onset) {
                Ok(true) => self.flashes[k].onset = onset,
                Ok(false) => {}
                Err(SessionError::MarkerTooLate { .. }) => {
                    self.refused_onsets += 1;
                    if self.epocher.cancel(k) {
                        self.flashes[k].accepted = Some(false);
                    }
                }
                Err(e) => return Err(e),
            },
            Some(_) => {}
            None => {
                if self.epocher.cancel(k) {
                    self.flashes[k].accepted = Some(false);
                }
            }
        }
        Ok(())
    }

    /// Runs one trial to its end; returns its index.
    fn run_trial(&mut self, phase: Phase, intended: Option<u32>) -> Result<usize, SessionError> {
        let p = self.params.paradigm;
        let sfreq = self.subject.sfreq();
        // An operator's pause holds here, between trials: the EEG (and the arm) run on, no
        // trial starts and nothing flashes.
        while self.subject.hold()? {
            self.advance(self.params.chunk)?;
        }
        let n_rounds = match phase {
            Phase::Calibration => p.n_rounds,
            Phase::Online => self.params.rule.max_rounds(),
        };
        let schedule = p.trial(&mut self.rng, n_rounds);
        let start = self.subject.position();
        let trial = self.trials.len();
        self.trials.push(TrialRecord {
            phase,
            start,
            end: start,
            intended,
            outcome: TrialOutcome::Labelled,
            rounds: 0,
            posterior: Vec::new(),
            p_none: 0.0,
            arm_refusal: None,
            pen_m: None,
        });
        self.subject.trial_started(start, phase, intended)?;
        let planned: Vec<(u64, u32, usize)> = schedule
            .flashes
            .iter()
            .map(|f| (start + (f.onset_s * sfreq).round() as u64, f.code, f.round))
            .collect();
        let first_flash = self.flashes.len();
        let mut next = 0;
        loop {
            let pos = self.subject.position();
            let end = pos + self.params.chunk as u64 + self.subject.lead();
            while next < planned.len() && planned[next].0 < end {
                let (onset, code, round) = planned[next];
                let attended = intended == Some(code);
                self.subject.show(onset, code, attended)?;
                self.epocher.push_marker(Marker {
                    onset,
                    code,
                    tag: self.flashes.len(),
                })?;
                self.flashes.push(ShownFlash {
                    onset,
                    code,
                    trial,
                    round,
                    attended,
                    score: None,
                    accepted: None,
                });
                next += 1;
            }
            self.advance(self.params.chunk)?;
            let shown = &self.flashes[first_flash..];
            match phase {
                Phase::Calibration => {
                    if next == planned.len() && shown.iter().all(|f| f.accepted.is_some()) {
                        self.trials[trial].rounds = n_rounds;
                        break;
                    }
                }
                Phase::Online if self.unlabelled.is_some() => {
                    if next == planned.len() && shown.iter().all(|f| f.accepted.is_some()) {
                        let verdict = self.decide_unlabelled(trial)?;
                        self.conclude(trial, verdict, n_rounds)?;
                        break;
                    }
                }
                Phase::Online => {
                    let rounds = complete_rounds(shown);
                    let decision = self
                        .model
                        .as_ref()
                        .and_then(|m| m.decision)
                        .ok_or(SessionError::NotCalibrated)?;
                    let (verdict, used) = decision.decide(&rounds);
                    if verdict != Verdict::Continue || rounds.len() == n_rounds {
                        self.conclude(trial, verdict, used)?;
                        self.adapt(trial)?;
                        break;
                    }
                }
            }
        }
        self.trials[trial].end = self.subject.position();
        self.subject.trial_ended(&self.trials[trial])?;
        self.subject.channel_faults(self.epocher.channel_faults())?;
        Ok(trial)
    }

    /// Refits the unsupervised decoder on every online epoch so far and decides `trial` with it.
    fn decide_unlabelled(&mut self, trial: usize) -> Result<Verdict, SessionError> {
        let u = self
            .unlabelled
            .as_mut()
            .ok_or(SessionError::NotCalibrated)?;
        let n_stimuli = u.constraint.sets()[0].len();
        let none = |p: Vec<f64>| Verdict::Abstain {
            posterior: oddball_decode::decision::Posterior { p, p_none: 0.0 },
        };
        let uniform = vec![1.0 / n_stimuli as f64; n_stimuli];
        // Two epochs at least, and some from this trial, or there is nothing to decide from.
        if u.codes.len() < 2 || u.trials.last() != Some(&trial) {
            return Ok(none(uniform));
        }
        let n = u.codes.len();
        let x = ndarray::ArrayView2::from_shape((n, u.rows.len() / n), &u.rows).map_err(|e| {
            SessionError::InvalidParameter {
                name: "feature rows",
                value: u.rows.len().to_string(),
                reason: e.to_string(),
            }
        })?;
        // EM from a transferred model's scores of every epoch so far; or from the P300
        // template's, the last fit and (once there are as many epochs as features) random
        // starts, the likeliest kept.
        let fit = match (&u.transfer, &u.model) {
            (Some(_), _) => u.params.decoder.fit_from_scores(
                x,
                &u.codes,
                &u.trials,
                &u.constraint,
                &u.start_scores,
            ),
            (None, warm) => u.params.decoder.fit_features_from(
                x,
                &u.codes,
                &u.trials,
                &u.constraint,
                warm.as_ref(),
                Some(&u.start_scores),
            ),
        };
        let fitted = match fit {
            Ok(m) => m,
            // Too little data to separate anything yet: keep the arm still.
            Err(oddball_decode::unsupervised::UnsupervisedError::Degenerate { .. })
            | Err(oddball_decode::unsupervised::UnsupervisedError::NotPositiveDefinite {
                ..
            }) => return Ok(none(uniform)),
            Err(e) => return Err(e.into()),
        };
        let p = fitted
            .averaged_trials()
            .iter()
            .find(|t| t.trial == trial)
            .map_or(uniform, |t| t.sets[0].clone());
        u.model = Some(fitted);
        let posterior = oddball_decode::decision::Posterior { p, p_none: 0.0 };
        let (index, best) = posterior.best();
        Ok(if best >= u.params.abstain_below {
            Verdict::Choose { index, posterior }
        } else {
            Verdict::Abstain { posterior }
        })
    }

    fn conclude(
        &mut self,
        trial: usize,
        verdict: Verdict,
        used: usize,
    ) -> Result<(), SessionError> {
        let t = &mut self.trials[trial];
        t.rounds = used;
        t.pen_m = self.arm.as_ref().map(|a| [a.pen()[0], a.pen()[1]]);
        match verdict {
            Verdict::Choose { index, posterior } => {
                t.outcome = TrialOutcome::Chosen {
                    code: index as u32 + 1,
                };
                t.posterior = posterior.p;
                t.p_none = posterior.p_none;
                let command = self
                    .params
                    .paradigm
                    .command_of(index as u32 + 1)
                    .expect("four bulbs");
                if let Some(arm) = &mut self.arm {
                    if let Err(e) = arm.issue(command) {
                        t.arm_refusal = Some(e.to_string());
                    }
                }
            }
            Verdict::Abstain { posterior } => {
                t.outcome = TrialOutcome::Abstained;
                t.posterior = posterior.p;
                t.p_none = posterior.p_none;
            }
            Verdict::Continue => {
                // Rounds ran out without a verdict (cannot happen with a valid rule).
                t.outcome = TrialOutcome::Abstained;
            }
        }
        Ok(())
    }
}

/// Fits the preset on labelled epochs `x` and its score model on out-of-fold scores: fold `g % k`
/// holds the epochs of group `g` (a trial or a spelled character), so overlapping epochs of one
/// group never straddle a split. Returns the model with its decision rule, the cross-validated
/// AUC, the scores' d′ and the out-of-fold scores themselves (what stopping is chosen from).
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_session_model_oof(
    pipeline: &str,
    preprocess: oddball_decode::pipeline::Preprocess,
    rule: DecisionRule,
    folds: usize,
    sfreq: f64,
    ch_names: &[String],
    x: EpochSource<'_>,
    y: &[bool],
    groups: &[usize],
) -> Result<(Model, f64, f64, Vec<f64>), SessionError> {
    let params = PipelineParams::preset(pipeline, sfreq)?;
    let k = folds.max(2);
    let mut oof = vec![0.0; y.len()];
    // A front that learns nothing is computed once for every fold and the final fit; epochs
    // held as windows are read a part at a time (the scores are those of fitting on copies).
    let mut cache = FrontCache::new(x);
    for fold in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) =
            (0..y.len()).partition(|&i| groups[i] % k == fold);
        if test.is_empty() || train.is_empty() {
            continue;
        }
        let ytr: Vec<bool> = train.iter().map(|&i| y[i]).collect();
        let gtr: Vec<usize> = train.iter().map(|&i| groups[i]).collect();
        let s = params
            .fit_score_cached(&mut cache, &train, &ytr, Some(&gtr), &test)?
            .scores;
        for (&i, &v) in test.iter().zip(s.iter()) {
            oof[i] = v;
        }
    }
    let cv_auc = roc_auc(&oof, y)?;
    let scores = ScoreModelParams::default().fit(&oof, y)?;
    let mut model = Model::new(
        preprocess,
        sfreq,
        ch_names.to_vec(),
        params.fit_cached(&mut cache, y, Some(groups))?,
    );
    model.decision = Some(DecisionModel { scores, rule });
    Ok((model, cv_auc, scores.d_prime(), oof))
}

/// The scores of a trial's complete rounds, in order, stopping at the first incomplete one:
/// `rounds[r][code − 1]`, `None` for a rejected epoch. A round is complete when all four of its
/// flashes have their epoch.
pub fn complete_rounds(flashes: &[ShownFlash]) -> Vec<Vec<Option<f64>>> {
    let mut rounds: Vec<Vec<Option<f64>>> = Vec::new();
    let mut seen: Vec<usize> = Vec::new();
    for f in flashes {
        if f.round >= rounds.len() {
            rounds.resize(f.round + 1, vec![None; 4]);
            seen.resize(f.round + 1, 0);
        }
        if f.accepted.is_some() && (1..=4).contains(&f.code) {
            rounds[f.round][f.code as usize - 1] = f.score;
            seen[f.round] += 1;
        }
    }
    let n_complete = seen.iter().take_while(|&&n| n == 4).count();
    rounds.truncate(n_complete);
    rounds
}
