//! The replay subject: real EEG from P300-speller files (BCI2000's sample files, BCI
//! Competition II IIb's runs) played back as a four-choice session. Nothing is synthesised.
//! Calibration and test may each be several recordings (IIb: four training runs, two test
//! runs); each is streamed on its own (no filter runs across a file boundary) and characters
//! are numbered across them in the order given. A test run recorded without labels is
//! labelled by the text it spelled before it reaches here: its labels only say which row or
//! column is the attended bulb's, nothing is fitted on them.
//!
//! The recording is streamed, in its recorded order, through the same causal
//! [`OnlineEpocher`] as a live session, and every flash's epoch is scored as soon as it is
//! complete. A four-choice decision is then made of real flashes of one character: the attended
//! bulb's flashes are those of the character's target row (or column), the other three bulbs'
//! those of three non-target rows (or columns) of the same character, chosen with a seed; each
//! round is one speller sequence, in recorded order. A character of 15 sequences gives
//! `15 / rounds_per_decision` decisions from its rows and as many from its columns.
//!
//! Calibration fits the preset on every flash of the calibration recording (targets flagged),
//! with the score model fitted on cross-validated scores (folds by character).
//!
//! The timing of the four-bulb panel ([`ReplayParams::paradigm`]: the paper's countdown and
//! rounds of 1 s, or the `fast` preset's flash every 175 ms, which is the recording's own flash
//! rate) is used for the information transfer rate, as if the same flashes had been shown on
//! the panel; the speller showed each round's four flashes among eight others (a 12-flash
//! sequence every 2.1 s), so its targets came further apart than on a fast four-bulb panel and
//! their P300s were not shrunk by a short target-to-target interval as the panel's would be.

use oddball_arm::Command;
use oddball_decode::decision::DecisionModel;
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_decode::preset::Preset;
use oddball_io::Recording;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::decision::{CalibrationReport, Decision, TrialOutcome};
use crate::decoder::DecoderParams;
use crate::fit::fit_session_model_oof;
use crate::online::{Marker, OnlineEpocher, ReadyEpoch};
use crate::paradigm::FourBulbParams;
use crate::SessionError;
use oddball_decode::stopping::Expected;

/// Settings of a replayed session.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplayParams {
    pub paradigm: FourBulbParams,
    /// The pipeline, pre-processing, decision rule and folds, as a session has them (the seed
    /// chooses the non-targets and the bulb assignment; with `stopping`, the rule is chosen
    /// from the calibration recording for the most expected bits per minute at `paradigm`'s
    /// timing, [`calibrate_for_bit_rate`]).
    #[serde(flatten)]
    pub decoder: DecoderParams,
    /// Speller sequences (rounds) available to one decision.
    pub rounds_per_decision: usize,
}

impl ReplayParams {
    /// The paper's four-bulb timing and causal 1–15 Hz band-pass, without amplitude rejection:
    /// the BCI2000 sample files run large (median epoch peak-to-peak 110 µV on eeg3_1 after
    /// the band-pass), a 150 µV threshold would drop 15 % of their flashes, and the peer stack
    /// rejects none either. 4 folds, 20-sample chunks.
    pub fn paper(pipeline: Preset) -> Self {
        let paradigm = FourBulbParams::paper();
        Self {
            paradigm,
            decoder: DecoderParams {
                preprocess: Preprocess {
                    reject_peak_to_peak_uv: None,
                    ..Preprocess::online()
                },
                cv_folds: 4,
                ..DecoderParams::paper(pipeline, &paradigm)
            },
            rounds_per_decision: paradigm.n_rounds,
        }
    }
}

/// Every epoch of a recording's events, streamed causally; `None` where the recording ends
/// before the epoch does.
pub fn stream_epochs(
    rec: &Recording,
    pre: &Preprocess,
    chunk: usize,
) -> Result<Vec<Option<ReadyEpoch>>, SessionError> {
    let mut out: Vec<Option<ReadyEpoch>> = vec![None; rec.raw.events().len()];
    stream_epochs_with(rec, pre, chunk, &mut |e| {
        let tag = e.marker.tag;
        out[tag] = Some(e);
        Ok(())
    })?;
    Ok(out)
}

