//! What `oddball online` reports of a live session: one row per decision, the flash timing, the
//! replayed file's coincidence, and `summary.json` ([`OnlineSummary`]); the printed lines' text.

use std::path::{Path, PathBuf};

use oddball_session::decision::Decision;
use oddball_session::decision::ShownFlash;
use oddball_session::report::{headline, numbered, BitsBy, Row, Scores, SessionFacts};
use oddball_session::SessionError;
use serde::Serialize;

use crate::live::EegSource;
use crate::panel::PresentationFaults;
use crate::source::AnySource;
use crate::timing::{FlashTiming, Summary};
use crate::LiveError;

/// A [`Summary`] of delays with its unit in the field names (ms).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimingRow {
    pub n: usize,
    pub mean_ms: f64,
    pub sd_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

impl From<Summary> for TimingRow {
    fn from(s: Summary) -> Self {
        Self {
            n: s.n,
            mean_ms: s.mean,
            sd_ms: s.sd,
            min_ms: s.min,
            max_ms: s.max,
        }
    }
}

/// `summary.json` of `oddball online`: the facts every session's summary starts with, the
/// result and the decisions as `demo` writes them, then what only a live session has (flash
/// timing, the recording, a replay's coincidence, why it ended early).
#[derive(Debug, Serialize)]
pub struct OnlineSummary<'a> {
    #[serde(flatten)]
    pub facts: SessionFacts<'a>,
    pub source: String,
    pub result: Scores,
    /// Bits delivered in the first minutes after the session started
    /// ([`oddball_session::report::headline`]).
    pub bits_since_start: Vec<BitsBy>,
    pub decisions: Vec<Row<'a>>,
    pub flash_on_time: Option<TimingRow>,
    pub flash_onset_error: Option<TimingRow>,
    pub stamp_delay: Option<TimingRow>,
    pub undrawn_flashes: usize,
    /// Page stamps refused as implausible (`timing::plausible_stamp`); their flashes are undrawn.
    pub refused_stamps: usize,
    /// What went wrong with what the person was shown (hidden or stalled subject view, late or
    /// undrawn flashes, frame gaps, several bulbs lit), and how long calibration held for it.
    pub presentation: PresentationFaults,
    pub decision_latency: Option<TimingRow>,
    pub recording: String,
    /// `--source replay:…`: how many flashes fell on the file's flashes.
    pub replay: Option<String>,
    /// What stopped the session early (the replayed file's end).
    pub ended: Option<String>,
}

/// How a live session was run and what it scored, for its summary.
#[derive(Debug)]
pub struct OnlineRun<'a> {
    pub facts: SessionFacts<'a>,
    pub source: String,
    /// The decisions' scores ([`oddball_session::report::scores`] under the session's rule).
    pub result: Scores,
    pub presentation: PresentationFaults,
}

impl<'a> OnlineSummary<'a> {
    /// The summary of `steps` with the panel's `timing` and the decision latencies (ms).
    pub fn new(
        run: OnlineRun<'a>,
        steps: &'a [Decision],
        timing: &FlashTiming,
        latency_ms: &[f64],
        recording: &Path,
        replay: Option<String>,
        ended: Option<String>,
    ) -> Self {
        Self {
            facts: run.facts,
            source: run.source,
            result: run.result,
            bits_since_start: headline(steps),
            decisions: numbered(steps),
            flash_on_time: Summary::of(&timing.on_ms).map(Into::into),
            flash_onset_error: Summary::of(&timing.onset_error_ms).map(Into::into),
            stamp_delay: Summary::of(&timing.report_delay_ms).map(Into::into),
            undrawn_flashes: timing.undrawn,
            refused_stamps: timing.refused_stamps,
            presentation: run.presentation,
            decision_latency: Summary::of(latency_ms).map(Into::into),
            recording: recording.display().to_string(),
            replay,
            ended,
        }
    }

    /// `3/4 decisions right, 1 abstained`, and when the session stopped early (the recording
    /// ended, a stop request, an abort) how many of the `n_commands` were made.
    pub fn line(&self, n_commands: usize) -> String {
        let mut line = format!(
            "{}/{} decisions right, {} abstained",
            self.result.correct,
            self.decisions.len(),
            self.result.abstained
        );
        if self.ended.is_some() {
            line.push_str(&format!(
                " ({} of {n_commands} made before the session stopped)",
                self.decisions.len(),
            ));
        }
        line
    }
}

/// One decision as printed: `decision 1: up → up ✓ (p 0.998, 4 rounds, 2.40 s)`.
pub fn decision_line(index: usize, s: &Decision) -> String {
    format!(
        "decision {}: {} → {}{} (p {:.3}, {} rounds, {:.2} s)",
        index + 1,
        s.intended,
        s.decided.map_or("abstain", |c| c.name()),
        match s.decided {
            Some(d) if d == s.intended => " ✓",
            Some(_) => " ✗",
            None => "",
        },
        s.confidence,
        s.rounds,
        s.seconds
    )
}

/// The first free recording name in `out`, never overwriting an earlier one: session.xdf, else
/// session-1.xdf, session-2.xdf, …
pub fn free_recording_path(out: &Path) -> PathBuf {
    (0..)
        .map(|i| match i {
            0 => out.join("session.xdf"),
            i => out.join(format!("session-{i}.xdf")),
        })
        .find(|p| !p.exists())
        .expect("a free name")
}

/// Flashes of a replayed session within this of a flash in the file coincide with it, s.
pub const REPLAY_TOLERANCE_S: f64 = 0.010;

/// How many of this session's flashes fall on a flash of the same bulb in the replayed file;
/// `None` unless `source` plays a file back.
pub fn coincidence(source: &AnySource, flashes: &[ShownFlash]) -> Option<String> {
    let AnySource::Playback(source) = source else {
        return None;
    };
    // A P300 spans hundreds of ms: a page's few ms of onset jitter do not matter.
    let tolerance = (REPLAY_TOLERANCE_S * source.sfreq()).round().max(1.0) as u64;
    let shown: Vec<(u64, u32)> = flashes.iter().map(|f| (f.onset, f.code)).collect();
    let k = source.coincidence(&shown, tolerance);
    let mut line = format!(
        "replay: {k} of {} flashes of this session fall on a flash of the same bulb in the file (±{tolerance} samples)",
        shown.len()
    );
    if k < shown.len() {
        line.push_str("; the others were never drawn in the recording (their epochs lost)");
    }
    Some(line)
}

/// What stops a session cleanly, keeping what it has (the recording closed, the decisions so
/// far summarised): the replayed file's end, a stop request (SIGINT/SIGTERM, the operator
/// view's abort), an amplifier
/// that dropped out and did not come back within its reconnection attempts, a stream lost or
/// stalled.
pub fn is_recording_end(e: &SessionError) -> bool {
    matches!(
        LiveError::from_session(e),
        Some(
            LiveError::RecordingEnded { .. }
                | LiveError::Stopped
                | LiveError::Aborted
                | LiveError::Reconnect { .. }
                | LiveError::StreamLost { .. }
                | LiveError::StreamStalled { .. }
        )
    )
}

/// What stopped a session, in the live source's own words (the recording's end) rather than
/// the engine's wrapper.
pub fn stop_reason(e: &SessionError) -> String {
    LiveError::from_session(e).map_or_else(|| e.to_string(), |l| l.to_string())
}
