//! How a session decides online, and how it starts deciding.
//!
//! A session starts once, one of three ways ([`Start`]): it calibrates (and may then adapt its
//! `lda` online, [`AdaptParams`]), it decides with a model trained elsewhere, or it starts
//! without calibration (the unsupervised decoder, optionally from a transferred model). Each
//! start leaves the engine one `OnlineDecoder`; the engine asks it to score each online epoch,
//! to decide a trial without labels, and to adapt after a decision.

use ndarray::{ArrayView2, Axis};
use oddball_decode::adaptive::{AdaptiveLda, Update};
use oddball_decode::classifiers::Classifier;
use oddball_decode::decision::{DecisionModel, DecisionRule, Posterior, ScoreModel, Verdict};
use oddball_decode::pipeline::{Model, Preprocess};
pub use oddball_decode::preset::Preset;
use oddball_decode::stopping::StoppingSearch;
use oddball_decode::unsupervised::{
    Constraint, MatchedTemplate, P300Template, Unsupervised, UnsupervisedError, UnsupervisedParams,
};
use serde::{Deserialize, Serialize};

use crate::decision::TrialRecord;
use crate::prequential::HonestParams;
use crate::SessionError;

/// The decoder settings a session ([`crate::engine::SessionParams`]) and a replay
/// ([`crate::replay::ReplayParams`]) share: the pipeline fitted, its pre-processing, the
/// decision rule, the folds of its score model, the stream's chunks and the seed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecoderParams {
    /// The pipeline preset.
    pub pipeline: Preset,
    pub preprocess: Preprocess,
    /// The online decision rule (fixed rounds, or dynamic stopping).
    pub rule: DecisionRule,
    /// Cross-validation folds for the score model.
    pub cv_folds: usize,
    /// Samples per streamed chunk.
    pub chunk: usize,
    /// Seed of the flash orders and the calibration order (a session), of the non-target
    /// choice and the bulb assignment (a replay).
    pub seed: u64,
    /// Choose the stopping rule from the calibration to maximise the expected bit rate
    /// (replacing `rule`); `None` keeps `rule`.
    #[serde(default)]
    pub stopping: Option<StoppingSearch>,
}

impl DecoderParams {
    /// The paper's decoder for `pipeline` on `paradigm`: causal 1–15 Hz band-pass, the
    /// paradigm's rounds fixed, 20-sample chunks, 5 folds, seed 0, no stopping search.
    pub fn paper(pipeline: Preset, paradigm: &crate::paradigm::FourBulbParams) -> Self {
        Self {
            pipeline,
            preprocess: Preprocess::online(),
            rule: DecisionRule::Fixed {
                rounds: paradigm.n_rounds,
            },
            chunk: 20,
            cv_folds: 5,
            seed: 0,
            stopping: None,
        }
    }
}

/// How a session starts deciding ([`crate::engine::Session::start`]); a session starts once.
#[derive(Debug, Clone)]
pub enum Start {
    /// Labelled calibration decisions, a model fitted on them; with `adapt`, the calibrated
    /// `lda` then adapts online.
    Calibrate { adapt: Option<AdaptParams> },
    /// A model trained elsewhere (see [`crate::engine::Session::start`] for how it is matched).
    Model(Model),
    /// No calibration: the unsupervised decoder learns from the session itself, its EM started
    /// from `transfer`'s scores when a model of other recordings is given. `params: None`
    /// takes [`UncalibratedParams::for_sfreq`] at the session's rate.
    Uncalibrated {
        params: Option<Box<UncalibratedParams>>,
        transfer: Option<Model>,
    },
}

/// Online adaptation of a calibrated `lda`: after each decision its class means take in the
/// decision's epochs, labelled by the decision (the person corrects nothing), through
/// incremental statistics ([`AdaptiveLda`]); an update that turns the weights below a cosine of
/// `min_cosine` with the calibrated ones is undone. Only decisions whose posterior reaches
/// `min_confidence` are taken in (an unsure decision is more often wrong, and a wrong label
/// pulls the means the wrong way).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdaptParams {
    pub min_cosine: f64,
    pub min_confidence: f64,
}

