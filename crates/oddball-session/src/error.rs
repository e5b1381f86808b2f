use thiserror::Error;

/// Errors of the session crate.
#[derive(Debug, Error)]
pub enum SessionError {
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    /// A drawing (text, or a list of commands) leaves the board or the arm's reach.
    #[error("the path of {what}, with steps of {} mm from ({:.3}, {:.3}) m, leaves the board or the arm's reach at ({:.3}, {:.3}) m{}", .step_m * 1e3, .start_m[0], .start_m[1], .at_m[0], .at_m[1], fit_text(.max_step_m))]
    PathOffBoard {
        /// What is drawn, e.g. `the text "HELLO"`.
        what: String,
        step_m: f64,
        start_m: [f64; 2],
        /// The first vertex off the board or out of reach.
        at_m: [f64; 2],
        /// The largest step (a multiple of 0.5 mm) at which the whole path fits, if any.
        max_step_m: Option<f64>,
    },
    #[error("marker at sample {onset} arrived too late: its epoch starts before the oldest buffered sample {oldest_kept}")]
    MarkerTooLate { onset: u64, oldest_kept: u64 },
    #[error("the session has no model yet: calibrate first or load a model")]
    NotCalibrated,
    /// A session starts once ([`crate::engine::Session::start`]).
    #[error("the session has started already: it starts once, before its first decision")]
    AlreadyStarted,
    /// A model without the decision model a session decides with.
    #[error("model {pipeline}: {}", oddball_decode::model::NO_DECISION_MODEL)]
    NoDecisionModel { pipeline: String },
    /// A model at another rate than the EEG the session receives (the command line resamples
    /// a stream to its model's rate first: `oddball_live::source::AnySource::resampled`).
    #[error("the EEG arrives at {stream_sfreq} Hz and the model runs at {model_sfreq} Hz: resample the EEG to the model's rate before the session")]
    ModelRate { model_sfreq: f64, stream_sfreq: f64 },
    /// The EEG lacks channels the model needs (matched by name, case aside).
    #[error("the EEG has no channel named {missing:?} that the model needs (its channels: {have:?}): name its channels in order with a montage (an EEGLAB .loc, e.g. eeg64.loc)")]
    ModelChannels {
        missing: Vec<String>,
        have: Vec<String>,
    },
    /// A model or montage given after the session already took samples (its filter would
    /// start late, its names change midway).
    #[error(
        "{what} is set before the session's first sample; {n_times} samples were already taken"
    )]
    TooLate { what: &'static str, n_times: usize },
    #[error(
        "{path} is not a P300-speller recording (no TargetDefinitions): it cannot be replayed"
    )]
    NotASpeller { path: String },
    #[error("{path} is not an oddball session file: no {missing}")]
    NotASession { path: String, missing: String },
    /// A live source failed (`oddball_live::LiveError`, say): the cause is kept, typed, for
    /// callers to downcast.
    #[error("live source: {0}")]
    Source(#[source] Box<dyn std::error::Error + Send + Sync + 'static>),
    #[error(transparent)]
    Signal(#[from] oddball_signal::SignalError),
    #[error(transparent)]
    Decode(#[from] oddball_decode::DecodeError),
    #[error(transparent)]
    Arm(#[from] oddball_arm::ArmError),
    #[error(transparent)]
    Unsupervised(#[from] oddball_decode::unsupervised::UnsupervisedError),
    #[error(transparent)]
    Io(#[from] oddball_io::IoError),
    #[error("the session kept no samples (a live session's recording has them): nothing to save")]
    NoSamples,
    /// The session's samples could not be kept in their temporary file (in the system's
    /// temporary directory: `TMPDIR` on Unix).
    #[error("cannot {action} the session's samples in a temporary file in {}: {source}", std::env::temp_dir().display())]
    Spill {
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
}

fn fit_text(max_step_m: &Option<f64>) -> String {
    match max_step_m {
        Some(m) => format!("; it fits with steps of at most {} mm", m * 1e3),
        None => "; it does not fit with any step from this start".into(),
    }
}

impl SessionError {
    /// A failed `action` on the session's sample store, for `map_err`.
    pub(crate) fn spill(action: &'static str) -> impl Fn(std::io::Error) -> Self {
        move |source| Self::Spill { action, source }
    }
}
