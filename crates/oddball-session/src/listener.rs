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

use ndarray::{Array2, Array3, ArrayView2, Axis};
use oddball_decode::decision::{DecisionRule, Posterior, Verdict};
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_decode::unsupervised::Constraint;
use oddball_io::paradigm::{MarkerKind, Paradigm, TrialEnd};
use serde::Serialize;

use crate::decoder::{
    model_channels, DecoderParams, OnlineDecoder, UncalibratedParams, Unlabelled,
};
use crate::online::{Marker, OnlineEpocher, ReadyEpoch};
use crate::SessionError;

/// A flash stamped further than this past the newest EEG sample is not believed, s.
pub const MAX_AHEAD_S: f64 = 5.0;
/// A flag (target / non-target) belongs to the flash stamped within this of it, s.
pub const FLAG_TOLERANCE_S: f64 = 0.002;
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
    Uncalibrated { params: Option<UncalibratedParams> },
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

/// What the listener says.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Output {
    /// Trial `trial` is decided before its flashes ran out: the program may end it.
    Stop {
        trial: usize,
    },
    Decision(ListenerDecision),
    /// The in-stream calibration is fitted; decisions follow.
    Calibrated {
        trials: usize,
        epochs: usize,
        targets: usize,
        cv_auc: f64,
    },
}

/// One trial decided.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ListenerDecision {
    /// 1, 2, … in the order trials started.
    pub trial: usize,
    /// The chosen choice's index; `None`: abstention (no choice credible).
    pub choice: Option<usize>,
    /// The most probable choice (chosen or not).
    pub best: usize,
    /// Posterior of each choice.
    pub posterior: Vec<f64>,
    /// Posterior that no choice was attended (dynamic stopping's no-control prior).
    pub p_none: f64,
    /// Flashes whose epochs were scored.
    pub flashes: usize,
    /// Flashes the trial announced until the decision.
    pub flashes_shown: usize,
    /// Decided before the trial's end (dynamic stopping).
    pub early: bool,
    /// The sample (index in the stream) that completed the last epoch the decision used.
    pub completed_at: u64,
}

/// Markers the listener could not use, by reason, and what it read.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct MarkerCounts {
    pub markers: u64,
    pub flashes: u64,
    /// Texts no pattern of the paradigm reads (or a code it has no choice for).
    pub unknown: u64,
    /// Flashes whose epoch started before the samples still kept (far in the past).
    pub too_old: u64,
    /// Flashes stamped more than [`MAX_AHEAD_S`] past the newest sample.
    pub future: u64,
    /// Flashes stamped before the previous flash.
    pub out_of_order: u64,
    /// The same flash twice.
    pub duplicate: u64,
    /// Target / non-target flags with no flash at their timestamp.
    pub orphan_flags: u64,
    /// Flashes outside a trial, which opened one.
    pub implicit_trials: u64,
    /// Trials a new trial start cut short (no end marker).
    pub unended_trials: u64,
    /// Trial ends with no trial open.
    pub stray_ends: u64,
    /// Calibration flashes with neither a flag nor a cue.
    pub unlabelled: u64,
    /// Epochs of flashes after their trial was decided (dynamic stopping) or given up.
    pub after_decision: u64,
    /// Epochs the rejection rule dropped.
    pub rejected: u64,
    /// Markers dropped because too many waited for the first EEG sample.
    pub held_overflow: u64,
    /// Trials given up because too many were open.
    pub abandoned_trials: u64,
    /// Trials that ended with no flash.
    pub empty_trials: u64,
}

#[derive(Debug, Clone, Copy)]
struct Flash {
    trial: usize,
    code: u32,
    target: Option<bool>,
}

#[derive(Debug)]
struct Trial {
    number: usize,
    cue: Option<usize>,
    announced: usize,
    completed: usize,
    ended: bool,
    decided: bool,
    calibration: bool,
    evidence: Vec<f64>,
    per_code: BTreeMap<u32, usize>,
    scored: usize,
    last_sample: u64,
}