impl Default for AdaptParams {
    /// Cosine 0.8, posterior 0.9.
    fn default() -> Self {
        Self {
            min_cosine: 0.8,
            min_confidence: 0.9,
        }
    }
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

/// Settings of a session without calibration: the unsupervised decoder, refitted after every
/// decision on the epochs of the last `max_trials` trials, and how sure it must be to move the
/// arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct UncalibratedParams {
    pub decoder: UnsupervisedParams,
    /// A decision whose best bulb has a smaller posterior abstains (the arm stays still).
    pub abstain_below: f64,
    /// The refits use the epochs of the last `max_trials` trials at most (older ones are
    /// dropped): what the session holds, and each refit's time, stop growing with its length.
    /// [`DEFAULT_MAX_TRIALS`] is about 50 minutes of the paper's timing.
    #[serde(default = "default_max_trials")]
    pub max_trials: usize,
    /// How dynamic stopping weighs the evidence of a trial: its scores by the model fitted
    /// before it, through a score model of out-of-sample (leave-one-trial-out) scores
    /// ([`crate::prequential`]).
    #[serde(default)]
    pub honest: HonestParams,
    /// How much longer the first trials run, while the decoder has few epochs to learn from
    /// (off in settings saved before this field existed).
    #[serde(default = "LearningRounds::off")]
    pub learning: LearningRounds,
    /// A session's online pre-processing while it runs without calibration, unless a
    /// transferred model starts it (the session then epochs as that model was trained, a
    /// zero-phase band run causally): [`Preprocess::online_unsupervised`] by default; `None`
    /// keeps the session's (as in settings saved before this field existed). `oddball decode`'s listener keeps its
    /// own (the same band, causal, and the paradigm's window).
    #[serde(default)]
    pub preprocess: Option<Preprocess>,
}

/// The first trials of an uncalibrated session (without a transferred model) run `factor` times
/// the decision rule's most rounds while the decoder holds fewer than `epochs_per_feature`
/// epochs per feature of its EM. With few trials the EM can pick any of very many labellings
/// (four bulbs: 4^T for T trials), and with about as many epochs as features some wrong one
/// fits the noise best: a
/// confident, wrong decision the warm start then follows for several trials. Longer trials give
/// each labelling more epochs, so fewer labellings reach the same data, and the session learns
/// from fewer, surer trials. On the simulated typical subject at the fast timing (tuning seeds
/// 11–20, 40 decisions): 79.3 % right and 44.8 bits in the first 5 minutes on average without
/// it, 91.3 % and 64.6 bits with the default (3×, below 2 epochs per feature); 1× below 1, 2×
/// below 2 and 3× below 1 gave 85.3/59.1, 89.5/62.0 and 86.8/56.6.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LearningRounds {
    /// Rounds of a learning trial, in multiples of the rule's most rounds (1: off).
    pub factor: usize,
    /// Trials are learning trials while the decoder holds fewer epochs per EM feature.
    pub epochs_per_feature: f64,
}

impl Default for LearningRounds {
    /// 3× the rounds below 2 epochs per feature.
    fn default() -> Self {
        Self {
            factor: 3,
            epochs_per_feature: 2.0,
        }
    }
}

impl LearningRounds {
    /// Every trial runs the rule's rounds.
    pub fn off() -> Self {
        Self {
            factor: 1,
            epochs_per_feature: 0.0,
        }
    }

    fn check(&self) -> Result<(), SessionError> {
        if !(1..=10).contains(&self.factor) {
            return Err(SessionError::InvalidParameter {
                name: "learning.factor",
                value: self.factor.to_string(),
                reason: "1 (off) to 10 times the rule's rounds".into(),
            });
        }
        if !(self.epochs_per_feature >= 0.0 && self.epochs_per_feature.is_finite()) {
            return Err(SessionError::InvalidParameter {
                name: "learning.epochs_per_feature",
                value: self.epochs_per_feature.to_string(),
                reason: "a finite number, 0 or more".into(),
            });
        }
        Ok(())
    }
}

/// The trials an uncalibrated session refits on at most, by default.
pub const DEFAULT_MAX_TRIALS: usize = 300;

fn default_max_trials() -> usize {
    DEFAULT_MAX_TRIALS
}

impl UncalibratedParams {
    /// The `lda` preset's features at `sfreq`, abstaining below a posterior of 0.9.
    pub fn for_sfreq(sfreq: f64) -> Result<Self, SessionError> {
        Ok(Self {
            decoder: UnsupervisedParams::for_sfreq(sfreq)?,
            abstain_below: 0.9,
            max_trials: DEFAULT_MAX_TRIALS,
            honest: HonestParams::default(),
            learning: LearningRounds::default(),
            preprocess: Some(Preprocess::online_unsupervised()),
        })
    }

