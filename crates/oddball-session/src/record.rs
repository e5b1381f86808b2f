//! A session on disk: BCI2000 `.dat` (float32 samples, so the µV values come back bit for bit)
//! with the flashes, trials and decisions as states, and the offline re-evaluation that turns
//! the file back into the same decisions.
//!
//! States written (besides BCI2000's `StimulusCode`/`StimulusType`, held for each flash's
//! on-time; `StimulusType` = 1 on the attended bulb):
//!
//! | state | bits | value over a trial's samples `[start, end)` |
//! |---|---|---|
//! | `TrialNumber` | 16 | the trial's number, from 1 (0 between trials) |
//! | `TargetCode` | 8 | the attended bulb's code (0: attending nothing) |
//! | `ResultCode` | 8 | the decided bulb's code (0: calibration or abstention) |
//! | `Calibration` | 1 | 1 for calibration trials |
//!
//! A trial's `end` is the sample at which its decision was made: the decoder had received every
//! sample before it. Parameters under `Application:Oddball` name the paradigm and the command of
//! each bulb. Re-evaluation ([`reevaluate`]) filters the whole file causally (equal, bit for bit,
//! to the online stream), scores each flash whose epoch was complete before the trial's end,
//! and replays the decision rule over complete rounds.

use std::path::Path;

use oddball_arm::Command;
use oddball_decode::pipeline::Model;
use oddball_io::xdf::session_markers;
use oddball_io::{
    stimulus_runs, write_bci2000_blocks, Bci2000WriteOptions, Bci2000WriteSummary, Recording,
    StateRun, StateRuns,
};
use oddball_signal::Event;
use serde::{Deserialize, Serialize};

use crate::decision::{complete_rounds, Phase, SessionLog, ShownFlash, TrialOutcome, TrialRecord};
use crate::online::offline_epochs;
use crate::paradigm::FourBulbParams;
use crate::SessionError;

/// Writes a session log as a BCI2000 `.dat` file.
pub fn save_session(
    path: impl AsRef<Path>,
    log: &SessionLog,
    paradigm: &FourBulbParams,
) -> Result<Bci2000WriteSummary, SessionError> {
    let samples = log.samples.as_ref().ok_or(SessionError::NoSamples)?;
    let n = log.n_times;
    let events = flash_events(log, |f| {
        Event::new(f.onset as usize, f.code).with_target(f.attended)
    });
    let flash_samples = (paradigm.flash_s * log.sfreq).round() as usize;
    let mut states = stimulus_runs(&events, n, flash_samples);
    let mut trial_no = Vec::new();
    let mut target = Vec::new();
    let mut result = Vec::new();
    let mut calib = Vec::new();
    for (i, t) in log.trials.iter().enumerate() {
        let (a, b) = (t.start as usize, (t.end as usize).min(n));
        push_run(&mut trial_no, a, b, i as u64 + 1);
        push_run(&mut target, a, b, u64::from(t.intended.unwrap_or(0)));
        push_run(&mut result, a, b, u64::from(t.decided().unwrap_or(0)));
        push_run(&mut calib, a, b, u64::from(t.phase == Phase::Calibration));
    }
    states.push(StateRuns::new("TrialNumber", 16, trial_no));
    states.push(StateRuns::new("TargetCode", 8, target));
    states.push(StateRuns::new("ResultCode", 8, result));
    states.push(StateRuns::new("Calibration", 1, calib));
    let bulbs: Vec<&str> = paradigm.bulbs.iter().map(|c| c.name()).collect();
    let options = Bci2000WriteOptions {
        extra_parameters: vec![
            "Application:Oddball string Paradigm= four-bulb % % % // oddball's four-bulb panel"
                .into(),
            format!(
                "Application:Oddball list BulbCommands= 4 {} % % % // command of stimulus codes 1..4",
                bulbs.join(" ")
            ),
            format!(
                "Application:Oddball float FlashDuration= {}s % % % // bulb on-time",
                paradigm.flash_s
            ),
            format!(
                "Application:Oddball float RoundDuration= {}s % % % // a round of four flashes",
                paradigm.round_s
            ),
            format!(
                "Application:Oddball float Countdown= {}s % % % // before each decision",
                paradigm.countdown_s
            ),
        ],
    };
    Ok(write_bci2000_blocks(
        path,
        samples,
        log.sfreq,
        &log.ch_names,
        &states,
        &options,
    )?)
}

