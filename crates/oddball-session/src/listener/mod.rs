//! Decoding another program's session: EEG and the stimulus program's markers in, decisions out.
//!
//! A [`Listener`] is the online decoder behind any stimulus program (PsychoPy, BCI2000's
//! P3Speller, Unity, a web page): the program flashes its choices and says so in markers, the
//! [`Paradigm`] file says what each marker means, and the listener answers with a decision per
//! trial (and, with dynamic stopping, a [`Output::Stop`] as soon as it is sure, so the program may
//! end the trial early). It knows no transport: `oddball decode` feeds it from Lab Streaming
//! Layer, a test from a file, the Python package from a script.
//!
//! **Time.** EEG arrives in blocks, each with the time of its last sample; markers arrive with
//! their own times, on the same clock (the caller maps the two streams onto one clock — LSL's
//! time correction — and need not deliver them in any order within the epoch window). A marker
//! at time `t` is the flash at sample `i + round((t − tᵢ)·sfreq)`, `i` the newest sample and
//! `tᵢ` its time: anchored at the newest sample, so an amplifier's clock drifting against the
//! computer's over hours moves no onset. Markers that arrive before any EEG wait for it.
//!
//! **Deciding.** Each flash's epoch goes through the one causal epocher
//! ([`crate::online::OnlineEpocher`]: the streaming band-pass, the rejection rule). A labelled
//! decoder scores it, and the log-likelihood ratio of its score adds to the evidence of every
//! choice the flash showed; a trial is decided at its end on all its flashes, or earlier under a
//! dynamic [`DecisionRule`] (complete rounds: every code flashed as often). Without calibration
//! the unsupervised decoder ([`crate::decoder`]) is refitted at each trial's end under the
//! paradigm's constraint (one choice per trial: one code, or one row and one column). In-stream
//! calibration takes the first trials' flags or cues as labels, fits, then decides.
//!
//! **Bad markers** (unknown texts, flashes too old to epoch or too far in the future, out of
//! order, a flag with no flash) are counted in [`MarkerCounts`], never fatal. What the listener
//! keeps is bounded by the trials in flight, not the session's length.

use std::collections::{BTreeMap, VecDeque};

use ndarray::{Array3, ArrayView2, Axis};
use oddball_decode::decision::{DecisionRule, Posterior, Verdict};
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_decode::unsupervised::Constraint;
use oddball_io::paradigm::{MarkerKind, Paradigm, TrialEnd};

use crate::decoder::{
    model_channels, DecoderParams, OnlineDecoder, UncalibratedParams, Unlabelled,
};
use crate::online::{Marker, OnlineEpocher, ReadyEpoch};
use crate::SessionError;

mod messages;
mod trials;
pub use messages::{ListenerDecision, MarkerCounts, Output};
use trials::{CalibrationSet, Flash, Trial};

/// A flash stamped further than this past the newest EEG sample is not believed, s.
pub const MAX_AHEAD_S: f64 = 5.0;
/// A flag (target / non-target) belongs to the flash stamped within this of it, s.
pub const FLAG_TOLERANCE_S: f64 = 0.002;
/// A flag waits this long for its flash (it may arrive first), s after the newest sample.
pub const MAX_FLAG_WAIT_S: f64 = 2.0;
/// Flags waiting for their flash at most.
pub const MAX_LOOSE_FLAGS: usize = 64;
/// Markers kept while no EEG has arrived yet.
pub const MAX_HELD_MARKERS: usize = 10_000;
/// Trials open at once (announced and not yet decided) before the oldest is given up.
pub const MAX_OPEN_TRIALS: usize = 8;

/// How a listener starts deciding.
#[derive(Debug, Clone)]
pub enum ListenerStart {
    /// A model trained elsewhere (`oddball train`, an earlier session); offline models run
    /// their causal fit.
    Model(Box<Model>),
    /// The first `trials` trials are calibration: their flags or cues label the flashes, the
    /// decoder's preset is fitted on them, then every later trial is decided.
    Calibrate { trials: usize },
    /// No calibration: the unsupervised decoder under the paradigm's constraint.
    Uncalibrated {
        params: Option<Box<UncalibratedParams>>,
    },
}

/// A listener's settings.
#[derive(Debug, Clone)]
pub struct ListenerParams {
    pub paradigm: Paradigm,
    pub start: ListenerStart,
    /// Dynamic stopping (stop as soon as a choice is probable enough; abstain when none is
    /// credible at the trial's end). `None`: decide at each trial's end on all its flashes.
    pub rule: Option<DecisionRule>,
    /// The preset, pre-processing, folds and seed a calibration fits with; the pre-processing
    /// (its window replaced by the paradigm's `[epoch]`, if any) is also the unsupervised
    /// decoder's. A model brings its own.
    pub decoder: DecoderParams,
}

impl ListenerParams {
    /// `oddball decode`'s settings (any front end's): a calibration fits `pipeline` on the
    /// peer stack's band and window (what `train` and `evaluate` use) band-passed causally, with
    /// 5 folds; `dynamic_threshold` stops a trial once a choice's posterior reaches it (the other
    /// settings [`DecisionRule::dynamic_at`]'s), `None` decides at each trial's end.
    pub fn new(
        paradigm: Paradigm,
        start: ListenerStart,
        pipeline: oddball_decode::preset::Preset,
        dynamic_threshold: Option<f64>,
    ) -> Self {
        use oddball_decode::decision::MAX_ROUNDS;
        Self {
            paradigm,
            start,
            rule: dynamic_threshold.map(|t| DecisionRule::dynamic_at(t, MAX_ROUNDS)),
            decoder: DecoderParams {
                pipeline,
                preprocess: Preprocess::peer().as_causal(),
                rule: DecisionRule::Fixed { rounds: MAX_ROUNDS },
                cv_folds: 5,
                chunk: 20,
                seed: 0,
                stopping: None,
            },
        }
    }
}

