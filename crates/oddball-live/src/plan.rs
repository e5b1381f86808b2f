//! A session assembled from its plan, so that any front end (the command line, a GUI, Python)
//! runs one the same way: a [`SessionPlan`] says where the EEG comes from and how it is opened,
//! the session's settings, how it starts ([`Start`]), the channels' names and the arm's step;
//! [`SessionPlan::check`] checks it before anything is opened, [`SessionPlan::open`] opens the
//! source, builds the session over it and starts it.
//!
//! A front end that must put something between the steps (`oddball online` attaches its
//! recorder and panel to the live subject) calls them one by one: [`SessionPlan::open_source`],
//! [`SessionPlan::at_model_rate`], [`SessionPlan::session`], [`SessionPlan::start`].
//!
//! Errors say which step failed ([`PlanError`]) and never name a command-line option: the
//! command line maps them back to its flags.

use oddball_arm::{ArmConfig, ArmError, ArmSim};
use oddball_session::decision::{CalibrationProgress, CalibrationReport};
use oddball_session::decoder::{Preset, Start};
use oddball_session::engine::{Session, SessionParams};
use oddball_session::roles::Subject;
use oddball_session::SessionError;
use thiserror::Error;

use crate::clock::Clock;
use crate::live::{LiveSubject, MarkerSink};
use crate::source::{AnySource, OpenOptions, RateChange, SourceSpec};
use crate::LiveError;

/// Everything a live session needs before it opens anything.
#[derive(Debug)]
pub struct SessionPlan {
    /// Where the EEG comes from.
    pub source: SourceSpec,
    /// How the source is opened (the simulated subject, pacing, NIC's framing, …).
    pub open: OpenOptions,
    pub params: SessionParams,
    /// How the session starts: calibrating, with a model, or without calibration.
    pub start: Start,
    /// The EEG's channel names in order (a montage), for a stream whose own names are not the
    /// model's; `None` keeps the stream's.
    pub montage: Option<Vec<String>>,
    /// The step one command moves the pen, metres (`None`: the arm's own).
    pub step_m: Option<f64>,
}