/// The log's flashes within its samples, each as `event` makes it.
fn flash_events(log: &SessionLog, event: impl Fn(&ShownFlash) -> Event) -> Vec<Event> {
    log.flashes
        .iter()
        .filter(|f| (f.onset as usize) < log.n_times)
        .map(event)
        .collect()
}

/// Appends the run `value` over `[start, end)`; a run before it that reaches past `start` is
/// cut there (the later trial wins), an empty one is left out.
fn push_run(runs: &mut Vec<StateRun>, start: usize, end: usize, value: u64) {
    if let Some(last) = runs.last_mut() {
        last.end = last.end.min(start);
        if last.start >= last.end {
            runs.pop();
        }
    }
    if start < end {
        runs.push(StateRun { start, end, value });
    }
}

/// One trial as read back from a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SavedTrial {
    pub number: usize,
    pub phase: Phase,
    pub start: u64,
    pub end: u64,
    pub intended: Option<u32>,
    /// The decision recorded in the file (`None`: abstention or calibration).
    pub recorded: Option<u32>,
    /// The trial's flashes, in order.
    pub flashes: Vec<SavedFlash>,
}

/// A flash as read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SavedFlash {
    pub onset: u64,
    /// Bulb code 1..=4.
    pub code: u32,
    pub attended: bool,
}

/// A four-bulb session read back from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedSession {
    pub bulbs: [Command; 4],
    pub trials: Vec<SavedTrial>,
}

/// Whether a recording is an oddball four-bulb session file (BCI2000, `.easy`, or the XDF a
/// live session records, whose flashes carry their flags).
pub fn is_session(rec: &Recording) -> bool {
    rec.xdf().is_some_and(|x| {
        x.markers
            .iter()
            .any(|m| session_markers::parse_flash_marker(&m.text).is_some())
    }) || rec
        .bci2000()
        .and_then(|b| b.parameters.get("Paradigm"))
        .and_then(|p| p.as_str())
        == Some("four-bulb")
        || rec
            .easy()
            .and_then(|e| e.info_value(EASY_PARADIGM))
            .is_some_and(|v| v == "four-bulb")
}

/// Reads the trials of a session file (BCI2000 `.dat` or NIC `.easy`).
pub fn read_session(rec: &Recording) -> Result<SavedSession, SessionError> {
    if rec.easy().is_some() {
        return read_session_easy(rec);
    }
    if let Some(x) = rec.xdf() {
        return read_session_xdf(rec, x);
    }
    let path = rec.path.display().to_string();
    let missing = |what: &str| SessionError::NotASession {
        path: path.clone(),
        missing: what.to_string(),
    };
    let info = rec.bci2000().ok_or_else(|| missing("BCI2000 format"))?;
    if !is_session(rec) {
        return Err(missing("parameter Paradigm= four-bulb"));
    }
    let names = info
        .parameters
        .get("BulbCommands")
        .and_then(|p| p.list_items())
        .ok_or_else(|| missing("parameter BulbCommands"))?;
    let parsed: Vec<Command> = names
        .iter()
        .map(|n| n.parse::<Command>())
        .collect::<Result<_, _>>()
        .map_err(|_| missing("four commands in BulbCommands"))?;
    let bulbs: [Command; 4] = parsed
        .try_into()
        .map_err(|_| missing("four commands in BulbCommands"))?;
    crate::paradigm::check_bulbs(&bulbs)?;
    let state = |name: &str| {
        info.states
            .get(name)
            .ok_or_else(|| missing(&format!("state {name}")))
    };
    let trial_no = state("TrialNumber")?;
    let target = state("TargetCode")?;
    let result = state("ResultCode")?;
    let calib = state("Calibration")?;
    let events = rec.raw.events().as_slice();
    let mut trials: Vec<SavedTrial> = Vec::new();
    let mut t = 0;
    while t < trial_no.len() {
        let no = trial_no[t];
        if no == 0 {
            t += 1;
            continue;
        }
        let start = t;
        while t < trial_no.len() && trial_no[t] == no {
            t += 1;
        }
        let flashes = flashes_in(events, start as u64, t as u64);
        trials.push(SavedTrial {
            number: no as usize,
            phase: if calib[start] != 0 {
                Phase::Calibration
            } else {
                Phase::Online
            },
            start: start as u64,
            end: t as u64,
            intended: (target[start] != 0).then_some(target[start] as u32),
            recorded: (result[start] != 0).then_some(result[start] as u32),
            flashes,
        });
    }
    check_trials(&path, &trials, rec.raw.n_times())?;
    Ok(SavedSession { bulbs, trials })
}