/// Labelled calibration epochs of the first trials.
#[derive(Debug, Default)]
struct CalibrationSet {
    epochs: Vec<Array2<f64>>,
    labels: Vec<bool>,
    trials: Vec<usize>,
    done: usize,
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
                    Some(p) => p,
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
        for t in self.trials.iter_mut() {
            t.ended = true;
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
        self.trials.push_back(Trial {
            number: self.trial_count,
            cue: self.next_cue.take(),
            announced: 0,
            completed: 0,
            ended: false,
            decided: false,
            calibration,
            evidence: vec![0.0; self.paradigm.labels.len()],
            per_code: BTreeMap::new(),
            scored: 0,
            last_sample: 0,
        });
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
                    .last_flash
                    .filter(|&(_, t)| (t - time).abs() <= FLAG_TOLERANCE_S)
                    .and_then(|(tag, _)| self.flashes.get_mut(&tag));
                match hit {
                    Some(f) => f.target = Some(target),
                    None => self.counts.orphan_flags += 1,
                }
            }
            MarkerKind::TrialStart => {
                if self.current().is_some() {
                    self.counts.unended_trials += 1;
                    self.end_current();
                }
                self.open_trial();
            }
            MarkerKind::TrialEnd => {
                if self.current().is_some() {
                    self.end_current();
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

    fn end_current(&mut self) {
        if let Some(t) = self.current() {
            t.ended = true;
        }
    }

    fn flash(&mut self, code: u32, time: f64) {
        if !self.paradigm.groups.contains_key(&code) {
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
        if self.current().is_none() {
            self.counts.implicit_trials += 1;
            self.open_trial();
        }
        let tag = self.next_tag;
        let trial = self.current().map_or(0, |t| t.number);
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
        self.flashes.insert(
            tag,
            Flash {
                trial,
                code,
                target: None,
            },
        );
        self.last_flash = Some((tag, time));
        let per_trial = match self.paradigm.trial_end {
            TrialEnd::Flashes(n) => Some(n),
            TrialEnd::Marker => None,
        };
        if let Some(t) = self.current() {
            t.announced += 1;
            if per_trial == Some(t.announced) {
                t.ended = true;
            }
        }
    }

    fn epoch(&mut self, e: ReadyEpoch, out: &mut Vec<Output>) -> Result<(), SessionError> {
        let Some(flash) = self.flashes.remove(&e.marker.tag) else {
            self.counts.after_decision += 1;
            return Ok(());
        };
        let completed_at = self.epocher.received().saturating_sub(1);
        let Some(ti) = self.trials.iter().position(|t| t.number == flash.trial) else {
            self.counts.after_decision += 1;
            return Ok(());
        };
        let groups = &self.paradigm.groups;
        let t = &mut self.trials[ti];
        t.completed += 1;
        if t.decided {
            self.counts.after_decision += 1;
            return Ok(());
        }
        *t.per_code.entry(flash.code).or_insert(0) += 1;
        if !e.accepted {
            self.counts.rejected += 1;
            return Ok(());
        }
        t.last_sample = completed_at;
        if t.calibration {
            let label = flash
                .target
                .or_else(|| t.cue.map(|c| groups[&flash.code].contains(&c)));
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
        if let Ok(d) = self.decoder.decision() {
            let llr = d.scores.llr(score);
            for &c in &groups[&flash.code] {
                t.evidence[c] += llr;
            }
            if let Some(rule) = self.rule {
                if !t.ended || t.completed < t.announced {
                    let rounds = rounds_done(&t.per_code, groups.len());
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

    /// Decides every trial whose flashes are all in, oldest first; fits the calibration once
    /// its trials are. A trial decided early goes once it has ended (its later epochs are
    /// counted as they arrive).
    fn settle(&mut self, out: &mut Vec<Output>) -> Result<(), SessionError> {
        while let Some(t) = self.trials.front() {
            let complete = t.ended && t.completed >= t.announced;
            if t.decided {
                if !t.ended {
                    break;
                }
                self.trials.pop_front();
                continue;
            }
            if !complete {
                break;
            }
            let mut t = self.trials.pop_front().expect("front exists");
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
/// flash), or one row and one column (a speller).
fn constraint_of(paradigm: &Paradigm) -> Result<Constraint, SessionError> {
    if let Some(sp) = &paradigm.speller {
        return Ok(Constraint::speller(sp)?);
    }
    if paradigm.one_choice_per_flash() {
        return Ok(Constraint::one_of(&paradigm.codes())?);
    }
    Err(SessionError::InvalidParameter {
        name: "calibration none",
        value: paradigm.path.display().to_string(),
        reason: "the unsupervised decoder needs one choice per flash or a row/column speller; \
                 this paradigm's flashes show other groups"
            .into(),
    })
}

/// Each choice's posterior from the constraint sets' posteriors: a code's choice takes its
/// code's; a speller's symbol, its row's times its column's.
fn choice_posterior(paradigm: &Paradigm, constraint: &Constraint, sets: &[Vec<f64>]) -> Vec<f64> {
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