/// [`stream_epochs`] handing each epoch to `on_epoch` as it completes (its marker's tag is the
/// event's index) instead of keeping them all.
pub fn stream_epochs_with(
    rec: &Recording,
    pre: &Preprocess,
    chunk: usize,
    on_epoch: &mut dyn FnMut(ReadyEpoch) -> Result<(), SessionError>,
) -> Result<(), SessionError> {
    let raw = &rec.raw;
    let mut ep = OnlineEpocher::new(pre, raw.sfreq(), raw.n_channels())?;
    for (tag, e) in raw.events().iter().enumerate() {
        ep.push_marker(Marker {
            onset: e.onset as u64,
            code: e.code,
            tag,
        })?;
    }
    let data = raw.data();
    let n = data.ncols();
    let mut at = 0;
    while at < n {
        let end = (at + chunk.max(1)).min(n);
        for e in ep.push_samples(data.slice(ndarray::s![.., at..end]))? {
            on_epoch(e)?;
        }
        at = end;
    }
    Ok(())
}

/// Every recording's accepted epochs, as the online epocher streams them, held as windows
/// into each recording's band-passed copy ([`crate::online::offline_windows`], the offline
/// twin of the stream: the same epochs kept and dropped, the same samples to the bit): the
/// pooled epochs, each one's (recording, event index), and how many were rejected (not
/// counting those the recording ends before).
struct Accepted {
    epochs: oddball_signal::Epochs,
    at: Vec<(usize, usize)>,
    rejected: usize,
}

fn accepted_windows(recs: &[Recording], pre: &Preprocess) -> Result<Accepted, SessionError> {
    let first = first_of(recs)?;
    for other in &recs[1..] {
        check_same_layout(first, other)?;
    }
    let mut parts = Vec::with_capacity(recs.len());
    let mut at = Vec::new();
    let mut rejected = 0;
    for (r, rec) in recs.iter().enumerate() {
        let events = rec.raw.events().as_slice();
        let (epochs, log) = crate::online::offline_windows(pre, &rec.raw, events)?;
        let mut dropped = log.dropped.iter().map(|d| d.index).peekable();
        rejected += log
            .dropped
            .iter()
            .filter(|d| {
                !matches!(
                    d.reason,
                    oddball_signal::epochs::DropReason::OutOfBounds { .. }
                )
            })
            .count();
        for i in 0..events.len() {
            if dropped.next_if_eq(&i).is_none() {
                at.push((r, i));
            }
        }
        parts.push(epochs);
    }
    Ok(Accepted {
        epochs: oddball_signal::Epochs::pool(parts)?,
        at,
        rejected,
    })
}

/// The first of `recs`, or the error saying there is none.
fn first_of(recs: &[Recording]) -> Result<&Recording, SessionError> {
    recs.first().ok_or_else(|| SessionError::InvalidParameter {
        name: "replayed recordings",
        value: "[]".into(),
        reason: "at least one recording".into(),
    })
}

/// What a replayed subject's report says about its decisions.
pub const REPLAY_NOTE: &str = "replayed speller flashes: the four bulbs of each decision are the target and three non-target rows (or columns) of one spelled character; seconds and ITR use the four-bulb panel's timing; the raw EEG is the source file itself, so no session.dat is written";

/// The recording's speller layout, or the error saying it has none.
fn speller_of(rec: &Recording) -> Result<&oddball_io::Speller, SessionError> {
    rec.speller
        .as_ref()
        .ok_or_else(|| SessionError::NotASpeller {
            path: rec.path.display().to_string(),
        })
}

/// The character (block) of each event, from the speller's flashes per character.
fn character_of_events(rec: &Recording) -> Result<Vec<usize>, SessionError> {
    let speller = speller_of(rec)?;
    let n = rec.raw.events().len();
    let per = speller.flashes_per_character.unwrap_or(n).max(1);
    Ok((0..n).map(|i| i / per).collect())
}

/// Trains the preset on every accepted epoch of `recs` and fits the score model on scores
/// cross-validated by character.
pub fn calibrate(
    recs: &[Recording],
    params: &ReplayParams,
) -> Result<(Model, CalibrationReport), SessionError> {
    let c = calibrate_for_bit_rate(recs, params)?;
    Ok((c.model, c.report))
}