/// The online trials of a live session's XDF recording (`oddball_live::record`): each
/// decision's trial record (the `oddball-decisions` stream, JSON) with the flagged flashes
/// inside it. The recording does not name the bulbs' commands: the paper's are assumed.
fn read_session_xdf(
    rec: &Recording,
    x: &oddball_io::xdf::XdfInfo,
) -> Result<SavedSession, SessionError> {
    let path = rec.path.display().to_string();
    if !is_session(rec) {
        return Err(SessionError::NotASession {
            path,
            missing: "flash markers with target flags (`flash C target`)".into(),
        });
    }
    let events = rec.raw.events().as_slice();
    let mut trials = Vec::new();
    for m in &x.markers {
        if !m.text.starts_with('{') {
            continue;
        }
        let t: TrialRecord =
            serde_json::from_str(&m.text).map_err(|e| SessionError::NotASession {
                path: path.clone(),
                missing: format!("a readable trial record ({e})"),
            })?;
        let flashes = flashes_in(events, t.start, t.end);
        trials.push(SavedTrial {
            number: trials.len() + 1,
            phase: t.phase,
            start: t.start,
            end: t.end,
            intended: t.intended,
            recorded: t.decided(),
            flashes,
        });
    }
    check_trials(&path, &trials, rec.raw.n_times())?;
    Ok(SavedSession {
        bulbs: FourBulbParams::paper().bulbs,
        trials,
    })
}

/// The calibration a session recording begins with: what a replay with a model passes over
/// ([`crate::engine::Session::pass_calibration`]) rather than playing it as commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CalibrationPart {
    /// Calibration trials recorded.
    pub n_trials: usize,
    /// The sample where control starts (the first online trial's start, or the end of the
    /// recording when it holds none).
    pub end: u64,
}

/// The calibration part of a session recording (`.dat`, `.easy` or a live session's XDF);
/// `None` for other recordings and sessions without calibration.
pub fn calibration_part(rec: &Recording) -> Option<CalibrationPart> {
    if !is_session(rec) {
        return None;
    }
    let saved = read_session(rec).ok()?;
    let end = saved
        .trials
        .iter()
        .find(|t| t.phase == Phase::Online)
        .map_or(rec.raw.n_times() as u64, |t| t.start);
    let n_trials = match rec.xdf() {
        // The XDF keeps online trial records only; its cues say which trials calibrated.
        Some(x) => x
            .markers
            .iter()
            .filter(|m| session_markers::parse_cue_marker(&m.text).is_some_and(|(_, cal)| cal))
            .count(),
        None => saved
            .trials
            .iter()
            .filter(|t| t.phase == Phase::Calibration)
            .count(),
    };
    (n_trials > 0).then_some(CalibrationPart { n_trials, end })
}

/// The flashes among `events` with onsets in `start..end`, attended when the reader flagged them
/// as targets (it took any attended offset off the code). Events are sorted by onset: a binary
/// search, so reading a session is linear in its trials and events.
fn flashes_in(events: &[Event], start: u64, end: u64) -> Vec<SavedFlash> {
    let a = events.partition_point(|e| (e.onset as u64) < start);
    let b = events.partition_point(|e| (e.onset as u64) < end);
    events[a..b.max(a)]
        .iter()
        .map(|e| SavedFlash {
            onset: e.onset as u64,
            code: e.code,
            attended: e.target == Some(true),
        })
        .collect()
}