    fn check(&self) -> Result<(), SessionError> {
        self.honest.check()?;
        self.learning.check()?;
        if !(self.abstain_below > 0.0 && self.abstain_below <= 1.0) {
            return Err(SessionError::InvalidParameter {
                name: "abstain_below",
                value: self.abstain_below.to_string(),
                reason: "a probability in (0, 1]".into(),
            });
        }
        if self.max_trials < 2 {
            return Err(SessionError::InvalidParameter {
                name: "max_trials",
                value: self.max_trials.to_string(),
                reason: "the refits need two trials at least".into(),
            });
        }
        Ok(())
    }
}

/// Where `model`'s channels are among `ch_names` (matched by name, case aside; the stream may
/// have more, in any order), refusing a model of another rate.
pub(crate) fn model_channels(
    model: &Model,
    ch_names: &[String],
    sfreq: f64,
) -> Result<Vec<usize>, SessionError> {
    if !oddball_signal::rate::same_sfreq(sfreq, model.sfreq) {
        return Err(SessionError::ModelRate {
            model_sfreq: model.sfreq,
            stream_sfreq: sfreq,
        });
    }
    model
        .channel_order(ch_names, sfreq)
        .map_err(|_| SessionError::ModelChannels {
            missing: model
                .ch_names
                .iter()
                .filter(|w| !ch_names.iter().any(|h| h.eq_ignore_ascii_case(w)))
                .cloned()
                .collect(),
            have: ch_names.to_vec(),
        })
}

/// The decoder a session decides with once started.
#[derive(Debug)]
pub(crate) enum OnlineDecoder {
    /// Not started: nothing decides (a calibration may be running).
    Unstarted,
    /// A model calibrated in this session or trained elsewhere.
    Fixed(Model),
    /// A calibrated `lda` adapting online.
    Adaptive {
        model: Model,
        adaptation: Box<Adaptation>,
    },
    /// No calibration: the unsupervised decoder.
    Unlabelled(Box<Unlabelled>),
}

/// A calibrated LDA adapting to the session: the feature rows of the current trial's epochs.
#[derive(Debug)]
pub(crate) struct Adaptation {
    model: AdaptiveLda,
    rows: Vec<f64>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    min_confidence: f64,
    report: AdaptationReport,
}

/// What an uncalibrated session has seen: the feature row, code and trial of every accepted
/// online epoch, and the latest EM fit.
#[derive(Debug)]
pub(crate) struct Unlabelled {
    params: UncalibratedParams,
    constraint: Constraint,
    rows: Vec<f64>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    /// The score model of the latest fit's out-of-sample scores of the last trials
    /// ([`crate::prequential`]), after the latest refit.
    honest: Option<ScoreModel>,
    model: Option<Unsupervised>,
    /// A model from other recordings and its score of every epoch.
    transfer: Option<Model>,
    /// Each epoch's score by `transfer`, or (without one) by the [`P300Template`] as this
    /// session's band-pass shows it: where every refit's EM starts.
    start_scores: Vec<f64>,
    template: MatchedTemplate,
}

impl Unlabelled {
    /// Controls without calibration: the first decision comes from the first trial's epochs,
    /// and after every decision the unsupervised decoder is refitted (EM over "one bulb per
    /// trial", started from the [`P300Template`]'s score of every epoch, the last fit and, once
    /// there are as many epochs as features, random starts) on all online epochs so far — no
    /// label is used.
    ///
    /// With `transfer`, a model fitted on other recordings (other people, other sessions): its
    /// scores of the session's epochs start the EM, which from then on follows its own last fit
    /// only (no random initialisations), so the session adapts the transferred model instead of
    /// searching from scratch.
    ///
    /// `constraint` says which codes compete in a trial (the panel's bulbs: one of them; a
    /// speller: one row and one column).
    pub(crate) fn new(
        params: UncalibratedParams,
        transfer: Option<Model>,
        constraint: Constraint,
        preprocess: &Preprocess,
        sfreq: f64,
    ) -> Result<Self, SessionError> {
        params.check()?;
        Ok(Self {
            params,
            constraint,
            rows: Vec::new(),
            codes: Vec::new(),
            trials: Vec::new(),
            honest: None,
            model: None,
            transfer,
            start_scores: Vec::new(),
            template: P300Template::default().matched(preprocess, sfreq)?,
        })
    }
}