/// A replayed subject's calibration ([`calibrate_for_bit_rate`]).
#[derive(Debug)]
pub struct Calibrated {
    pub model: Model,
    pub report: CalibrationReport,
    /// With [`DecoderParams::stopping`]: the stopping rule chosen and what it expects.
    pub expected: Option<Expected>,
    /// The accepted epochs it was fitted on, as the online epocher streams them (windows into
    /// each recording's band-passed copy, targets flagged): what a report's ERP plot shows.
    pub epochs: oddball_signal::Epochs,
}

/// [`calibrate`], and with [`DecoderParams::stopping`] the stopping rule chosen from the
/// cross-validated calibration scores (set in the model's decision model) with what it expects.
pub fn calibrate_for_bit_rate(
    recs: &[Recording],
    params: &ReplayParams,
) -> Result<Calibrated, SessionError> {
    let t0 = std::time::Instant::now();
    let accepted = accepted_windows(recs, &params.decoder.preprocess)?;
    let rec = &recs[0];
    let mut y = Vec::with_capacity(accepted.at.len());
    let mut groups = Vec::with_capacity(accepted.at.len());
    // Characters are numbered across the recordings, in order.
    let mut char_base = Vec::with_capacity(recs.len());
    let mut n_chars = 0;
    let mut chars_of = Vec::with_capacity(recs.len());
    for rec in recs {
        let chars = character_of_events(rec)?;
        char_base.push(n_chars);
        n_chars += chars.last().map_or(0, |c| c + 1);
        chars_of.push(chars);
    }
    for &(r, i) in &accepted.at {
        let ev = &recs[r].raw.events().as_slice()[i];
        let target = ev.target.ok_or_else(|| SessionError::InvalidParameter {
            name: "calibration recording",
            value: recs[0].path.display().to_string(),
            reason: format!(
                "the event at sample {} (code {}) has no target flag",
                ev.onset, ev.code
            ),
        })?;
        y.push(target);
        groups.push(char_base[r] + chars_of[r][i]);
    }
    let rejected = accepted.rejected;
    let (mut model, cv_auc, d_prime, oof) = fit_session_model_oof(
        &params.decoder,
        rec.raw.sfreq(),
        rec.raw.ch_names(),
        (&accepted.epochs).into(),
        &y,
        &groups,
    )?;
    let mut chosen = None;
    if let (Some(search), Some(decision)) = (&params.decoder.stopping, &mut model.decision) {
        let e = crate::timing::choose_stopping(
            search,
            &decision.scores,
            &oof,
            &y,
            &params.paradigm,
            &params.decoder.preprocess,
        )?;
        decision.rule = e.rule;
        chosen = Some(e);
    }
    Ok(Calibrated {
        model,
        report: CalibrationReport {
            n_trials: n_chars,
            n_epochs: y.len(),
            n_targets: y.iter().filter(|&&t| t).count(),
            n_rejected: rejected,
            cv_auc,
            d_prime,
            fit_seconds: t0.elapsed().as_secs_f64(),
        },
        expected: chosen,
        epochs: accepted.epochs,
    })
}

/// A second calibration or test recording must have the first's channels (same order) and rate.
fn check_same_layout(first: &Recording, other: &Recording) -> Result<(), SessionError> {
    if other.raw.ch_names() != first.raw.ch_names() || other.raw.sfreq() != first.raw.sfreq() {
        return Err(SessionError::InvalidParameter {
            name: "replayed recording",
            value: other.path.display().to_string(),
            reason: format!(
                "its {} channels at {} Hz differ from the {} channels at {} Hz of {}",
                other.raw.n_channels(),
                other.raw.sfreq(),
                first.raw.n_channels(),
                first.raw.sfreq(),
                first.path.display()
            ),
        });
    }
    Ok(())
}

/// Rows or columns of the speller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Dimension {
    Rows,
    Columns,
}