/// Trials read back must make sense: inside the recording, in order without overlap, with
/// intended and decided codes of the four bulbs (0: none).
fn check_trials(path: &str, trials: &[SavedTrial], n_times: usize) -> Result<(), SessionError> {
    let mut previous_end = 0;
    for t in trials {
        let bad = |why: String| SessionError::NotASession {
            path: path.to_string(),
            missing: format!("a valid trial {} ({why})", t.number),
        };
        if t.start >= t.end || t.end > n_times as u64 {
            return Err(bad(format!(
                "samples {}..{} of a recording of {n_times}",
                t.start, t.end
            )));
        }
        if t.start < previous_end {
            return Err(bad(format!(
                "starts at sample {}, before the trial before it ends ({previous_end})",
                t.start
            )));
        }
        for (what, code) in [("intended", t.intended), ("decided", t.recorded)] {
            if let Some(c) = code.filter(|c| !(1..=4).contains(c)) {
                return Err(bad(format!("{what} code {c}: the bulbs are 1 to 4")));
            }
        }
        previous_end = t.end;
    }
    Ok(())
}

/// A decision recomputed from the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Redecision {
    pub number: usize,
    pub intended: Option<u32>,
    pub recorded: Option<u32>,
    pub outcome: TrialOutcome,
    pub rounds: usize,
    pub posterior: Vec<f64>,
    /// Seconds from the trial's start to the decision.
    pub seconds: f64,
}

impl Redecision {
    pub fn decided(&self) -> Option<u32> {
        match self.outcome {
            TrialOutcome::Chosen { code } => Some(code),
            _ => None,
        }
    }
}

/// Recomputes every online decision of a session file with `model` (which must carry its
/// decision model), as a session runs it ([`Model::for_session`]): the model's channels
/// picked by name, its band-pass causal.
pub fn reevaluate(
    rec: &Recording,
    saved: &SavedSession,
    model: &Model,
) -> Result<Vec<Redecision>, SessionError> {
    let model = &model.clone().for_session();
    model.channel_order(rec.raw.ch_names(), rec.raw.sfreq())?;
    let picked;
    let raw = if rec.raw.ch_names() == model.ch_names.as_slice() {
        &rec.raw
    } else {
        picked = rec.raw.pick_channels(&model.ch_names)?;
        &picked
    };
    let decision = model
        .decision
        .ok_or_else(|| SessionError::NoDecisionModel {
            pipeline: model.pipeline.name().to_string(),
        })?;
    let preprocess = model.preprocess;
    let online: Vec<&SavedTrial> = saved
        .trials
        .iter()
        .filter(|t| t.phase == Phase::Online)
        .collect();
    let onsets: Vec<u64> = online
        .iter()
        .flat_map(|t| t.flashes.iter().map(|f| f.onset))
        .collect();
    let epochs = offline_epochs(&preprocess, raw, &onsets)?;
    let (first, n_times) = preprocess.window(raw.sfreq());
    let mut out = Vec::new();
    let mut i = 0;
    for t in online {
        let mut shown = Vec::with_capacity(t.flashes.len());
        for (k, e) in t.flashes.iter().enumerate() {
            let ready = e.onset as i64 + first + n_times as i64 <= t.end as i64;
            let epoch = &epochs[i];
            i += 1;
            let (accepted, score) = match (epoch, ready) {
                (Some(ep), true) => {
                    let score = if ep.accepted {
                        Some(model.pipeline.score_epoch(ep.data.view())?)
                    } else {
                        None
                    };
                    (Some(ep.accepted), score)
                }
                _ => (None, None),
            };
            shown.push(ShownFlash {
                onset: e.onset,
                code: e.code,
                trial: t.number,
                round: k / 4,
                attended: e.attended,
                score,
                accepted,
            });
        }
        let rounds = complete_rounds(&shown);
        let (verdict, used) = decision.decide(&rounds);
        let (outcome, posterior) = TrialOutcome::of(verdict);
        let posterior = posterior.unwrap_or_default();
        out.push(Redecision {
            number: t.number,
            intended: t.intended,
            recorded: t.recorded,
            outcome,
            rounds: used,
            posterior,
            seconds: (t.end - t.start) as f64 / raw.sfreq(),
        });
    }
    Ok(out)
}

/// `.info` key naming the paradigm of a session `.easy` (the reader's, which labels its flashes).
const EASY_PARADIGM: &str = oddball_io::easy::ODDBALL_PARADIGM_KEY;
/// `.info` key of the bulbs' commands.
const EASY_BULBS: &str = "Oddball bulb commands";
/// Trigger offset of attended flashes in a session `.easy` (NIC triggers carry one number).
pub const EASY_ATTENDED_OFFSET: u32 = oddball_io::easy::ODDBALL_ATTENDED_OFFSET;