impl Unlabelled {
    /// A decision whose best choice has a smaller posterior abstains.
    pub(crate) fn abstain_below(&self) -> f64 {
        self.params.abstain_below
    }

    /// Features per feature row (0 before the first epoch).
    fn n_features(&self) -> usize {
        self.rows.len() / self.codes.len().max(1)
    }

    /// Epochs held per EM feature (0 before the first epoch).
    fn epochs_per_feature(&self) -> f64 {
        match self.n_features() {
            0 => 0.0,
            p => self.codes.len() as f64 / p as f64,
        }
    }

    /// Drops the epochs of all but the last `max_trials` trials (trials arrive in order).
    fn keep_last_trials(&mut self) {
        let mut seen = 0;
        let mut prev = None;
        let mut cut = 0;
        for (i, &t) in self.trials.iter().enumerate().rev() {
            if prev != Some(t) {
                seen += 1;
                prev = Some(t);
            }
            if seen > self.params.max_trials {
                cut = i + 1;
                break;
            }
        }
        if cut > 0 {
            let p = self.rows.len() / self.trials.len();
            self.rows.drain(..cut * p);
            self.codes.drain(..cut);
            self.trials.drain(..cut);
            self.start_scores.drain(..cut);
        }
    }
}

impl Adaptation {
    /// Adaptation of `model` (the `lda` pipeline calibrated in this session on labels `y`).
    pub(crate) fn new(model: &Model, y: &[bool], p: AdaptParams) -> Result<Self, SessionError> {
        let not_lda = || SessionError::InvalidParameter {
            name: "adaptation",
            value: model.pipeline.name().to_string(),
            reason: "online adaptation needs the lda pipeline, calibrated in this session".into(),
        };
        let Classifier::Lda(lda) = model.pipeline.classifier() else {
            return Err(not_lda());
        };
        if !model.pipeline.fused().is_empty() || model.pipeline.pca().is_some() || y.is_empty() {
            return Err(not_lda());
        }
        Ok(Self {
            model: AdaptiveLda::from_lda(lda, y, p.min_cosine)?,
            rows: Vec::new(),
            codes: Vec::new(),
            trials: Vec::new(),
            min_confidence: p.min_confidence,
            report: AdaptationReport::default(),
        })
    }

    /// Features per row.
    fn model_features(&self) -> usize {
        self.rows.len() / self.codes.len().max(1)
    }
}

impl OnlineDecoder {
    /// The model deciding (calibrated or given; `None` before the start and without
    /// calibration).
    pub(crate) fn model(&self) -> Option<&Model> {
        match self {
            Self::Fixed(model) | Self::Adaptive { model, .. } => Some(model),
            Self::Unstarted | Self::Unlabelled(_) => None,
        }
    }

    pub(crate) fn into_model(self) -> Option<Model> {
        match self {
            Self::Fixed(model) | Self::Adaptive { model, .. } => Some(model),
            Self::Unstarted | Self::Unlabelled(_) => None,
        }
    }

    pub(crate) fn is_started(&self) -> bool {
        !matches!(self, Self::Unstarted)
    }

    /// The settings of an uncalibrated decoder (`None` for any other).
    pub(crate) fn uncalibrated_params(&self) -> Option<&UncalibratedParams> {
        match self {
            Self::Unlabelled(u) => Some(&u.params),
            _ => None,
        }
    }

    /// The learning trials this decoder runs ([`LearningRounds`]): an uncalibrated one's, unless
    /// a transferred model starts it (its EM follows that model's scores, with no random starts
    /// to land on a wrong labelling: the paper's G from seed 2's model on seeds 1, 3, 4, 5 was
    /// 6/6 each either way, and 40 s longer with learning trials).
    pub(crate) fn learning(&self) -> Option<LearningRounds> {
        match self {
            Self::Unlabelled(u) if u.transfer.is_none() && u.params.learning.factor > 1 => {
                Some(u.params.learning)
            }
            _ => None,
        }
    }

    /// The most rounds of the next online trial when the rule allows `max_rounds`: more while
    /// the decoder is still learning ([`Self::learning`]).
    pub(crate) fn online_rounds(&self, max_rounds: usize) -> usize {
        match (self, self.learning()) {
            (Self::Unlabelled(u), Some(l)) if u.epochs_per_feature() < l.epochs_per_feature => {
                max_rounds * l.factor
            }
            _ => max_rounds,
        }
    }