/// The online decoder behind another program's stimuli (see the module doc).
#[derive(Debug)]
pub struct Listener {
    paradigm: Paradigm,
    rule: Option<DecisionRule>,
    decoder_params: DecoderParams,
    decoder: OnlineDecoder,
    epocher: OnlineEpocher,
    pick: Option<Vec<usize>>,
    sfreq: f64,
    ch_names: Vec<String>,
    constraint: Option<Constraint>,
    calibration_trials: usize,
    calibration: CalibrationSet,
    /// (index, time) of the newest sample.
    anchor: Option<(u64, f64)>,
    held: Vec<(String, f64)>,
    flashes: BTreeMap<usize, Flash>,
    next_tag: usize,
    last_flash: Option<(usize, f64)>,
    /// The latest end marker's time among the trials already settled: a flash stamped before
    /// it that arrives late belongs to a finished trial, not to a new one.
    settled_end: Option<f64>,
    loose_flags: VecDeque<(f64, bool)>,
    trials: VecDeque<Trial>,
    trial_count: usize,
    next_cue: Option<usize>,
    counts: MarkerCounts,
}

impl Listener {
    /// A listener for a stream of `ch_names` at `sfreq` Hz. Checks the model against the stream
    /// (rate, channels, window) and the start against the paradigm before any sample.
    pub fn new(
        params: ListenerParams,
        sfreq: f64,
        ch_names: &[String],
    ) -> Result<Self, SessionError> {
        let ListenerParams {
            paradigm,
            start,
            rule,
            mut decoder,
        } = params;
        if let Some(r) = &rule {
            r.validate()?;
        }
        if let Some((tmin, tmax)) = paradigm.epoch {
            decoder.preprocess.tmin = tmin;
            decoder.preprocess.tmax = tmax;
        }
        decoder.preprocess = decoder.preprocess.as_causal();
        let mut pick = None;
        let mut constraint = None;
        let mut calibration_trials = 0;
        let (online, preprocess) = match start {
            ListenerStart::Model(model) => {
                let model = (*model).for_session();
                if model.decision.is_none() {
                    return Err(SessionError::NoDecisionModel {
                        pipeline: model.pipeline.name().to_string(),
                    });
                }
                if let Some((tmin, tmax)) = paradigm.epoch {
                    let p = model.preprocess;
                    if (p.tmin - tmin).abs() > 1e-9 || (p.tmax - tmax).abs() > 1e-9 {
                        return Err(SessionError::InvalidParameter {
                            name: "paradigm [epoch]",
                            value: format!("{tmin}–{tmax} s"),
                            reason: format!(
                                "the model's epochs are {}–{} s; drop [epoch] or train on this window",
                                p.tmin, p.tmax
                            ),
                        });
                    }
                }
                let order = model_channels(&model, ch_names, sfreq)?;
                let identity =
                    order.len() == ch_names.len() && order.iter().enumerate().all(|(i, &o)| i == o);
                pick = (!identity).then_some(order);
                let pre = model.preprocess;
                (OnlineDecoder::Fixed(model), pre)
            }
            ListenerStart::Calibrate { trials } => {
                if trials == 0 {
                    return Err(SessionError::InvalidParameter {
                        name: "calibration trials",
                        value: "0".into(),
                        reason: "calibrate on one trial at least".into(),
                    });
                }
                if !paradigm.labels_targets() {
                    return Err(SessionError::InvalidParameter {
                        name: "calibration",
                        value: paradigm.path.display().to_string(),
                        reason: "the paradigm names no target flags ([events]) and no cue \
                                 (markers.cue): nothing labels the calibration flashes"
                            .into(),
                    });
                }
                calibration_trials = trials;
                (OnlineDecoder::Unstarted, decoder.preprocess)
            }
            ListenerStart::Uncalibrated { params } => {
                let c = constraint_of(&paradigm)?;
                let params = match params {
                    Some(p) => *p,
                    None => UncalibratedParams::for_sfreq(sfreq)?,
                };
                constraint = Some(c.clone());
                let u = Unlabelled::new(params, None, c, &decoder.preprocess, sfreq)?;
                (OnlineDecoder::Unlabelled(Box::new(u)), decoder.preprocess)
            }
        };
        let n_channels = pick.as_ref().map_or(ch_names.len(), Vec::len);
        let epocher = OnlineEpocher::new(&preprocess, sfreq, n_channels)?;
        decoder.preprocess = preprocess;
        Ok(Self {
            paradigm,
            rule,
            decoder_params: decoder,
            decoder: online,
            epocher,
            pick,
            sfreq,
            ch_names: ch_names.to_vec(),
            constraint,
            calibration_trials,
            calibration: CalibrationSet::default(),
            anchor: None,
            held: Vec::new(),
            flashes: BTreeMap::new(),
            next_tag: 0,
            last_flash: None,
            settled_end: None,
            loose_flags: VecDeque::new(),
            trials: VecDeque::new(),
            trial_count: 0,
            next_cue: None,
            counts: MarkerCounts::default(),
        })
    }

    /// The paradigm decoded.
    pub fn paradigm(&self) -> &Paradigm {
        &self.paradigm
    }

    /// What the markers held, so far.
    pub fn counts(&self) -> &MarkerCounts {
        &self.counts
    }

    /// The pre-processing the epochs get (the model's, or the calibration's).
    pub fn preprocess(&self) -> &Preprocess {
        &self.decoder_params.preprocess
    }

    /// The model deciding (given or calibrated in-stream).
    pub fn model(&self) -> Option<&Model> {
        self.decoder.model()
    }

    /// Samples received so far.
    pub fn received(&self) -> u64 {
        self.epocher.received()
    }

    /// One marker, `time` on the EEG's clock (s).
    pub fn push_marker(&mut self, text: &str, time: f64) -> Result<Vec<Output>, SessionError> {
        if self.anchor.is_none() {
            if self.held.len() >= MAX_HELD_MARKERS {
                self.counts.held_overflow += 1;
            } else {
                self.held.push((text.to_string(), time));
            }
            return Ok(Vec::new());
        }
        let mut out = Vec::new();
        self.marker(text, time);
        self.settle(&mut out)?;
        Ok(out)
    }

