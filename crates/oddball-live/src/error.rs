use thiserror::Error;

/// Errors of live operation.
#[derive(Debug, Error)]
pub enum LiveError {
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    #[error("no LSL stream matching {query} within {timeout_s} s")]
    StreamNotFound { query: String, timeout_s: f64 },
    #[error("the stream {name} sent nothing for {seconds} s: stopped")]
    StreamStalled { name: String, seconds: f64 },
    #[error("cannot serve the panel on {addr}: {reason}")]
    Bind { addr: String, reason: String },
    #[error("the stream {name} is gone (its outlet closed and cannot be recovered)")]
    StreamLost { name: String },
    #[error("the recording {} ended after {n_times} samples ({seconds:.1} s): playback stopped", path.display())]
    RecordingEnded {
        path: std::path::PathBuf,
        n_times: usize,
        seconds: f64,
    },
    /// A recording played back does not hold the session's flashes: fewer than half of the
    /// `asked` flashes shown so far fall on a recorded flash of the same bulb (see
    /// [`crate::playback`]).
    #[error("the recording {} does not hold this session's flashes: {found} of the {asked} flashes shown so far fall on a flash of the same bulb in it (within ±{window_ms} ms), so its EEG holds no response to the others and nothing can be decided on it; replay a recording of this session set up as it was (the same seed, commands and model or calibration)", path.display())]
    ReplayMismatch {
        path: std::path::PathBuf,
        found: usize,
        asked: usize,
        window_ms: f64,
    },
    #[error("cannot connect to {addr}: {reason}")]
    Connect { addr: String, reason: String },
    #[error("the stream from {addr} dropped and {attempts} reconnection attempts failed")]
    Reconnect { addr: String, attempts: usize },
    #[error(transparent)]
    Nic(#[from] oddball_io::nic::NicError),
    #[error("LSL: {0}")]
    Lsl(String),
    /// liblsl could not be loaded from any of the places tried ([`crate::lsl`] says where it
    /// looks), each with the loader's reason.
    #[error("Lab Streaming Layer needs liblsl, which could not be loaded (tried {}); install pylsl, whose wheels carry it (pip install pylsl), or set ODDBALL_LIBLSL to liblsl's path", tried.join("; "))]
    LiblslNotFound { tried: Vec<String> },
    #[error(transparent)]
    Session(#[from] oddball_session::SessionError),
    #[error(transparent)]
    Io(#[from] oddball_io::IoError),
    /// SIGINT or SIGTERM asked the session to stop ([`crate::stop`]).
    #[error("stopped on request (SIGINT or SIGTERM)")]
    Stopped,
    /// The operator view's abort button: a stop like [`LiveError::Stopped`].
    #[error("aborted from the operator view")]
    Aborted,
}

/// A live source's error reaches the session engine as its typed cause
/// ([`oddball_session::SessionError::Source`]); find it again with
/// [`LiveError::from_session`].
impl From<LiveError> for oddball_session::SessionError {
    fn from(e: LiveError) -> Self {
        oddball_session::SessionError::Source(Box::new(e))
    }
}

impl LiveError {
    /// The live error behind a session error, if a live source caused it.
    pub fn from_session(e: &oddball_session::SessionError) -> Option<&LiveError> {
        match e {
            oddball_session::SessionError::Source(cause) => cause.downcast_ref(),
            _ => None,
        }
    }
}