/// Where a replayed decision's flashes come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplayOrigin {
    /// Character (0-based) of the test recording the flashes come from.
    pub character: usize,
    pub dimension: Dimension,
    /// First speller sequence (0-based) used.
    pub first_sequence: usize,
    /// The speller stimulus code shown as each bulb (bulb `k` = paradigm code `k + 1`).
    pub bulb_source_codes: [u32; 4],
}

/// Seconds a decision of `rounds` rounds takes on the four-bulb panel: countdown, the rounds,
/// and the last flash's epoch (the decision comes when its last sample has arrived).
pub fn panel_seconds(p: &FourBulbParams, pre: &Preprocess, rounds: usize) -> f64 {
    p.time_split(rounds, pre.tmax).total_s()
}

/// One decision's worth of real flashes: a character's rows (or columns) over
/// `rounds_per_decision` sequences.
#[derive(Debug, Clone, PartialEq)]
struct Slot {
    character: usize,
    dimension: Dimension,
    first_sequence: usize,
    target: u32,
    /// The other codes of the dimension.
    others: Vec<u32>,
    /// Per sequence, the score of each code of the dimension (`None`: rejected epoch).
    scores: Vec<std::collections::BTreeMap<u32, Option<f64>>>,
}

/// Scores every flash of `rec` with `model` and appends its decision slots to `slots`, its
/// characters numbered from `first_char`; returns its number of characters.
fn slots_of(
    rec: &Recording,
    model: &Model,
    params: &ReplayParams,
    first_char: usize,
    slots: &mut Vec<Slot>,
) -> Result<usize, SessionError> {
    let speller = speller_of(rec)?;
    let events = rec.raw.events().as_slice();
    if !events.iter().any(|e| e.target == Some(true)) {
        return Err(SessionError::InvalidParameter {
            name: "replayed recording",
            value: rec.path.display().to_string(),
            reason: format!(
                "none of its {} flashes is labelled target: label a run recorded without labels \
                 by the text it spelled",
                events.len()
            ),
        });
    }
    let chars = character_of_events(rec)?;
    // Each epoch scored as it is streamed (none kept).
    let mut scores: Vec<Option<Option<f64>>> = vec![None; events.len()];
    stream_epochs_with(rec, &model.preprocess, params.decoder.chunk, &mut |e| {
        scores[e.marker.tag] = Some(if e.accepted {
            Some(model.pipeline.score_epoch(e.data.view())?)
        } else {
            None
        });
        Ok(())
    })?;
    let per_seq = speller.n_rows() + speller.n_cols();
    let n_chars = chars.last().map_or(0, |c| c + 1);
    let r = params
        .rounds_per_decision
        .max(params.decoder.rule.max_rounds());
    for ch in 0..n_chars {
        let idx: Vec<usize> = (0..events.len()).filter(|&i| chars[i] == ch).collect();
        let n_seq = idx.len() / per_seq;
        for dim in [Dimension::Rows, Dimension::Columns] {
            let codes: Vec<u32> = match dim {
                Dimension::Rows => (0..speller.n_rows())
                    .map(|i| speller.code_of_row(i))
                    .collect(),
                Dimension::Columns => (0..speller.n_cols())
                    .map(|i| speller.code_of_col(i))
                    .collect(),
            };
            let Some(target) = idx
                .iter()
                .find(|&&i| events[i].target == Some(true) && codes.contains(&events[i].code))
                .map(|&i| events[i].code)
            else {
                continue;
            };
            'slot: for d in 0..n_seq / r {
                let mut per_sequence = Vec::with_capacity(r);
                for seq in d * r..(d + 1) * r {
                    let seq_idx = &idx[seq * per_seq..(seq + 1) * per_seq];
                    let mut m = std::collections::BTreeMap::new();
                    for &code in &codes {
                        match seq_idx.iter().find(|&&i| events[i].code == code) {
                            Some(&i) => match scores[i] {
                                Some(s) => {
                                    m.insert(code, s);
                                }
                                None => continue 'slot,
                            },
                            None => continue 'slot,
                        }
                    }
                    per_sequence.push(m);
                }
                slots.push(Slot {
                    character: first_char + ch,
                    dimension: dim,
                    first_sequence: d * r,
                    target,
                    others: codes.iter().copied().filter(|&c| c != target).collect(),
                    scores: per_sequence,
                });
            }
        }
    }
    Ok(n_chars)
}