    /// One marker already read (a recording's events, which carry codes and flags rather than
    /// a program's texts), `time` on the EEG's clock (s). Markers before the first EEG block
    /// are refused here (the caller has the whole recording: it feeds them in time).
    pub fn push_event(&mut self, kind: MarkerKind, time: f64) -> Result<Vec<Output>, SessionError> {
        let mut out = Vec::new();
        self.counts.markers += 1;
        self.kind(kind, time);
        self.settle(&mut out)?;
        Ok(out)
    }

    /// A block of EEG `(n_channels, n)` in µV whose last sample is at `last_time` (s).
    pub fn push_eeg(
        &mut self,
        block: ArrayView2<'_, f64>,
        last_time: f64,
    ) -> Result<Vec<Output>, SessionError> {
        let mut out = Vec::new();
        if block.ncols() == 0 {
            return Ok(out);
        }
        if block.nrows() != self.ch_names.len() {
            return Err(SessionError::InvalidParameter {
                name: "EEG block",
                value: format!("{} channels", block.nrows()),
                reason: format!("the stream has {}", self.ch_names.len()),
            });
        }
        let newest = self.epocher.received() + block.ncols() as u64 - 1;
        if last_time.is_finite() {
            self.anchor = Some((newest, last_time));
        } else if let Some((i, t)) = self.anchor {
            self.anchor = Some((newest, t + (newest - i) as f64 / self.sfreq));
        } else {
            self.anchor = Some((newest, newest as f64 / self.sfreq));
        }
        for (text, time) in std::mem::take(&mut self.held) {
            self.marker(&text, time);
        }
        self.drop_stale_flags();
        let ready = match &self.pick {
            Some(order) => self
                .epocher
                .push_samples(block.select(Axis(0), order).view())?,
            None => self.epocher.push_samples(block)?,
        };
        for e in ready {
            self.epoch(e, &mut out)?;
            self.settle(&mut out)?;
        }
        self.settle(&mut out)?;
        Ok(out)
    }

    /// The streams ended: the trials still open are decided on what arrived.
    pub fn finish(&mut self) -> Result<Vec<Output>, SessionError> {
        let mut out = Vec::new();
        self.counts.orphan_flags += self.loose_flags.len() as u64;
        self.loose_flags.clear();
        for t in self.trials.iter_mut() {
            t.ended = true;
            t.end_time = None;
            self.counts.after_decision += (t.announced - t.completed) as u64;
            t.announced = t.completed;
        }
        self.settle(&mut out)?;
        Ok(out)
    }

    fn onset_of(&self, time: f64) -> Option<i64> {
        let (i, t) = self.anchor?;
        Some(i as i64 + ((time - t) * self.sfreq).round() as i64)
    }

    fn open_trial(&mut self) {
        self.trial_count += 1;
        if self.trials.len() >= MAX_OPEN_TRIALS {
            if let Some(old) = self.trials.pop_front() {
                self.counts.abandoned_trials += 1;
                self.flashes.retain(|_, f| f.trial != old.number);
            }
        }
        let calibration = self.trial_count <= self.calibration_trials;
        let cue = self.next_cue.take();
        let n_choices = self.paradigm.labels.len();
        self.trials
            .push_back(Trial::new(self.trial_count, cue, calibration, n_choices));
    }

    /// The trial flashes now go to: the newest, unless it has ended.
    fn current(&mut self) -> Option<&mut Trial> {
        self.trials.back_mut().filter(|t| !t.ended)
    }

    fn marker(&mut self, text: &str, time: f64) {
        self.counts.markers += 1;
        if !time.is_finite() {
            self.counts.unknown += 1;
            return;
        }
        let kind = self.paradigm.read(text);
        self.kind(kind, time);
    }

    fn kind(&mut self, kind: MarkerKind, time: f64) {
        match kind {
            MarkerKind::Unknown => self.counts.unknown += 1,
            MarkerKind::Flash { code } => self.flash(code, time),
            MarkerKind::Flag { target } => {
                let hit = self
                    .flashes
                    .values_mut()
                    .rev()
                    .find(|f| (f.time - time).abs() <= FLAG_TOLERANCE_S);
                match hit {
                    Some(f) => f.target = Some(target),
                    // Its flash may still be on its way.
                    None => {
                        self.loose_flags.push_back((time, target));
                        self.drop_stale_flags();
                    }
                }
            }
            MarkerKind::TrialStart => {
                // A start that comes after its trial's first flash (out of order) adopts the
                // trial that flash opened.
                if let Some(t) = self.current() {
                    if t.implicit && t.first_time >= time - FLAG_TOLERANCE_S {
                        t.implicit = false;
                        t.start_time = Some(time);
                        self.counts.implicit_trials -= 1;
                        return;
                    }
                }
                if self.current().is_some() {
                    self.counts.unended_trials += 1;
                    self.end_current(None);
                }
                self.open_trial();
                if let Some(t) = self.trials.back_mut() {
                    t.start_time = Some(time);
                }
            }
            MarkerKind::TrialEnd => {
                if self.current().is_some() {
                    self.end_current(Some(time));
                } else {
                    self.counts.stray_ends += 1;
                }
            }
            MarkerKind::Cue { choice } => match self.current() {
                Some(t) if t.announced == 0 => t.cue = Some(choice),
                _ => self.next_cue = Some(choice),
            },
        }
    }

    /// A flag that arrived before its flash, for the flash at `time`.
    fn take_loose_flag(&mut self, time: f64) -> Option<bool> {
        let i = self
            .loose_flags
            .iter()
            .position(|&(t, _)| (t - time).abs() <= FLAG_TOLERANCE_S)?;
        self.loose_flags.remove(i).map(|(_, target)| target)
    }

