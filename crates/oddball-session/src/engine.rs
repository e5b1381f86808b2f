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
//!    are turned into log-likelihood ratios by a score model fitted on
//!    *cross-validated* scores (folds by decision), so the evidence is not over-confident.
//!    With [`DecoderParams::stopping`] the stopping rule is then chosen from those same
//!    cross-validated scores for the most expected bits per minute ([`crate::timing`]).
//! 3. **Online**: per decision, a countdown, then rounds of four flashes. Flashes are shown (to
//!    the subject and the epocher) when the stream reaches their onset; each epoch is scored as
//!    soon as its last sample (600 ms after onset) has arrived; after each complete round the
//!    [`DecisionRule`](oddball_decode::decision::DecisionRule) decides, continues or abstains. A decision issues the bulb's command to the
//!    arm, which runs on the same clock as the EEG, one chunk at a time. Without calibration
//!    the trial is decided by the unsupervised refit once its rounds are done; with a dynamic
//!    rule it stops earlier only when the out-of-sample score model
//!    ([`crate::prequential`]) makes a bulb probable enough.
//!
//! Before every trial the presenter may hold the session ([`Presenter::hold`](crate::roles::Presenter::hold): an operator's
//! pause): the EEG and the arm run on, no trial starts. After every trial the observer hears
//! each channel's rejected epochs ([`Observer::channel_faults`](crate::roles::Observer::channel_faults)).
//!
//! Everything shown and decided is kept ([`SessionLog`]) so a session can be saved and
//! re-evaluated offline to the same decisions ([`crate::record`]).

use ndarray::Axis;
use oddball_arm::{ArmSim, Command};
use oddball_decode::decision::Verdict;
use oddball_decode::pipeline::Model;
use oddball_decode::preprocess::Preprocess;
use oddball_decode::preset::Preset;
use oddball_decode::stopping::Expected;
use oddball_decode::unsupervised::Unsupervised;
use oddball_io::SampleSpill;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::decision::{
    complete_rounds, CalibrationProgress, CalibrationReport, Phase, SessionLog, ShownFlash,
    TrialOutcome, TrialRecord,
};
use crate::decoder::{Adaptation, OnlineDecoder, Unlabelled};
use crate::decoder::{AdaptationReport, DecoderParams, Start, UncalibratedParams};
use crate::fit::{fit_session_model_oof, Calibration};
use crate::online::{Marker, OnlineEpocher};
use crate::paradigm::FourBulbParams;
use crate::roles::{Drawn, Subject};
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
    /// The pipeline, pre-processing, decision rule and folds, as a replay has them.
    #[serde(flatten)]
    pub decoder: DecoderParams,
    /// Calibration decisions per bulb.
    pub calibration_per_bulb: usize,
}

impl SessionParams {
    /// The paper's session: four bulbs, 5 rounds, causal 1–15 Hz, 10 calibration decisions
    /// per bulb, 20-sample chunks, 5 folds.
    pub fn paper(pipeline: Preset) -> Self {
        let paradigm = FourBulbParams::paper();
        Self {
            paradigm,
            decoder: DecoderParams::paper(pipeline, &paradigm),
            calibration_per_bulb: 10,
        }
    }

