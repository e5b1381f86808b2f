//! The calibrated pilot of `oddball demo` and `oddball task`: a session over any live source, or
//! a replayed speller recording, as one [`Pilot`]; what a run of it leaves behind (the raw EEG of
//! the session, `decisions.csv`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use oddball_arm::{ArmSim, Command, Vector2};
use oddball_session::decision::CalibrationReport;
use oddball_session::decision::Decision;
use oddball_session::engine::Session;
use oddball_session::paradigm::FourBulbParams;
use oddball_session::record::{save_session, save_session_easy};
use oddball_session::replay::REPLAY_NOTE;
use oddball_session::report::{headline, BitsBy, CalibrationSummary, SessionFacts};
use oddball_session::roles::EegStream;
use oddball_session::tasks::{Pilot, ReplayPilot};
use oddball_session::SessionError;
use oddball_signal::Epochs;
use serde::Serialize;

use crate::live::LiveSubject;
use crate::source::AnySource;

/// A session over a live source, or a replayed recording, as one pilot.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum AnyPilot {
    Live(Session<LiveSubject<AnySource>>),
    Replay(ReplayPilot),
}

impl Pilot for AnyPilot {
    fn decide(&mut self, intended: Command) -> Result<Option<Decision>, SessionError> {
        match self {
            // A stop request or a source that ended: no more decisions (the run keeps what it
            // has; the reason is kept in `crate::stop::reason`).
            AnyPilot::Live(s) => match Pilot::decide(s, intended) {
                Err(e) if crate::online::is_recording_end(&e) => {
                    crate::stop::note(crate::online::stop_reason(&e));
                    Ok(None)
                }
                r => r,
            },
            AnyPilot::Replay(r) => r.decide(intended),
        }
    }
    fn arm(&self) -> &ArmSim {
        match self {
            AnyPilot::Live(s) => Pilot::arm(s),
            AnyPilot::Replay(r) => r.arm(),
        }
    }
    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        match self {
            AnyPilot::Live(s) => match s.wait(seconds) {
                Err(e) if crate::online::is_recording_end(&e) => {
                    crate::stop::note(crate::online::stop_reason(&e));
                    Ok(())
                }
                r => r,
            },
            AnyPilot::Replay(r) => r.wait(seconds),
        }
    }
    fn time_s(&self) -> f64 {
        match self {
            AnyPilot::Live(s) => Pilot::time_s(s),
            AnyPilot::Replay(r) => r.time_s(),
        }
    }
}

/// The calibrated pilot, its calibration, the calibration epochs and the model (JSON).
#[derive(Debug)]
pub struct Prepared {
    pub pilot: AnyPilot,
    pub calibration: CalibrationReport,
    pub erp: Epochs,
    pub model_json: String,
    /// How the subject is named in reports.
    pub subject: String,
    pub pen_start: Vector2<f64>,
}

impl Prepared {
    /// A live stream's health (samples lost, reconnections); `None` for simulated sources.
    pub fn stream_health(&self) -> Option<String> {
        match &self.pilot {
            AnyPilot::Live(s) => s.subject().stream_health(),
            AnyPilot::Replay(_) => None,
        }
    }

    /// Where [`Self::save_session`] writes in `out`: `session.easy` (NIC's format) for a NIC
    /// stream, `session.dat` (BCI2000) otherwise; `None` for a replayed recording.
    pub fn session_file(&self, out: &Path) -> Option<PathBuf> {
        match &self.pilot {
            AnyPilot::Live(s) => Some(if matches!(s.subject().source(), AnySource::Nic(_)) {
                out.join("session.easy")
            } else {
                out.join("session.dat")
            }),
            AnyPilot::Replay(_) => None,
        }
    }

    /// Ends a live session with the panel message `end` and saves its raw EEG to `path` (see
    /// [`Self::session_file`]); does nothing for a replayed recording.
    pub fn save_session(self, path: &Path, end: &str) -> Result<(), SessionError> {
        let AnyPilot::Live(mut session) = self.pilot else {
            return Ok(());
        };
        session.subject_mut().end(end);
        let nic = matches!(session.subject().source(), AnySource::Nic(_));
        let paradigm = session.params().paradigm;
        let (log, _, _) = session.finish()?;
        if nic {
            save_session_easy(path, &log, &paradigm, 0).map(|_| ())
        } else {
            save_session(path, &log, &paradigm).map(|_| ())
        }
    }
}

/// `summary.json` of a task: what ran (the facts every session's summary starts with), the
/// task, and the task's report.
#[derive(Debug, Serialize)]
pub struct TaskSummary<'a, T> {
    #[serde(flatten)]
    pub facts: SessionFacts<'a>,
    pub task: &'static str,
    /// A live session's presentation faults (`null` for a replayed recording).
    pub presentation: Option<crate::panel::PresentationFaults>,
    /// What a replayed recording's decisions mean ([`REPLAY_NOTE`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<&'static str>,
    /// Bits delivered in the first minutes after the session started
    /// ([`oddball_session::report::headline`]; empty for a replayed recording).
    pub bits_since_start: Vec<BitsBy>,
    pub report: &'a T,
}

impl Prepared {
    /// The summary of the task `task` (`draw`, `track`) run by this pilot with `pipeline`,
    /// `seed` and `paradigm`, whose decisions were `steps`.
    pub fn task_summary<'a, T>(
        &'a self,
        task: &'static str,
        pipeline: &'a str,
        seed: u64,
        paradigm: FourBulbParams,
        steps: &[Decision],
        report: &'a T,
    ) -> TaskSummary<'a, T> {
        TaskSummary {
            facts: SessionFacts {
                command: "task",
                subject: &self.subject,
                pipeline,
                seed,
                paradigm,
                calibration: CalibrationSummary::from(&self.calibration),
            },
            task,
            presentation: match &self.pilot {
                AnyPilot::Live(s) => Some(s.subject().presentation_faults()),
                AnyPilot::Replay(_) => None,
            },
            note: matches!(self.pilot, AnyPilot::Replay(_)).then_some(REPLAY_NOTE),
            bits_since_start: headline(steps),
            report,
        }
    }
}

/// The text of `decisions.csv`: one row per step (commas in an arm's refusal become `;`).
pub fn decisions_csv(steps: &[Decision]) -> String {
    let mut csv =
        String::from("decision,intended,decided,abstained,rounds,confidence,seconds,arm_refusal\n");
    for (i, s) in steps.iter().enumerate() {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.6},{:.4},{}",
            i + 1,
            s.intended,
            s.decided.map(|c| c.to_string()).unwrap_or_default(),
            s.abstained,
            s.rounds,
            s.confidence,
            s.seconds,
            s.arm_refusal.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    csv
}