    /// Flags whose flash never came (older than the samples an epoch can still use, or too
    /// many waiting) are orphans.
    fn drop_stale_flags(&mut self) {
        let newest = self.anchor.map_or(f64::NEG_INFINITY, |(_, t)| t);
        let horizon = newest - MAX_FLAG_WAIT_S;
        while let Some(&(t, _)) = self.loose_flags.front() {
            if t < horizon || self.loose_flags.len() > MAX_LOOSE_FLAGS {
                self.loose_flags.pop_front();
                self.counts.orphan_flags += 1;
            } else {
                break;
            }
        }
    }

    fn end_current(&mut self, time: Option<f64>) {
        if let Some(t) = self.current() {
            t.ended = true;
            t.end_time = time;
        }
    }

    /// The trial a flash stamped `time` belongs to: an ended, undecided trial whose end marker
    /// is stamped at or after it (the flash's marker came after the end's), else the open one —
    /// unless the flash is stamped before the open one started and within a trial already
    /// settled (`None`: its marker came after its trial was decided and ended).
    fn trial_of(&mut self, time: f64) -> Option<usize> {
        let late = self.trials.iter().position(|t| {
            t.ended && !t.decided && t.end_time.is_some_and(|e| time <= e + FLAG_TOLERANCE_S)
        });
        let settled = self.settled_end;
        late.or_else(|| {
            self.trials
                .back()
                .filter(|t| !t.ended)
                .filter(|t| {
                    let before_start = t.start_time.is_some_and(|s| time < s - FLAG_TOLERANCE_S);
                    !(before_start && settled.is_some_and(|e| time <= e + FLAG_TOLERANCE_S))
                })
                .map(|_| self.trials.len() - 1)
        })
    }

    fn flash(&mut self, code: u32, time: f64) {
        if !self.paradigm.is_flash(code) {
            self.counts.unknown += 1;
            return;
        }
        let Some(onset) = self.onset_of(time) else {
            return;
        };
        let newest = self.anchor.map_or(0, |(i, _)| i) as i64;
        if onset < 0 {
            self.counts.too_old += 1;
            return;
        }
        if (onset - newest) as f64 > MAX_AHEAD_S * self.sfreq {
            self.counts.future += 1;
            return;
        }
        if let Some((_, t)) = self.last_flash {
            if time < t {
                self.counts.out_of_order += 1;
            }
        }
        let ti = match self.trial_of(time) {
            Some(i) => i,
            // A late marker of a flash of a trial already decided and ended.
            None if self
                .settled_end
                .is_some_and(|e| time <= e + FLAG_TOLERANCE_S) =>
            {
                if self.epocher.is_kept(onset as u64) {
                    self.counts.after_decision += 1;
                } else {
                    self.counts.too_old += 1;
                }
                return;
            }
            None => {
                self.counts.implicit_trials += 1;
                self.open_trial();
                if let Some(t) = self.trials.back_mut() {
                    t.implicit = true;
                }
                self.trials.len() - 1
            }
        };
        let tag = self.next_tag;
        let trial = self.trials[ti].number;
        match self.epocher.push_marker(Marker {
            onset: onset as u64,
            code,
            tag,
        }) {
            Ok(true) => {}
            Ok(false) => {
                self.counts.duplicate += 1;
                return;
            }
            // Its epoch starts before the samples kept (or before the stream).
            Err(_) => {
                self.counts.too_old += 1;
                return;
            }
        }
        self.next_tag += 1;
        self.counts.flashes += 1;
        let target = self.take_loose_flag(time);
        self.flashes.insert(
            tag,
            Flash {
                trial,
                code,
                time,
                target,
            },
        );
        self.last_flash = Some((tag, time));
        let per_trial = match self.paradigm.trial_end {
            TrialEnd::Flashes(n) => Some(n),
            TrialEnd::Marker => None,
        };
        let t = &mut self.trials[ti];
        t.first_time = t.first_time.min(time);
        t.announced += 1;
        if per_trial == Some(t.announced) {
            t.ended = true;
        }
    }

    fn epoch(&mut self, e: ReadyEpoch, out: &mut Vec<Output>) -> Result<(), SessionError> {
        let Some(flash) = self.flashes.remove(&e.marker.tag) else {
            self.counts.after_decision += 1;
            return Ok(());
        };
        // The sample that completed this epoch (whatever block it came in).
        let completed_at = (self.epocher.epoch_end(e.marker.onset) - 1).max(0) as u64;
        let Some(ti) = self.trials.iter().position(|t| t.number == flash.trial) else {
            self.counts.after_decision += 1;
            return Ok(());
        };
        let paradigm = &self.paradigm;
        // What the flash showed: no choice for a decoy.
        let shown = paradigm.choices_of(flash.code);
        let t = &mut self.trials[ti];
        t.completed += 1;
        if t.decided {
            self.counts.after_decision += 1;
            return Ok(());
        }
        if !shown.is_empty() {
            *t.per_code.entry(flash.code).or_insert(0) += 1;
        }
        if !e.accepted {
            self.counts.rejected += 1;
            return Ok(());
        }
        t.last_sample = completed_at;
        if t.calibration {
            let label = flash.target.or_else(|| t.cue.map(|c| shown.contains(&c)));
            match label {
                Some(y) => {
                    self.calibration.epochs.push(e.data);
                    self.calibration.labels.push(y);
                    self.calibration.trials.push(t.number);
                }
                None => self.counts.unlabelled += 1,
            }
            return Ok(());
        }
        let number = t.number;
        let score = self.decoder.score(e.data.view(), flash.code, number)?;
        let t = &mut self.trials[ti];
        // An unsupervised decoder keeps every epoch for its refit (scored or not yet).
        if score.is_some() || self.decoder.is_unlabelled() {
            t.scored += 1;
        }
        let Some(score) = score else { return Ok(()) };
        // A decoy's epoch is evidence for no choice (an unsupervised decoder keeps it above).
        let shown = self.paradigm.choices_of(flash.code);
        if shown.is_empty() {
            return Ok(());
        }
        if let Ok(d) = self.decoder.decision() {
            let llr = d.scores.llr(score);
            for &c in shown {
                t.evidence[c] += llr;
            }
            if let Some(rule) = self.rule {
                if !t.ended || t.completed < t.announced {
                    let rounds = rounds_done(&t.per_code, self.paradigm.groups.len());
                    if let v @ (Verdict::Choose { .. } | Verdict::Abstain { .. }) =
                        rule.check(rounds, &t.evidence)
                    {
                        let d = decision_of(t, v, true);
                        t.decided = true;
                        out.push(Output::Stop { trial: t.number });
                        out.push(Output::Decision(d));
                    }
                }
            }
        }
        Ok(())
    }

