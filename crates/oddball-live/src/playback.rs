//! A recording played back as a live source, paced by the wall clock (BCI2000's FilePlayback):
//! `oddball online --source replay:FILE`.
//!
//! The session runs as it would live: its own schedule of flashes, its own cues and
//! decisions, its own recording. The EEG is the file's, sample by sample from its first, in µV.
//! A recording made by `oddball online` replays to the same flashes at the same samples, and so
//! to the same decisions, when the session is set up the same way (seed, commands, model or
//! calibration): that is how a session is re-run with another model, or a panel demonstrated
//! without an amplifier. Two things the recorded session did are taken from the recording,
//! not re-run:
//!
//! * **Where each flash was drawn** ([`EegSource::recorded_flash`]): live, the page stamped the
//!   frame that drew each flash and the recording holds that onset; a flash never drawn holds
//!   none. Each flash this session shows is matched with the recorded flash nearest its
//!   planned onset among those after the last one matched (a page draws flashes in order),
//!   within [`UNDRAWN_AFTER_MS`] (how far a live stamp may be from its schedule): when that
//!   flash is of the same bulb, this flash is drawn at the recorded onset (the engine moves its
//!   epoch there, as it moves a live stamp); otherwise it was never drawn and loses its epoch,
//!   as it did live.
//! * **Where the session held** ([`EegSource::recorded_hold`]): an operator's pause holds a
//!   live session between trials (`pause` and `resume` in the recording,
//!   [`session_markers`]). The replay holds at the same place: from the end of the trial
//!   before a recorded `resume` to the cue of the trial that followed it (the cue nearest the
//!   `resume`, within [`CUE_AFTER_RESUME_S`]); a `pause` never resumed holds to the end of the
//!   file.
//!
//! Only an XDF recording (oddball's own format, and LSL's) holds the flashes as the page drew
//! them; a recording in another format (a lab's `.dat`, `.csv`, `.edf`, `.mat`) plays as EEG
//! under this session's own flashes, which it cannot hold responses to: decisions on it mean
//! nothing, and the run says so ([`PlaybackSource::holds_flashes`]; a panel demonstration).
//!
//! An XDF recording whose flashes are not this session's is refused before the session decides
//! on it: once [`JUDGED_AFTER`] flashes have been shown, fewer than half of the flashes shown so far
//! matching a recorded flash is a [`LiveError::ReplayMismatch`] (another seed, other commands or
//! another model's stopping, or a file oddball did not record, or one without flashes: its EEG
//! holds no response where this session looks for one). A faithful recording passes unless most
//! of its session's flashes were never drawn. [`PlaybackSource::coincidence`] says at the end
//! how many of this session's flashes fall on a flash of the file.
//!
//! At the end of the file the source stops with [`LiveError::RecordingEnded`]: the session
//! stops cleanly and its recording is kept.

use std::path::{Path, PathBuf};
use std::time::Instant;

use ndarray::{s, Array2};
use oddball_io::xdf::session_markers;
use oddball_io::Recording;
use oddball_session::record::{calibration_part, CalibrationPart};
use oddball_session::roles::Drawn;
use oddball_signal::Event;

use crate::clock::Clock;
use crate::live::{EegSource, UNDRAWN_AFTER_MS};
use crate::LiveError;

/// Flashes shown before a replay is judged ([`LiveError::ReplayMismatch`]): one round of the four
/// bulbs, fewer than any decision rests on.
pub const JUDGED_AFTER: usize = 4;

/// How far a recorded `resume` may be from the cue of the trial it let start, s: the marker is
/// written at the wall clock, the cue at its sample; a trial lasts longer.
pub const CUE_AFTER_RESUME_S: f64 = 0.5;

/// Where a recorded session held between trials, in samples: after the cue `after` (its trial
/// ended first; `None`: before the first trial) until the cue `until` (`None`: to the end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordedHold {
    pub after: Option<u64>,
    pub until: Option<u64>,
}