/// Writes a session as NIC `.easy` + `.info`: samples in nV (the values a NIC stream
/// delivers come back exactly), each flash's bulb code in the trigger column at its onset
/// (plus [`EASY_ATTENDED_OFFSET`] when attended), and the trials as `.info` lines
/// `Oddball trial N: phase start end intended decided`.
pub fn save_session_easy(
    path: impl AsRef<Path>,
    log: &SessionLog,
    paradigm: &FourBulbParams,
    start_ms: u64,
) -> Result<oddball_io::EasyWriteSummary, SessionError> {
    let samples = log.samples.as_ref().ok_or(SessionError::NoSamples)?;
    let events = flash_events(log, |f| {
        Event::new(
            f.onset as usize,
            f.code + if f.attended { EASY_ATTENDED_OFFSET } else { 0 },
        )
    });
    let mut extra = vec![
        (EASY_PARADIGM.to_string(), "four-bulb".to_string()),
        (
            EASY_BULBS.to_string(),
            paradigm
                .bulbs
                .iter()
                .map(|c| c.name())
                .collect::<Vec<_>>()
                .join(" "),
        ),
    ];
    for (i, t) in log.trials.iter().enumerate() {
        extra.push((
            format!("Oddball trial {}", i + 1),
            format!(
                "{} {} {} {} {}",
                match t.phase {
                    Phase::Calibration => "calibration",
                    Phase::Online => "online",
                },
                t.start,
                t.end,
                t.intended.unwrap_or(0),
                t.decided().unwrap_or(0)
            ),
        ));
    }
    let options = oddball_io::EasyWriteOptions {
        start_ms,
        extra_info: extra,
        ..Default::default()
    };
    Ok(oddball_io::write_easy_blocks(
        path,
        samples,
        log.sfreq,
        &log.ch_names,
        &events,
        &options,
    )?)
}

fn read_session_easy(rec: &Recording) -> Result<SavedSession, SessionError> {
    let path = rec.path.display().to_string();
    let missing = |what: &str| SessionError::NotASession {
        path: path.clone(),
        missing: what.to_string(),
    };
    let info = rec.easy().ok_or_else(|| missing(".easy details"))?;
    if info.info_value(EASY_PARADIGM) != Some("four-bulb") {
        return Err(missing("`Oddball paradigm: four-bulb` in the .info"));
    }
    let parsed: Vec<Command> = info
        .info_value(EASY_BULBS)
        .ok_or_else(|| missing("`Oddball bulb commands` in the .info"))?
        .split_whitespace()
        .map(|n| n.parse::<Command>())
        .collect::<Result<_, _>>()
        .map_err(|_| missing("four commands in `Oddball bulb commands`"))?;
    let bulbs: [Command; 4] = parsed
        .try_into()
        .map_err(|_| missing("four commands in `Oddball bulb commands`"))?;
    crate::paradigm::check_bulbs(&bulbs)?;
    let events = rec.raw.events().as_slice();
    let index = info.info_index();
    let mut trials = Vec::new();
    for number in 1.. {
        let Some(v) = index.get(&format!("Oddball trial {number}")) else {
            break;
        };
        let f: Vec<&str> = v.split_whitespace().collect();
        let bad = || {
            missing(&format!(
                "a valid `Oddball trial {number}` line (got {:?})",
                oddball_io::bounded(v)
            ))
        };
        if f.len() != 5 {
            return Err(bad());
        }
        let num = |k: usize| f[k].parse::<u64>().map_err(|_| bad());
        let code = |k: usize| f[k].parse::<u32>().map_err(|_| bad());
        let (start, end, intended, decided) = (num(1)?, num(2)?, code(3)?, code(4)?);
        let phase = match f[0] {
            "calibration" => Phase::Calibration,
            "online" => Phase::Online,
            _ => return Err(bad()),
        };
        let flashes = flashes_in(events, start, end);
        trials.push(SavedTrial {
            number,
            phase,
            start,
            end,
            intended: (intended != 0).then_some(intended),
            recorded: (decided != 0).then_some(decided),
            flashes,
        });
    }
    if trials.is_empty() {
        return Err(missing("`Oddball trial 1` in the .info"));
    }
    check_trials(&path, &trials, rec.raw.n_times())?;
    Ok(SavedSession { bulbs, trials })
}