    pub(crate) fn is_unlabelled(&self) -> bool {
        matches!(self, Self::Unlabelled(_))
    }

    /// The decision model of a labelled decoder.
    pub(crate) fn decision(&self) -> Result<DecisionModel, SessionError> {
        self.model()
            .and_then(|m| m.decision)
            .ok_or(SessionError::NotCalibrated)
    }

    pub(crate) fn adaptation(&self) -> Option<AdaptationReport> {
        match self {
            Self::Adaptive { adaptation, .. } => Some(adaptation.report),
            _ => None,
        }
    }

    pub(crate) fn unsupervised(&self) -> Option<&Unsupervised> {
        match self {
            Self::Unlabelled(u) => u.model.as_ref(),
            _ => None,
        }
    }

    /// Scores an accepted online epoch (`data`, of flash `code` in `trial`); `None` when the
    /// decoder has no score for it yet (an unsupervised one before its first fit).
    pub(crate) fn score(
        &mut self,
        data: ArrayView2<'_, f64>,
        code: u32,
        trial: usize,
    ) -> Result<Option<f64>, SessionError> {
        match self {
            Self::Unlabelled(u) => {
                let mut score = None;
                let row = u
                    .params
                    .decoder
                    .features
                    .transform(data.insert_axis(Axis(0)))?;
                if let Some(t) = &u.transfer {
                    let s = t.pipeline.score_epoch(data)?;
                    u.start_scores.push(s);
                    score = Some(s);
                } else {
                    u.start_scores.push(u.template.score(data)?);
                }
                if let Some(m) = &u.model {
                    score = Some(m.decision_function_features(row.view())?[0]);
                }
                u.rows.extend(row.iter());
                u.codes.push(code);
                u.trials.push(trial);
                Ok(score)
            }
            Self::Adaptive { model, adaptation } => {
                let row = model
                    .pipeline
                    .features(data.insert_axis(Axis(0)))?
                    .into_rows("adaptive LDA")?;
                let score = adaptation.model.decision_function(row.view())?[0];
                adaptation.rows.extend(row.iter());
                adaptation.codes.push(code);
                adaptation.trials.push(trial);
                Ok(Some(score))
            }
            Self::Fixed(model) => Ok(Some(model.pipeline.score_epoch(data)?)),
            Self::Unstarted => Err(SessionError::NotCalibrated),
        }
    }