    /// Remembers the end of a trial taken off the open ones.
    fn settled(&mut self, end: Option<f64>) {
        if let Some(e) = end {
            self.settled_end = Some(self.settled_end.map_or(e, |s| s.max(e)));
        }
    }

    /// Decides every trial whose flashes are all in, oldest first; fits the calibration once
    /// its trials are. A trial decided early goes once it has ended (its later epochs are
    /// counted as they arrive).
    fn settle(&mut self, out: &mut Vec<Output>) -> Result<(), SessionError> {
        while let Some(t) = self.trials.front() {
            let past_end = t.end_time.is_none_or(|e| {
                self.onset_of(e).is_some_and(|o| {
                    self.epocher.received() as i64 >= self.epocher.epoch_end(o.max(0) as u64)
                })
            });
            let complete = t.ended && t.completed >= t.announced && past_end;
            if t.decided {
                if !t.ended {
                    break;
                }
                let t = self.trials.pop_front().expect("front exists");
                self.settled(t.end_time);
                continue;
            }
            if !complete {
                break;
            }
            let mut t = self.trials.pop_front().expect("front exists");
            self.settled(t.end_time);
            if t.announced == 0 {
                self.counts.empty_trials += 1;
                continue;
            }
            if t.calibration {
                self.calibration.done += 1;
                if self.calibration.done == self.calibration_trials {
                    out.push(self.fit_calibration()?);
                }
                continue;
            }
            if let Some(d) = self.final_decision(&mut t)? {
                out.push(Output::Decision(d));
            }
        }
        Ok(())
    }

    fn final_decision(&mut self, t: &mut Trial) -> Result<Option<ListenerDecision>, SessionError> {
        if self.decoder.is_unlabelled() {
            let constraint = self
                .constraint
                .as_ref()
                .expect("an unlabelled listener has one");
            let abstain_below = match &self.decoder {
                OnlineDecoder::Unlabelled(u) => u.abstain_below(),
                _ => 0.0,
            };
            let n = self.paradigm.labels.len();
            let sets = if t.scored > 0 {
                self.decoder.refit_unlabelled(t.number)?
            } else {
                None
            };
            let posterior = match sets {
                Some(sets) => choice_posterior(&self.paradigm, constraint, &sets),
                None => vec![1.0 / n as f64; n],
            };
            let p = Posterior {
                p: posterior,
                p_none: 0.0,
            };
            let (best, pb) = p.best();
            let v = if t.scored > 0 && pb >= abstain_below && pb.is_finite() {
                Verdict::Choose {
                    index: best,
                    posterior: p,
                }
            } else {
                Verdict::Abstain { posterior: p }
            };
            return Ok(Some(decision_of(t, v, false)));
        }
        let Ok(d) = self.decoder.decision() else {
            return Ok(None);
        };
        let rule = self.rule.unwrap_or(d.rule);
        let rounds = rounds_done(&t.per_code, self.paradigm.groups.len()).max(rule.max_rounds());
        let v = match rule.check(rounds, &t.evidence) {
            Verdict::Choose { posterior, .. } if t.scored == 0 => Verdict::Abstain { posterior },
            Verdict::Continue => Verdict::Abstain {
                posterior: Posterior::from_evidence(&t.evidence, 0.0),
            },
            v => v,
        };
        Ok(Some(decision_of(t, v, false)))
    }

    fn fit_calibration(&mut self) -> Result<Output, SessionError> {
        let cal = std::mem::take(&mut self.calibration);
        let n = cal.epochs.len();
        let n_ch = self.ch_names.len();
        let (c, nt) = cal.epochs.first().map_or((n_ch, 0), |e| e.dim());
        let mut x = Array3::zeros((n, c, nt));
        for (i, e) in cal.epochs.iter().enumerate() {
            x.index_axis_mut(Axis(0), i).assign(e);
        }
        let targets = cal.labels.iter().filter(|&&y| y).count();
        if targets == 0 || targets == n {
            return Err(SessionError::InvalidParameter {
                name: "calibration",
                value: format!("{n} epochs, {targets} targets"),
                reason: "the calibration trials need both target and non-target flashes".into(),
            });
        }
        let (model, cv_auc, _, _) = crate::fit::fit_session_model_oof(
            &self.decoder_params,
            self.sfreq,
            &self.ch_names,
            x.view().into(),
            &cal.labels,
            &cal.trials,
        )?;
        self.decoder = OnlineDecoder::Fixed(model);
        self.calibration.done = cal.done;
        Ok(Output::Calibrated {
            trials: cal.done,
            epochs: n,
            targets,
            cv_auc,
        })
    }
}

/// Complete rounds: how often the least flashed code of the paradigm's `n_codes` flashed.
fn rounds_done(per_code: &BTreeMap<u32, usize>, n_codes: usize) -> usize {
    if per_code.len() < n_codes {
        return 0;
    }
    per_code.values().copied().min().unwrap_or(0)
}

fn decision_of(t: &Trial, v: Verdict, early: bool) -> ListenerDecision {
    let (choice, posterior) = match v {
        Verdict::Choose { index, posterior } => (Some(index), posterior),
        Verdict::Abstain { posterior } => (None, posterior),
        Verdict::Continue => (None, Posterior::from_evidence(&t.evidence, 0.0)),
    };
    ListenerDecision {
        trial: t.number,
        choice,
        best: posterior.best().0,
        p_none: posterior.p_none,
        posterior: posterior.p,
        flashes: t.scored,
        flashes_shown: t.announced,
        early,
        completed_at: t.last_sample,
    }
}