/// Which step of a plan failed.
#[derive(Debug, Error)]
pub enum PlanError {
    /// The plan contradicts itself (see [`SessionPlan::check`]).
    #[error("{0}")]
    Invalid(String),
    /// The arm refuses the step.
    #[error("the arm: {0}")]
    Arm(#[source] ArmError),
    /// The source could not be opened.
    #[error("opening the source: {0}")]
    Open(#[source] LiveError),
    /// The source could not be brought to the model's rate.
    #[error("resampling the EEG to the model's rate: {0}")]
    Rate(#[source] LiveError),
    /// The session refused its settings.
    #[error("setting up the session: {0}")]
    Session(#[source] SessionError),
    /// The montage does not fit the EEG (or came too late).
    #[error("naming the channels: {0}")]
    Montage(#[source] SessionError),
    /// The start failed: the calibration, the model or the uncalibrated decoder.
    #[error("starting the session: {0}")]
    Start(#[source] SessionError),
}

impl PlanError {
    /// The session error behind this one, if any.
    pub fn session_error(&self) -> Option<&SessionError> {
        match self {
            PlanError::Session(e) | PlanError::Montage(e) | PlanError::Start(e) => Some(e),
            _ => None,
        }
    }
}

/// A session opened from a plan and started.
#[derive(Debug)]
pub struct OpenedSession {
    pub session: Session<LiveSubject<AnySource>>,
    /// What calibration measured (`None` when the session did not calibrate).
    pub calibration: Option<CalibrationReport>,
    /// How the source was brought to the model's rate, if it was.
    pub rate_change: Option<RateChange>,
}

/// The arm every session drives, with `step_m` (`None`: the default arm's step): its pen trace
/// is kept (a vertex per trace spacing moved), its per-step samples are not (a 1 kHz control
/// step's sample each millisecond would grow a session of hours by gigabytes).
pub fn recording_arm(step_m: Option<f64>) -> Result<ArmSim, ArmError> {
    let mut config = ArmConfig::default();
    if let Some(step) = step_m {
        config.reference.step_m = step;
    }
    let mut arm = ArmSim::from_config(&config)?;
    arm.set_recording(false);
    Ok(arm)
}

impl SessionPlan {
    /// Checks the plan before anything is opened: the source's options, the session's
    /// settings, the arm's step, and the start against the settings (adaptation adapts the
    /// `lda` pipeline; a stopping rule is chosen from a calibration, which a given model skips).
    pub fn check(&self) -> Result<(), PlanError> {
        self.open.check().map_err(PlanError::Open)?;
        self.params.validate().map_err(PlanError::Session)?;
        self.arm()?;
        match &self.start {
            Start::Calibrate { adapt: Some(_) } if self.params.decoder.pipeline != Preset::Lda => {
                Err(PlanError::Invalid(format!(
                    "online adaptation adapts the lda pipeline, not {}",
                    self.params.decoder.pipeline
                )))
            }
            Start::Model(_) | Start::Uncalibrated { .. }
                if self.params.decoder.stopping.is_some() =>
            {
                Err(PlanError::Invalid(
                    "the stopping rule is chosen from a calibration: this session does not calibrate"
                        .into(),
                ))
            }
            _ => Ok(()),
        }
    }

    /// The arm the session drives (recording its trace).
    pub fn arm(&self) -> Result<ArmSim, PlanError> {
        recording_arm(self.step_m).map_err(PlanError::Arm)
    }

    /// Opens the source (unpaced or paced by `clock`, as the open options say), and the
    /// marker outlet of a source that has one.
    pub fn open_source(
        &self,
        clock: Clock,
    ) -> Result<(AnySource, Option<Box<dyn MarkerSink>>), PlanError> {
        self.source
            .open(self.open.clone(), clock)
            .map_err(PlanError::Open)
    }

    /// `source` at the rate of the model the session starts with ([`AnySource::at_rate`]);
    /// as it is without one.
    pub fn at_model_rate(
        &self,
        source: AnySource,
    ) -> Result<(AnySource, Option<RateChange>), PlanError> {
        match &self.start {
            Start::Model(m) => source.at_rate(m.sfreq).map_err(PlanError::Rate),
            _ => Ok((source, None)),
        }
    }

    /// The session over `subject`, not started: the plan's settings, a recording arm, the
    /// channels named by the montage.
    pub fn session<S: Subject>(&self, subject: S) -> Result<Session<S>, PlanError> {
        let mut session = Session::new(self.params.clone(), subject, Some(self.arm()?))
            .map_err(PlanError::Session)?;
        if let Some(names) = &self.montage {
            session
                .name_channels(names.clone())
                .map_err(PlanError::Montage)?;
        }
        Ok(session)
    }

    /// Starts `session` as planned, telling `progress` how far a calibration is; what the
    /// calibration measured (`None` when the session does not calibrate).
    pub fn start<S: Subject>(
        &self,
        session: &mut Session<S>,
        progress: &mut dyn FnMut(CalibrationProgress),
    ) -> Result<Option<CalibrationReport>, PlanError> {
        session
            .start(self.start.clone(), progress)
            .map_err(PlanError::Start)
    }

    /// The whole set-up of a live session: the source opened at the model's rate, the live
    /// subject over it (with its marker outlet), the session, started.
    pub fn open(
        &self,
        clock: Clock,
        progress: &mut dyn FnMut(CalibrationProgress),
    ) -> Result<OpenedSession, PlanError> {
        let (source, markers) = self.open_source(clock)?;
        let (source, rate_change) = self.at_model_rate(source)?;
        let mut subject = LiveSubject::new(source, self.params.paradigm, clock);
        if let Some(m) = markers {
            subject = subject.with_markers(m);
        }
        let mut session = self.session(subject)?;
        let calibration = self.start(&mut session, progress)?;
        Ok(OpenedSession {
            session,
            calibration,
            rate_change,
        })
    }
}