/// Real speller EEG as a source of four-choice decisions, one at a time, for whatever the
/// person intends next (the decision slots are used in recorded order).
#[derive(Debug, Clone)]
pub struct ReplaySource {
    slots: Vec<Slot>,
    next: usize,
    decision: DecisionModel,
    paradigm: FourBulbParams,
    preprocess: Preprocess,
    rng: ChaCha8Rng,
}

impl ReplaySource {
    /// Streams and scores every flash of `recs` (in order) with `model`, and cuts the decision
    /// slots.
    pub fn new(
        recs: &[Recording],
        model: &Model,
        params: &ReplayParams,
    ) -> Result<Self, SessionError> {
        first_of(recs)?;
        params.decoder.rule.validate()?;
        let decision = DecisionModel {
            scores: model.decision.ok_or(SessionError::NotCalibrated)?.scores,
            rule: params.decoder.rule,
        };
        let mut slots = Vec::new();
        let mut first_char = 0;
        for rec in recs {
            model.check_layout(rec.raw.ch_names(), rec.raw.sfreq())?;
            first_char += slots_of(rec, model, params, first_char, &mut slots)?;
        }
        Ok(Self {
            slots,
            next: 0,
            decision,
            paradigm: params.paradigm,
            preprocess: model.preprocess,
            rng: ChaCha8Rng::seed_from_u64(params.decoder.seed),
        })
    }

    /// Decisions left.
    pub fn remaining(&self) -> usize {
        self.slots.len() - self.next
    }

    /// The next decision while the person intends `intended` (no arm: nothing refused, no
    /// pen), and where its flashes come from; `None` when the recording is used up.
    pub fn decide(&mut self, intended: Command) -> Option<(Decision, ReplayOrigin)> {
        let slot = self.slots.get(self.next)?;
        self.next += 1;
        let mut others = slot.others.clone();
        others.shuffle(&mut self.rng);
        others.truncate(3);
        let attended_bulb = self.paradigm.code_of(intended) as usize - 1;
        let mut source = [0u32; 4];
        let mut it = others.into_iter();
        for (k, s) in source.iter_mut().enumerate() {
            *s = if k == attended_bulb {
                slot.target
            } else {
                it.next().expect("three non-targets")
            };
        }
        let rounds: Vec<Vec<Option<f64>>> = slot
            .scores
            .iter()
            .map(|m| source.iter().map(|c| m[c]).collect())
            .collect();
        let (verdict, used) = self.decision.decide(&rounds);
        let (outcome, posterior) = TrialOutcome::of(verdict);
        let posterior = posterior.unwrap_or_else(|| vec![0.25; 4]);
        let decided = match outcome {
            TrialOutcome::Chosen { code } => self.paradigm.command_of(code),
            _ => None,
        };
        Some((
            Decision {
                intended,
                decided,
                abstained: outcome == TrialOutcome::Abstained,
                rounds: used,
                confidence: outcome.confidence(&posterior),
                seconds: panel_seconds(&self.paradigm, &self.preprocess, used),
                ended_s: None,
                arm_refusal: None,
                pen_m: None,
            },
            ReplayOrigin {
                character: slot.character,
                dimension: slot.dimension,
                first_sequence: slot.first_sequence,
                bulb_source_codes: source,
            },
        ))
    }
}

/// Plays `recs` back, in order, as four-choice decisions, the person intending `commands` in turn
/// (cycled), as many decisions as the recordings hold.
pub fn replay(
    recs: &[Recording],
    model: &Model,
    commands: &[Command],
    params: &ReplayParams,
) -> Result<Vec<(Decision, ReplayOrigin)>, SessionError> {
    if commands.is_empty() {
        return Err(SessionError::InvalidParameter {
            name: "commands",
            value: "[]".into(),
            reason: "at least one command".into(),
        });
    }
    let mut source = ReplaySource::new(recs, model, params)?;
    let mut out = Vec::new();
    while let Some(d) = source.decide(commands[out.len() % commands.len()]) {
        out.push(d);
    }
    Ok(out)
}