/// The holds of a session recording: its `pause` and `resume` markers against its cues.
fn recorded_holds(rec: &Recording) -> Vec<RecordedHold> {
    let Some(x) = rec.xdf() else {
        return Vec::new();
    };
    let n = rec.raw.n_times() as u64;
    let at = |m: &oddball_io::xdf::XdfMarker| m.sample.map_or(n, |s| s as u64);
    let mut cues: Vec<u64> = x
        .markers
        .iter()
        .filter(|m| session_markers::parse_cue_marker(&m.text).is_some())
        .map(at)
        .collect();
    cues.sort_unstable();
    let tol = (CUE_AFTER_RESUME_S * rec.raw.sfreq()).round() as u64;
    // The last cue before sample `t`; the cue nearest `t` within the tolerance.
    let before = |t: u64| cues[..cues.partition_point(|&c| c < t)].last().copied();
    let near = |t: u64| {
        let i = cues.partition_point(|&c| c < t);
        [i.checked_sub(1), Some(i)]
            .into_iter()
            .flatten()
            .filter_map(|k| cues.get(k).copied())
            .filter(|c| c.abs_diff(t) <= tol)
            .min_by_key(|c| c.abs_diff(t))
    };
    let mut holds = Vec::new();
    let mut open: Option<u64> = None;
    for m in &x.markers {
        match m.text.as_str() {
            session_markers::PAUSE => open = open.or(Some(at(m))),
            session_markers::RESUME => {
                if let Some(c) = near(at(m)) {
                    holds.push(RecordedHold {
                        after: before(c),
                        until: Some(c),
                    });
                }
                open = None;
            }
            _ => {}
        }
    }
    if let Some(p) = open {
        holds.push(RecordedHold {
            after: before(p),
            until: None,
        });
    }
    holds
}

/// A recording as a live EEG source.
#[derive(Debug)]
pub struct PlaybackSource {
    path: PathBuf,
    data: Array2<f64>,
    sfreq: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
    calibration: Option<CalibrationPart>,
    clock: Clock,
    start_ms: f64,
    position: usize,
    paced: bool,
    /// The recording's flashes (onset, code), by onset; those before `next` are passed (this
    /// session's flashes are drawn in order).
    flashes: Vec<(u64, u32)>,
    next: usize,
    /// Where the recorded session held between trials.
    holds: Vec<RecordedHold>,
    /// Flashes of this session asked about, and those drawn at a recorded flash.
    asked: usize,
    found: usize,
    /// Whether the file records flashes as drawn (XDF): they are matched, and a mismatch
    /// refused.
    holds_flashes: bool,
}