    pub fn validate(&self) -> Result<(), SessionError> {
        self.paradigm.validate()?;
        self.decoder.rule.validate()?;
        if let Some(s) = &self.decoder.stopping {
            s.validate()?;
        }
        let bad = |name: &'static str, value: usize, reason: &str| {
            Err(SessionError::InvalidParameter {
                name,
                value: value.to_string(),
                reason: reason.into(),
            })
        };
        if self.decoder.chunk == 0 {
            return bad("chunk", 0, "at least one sample per chunk");
        }
        if self.decoder.cv_folds < 2 {
            return bad("cv_folds", self.decoder.cv_folds, "at least 2 folds");
        }
        if self.calibration_per_bulb > MAX_CALIBRATION_PER_BULB {
            return bad(
                "calibration_per_bulb",
                self.calibration_per_bulb,
                &format!("at most {MAX_CALIBRATION_PER_BULB} calibration decisions per bulb"),
            );
        }
        if self.calibration_per_bulb < self.decoder.cv_folds.div_ceil(4).max(1) {
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

/// A running session.
#[derive(Debug)]
pub struct Session<S: Subject> {
    params: SessionParams,
    subject: S,
    epocher: OnlineEpocher,
    rng: ChaCha8Rng,
    /// Every sample taken, spilled to disk as it comes (`None` once discarded,
    /// [`Session::discard_samples`]).
    samples: Option<SampleSpill>,
    /// Samples taken so far.
    n_times: usize,
    flashes: Vec<ShownFlash>,
    trials: Vec<TrialRecord>,
    calibration: Calibration,
    /// How the session decides online, once started ([`Session::start`]).
    decoder: OnlineDecoder,
    arm: Option<ArmSim>,
    /// The arm runs from the first online decision on (it holds still during calibration).
    arm_running: bool,
    /// Drawn onsets refused (see [`Session::refused_onsets`]).
    refused_onsets: u64,
    /// The stopping rule chosen from the calibration, with its expected performance.
    stopping: Option<Expected>,
    /// Rows of the subject's channels the epocher takes, in the model's order (a model set
    /// with other or reordered channels, see [`Session::start`]); `None`: all, as they are.
    pick: Option<Vec<usize>>,
    /// The channels' names: the subject's, or a montage's ([`Session::name_channels`]).
    ch_names: Vec<String>,
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
            &params.decoder.preprocess,
            subject.sfreq(),
            subject.ch_names().len(),
        )?;
        let ch_names = subject.ch_names().to_vec();
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(params.decoder.seed),
            samples: Some(
                SampleSpill::new(subject.ch_names().len())
                    .map_err(SessionError::spill("create"))?,
            ),
            n_times: 0,
            params,
            subject,
            epocher,
            flashes: Vec::new(),
            trials: Vec::new(),
            calibration: Calibration::default(),
            decoder: OnlineDecoder::Unstarted,
            arm,
            arm_running: false,
            refused_onsets: 0,
            stopping: None,
            pick: None,
            ch_names,
        })
    }

    /// Starts deciding, once, before any online decision:
    ///
    /// * [`Start::Calibrate`] runs the calibration trials and trains the model (telling
    ///   `progress` after each trial how far it is, for a live or real-time calibration, which
    ///   takes minutes), then with `adapt` lets the calibrated `lda` adapt online. Returns what
    ///   calibration measured.
    /// * [`Start::Model`] decides with a model trained elsewhere, before the session's first
    ///   sample: a session's, or one `oddball train` fitted offline (it must carry a decision
    ///   model, as format 4 on does). Its channels are matched by name (the subject may have
    ///   more, in any order: the session epochs only the model's, in the model's order). A model
    ///   trained offline (zero-phase band-pass) runs its causal fit ([`Model::for_session`]);
    ///   the model kept, and saved, is the one that ran, so re-evaluating the session
    ///   reproduces its decisions.
    /// * [`Start::Uncalibrated`] controls without calibration (see [`UncalibratedParams`]); a
    ///   `transfer` model must match the session's channels, rate and pre-processing.
    pub fn start(
        &mut self,
        start: Start,
        progress: &mut dyn FnMut(CalibrationProgress),
    ) -> Result<Option<CalibrationReport>, SessionError> {
        if self.decoder.is_started() || !self.trials.is_empty() {
            return Err(SessionError::AlreadyStarted);
        }
        match start {
            Start::Calibrate { adapt } => {
                let report = self.calibrate_with(progress)?;
                if let Some(p) = adapt {
                    let OnlineDecoder::Fixed(model) =
                        std::mem::replace(&mut self.decoder, OnlineDecoder::Unstarted)
                    else {
                        return Err(SessionError::NotCalibrated);
                    };
                    let adaptation = Adaptation::new(&model, &self.calibration.labels, p);
                    match adaptation {
                        Ok(a) => {
                            self.decoder = OnlineDecoder::Adaptive {
                                model,
                                adaptation: Box::new(a),
                            }
                        }
                        Err(e) => {
                            self.decoder = OnlineDecoder::Fixed(model);
                            return Err(e);
                        }
                    }
                }
                Ok(Some(report))
            }
            Start::Model(model) => {
                self.use_model(model)?;
                Ok(None)
            }
            Start::Uncalibrated { params, transfer } => {
                // A transferred model scores epochs cut as it was trained (a zero-phase one run
                // causally, as `--model` runs it); without one, the uncalibrated decoder's own.
                let transfer = transfer.map(Model::for_session);
                if let Some(model) = &transfer {
                    model.check_layout(&self.ch_names, self.subject.sfreq())?;
                }
                let params = match params {
                    Some(p) => *p,
                    None => UncalibratedParams::for_sfreq(self.subject.sfreq())?,
                };
                let pre = match &transfer {
                    Some(model) => Some(model.preprocess),
                    None => params.preprocess,
                };
                if let Some(pre) = pre {
                    let n_channels = self.ch_names.len();
                    self.use_preprocess(pre, n_channels, "an uncalibrated session's start")?;
                }
                self.decoder = OnlineDecoder::Unlabelled(Box::new(Unlabelled::new(
                    params,
                    transfer,
                    oddball_decode::unsupervised::Constraint::one_of(
                        &(1..=self.params.paradigm.bulbs.len() as u32).collect::<Vec<_>>(),
                    )?,
                    &self.params.decoder.preprocess,
                    self.subject.sfreq(),
                )?));
                Ok(None)
            }
        }
    }

    /// What online adaptation did so far (`None` without it).
    pub fn adaptation(&self) -> Option<AdaptationReport> {
        self.decoder.adaptation()
    }

    /// The latest unsupervised fit of an uncalibrated session.
    pub fn unsupervised(&self) -> Option<&Unsupervised> {
        self.decoder.unsupervised()
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

    /// The stopping rule calibration chose ([`DecoderParams::stopping`]) and what it expects.
    pub fn stopping(&self) -> Option<&Expected> {
        self.stopping.as_ref()
    }

    /// The model deciding: calibrated or given (`None` before the start and without
    /// calibration).
    pub fn model(&self) -> Option<&Model> {
        self.decoder.model()
    }

    /// Names the subject's channels in order (a montage: the stream's own names are not the
    /// model's), before the session's first sample: models are matched to these names,
    /// calibration fits and the session's log carry them.
    pub fn name_channels(&mut self, names: Vec<String>) -> Result<(), SessionError> {
        let taken = self.n_times;
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

    /// Decides with `model`, trained elsewhere ([`Start::Model`]).
    fn use_model(&mut self, model: Model) -> Result<(), SessionError> {
        let model = model.for_session();
        if model.decision.is_none() {
            return Err(SessionError::NoDecisionModel {
                pipeline: model.pipeline.name().to_string(),
            });
        }
        let order = crate::decoder::model_channels(&model, &self.ch_names, self.subject.sfreq())?;
        self.use_preprocess(model.preprocess, order.len(), "a model")?;
        let identity =
            order.len() == self.ch_names.len() && order.iter().enumerate().all(|(i, &o)| i == o);
        self.pick = (!identity).then_some(order);
        self.decoder = OnlineDecoder::Fixed(model);
        Ok(())
    }

    /// Epochs of `n_channels` channels from now on cut by `pre` (before any sample has been
    /// taken: `what` names what needed it too late).
    fn use_preprocess(
        &mut self,
        pre: Preprocess,
        n_channels: usize,
        what: &'static str,
    ) -> Result<(), SessionError> {
        let taken = self.n_times;
        if taken > 0 {
            return Err(SessionError::TooLate {
                what,
                n_times: taken,
            });
        }
        self.epocher = OnlineEpocher::new(&pre, self.subject.sfreq(), n_channels)?;
        self.params.decoder.preprocess = pre;
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
        let x = cal.stacked(self.ch_names.len());
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
            self.params.decoder.preprocess.tmin,
            self.ch_names.clone(),
            events,
        )?)
    }

    /// The settings of the uncalibrated decoder the session started (`None` for any other).
    pub fn uncalibrated_params(&self) -> Option<&UncalibratedParams> {
        self.decoder.uncalibrated_params()
    }

    /// The learning trials the session runs ([`crate::decoder::LearningRounds`]; `None` when it
    /// runs none: calibrated, or started from a transferred model).
    pub fn learning_rounds(&self) -> Option<crate::decoder::LearningRounds> {
        self.decoder.learning()
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
            let n = (until - self.subject.position()).min(self.params.decoder.chunk as u64);
            self.advance(n as usize)?;
        }
        Ok(())
    }

    /// Runs the calibration trials and trains the model: [`Session::start`] with
    /// [`Start::Calibrate`], no adaptation, no progress told.
    pub fn calibrate(&mut self) -> Result<CalibrationReport, SessionError> {
        let report = self.start(Start::Calibrate { adapt: None }, &mut |_| {})?;
        report.ok_or(SessionError::NotCalibrated)
    }

    /// Runs the calibration trials (telling `progress` after each) and trains the model.
    fn calibrate_with(
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
        let x = cal.stacked(0);
        let y = &cal.labels;
        let sfreq = self.subject.sfreq();
        let groups: Vec<usize> = cal.trials.iter().map(|&t| t - first_trial).collect();
        let (mut model, cv_auc, d_prime, oof) = fit_session_model_oof(
            &self.params.decoder,
            sfreq,
            &self.ch_names,
            x.view().into(),
            y,
            &groups,
        )?;
        if let (Some(search), Some(decision)) = (&self.params.decoder.stopping, &mut model.decision)
        {
            let chosen = crate::timing::choose_stopping(
                search,
                &decision.scores,
                &oof,
                y,
                &self.params.paradigm,
                &self.params.decoder.preprocess,
            )?;
            decision.rule = chosen.rule;
            self.params.decoder.rule = chosen.rule;
            self.stopping = Some(chosen);
        }
        self.decoder = OnlineDecoder::Fixed(model);
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
        if !self.decoder.is_started() {
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
            let c = self.params.decoder.chunk.min(n - done);
            self.advance(c)?;
            done += c;
        }
        Ok(())
    }

    /// Ends the session and hands back its subject (a live one closes its recording).
    pub fn into_subject(self) -> S {
        self.subject
    }

    /// Keeps no samples from now on (a live session's recorder has them already): the log
    /// [`Session::finish`] returns then has none.
    pub fn discard_samples(&mut self) {
        self.samples = None;
    }

    /// Ends the session, returning its log, the model and the arm.
    pub fn finish(self) -> Result<(SessionLog, Option<Model>, Option<ArmSim>), SessionError> {
        let samples = match self.samples {
            Some(s) => Some(s.finish().map_err(SessionError::spill("write"))?),
            None => None,
        };
        Ok((
            SessionLog {
                sfreq: self.subject.sfreq(),
                ch_names: self.ch_names,
                samples,
                n_times: self.n_times,
                flashes: self.flashes,
                trials: self.trials,
            },
            self.decoder.into_model(),
            self.arm,
        ))
    }

    /// Renders one chunk, feeds the epocher, records, runs the arm; handles completed epochs.
    fn advance(&mut self, n: usize) -> Result<(), SessionError> {
        let data = self.subject.render(n)?;
        if let Some(spill) = &mut self.samples {
            spill
                .push(data.view())
                .map_err(SessionError::spill("write"))?;
        }
        self.n_times += data.ncols();
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
                Phase::Online if e.accepted => {
                    f.score = self.decoder.score(e.data.view(), f.code, f.trial)?;
                }
                Phase::Online => {}
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
            self.advance(self.params.decoder.chunk)?;
        }
        let n_rounds = match phase {
            Phase::Calibration => p.n_rounds,
            Phase::Online => self
                .decoder
                .online_rounds(self.params.decoder.rule.max_rounds()),
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
            let end = pos + self.params.decoder.chunk as u64 + self.subject.lead();
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
            self.advance(self.params.decoder.chunk)?;
            let shown = &self.flashes[first_flash..];
            match phase {
                Phase::Calibration => {
                    if next == planned.len() && shown.iter().all(|f| f.accepted.is_some()) {
                        self.trials[trial].rounds = n_rounds;
                        break;
                    }
                }
                Phase::Online if self.decoder.is_unlabelled() => {
                    let all = next == planned.len() && shown.iter().all(|f| f.accepted.is_some());
                    // Dynamic stopping weighs the rounds so far by the out-of-sample score
                    // model; it stops once sure, and the refit then learns from the trial.
                    let rule = self.params.decoder.rule;
                    if let Some(decision) = self.decoder.honest_decision(rule) {
                        let rounds = complete_rounds(shown);
                        let (verdict, used) = decision.decide(&rounds);
                        let stop = matches!(verdict, Verdict::Choose { .. }) && used < n_rounds;
                        if stop {
                            self.decoder.refit_unlabelled(trial)?;
                            self.conclude(trial, verdict, used)?;
                            break;
                        }
                    }
                    if all {
                        let verdict = self.decoder.decide_unlabelled(trial)?;
                        self.conclude(trial, verdict, n_rounds)?;
                        break;
                    }
                }
                Phase::Online => {
                    let rounds = complete_rounds(shown);
                    let decision = self.decoder.decision()?;
                    let (verdict, used) = decision.decide(&rounds);
                    if verdict != Verdict::Continue || rounds.len() == n_rounds {
                        self.conclude(trial, verdict, used)?;
                        self.decoder.adapt(trial, &self.trials[trial])?;
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