    /// Takes a decided trial's epochs into an adapting model, labelled by the decision.
    pub(crate) fn adapt(&mut self, trial: usize, t: &TrialRecord) -> Result<(), SessionError> {
        let Self::Adaptive { adaptation: a, .. } = self else {
            return Ok(());
        };
        let decided = t.decided();
        let sure = t.confidence() >= a.min_confidence;
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

    /// Refits the unsupervised decoder on every online epoch so far and decides `trial` with it
    /// (the panel's bulbs: the first constraint set).
    pub(crate) fn decide_unlabelled(&mut self, trial: usize) -> Result<Verdict, SessionError> {
        let Self::Unlabelled(u) = self else {
            return Err(SessionError::NotCalibrated);
        };
        let abstain_below = u.params.abstain_below;
        let n_stimuli = u.constraint.sets()[0].len();
        let Some(sets) = self.refit_unlabelled(trial)? else {
            return Ok(Verdict::Abstain {
                posterior: Posterior {
                    p: vec![1.0 / n_stimuli as f64; n_stimuli],
                    p_none: 0.0,
                },
            });
        };
        let posterior = Posterior {
            p: sets[0].clone(),
            p_none: 0.0,
        };
        let (index, best) = posterior.best();
        Ok(if best >= abstain_below {
            Verdict::Choose { index, posterior }
        } else {
            Verdict::Abstain { posterior }
        })
    }

    /// Refits the unsupervised decoder on every online epoch so far (the last `max_trials`
    /// trials) and returns `trial`'s posterior over each constraint set, in the sets' code
    /// order; `None` when there is nothing to decide from yet (too few epochs, none of this
    /// trial, or a fit that cannot separate anything).
    pub(crate) fn refit_unlabelled(
        &mut self,
        trial: usize,
    ) -> Result<Option<Vec<Vec<f64>>>, SessionError> {
        let Self::Unlabelled(u) = self else {
            return Err(SessionError::NotCalibrated);
        };
        // Two epochs at least, and some from this trial, or there is nothing to decide from.
        if u.codes.len() < 2 || u.trials.last() != Some(&trial) {
            return Ok(None);
        }
        u.keep_last_trials();
        let n = u.codes.len();
        let x = ArrayView2::from_shape((n, u.n_features()), &u.rows).map_err(|e| {
            SessionError::InvalidParameter {
                name: "feature rows",
                value: u.rows.len().to_string(),
                reason: e.to_string(),
            }
        })?;
        // EM from a transferred model's scores of every epoch so far; or from the P300
        // template's, the last fit and (once there are as many epochs as features) random
        // starts, the likeliest kept.
        let decoder = &u.params.decoder;
        let fit = decoder.prepare(x).and_then(|rows| {
            let fitted = match (&u.transfer, &u.model) {
                (Some(_), _) => decoder.fit_prepared_from_scores(
                    &rows,
                    &u.codes,
                    &u.trials,
                    &u.constraint,
                    &u.start_scores,
                ),
                (None, warm) => decoder.fit_prepared_starts(
                    &rows,
                    &u.codes,
                    &u.trials,
                    &u.constraint,
                    warm.as_ref(),
                    &[&u.start_scores],
                ),
            }?;
            Ok((rows, fitted))
        });
        let (rows, fitted) = match fit {
            Ok(m) => m,
            // Too little data to separate anything yet: keep the arm still.
            Err(UnsupervisedError::Degenerate { .. })
            | Err(UnsupervisedError::NotPositiveDefinite { .. }) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        let sets = fitted
            .averaged_trials()
            .iter()
            .find(|t| t.trial == trial)
            .map(|t| t.sets.clone());
        let attended = attended_weights(&fitted, &u.codes, &u.trials, &u.constraint);
        let held = u.params.honest.held(&u.trials);
        let scores = decoder.held_out_scores(&rows, &attended, &u.trials, &held)?;
        u.honest = u.params.honest.fit(&scores, &attended, &u.trials);
        u.model = Some(fitted);
        Ok(sets)
    }

    /// The decision model dynamic stopping weighs an uncalibrated trial's scores with: the
    /// score model of out-of-sample scores ([`crate::prequential`]) under `rule`; `None` before
    /// there is one, or when `rule` does not stop dynamically.
    pub(crate) fn honest_decision(&self, rule: DecisionRule) -> Option<DecisionModel> {
        match (self, rule) {
            (Self::Unlabelled(u), DecisionRule::Dynamic { .. }) => u
                .honest
                .map(|scores| DecisionModel { scores, rule })
                .filter(|d| d.validate().is_ok()),
            _ => None,
        }
    }
}

/// Each epoch's posterior of being the attended one under `model` (its trial's posterior of
/// the epoch's code; 0 where the model has no such trial or code).
fn attended_weights(
    model: &Unsupervised,
    codes: &[u32],
    trials: &[usize],
    constraint: &Constraint,
) -> Vec<f64> {
    let posteriors = model.averaged_trials();
    codes
        .iter()
        .zip(trials)
        .map(|(&code, &trial)| {
            posteriors
                .iter()
                .find(|t| t.trial == trial)
                .map_or(0.0, |t| constraint.attended_weight(code, &t.sets))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_uncalibrated_decoder_keeps_the_last_max_trials_trials() {
        let mut params = UncalibratedParams::for_sfreq(500.0).unwrap();
        params.max_trials = 3;
        let four = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
        let mut u = Unlabelled::new(params, None, four, &Preprocess::online(), 500.0).unwrap();
        // Trials 0..6, each with 2 + trial epochs of 3 features.
        for trial in 0..6usize {
            for k in 0..2 + trial {
                u.rows.extend([trial as f64, k as f64, 0.5]);
                u.codes.push(1 + k as u32 % 4);
                u.trials.push(trial);
                u.start_scores.push(trial as f64);
            }
            u.keep_last_trials();
            let first = trial.saturating_sub(2);
            let n: usize = (first..=trial).map(|t| 2 + t).sum();
            assert_eq!(u.trials.len(), n, "after trial {trial}");
            assert_eq!((u.codes.len(), u.start_scores.len()), (n, n));
            assert_eq!(u.rows.len(), 3 * n);
            assert_eq!(u.trials[0], first);
            assert_eq!(u.rows[0], first as f64);
            assert_eq!(u.start_scores[0], first as f64);
        }
        params.max_trials = 1;
        assert!(params.check().is_err());
    }
}