/// The unsupervised decoder's constraint for `paradigm`: one code per trial (one choice per
/// flash), one row and one column (a speller), or one choice whose flashes are those of the
/// groups showing it (`[groups]`); its decoys are known non-targets.
fn constraint_of(paradigm: &Paradigm) -> Result<Constraint, SessionError> {
    let c = if let Some(sp) = &paradigm.speller {
        Constraint::speller(sp)?
    } else if paradigm.one_choice_per_flash() {
        Constraint::one_of(&paradigm.codes())?
    } else {
        Constraint::groups(paradigm.labels.len(), paradigm.groups.clone())?
    };
    Ok(c.with_decoys(&paradigm.decoys)?)
}

/// Each choice's posterior from the constraint sets' posteriors: a code's choice takes its
/// code's; a speller's symbol, its row's times its column's; under group flashes the one set
/// is the choices'.
fn choice_posterior(paradigm: &Paradigm, constraint: &Constraint, sets: &[Vec<f64>]) -> Vec<f64> {
    if constraint.is_grouped() {
        return sets[0].clone();
    }
    let mut p = vec![1.0; paradigm.labels.len()];
    for (set, probs) in constraint.sets().iter().zip(sets) {
        for (code, &q) in set.iter().zip(probs) {
            for &c in &paradigm.groups[code] {
                p[c] *= q;
            }
        }
    }
    // Choices no set's code shows keep 1 × …: a speller's every symbol is in one row and one
    // column, a one-of paradigm's in one code; normalise anyway.
    let z: f64 = p.iter().sum();
    if z > 0.0 && z.is_finite() {
        p.iter_mut().for_each(|v| *v /= z);
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{s, Array2};
    use oddball_decode::preset::Preset;
    use std::path::Path;

    const PARADIGM: &str = r#"
name = "four"
[choices]
labels = ["up", "right", "down", "left"]
codes = [1, 2, 3, 4]
[markers]
flash = ["Stim/{code}", "{code}"]
trial_start = "TrialStart"
trial_end = "TrialEnd"
cue = "Cue/{label}"
[events]
target = ["Target"]
nontarget = ["NonTarget"]
"#;

    const SFREQ: f64 = 250.0;

    /// A synthetic four-choice session: `n_trials` trials of 5 rounds of the four codes (a flash
    /// every 0.24 s: whole samples, as a flash half-way between two samples could go to
    /// either), 2 s apart; trial `k` attends choice `k % 4`, whose flashes evoke a 6 µV
    /// half-sine 300–500 ms later on every channel over 10 µV peak-to-peak noise. Returns the
    /// EEG `(4, n)` and the markers `(text, time s)` in time order.
    fn session(n_trials: usize, seed: u64) -> (Array2<f64>, Vec<(String, f64)>) {
        session_with(n_trials, seed, false)
    }

    /// [`session`], with a decoy (code 5, never attended, flagged a non-target) flashed once a
    /// round when `decoy`.
    fn session_with(n_trials: usize, seed: u64, decoy: bool) -> (Array2<f64>, Vec<(String, f64)>) {
        let n_codes = if decoy { 5 } else { 4 };
        session_of(n_trials, seed, n_codes, &|code, k| {
            (code - 1) as usize == k % 4
        })
    }

    /// [`session`]'s EEG and markers for rounds of codes `1..=n_codes`, code `code` a target
    /// in trial `k` when `target(code, k)`.
    fn session_of(
        n_trials: usize,
        seed: u64,
        n_codes: u32,
        target: &dyn Fn(u32, usize) -> bool,
    ) -> (Array2<f64>, Vec<(String, f64)>) {
        let mut markers = Vec::new();
        let mut bumps = Vec::new();
        let mut t = 1.0;
        for k in 0..n_trials {
            markers.push(("TrialStart".to_string(), t - 0.001));
            for r in 0..5 {
                for j in 0..n_codes {
                    // A different order each round.
                    let code = 1 + (j + r as u32 + k as u32) % n_codes;
                    let target = target(code, k);
                    markers.push((format!("Stim/{code}"), t));
                    let flag = if target { "Target" } else { "NonTarget" };
                    markers.push((flag.to_string(), t));
                    if target {
                        bumps.push(t);
                    }
                    t += 0.24;
                }
            }
            markers.push(("TrialEnd".to_string(), t - 0.24));
            t += 2.0;
        }
        let n = ((t + 1.0) * SFREQ) as usize;
        let mut state = seed;
        let mut x = Array2::from_shape_fn((4, n), |_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10.0
        });
        for b in bumps {
            let (a, e) = (((b + 0.3) * SFREQ) as usize, ((b + 0.5) * SFREQ) as usize);
            for i in a..e {
                let v = 6.0 * (std::f64::consts::PI * (i - a) as f64 / (e - a) as f64).sin();
                x.column_mut(i).iter_mut().for_each(|s| *s += v);
            }
        }
        (x, markers)
    }

    fn params(start: ListenerStart, rule: Option<DecisionRule>) -> ListenerParams {
        ListenerParams {
            paradigm: Paradigm::parse(PARADIGM, Path::new("four.toml")).unwrap(),
            start,
            rule,
            decoder: DecoderParams {
                pipeline: Preset::Lda,
                preprocess: Preprocess::peer(),
                rule: DecisionRule::Fixed { rounds: 5 },
                cv_folds: 3,
                chunk: 20,
                seed: 0,
                stopping: None,
            },
        }
    }

    fn names() -> Vec<String> {
        ["Pz", "Oz", "P3", "P4"].map(String::from).to_vec()
    }

    /// Feeds `x` in blocks of `block(i)` samples; each marker is pushed once the EEG has
    /// reached its time plus `delay(k)` s (late deliveries, out of order among themselves).
    fn feed(
        listener: &mut Listener,
        x: &Array2<f64>,
        markers: &[(String, f64)],
        block: &mut dyn FnMut(usize) -> usize,
        delay: &dyn Fn(usize) -> f64,
    ) -> Vec<Output> {
        let mut due: Vec<(f64, usize)> = markers
            .iter()
            .enumerate()
            .map(|(k, (_, t))| {
                let at = t + delay(k);
                // Stamps that are no time (NaN) or far off arrive mid-session.
                (if at.is_finite() && at < 1e3 { at } else { 10.0 }, k)
            })
            .collect();
        due.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut next = 0;
        let mut out = Vec::new();
        let mut i = 0;
        let n = x.ncols();
        while i < n {
            let m = block(i).clamp(1, n - i);
            let last_time = (i + m - 1) as f64 / SFREQ;
            while next < due.len() && due[next].0 <= last_time {
                let (text, t) = &markers[due[next].1];
                out.extend(listener.push_marker(text, *t).unwrap());
                next += 1;
            }
            out.extend(
                listener
                    .push_eeg(x.slice(s![.., i..i + m]), last_time)
                    .unwrap(),
            );
            i += m;
        }
        out.extend(listener.finish().unwrap());
        out
    }

    fn decisions(out: &[Output]) -> Vec<&ListenerDecision> {
        out.iter()
            .filter_map(|o| match o {
                Output::Decision(d) => Some(d),
                _ => None,
            })
            .collect()
    }

    /// The transport loses nothing: blocks of any size, markers delivered late and out of
    /// order within the epoch window, give the same outputs bit for bit.
    #[test]
    fn blocks_and_late_markers_change_no_decision() {
        let (x, markers) = session(12, 7);
        let start = || ListenerStart::Calibrate { trials: 6 };
        let mut a = Listener::new(params(start(), None), SFREQ, &names()).unwrap();
        let reference = feed(&mut a, &x, &markers, &mut |_| 10, &|_| 0.0);
        assert!(matches!(reference[0], Output::Calibrated { trials: 6, .. }));
        let ds = decisions(&reference);
        assert_eq!(ds.len(), 6);
        for d in &ds {
            assert_eq!(d.choice, Some((d.trial - 1) % 4), "{d:?}");
            assert_eq!((d.flashes, d.flashes_shown, d.early), (20, 20, false));
        }
        let mut state = 3u64;
        let mut random = move |_| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            1 + (state >> 33) as usize % 97
        };
        let mut b = Listener::new(params(start(), None), SFREQ, &names()).unwrap();
        let late = feed(&mut b, &x, &markers, &mut random, &|k| {
            0.05 * ((k * 7919) % 6) as f64
        });
        let mut c = Listener::new(params(start(), None), SFREQ, &names()).unwrap();
        let only_late = feed(&mut c, &x, &markers, &mut |_| 10, &|k| {
            0.05 * ((k * 7919) % 6) as f64
        });
        let mut d = Listener::new(params(start(), None), SFREQ, &names()).unwrap();
        let only_blocks = feed(&mut d, &x, &markers, &mut |_| 37, &|_| 0.0);
        assert_eq!(only_blocks, reference, "blocks");
        assert_eq!(only_late, reference, "late");
        assert_eq!(late, reference);
        assert!(b.counts().out_of_order == 0 && b.counts().orphan_flags == 0);
    }

    #[test]
    fn dynamic_stopping_stops_early_with_the_same_choices() {
        let (x, markers) = session(12, 11);
        let cal = || ListenerStart::Calibrate { trials: 6 };
        let mut fixed = Listener::new(params(cal(), None), SFREQ, &names()).unwrap();
        let full = feed(&mut fixed, &x, &markers, &mut |_| 25, &|_| 0.0);
        let mut dynamic = Listener::new(
            params(cal(), Some(DecisionRule::dynamic(MAX_ROUNDS_TEST))),
            SFREQ,
            &names(),
        )
        .unwrap();
        let out = feed(&mut dynamic, &x, &markers, &mut |_| 25, &|_| 0.0);
        let (a, b) = (decisions(&full), decisions(&out));
        assert_eq!(a.len(), b.len());
        let mut fewer = 0;
        for (f, d) in a.iter().zip(&b) {
            assert_eq!(f.choice, d.choice);
            if d.early {
                fewer += 1;
                assert!(d.flashes < 20);
                // The stop for this trial came right before its decision.
                let i = out
                    .iter()
                    .position(|o| matches!(o, Output::Decision(x) if x.trial == d.trial))
                    .unwrap();
                assert_eq!(out[i - 1], Output::Stop { trial: d.trial });
            }
        }
        assert!(fewer >= 3, "{fewer} of {} trials stopped early", b.len());
        // The epochs of flashes after a stop are counted, not decided again.
        assert!(dynamic.counts().after_decision > 0);
        // Markers up to half a second late and out of order — also the late flashes of a trial
        // already stopped, decided and ended, which arrive after the next trial's start — decide
        // the same (they join no new trial).
        let mut late = Listener::new(
            params(cal(), Some(DecisionRule::dynamic(MAX_ROUNDS_TEST))),
            SFREQ,
            &names(),
        )
        .unwrap();
        let shuffled = feed(&mut late, &x, &markers, &mut |_| 25, &|k| {
            ((k * 7919) % 500) as f64 / 1000.0
        });
        let strip = |d: Vec<&ListenerDecision>| -> Vec<_> {
            d.into_iter()
                .map(|d| (d.trial, d.choice, d.flashes, d.early))
                .collect()
        };
        assert_eq!(strip(decisions(&shuffled)), strip(b));
        assert_eq!(late.counts().implicit_trials, 0, "{:?}", late.counts());
    }

    const MAX_ROUNDS_TEST: usize = 5;

    #[test]
    fn bad_markers_are_counted_and_change_nothing() {
        let (x, markers) = session(10, 5);
        let cal = || ListenerStart::Calibrate { trials: 6 };
        let mut clean = Listener::new(params(cal(), None), SFREQ, &names()).unwrap();
        let reference = feed(&mut clean, &x, &markers, &mut |_| 10, &|_| 0.0);
        let mut noisy = markers.clone();
        let mid = noisy[noisy.len() / 2].1;
        noisy.extend([
            ("Hello".to_string(), mid),
            ("Stim/9".to_string(), mid),
            ("Target".to_string(), mid + 0.1234),
            ("Stim/1".to_string(), mid + 1000.0),
            (String::from_utf8(vec![b'x'; 5000]).unwrap(), mid),
            ("Stim/2".to_string(), f64::NAN),
        ]);
        noisy.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut l = Listener::new(params(cal(), None), SFREQ, &names()).unwrap();
        let out = feed(&mut l, &x, &noisy, &mut |_| 10, &|_| 0.0);
        assert_eq!(decisions(&out), decisions(&reference));
        let c = l.counts();
        assert_eq!((c.unknown, c.orphan_flags, c.future), (4, 1, 1), "{c:?}");
        // A flash whose epoch is long gone is too old.
        let out = l.push_marker("Stim/3", 0.5).unwrap();
        assert!(out.is_empty());
        assert_eq!(l.counts().too_old, 1);
    }

    #[test]
    fn hours_of_trials_keep_nothing_per_trial() {
        let (x, markers) = session(40, 2);
        let p = params(ListenerStart::Calibrate { trials: 4 }, None);
        let mut l = Listener::new(p, SFREQ, &names()).unwrap();
        let out = feed(&mut l, &x, &markers, &mut |_| 50, &|_| 0.0);
        assert_eq!(decisions(&out).len(), 36);
        assert!(
            l.trials.is_empty() && l.flashes.is_empty(),
            "{:?}",
            l.trials
        );
        assert!(l.calibration.epochs.is_empty());
    }

    /// A decoy is a flash of no choice: calibrated, its epochs are non-targets and add no
    /// evidence; uncalibrated, the EM takes them as known non-targets. Both decide every trial.
    #[test]
    fn decoys_are_flashed_and_chosen_by_nobody() {
        let (x, markers) = session_with(12, 5, true);
        let decoyed = || {
            let text = PARADIGM.replace("name = \"four\"", "name = \"four\"\ndecoys = [5]");
            Paradigm::parse(&text, Path::new("four.toml")).unwrap()
        };
        let mut p = params(ListenerStart::Calibrate { trials: 6 }, None);
        p.paradigm = decoyed();
        let mut l = Listener::new(p, SFREQ, &names()).unwrap();
        let out = feed(&mut l, &x, &markers, &mut |_| 25, &|_| 0.0);
        // 6 trials × 5 rounds × 5 flashes, one target a round.
        assert!(
            matches!(
                out[0],
                Output::Calibrated {
                    trials: 6,
                    epochs: 150,
                    targets: 30,
                    ..
                }
            ),
            "{:?}",
            out[0]
        );
        let ds = decisions(&out);
        assert_eq!(ds.len(), 6);
        for d in &ds {
            assert_eq!(d.choice, Some((d.trial - 1) % 4), "{d:?}");
        }
        assert_eq!(l.counts().unknown, 0);
        let (l, _) = uncalibrated_twelve(decoyed(), &x, &markers, "with decoys");
        assert_eq!(l.counts().unknown, 0);
    }

    /// Feeds a 12-trial session to an uncalibrated listener of `paradigm` (trial k attends
    /// choice `k % 4`): every trial decided, at least 10 right.
    fn uncalibrated_twelve(
        paradigm: Paradigm,
        x: &Array2<f64>,
        markers: &[(String, f64)],
        what: &str,
    ) -> (Listener, Vec<ListenerDecision>) {
        let mut p = params(ListenerStart::Uncalibrated { params: None }, None);
        p.paradigm = paradigm;
        let mut l = Listener::new(p, SFREQ, &names()).unwrap();
        let out = feed(&mut l, x, markers, &mut |_| 25, &|_| 0.0);
        let ds: Vec<ListenerDecision> = decisions(&out).into_iter().cloned().collect();
        assert_eq!(ds.len(), 12);
        let right = ds
            .iter()
            .filter(|d| d.choice == Some((d.trial - 1) % 4))
            .count();
        println!("uncalibrated, {what}: {right}/12 right");
        assert!(right >= 10, "{what}: {right}/12");
        (l, ds)
    }

    #[test]
    fn a_start_the_paradigm_cannot_support_is_refused() {
        let no_flags = PARADIGM.replace("cue = \"Cue/{label}\"\n", "").replace(
            "[events]\ntarget = [\"Target\"]\nnontarget = [\"NonTarget\"]\n",
            "",
        );
        let mut p = params(ListenerStart::Calibrate { trials: 3 }, None);
        p.paradigm = Paradigm::parse(&no_flags, Path::new("x.toml")).unwrap();
        let e = Listener::new(p, SFREQ, &names()).unwrap_err();
        assert!(e.to_string().contains("nothing labels"), "{e}");
    }

    /// Flashes of groups of choices decode without calibration: each choice's evidence is the
    /// flashes showing it (`Constraint::groups`).
    #[test]
    fn group_flashes_decode_without_calibration() {
        let text = r#"
name = "g"
[choices]
labels = ["up", "right", "down", "left"]
[groups]
"1" = ["up", "right"]
"2" = ["down", "left"]
"3" = ["up", "down"]
"4" = ["right", "left"]
"5" = ["up"]
"6" = ["left"]
[markers]
flash = "Stim/{code}"
trial_start = "TrialStart"
trial_end = "TrialEnd"
"#;
        let paradigm = Paradigm::parse(text, Path::new("g.toml")).unwrap();
        let shows = paradigm.groups.clone();
        let (x, markers) = session_of(12, 3, 6, &|code, k| shows[&code].contains(&(k % 4)));
        let (_, ds) = uncalibrated_twelve(paradigm, &x, &markers, "group flashes");
        for d in &ds {
            assert!(
                (d.posterior.iter().sum::<f64>() - 1.0).abs() < 1e-9,
                "{d:?}"
            );
        }
    }
}
