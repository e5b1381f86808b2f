//! What can stop a run, with the facts: [`SettingError`] for settings that contradict each other
//! or a file they name (a front end maps each to its own option names: the command line to its
//! flags), [`AppError`] for everything else.

use std::path::PathBuf;

use oddball_arm::ArmError;
use oddball_decode::preset::Preset;
use oddball_decode::DecodeError;
use oddball_eval::dataset::DatasetError;
use oddball_io::IoError;
use oddball_live::plan::PlanError;
use oddball_live::source::SourceSpec;
use oddball_live::LiveError;
use oddball_plot::PlotError;
use oddball_session::SessionError;
use thiserror::Error;

/// Settings that cannot run, found before any EEG work.
#[derive(Debug, Error)]
pub enum SettingError {
    #[error("a session without calibration starts without a model: not with a given model")]
    ModelWithoutCalibration,
    #[error("online adaptation adapts a calibration made in this session, not a given model")]
    AdaptWithModel,
    #[error(
        "the stopping rule is chosen from this session's calibration, which a given model skips"
    )]
    OptimiseWithModel,
    #[error(
        "a replayed subject is calibrated on its recording's calibration file, not a given model"
    )]
    ReplayWithModel { files: Vec<PathBuf> },
    #[error("a transfer model starts an uncalibrated session: it needs no calibration")]
    TransferNeedsUncalibrated,
    #[error(
        "online adaptation adapts a labelled calibration; a session without one adapts by itself"
    )]
    AdaptUncalibrated,
    #[error("the texts of replayed files need a replayed subject")]
    TestTextWithoutReplay,
    #[error("online adaptation adapts the lda pipeline, not {pipeline}")]
    AdaptNeedsLda { pipeline: Preset },
    #[error("the panel's timing: {0}")]
    Timing(#[source] SessionError),
    #[error("the dynamic stopping rule: {0}")]
    DynamicRule(#[source] DecodeError),
    #[error("the stopping search: {0}")]
    StoppingSearch(#[source] DecodeError),
    #[error("the arm's step: {0}")]
    Arm(#[source] ArmError),
    #[error("the intended commands: {0}")]
    Commands(#[source] SessionError),
    #[error("a replayed subject is not a live source")]
    NotLive,
    #[error("building the simulated subject: {0}")]
    Subject(#[source] SessionError),
    #[error("opening the source: {0}")]
    SourceOptions(#[source] LiveError),
    #[error("{0}")]
    ModelFile(#[source] Box<IoError>),
    #[error("reading {}", path.display())]
    ReadModel {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("loading model {}", path.display())]
    LoadModel {
        path: PathBuf,
        #[source]
        source: DecodeError,
    },
    #[error("{}: {}", path.display(), oddball_decode::model::NO_DECISION_MODEL)]
    NoDecisionModel { path: PathBuf },
    #[error("reading the montage {}: {source}", path.display())]
    Montage {
        path: PathBuf,
        #[source]
        source: Box<IoError>,
    },
    #[error(
        "a replayed subject is calibrated on its recording; it cannot start without calibration"
    )]
    ReplayUncalibrated,
    #[error("a replayed recording: {0}")]
    ReplayedFile(#[source] Box<IoError>),
    #[error("{texts} texts for {files} replayed files (one per file)")]
    TestTextCount { texts: usize, files: usize },
    #[error("the calibration recording: {0}")]
    CalibrationFile(#[source] Box<IoError>),
    #[error("{} is both replayed and calibrated on: calibrate on other recordings", path.display())]
    ReplayedAndCalibrated { path: PathBuf },
    #[error("no calibration recording for {}", path.display())]
    NoSibling { path: PathBuf },
    #[error("{} has {n_events} events but none is labelled target or non-target (its events: {events})", path.display())]
    Unlabelled {
        path: PathBuf,
        n_events: usize,
        events: String,
        /// A calibration recording (else a replayed one).
        calibration: bool,
    },
    #[error("a replayed subject replays decisions offline: it takes no live source ({spec})")]
    ReplayWithSource {
        files: Vec<PathBuf>,
        spec: SourceSpec,
    },
    #[error(
        "a replayed recording's flashes are already fixed: the panel runs with simulated subjects"
    )]
    ServeReplay,
    #[error("the tracking task: {0}")]
    Track(#[source] SessionError),
    #[error("the text to draw {text:?}: {source}")]
    Drawing {
        text: String,
        #[source]
        source: SessionError,
    },
    #[error("the panel's wait for a page, {seconds} s: expected 0 to {max} seconds")]
    WaitPage { seconds: f64, max: f64 },
    #[error("{addr}: expected HOST:PORT")]
    Address {
        addr: String,
        #[source]
        source: Option<std::io::Error>,
    },
}

/// Why a run stopped.
#[derive(Debug, Error)]
pub enum AppError {
    #[error(transparent)]
    Setting(#[from] SettingError),
    /// A step of the session's plan; `start` says how the session was to start.
    #[error("{error}")]
    Plan {
        #[source]
        error: PlanError,
        source_spec: SourceSpec,
        start: StartKind,
    },
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    #[error("calibrating on {names}")]
    Calibrating {
        names: String,
        #[source]
        source: SessionError,
    },
    #[error("replaying {names}")]
    Replaying {
        names: String,
        #[source]
        source: SessionError,
    },
    #[error("drawing {text:?}")]
    DrawingTask {
        text: String,
        #[source]
        source: SessionError,
    },
    #[error("creating {}", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("writing {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: Box<IoError>,
    },
    #[error("writing {}", path.display())]
    SaveSession {
        path: PathBuf,
        #[source]
        source: SessionError,
    },
    #[error("drawing {}", path.display())]
    Draw {
        path: PathBuf,
        #[source]
        source: PlotError,
    },
    #[error("creating {}", path.display())]
    CreateRecording {
        path: PathBuf,
        #[source]
        source: LiveError,
    },
    #[error("closing {}", path.display())]
    CloseRecording {
        path: PathBuf,
        #[source]
        source: LiveError,
    },
    #[error("starting the panel")]
    Panel(#[source] LiveError),
    #[error("no page opened the panel at http://{addr}/ within {seconds} s")]
    NoPage { addr: String, seconds: f64 },
    #[error("passing over the recorded calibration")]
    PassCalibration(#[source] SessionError),
    #[error("running the commands")]
    Running(#[source] SessionError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// Writing what the run says (standard output, say) failed.
    #[error("writing the run's output")]
    Output(#[source] std::io::Error),
}

impl From<std::io::Error> for AppError {
    fn from(e: std::io::Error) -> Self {
        AppError::Output(e)
    }
}

/// How a session was to start, for saying what failed ([`AppError::Plan`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartKind {
    Calibrate,
    Model,
    Uncalibrated { transfer: bool },
}

impl From<&oddball_session::decoder::Start> for StartKind {
    fn from(s: &oddball_session::decoder::Start) -> Self {
        use oddball_session::decoder::Start;
        match s {
            Start::Calibrate { .. } => StartKind::Calibrate,
            Start::Model(_) => StartKind::Model,
            Start::Uncalibrated { transfer, .. } => StartKind::Uncalibrated {
                transfer: transfer.is_some(),
            },
        }
    }
}

pub type Result<T, E = AppError> = std::result::Result<T, E>;