impl PlaybackSource {
    /// Reads `path` (any format `oddball_io::read` knows), paced by the wall clock.
    pub fn open(path: impl AsRef<Path>, clock: Clock) -> Result<Self, LiveError> {
        let path = path.as_ref();
        let rec = oddball_io::read(path)?;
        let holds_flashes = rec.xdf().is_some();
        let calibration = calibration_part(&rec);
        let holds = recorded_holds(&rec);
        let (data, sfreq, ch_names, events) = rec.raw.into_parts();
        if data.ncols() == 0 {
            return Err(LiveError::InvalidParameter {
                name: "replay",
                value: path.display().to_string(),
                reason: "the recording holds no samples".into(),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            data,
            sfreq,
            ch_names,
            calibration,
            start_ms: clock.now_ms(),
            clock,
            position: 0,
            paced: true,
            flashes: Vec::new(),
            next: 0,
            holds,
            asked: 0,
            found: 0,
            holds_flashes,
            events: Vec::new(),
        }
        .with_events(events.into_vec()))
    }

    /// Whether the file records flashes as they were drawn (an XDF recording): each of this
    /// session's flashes is then drawn where the recording drew it, and a recording of other
    /// flashes is refused. Otherwise (another format) the session's own flashes are drawn on
    /// EEG that holds no response to them.
    pub fn holds_flashes(&self) -> bool {
        self.holds_flashes
    }

    /// The file played back.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `events` as the recording's flashes.
    fn with_events(mut self, events: Vec<Event>) -> Self {
        self.flashes = events.iter().map(|e| (e.onset as u64, e.code)).collect();
        self.flashes.sort_unstable();
        self.next = 0;
        self.events = events;
        self
    }

    /// The file resampled to `sfreq` Hz before it plays (polyphase, events moved with it:
    /// [`oddball_signal::resample::resample_raw`]), so a model at another rate can replay it.
    pub fn resampled(mut self, sfreq: f64) -> Result<Self, LiveError> {
        let raw = oddball_signal::Raw::new(
            std::mem::replace(&mut self.data, Array2::zeros((0, 0))),
            self.sfreq,
            std::mem::take(&mut self.ch_names),
            oddball_signal::Events::new(std::mem::take(&mut self.events)),
        )
        .and_then(|raw| oddball_signal::resample::resample_raw(&raw, sfreq))
        .map_err(oddball_session::SessionError::from)?;
        let (data, new_sfreq, ch_names, events) = raw.into_parts();
        // A recorded session's trial samples no longer hold at another rate; its holds move
        // with the samples (to the chunk after, where the session looks).
        let scale = |s: u64| (s as f64 * new_sfreq / self.sfreq).round() as u64;
        let holds = self
            .holds
            .iter()
            .map(|h| RecordedHold {
                after: h.after.map(scale),
                until: h.until.map(scale),
            })
            .collect();
        Ok(Self {
            data,
            sfreq: new_sfreq,
            ch_names,
            calibration: None,
            holds,
            ..self
        }
        .with_events(events.into_vec()))
    }

    /// As fast as it can (tests).
    pub fn unpaced(mut self) -> Self {
        self.paced = false;
        self
    }

    /// Samples in the file.
    pub fn n_times(&self) -> usize {
        self.data.ncols()
    }

    /// The calibration a session recording begins with (see
    /// [`oddball_session::engine::Session::pass_calibration`]).
    pub fn calibration(&self) -> Option<CalibrationPart> {
        self.calibration
    }

    /// The file's events (flash markers become events of the flash's code).
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Where the recorded session held between trials.
    pub fn holds(&self) -> &[RecordedHold] {
        &self.holds
    }

    /// Flashes of this session matched so far: (drawn at a recorded flash, asked about).
    pub fn matched(&self) -> (usize, usize) {
        (self.found, self.asked)
    }

    /// The onset of the recorded flash that drew this session's flash of bulb `code` planned
    /// at sample `planned`: of the recorded flashes after the last one drawn (a page draws
    /// flashes in their order), the one nearest `planned` within `window` samples, if it is of
    /// bulb `code`. A stamp later than half the flash period is still its own flash's, and a
    /// flash of another seed's schedule matches no more often than chance (one in four).
    fn take_flash(&mut self, planned: u64, code: u32, window: u64) -> Option<u64> {
        let rest = &self.flashes[self.next..];
        let i = rest.partition_point(|&(o, _)| o < planned);
        let k = [i.checked_sub(1), Some(i)]
            .into_iter()
            .flatten()
            .filter(|&k| k < rest.len())
            .min_by_key(|&k| rest[k].0.abs_diff(planned))?;
        let (onset, c) = rest[k];
        if c != code || onset.abs_diff(planned) > window {
            return None;
        }
        self.next += k + 1;
        Some(onset)
    }

    /// How many of `flashes` (onset sample, code) fall within `tolerance` samples of an event
    /// of the same code in the file.
    pub fn coincidence(&self, flashes: &[(u64, u32)], tolerance: u64) -> usize {
        let by_onset = &self.flashes;
        flashes
            .iter()
            .filter(|&&(onset, code)| {
                let lo = by_onset.partition_point(|&(o, _)| o + tolerance < onset);
                by_onset[lo..]
                    .iter()
                    .take_while(|&&(o, _)| o <= onset + tolerance)
                    .any(|&(_, c)| c == code)
            })
            .count()
    }
}

impl EegSource for PlaybackSource {
    fn sfreq(&self) -> f64 {
        self.sfreq
    }
    fn ch_names(&self) -> &[String] {
        &self.ch_names
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        if self.position + n > self.data.ncols() {
            return Err(LiveError::RecordingEnded {
                path: self.path.clone(),
                n_times: self.data.ncols(),
                seconds: self.data.ncols() as f64 / self.sfreq,
            });
        }
        if !self.paced {
            return Ok(());
        }
        let due = self.time_of((self.position + n) as u64);
        let at = self.clock.instant(due);
        let now = Instant::now();
        if at > now {
            std::thread::sleep(at - now);
        }
        Ok(())
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        let end = self.position + n;
        if end > self.data.ncols() {
            return Err(LiveError::RecordingEnded {
                path: self.path.clone(),
                n_times: self.data.ncols(),
                seconds: self.data.ncols() as f64 / self.sfreq,
            });
        }
        let block = self.data.slice(s![.., self.position..end]).to_owned();
        self.position = end;
        Ok(block)
    }
    fn time_of(&self, sample: u64) -> f64 {
        self.start_ms + sample as f64 * 1e3 / self.sfreq
    }
    fn start_now(&mut self) {
        self.start_ms = self.clock.now_ms() - self.position as f64 * 1e3 / self.sfreq;
    }
    fn recorded_flash(&mut self, planned: u64, code: u32) -> Result<Option<Drawn>, LiveError> {
        if !self.holds_flashes {
            return Ok(None);
        }
        let window = (UNDRAWN_AFTER_MS * self.sfreq / 1e3).round() as u64;
        let onset = self.take_flash(planned, code, window);
        self.asked += 1;
        self.found += usize::from(onset.is_some());
        if self.asked >= JUDGED_AFTER && 2 * self.found < self.asked {
            return Err(LiveError::ReplayMismatch {
                path: self.path.clone(),
                found: self.found,
                asked: self.asked,
                window_ms: UNDRAWN_AFTER_MS,
            });
        }
        Ok(Some(Drawn {
            planned,
            code,
            onset,
        }))
    }
    fn recorded_hold(&self, position: u64) -> Option<bool> {
        Some(
            self.holds.iter().any(|h| {
                h.after.is_none_or(|a| a < position) && h.until.is_none_or(|u| position < u)
            }),
        )
    }
}
