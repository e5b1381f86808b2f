//! The calibrated pilot of `demo` and `task`: a session over any live source, or a replayed
//! speller recording, and what both commands write about it.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use oddball_arm::{ArmSim, Command, Vector2};
use oddball_decode::decision::DecisionRule;
use oddball_live::clock::Clock;
use oddball_live::live::LiveSubject;
use oddball_live::source::{AnySource, SourceSpec};
use oddball_session::engine::{CalibrationReport, Session};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::record::{save_session, save_session_easy};
use oddball_session::replay::{accepted_epochs, ReplaySource};
use oddball_session::task::{Pilot, ReplayPilot, Step};
use oddball_session::SessionError;
use oddball_signal::Epochs;

use crate::args::{recording_arm, Replayed, SessionOptions, SourceArgs};

/// A session over a live source, or a replayed recording, as one pilot.
#[allow(clippy::large_enum_variant)]
pub enum AnyPilot {
    Live(Session<LiveSubject<AnySource>>),
    Replay(ReplayPilot),
}

impl Pilot for AnyPilot {
    fn decide(&mut self, intended: Command) -> Result<Option<Step>, SessionError> {
        match self {
            AnyPilot::Live(s) => Pilot::decide(s, intended),
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
            AnyPilot::Live(s) => s.wait(seconds),
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
pub struct Prepared {
    pub pilot: AnyPilot,
    pub calibration: CalibrationReport,
    pub erp: Epochs,
    pub model_json: String,
    /// How the subject is named in reports.
    pub subject: String,
    pub pen_start: Vector2<f64>,
}

/// The live subject over `--source` (the simulated subject of `opts` for `sim`), paced by the
/// wall clock when `paced`.
pub fn live_subject(
    opts: &SessionOptions,
    source: &SourceArgs,
    paced: bool,
    clock: Clock,
) -> Result<LiveSubject<AnySource>> {
    let sim = opts.simulated()?;
    let (eeg, markers) = source
        .source
        .open(source.open_options(sim, paced)?, clock)
        .with_context(|| format!("--source {}", source.source))?;
    let mut subject = LiveSubject::new(eeg, FourBulbParams::paper(), clock);
    if let Some(m) = markers {
        subject = subject.with_markers(m);
    }
    Ok(subject)
}

/// Calibrates a pilot: a replayed recording (`--subject replay:FILE`, offline, so only with
/// `--source sim`), or a session over `--source`, its calibration paced by the wall clock when
/// `paced`. Prints the calibration; `on_replay` sees a replayed subject's recordings and source
/// before they are used.
pub fn prepare(
    opts: &SessionOptions,
    source: &SourceArgs,
    rule: DecisionRule,
    paced: bool,
    on_replay: impl FnOnce(&Replayed, &ReplaySource) -> Result<()>,
) -> Result<Prepared> {
    if let Some((file, cal)) = opts.replay_files()? {
        if source.source != SourceSpec::Sim {
            bail!(
                "--subject replay:{} replays decisions offline: it takes no --source {}",
                file.display(),
                source.source
            );
        }
        let r = opts.calibrated_replay(&file, &cal, rule)?;
        let replay = ReplaySource::new(&r.test, &r.model, &r.params)
            .with_context(|| format!("replaying {}", file.display()))?;
        on_replay(&r, &replay)?;
        let arm = recording_arm()?;
        let pen_start = arm.pen();
        let erp = accepted_epochs(
            &r.calibration_recording,
            &r.params.preprocess,
            r.params.chunk,
        )?;
        return Ok(Prepared {
            pilot: AnyPilot::Replay(ReplayPilot::new(replay, arm, FourBulbParams::paper())),
            calibration: r.calibration,
            erp,
            model_json: r.model.to_json(),
            subject: format!("replay:{}", file.display()),
            pen_start,
        });
    }
    let preset = opts
        .preset()
        .expect("a simulated preset when not replaying");
    let subject = live_subject(opts, source, paced, Clock::new())?;
    let (session, calibration, pen_start) = opts.calibrated(subject, rule, true)?;
    let erp = session.calibration_epochs()?;
    let model_json = session
        .model()
        .map(|m| m.to_json())
        .context("the session has no model")?;
    Ok(Prepared {
        pilot: AnyPilot::Live(session),
        calibration,
        erp,
        model_json,
        subject: match &source.source {
            SourceSpec::Sim => preset.to_string(),
            other => format!("{preset} over {other}"),
        },
        pen_start,
    })
}

impl Prepared {
    /// A live stream's health (samples lost, reconnections); `None` for simulated sources.
    pub fn stream_health(&self) -> Option<String> {
        match &self.pilot {
            AnyPilot::Live(s) => oddball_session::roles::EegStream::stream_health(s.subject()),
            AnyPilot::Replay(_) => None,
        }
    }

    /// The session's raw EEG, saved in `out` (`session.easy`, NIC's format, for a NIC stream;
    /// `session.dat`, BCI2000, otherwise), for a live pilot; `None` for a replayed recording.
    pub fn save_session(self, out: &Path, end: &str) -> Result<Option<PathBuf>> {
        let AnyPilot::Live(mut session) = self.pilot else {
            return Ok(None);
        };
        session.subject_mut().end(end);
        let nic = matches!(session.subject().source(), AnySource::Nic(_));
        let paradigm = session.params().paradigm;
        let (log, _, _) = session.finish();
        let path = if nic {
            out.join("session.easy")
        } else {
            out.join("session.dat")
        };
        if nic {
            save_session_easy(&path, &log, &paradigm, 0).map(|_| ())
        } else {
            save_session(&path, &log, &paradigm).map(|_| ())
        }
        .with_context(|| format!("writing {}", path.display()))?;
        Ok(Some(path))
    }
}

/// decisions.csv: one row per step.
pub fn write_decisions_csv(path: &Path, steps: &[Step]) -> Result<()> {
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
    fs::write(path, csv).with_context(|| format!("writing {}", path.display()))
}
