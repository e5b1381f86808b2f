//! The one error type of `oddball-io`: every variant names the file and carries the facts
//! (field, byte offset or line/column, what was expected and what was found).

use std::path::{Path, PathBuf};

use oddball_signal::{Event, Events, Raw, SignalError};

/// What went wrong while reading or writing a recording.
///
/// Binary formats (BCI2000, EDF/BDF) report byte offsets counted from the start of the file;
/// CSV reports 1-based line and column numbers. No reader returns a partial recording: any
/// inconsistency between a header and the file's length is an error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system refused to open, read, create or write the file.
    #[error("{path}: cannot {action}: {source}")]
    Io {
        path: PathBuf,
        /// "read", "write", "create" or "rename".
        action: &'static str,
        #[source]
        source: std::io::Error,
    },

    /// The file is shorter than its header says: `field`, which starts at byte `offset`, needs
    /// the file to reach byte `needed`, but the file has only `file_len` bytes.
    #[error("{path}: truncated: {field} starting at byte offset {offset} needs {needed} bytes of file, but the file ends at byte {file_len}")]
    Truncated {
        path: PathBuf,
        field: String,
        offset: u64,
        needed: u64,
        file_len: u64,
    },

    /// A header field or data value at byte `offset` does not hold what the format requires.
    #[error("{path}: byte offset {offset}: {field}: expected {expected}, found {found:?}")]
    InvalidField {
        path: PathBuf,
        field: String,
        offset: u64,
        expected: String,
        found: String,
    },

    /// A CSV cell or line (1-based `line` and `column`) is malformed.
    #[error(
        "{path}: line {line}, column {column} ({field}): expected {expected}, found {found:?}"
    )]
    Csv {
        path: PathBuf,
        line: usize,
        column: usize,
        field: String,
        expected: String,
        found: String,
    },

    /// The configuration asks for something the file does not have (a column, a parameter).
    #[error("{path}: {what} {name:?} not found (available: {available:?})")]
    Missing {
        path: PathBuf,
        /// What kind of thing was looked for, e.g. "CSV column" or "parameter".
        what: &'static str,
        name: String,
        available: Vec<String>,
    },

    /// A valid file uses a feature this crate does not read or write (e.g. EDF+D with gaps).
    #[error("{path}: unsupported: {what}")]
    Unsupported { path: PathBuf, what: String },

    /// The file extension does not name a format [`crate::read`] knows.
    #[error("{path}: unknown file type ({}); known: {KNOWN_FORMATS}", extension_text(.extension))]
    UnknownFormat {
        path: PathBuf,
        extension: Option<String>,
    },

    /// A directory was given where a recording file was expected; `recordings` are the files
    /// in it that [`crate::read`] knows by their extension (the first few, sorted).
    #[error("{path} is a directory, not a recording: give a file{}", recordings_text(.recordings))]
    IsDirectory {
        path: PathBuf,
        recordings: Vec<String>,
    },

    /// The file does not exist.
    #[error("{path}: no such file")]
    NotFound { path: PathBuf },

    /// The path is a device, a pipe or a socket (or a link to one): its content has no end to
    /// bound what reading it costs, so it is refused.
    #[error("{path}: not a regular file (a device, pipe or socket): refused")]
    NotRegular { path: PathBuf },

    /// A sample a writer was asked to store is not finite or does not fit the file's number type.
    #[error("{path}: channel {channel:?} (index {channel_index}), sample {sample}: cannot write {value} µV: {reason}")]
    UnwritableSample {
        path: PathBuf,
        channel: String,
        channel_index: usize,
        sample: usize,
        value: f64,
        reason: &'static str,
    },

    /// A state column given to the BCI2000 writer is invalid (see [`StateProblem`]).
    #[error("{path}: state {state:?}: {problem}")]
    InvalidState {
        path: PathBuf,
        state: String,
        problem: StateProblem,
    },

    /// An extra parameter line given to the BCI2000 writer (the `index`-th, 0-based) is not a
    /// parameter line the readers can parse, or defines a parameter that is already defined.
    #[error(
        "{path}: extra parameter line {index} ({line:?}): expected {expected}, found {found:?}"
    )]
    InvalidParameterLine {
        path: PathBuf,
        index: usize,
        line: String,
        expected: String,
        found: String,
    },

    /// The decoded data could not form a valid [`oddball_signal::Raw`].
    #[error("{path}: {source}")]
    Signal {
        path: PathBuf,
        #[source]
        source: SignalError,
    },

    /// A BIDS layout or sidecar (see [`crate::bids`]).
    #[error(transparent)]
    Bids(Box<BidsError>),
}

impl From<BidsError> for IoError {
    fn from(e: BidsError) -> Self {
        IoError::Bids(Box::new(e))
    }
}

/// The [`Raw`] of a reader's parts; a part the signal crate refuses (shape, rate, names, events
/// out of range) is an error naming the file.
/// The most characters of a file's content an error message echoes.
pub const MAX_ECHO_CHARS: usize = 80;

/// `text` as an error message may echo it: at most [`MAX_ECHO_CHARS`] characters, the rest
/// replaced by `… (N more bytes)` (a 20 MB cell must not become a 20 MB message).
pub fn bounded(text: &str) -> String {
    match text.char_indices().nth(MAX_ECHO_CHARS) {
        None => text.to_string(),
        Some((cut, _)) => format!("{}… ({} more bytes)", &text[..cut], text.len() - cut),
    }
}

pub(crate) fn new_raw(
    path: &Path,
    data: ndarray::Array2<f64>,
    sfreq: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
) -> Result<Raw, IoError> {
    Raw::new(data, sfreq, ch_names, Events::new(events)).map_err(|source| IoError::Signal {
        path: path.to_path_buf(),
        source,
    })
}

impl IoError {
    /// A field with an unexpected value at a byte offset (every binary reader's error).
    pub(crate) fn invalid_field(
        path: &Path,
        field: impl Into<String>,
        offset: u64,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        IoError::InvalidField {
            path: path.to_path_buf(),
            field: field.into(),
            offset,
            expected: expected.into(),
            found: bounded(&found.into()),
        }
    }

    /// The file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            IoError::Io { path, .. }
            | IoError::Truncated { path, .. }
            | IoError::InvalidField { path, .. }
            | IoError::Csv { path, .. }
            | IoError::Missing { path, .. }
            | IoError::Unsupported { path, .. }
            | IoError::UnknownFormat { path, .. }
            | IoError::IsDirectory { path, .. }
            | IoError::NotFound { path }
            | IoError::NotRegular { path }
            | IoError::UnwritableSample { path, .. }
            | IoError::InvalidState { path, .. }
            | IoError::InvalidParameterLine { path, .. }
            | IoError::Signal { path, .. } => path,
            IoError::Bids(b) => b.path(),
        }
    }

    /// The byte offset the error points at, for the binary formats.
    pub fn offset(&self) -> Option<u64> {
        match self {
            IoError::Truncated { offset, .. } | IoError::InvalidField { offset, .. } => {
                Some(*offset)
            }
            _ => None,
        }
    }
}

/// What is wrong with a state column given to the BCI2000 writer ([`IoError::InvalidState`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum StateProblem {
    /// The column has `len` values but the recording has `n_times` samples.
    #[error("{len} values for a recording of {n_times} samples")]
    Length { len: usize, n_times: usize },
    /// `value` at `sample` needs more than the state's `bits`.
    #[error("value {value} at sample {sample} does not fit in {bits} bits (max {max})", max = (1u64 << bits) - 1)]
    ValueTooWide {
        sample: usize,
        value: u64,
        bits: u32,
    },
    /// The bit width is outside `1..=32`.
    #[error("{bits} bits (a state has 1 to 32 bits)")]
    Bits { bits: u32 },
    /// The name is empty, contains whitespace, or is not printable ASCII.
    #[error("invalid name: {reason}")]
    Name { reason: &'static str },
    /// Two columns (0-based indices `first` and `second`) have the same name.
    #[error("given twice (columns {first} and {second})")]
    Duplicate { first: usize, second: usize },
    /// Run `index` of a state given by runs is empty, starts before the end of the run before
    /// it, or ends after the recording's `n_times` samples.
    #[error("run {index} over samples [{start}, {end}) is empty, out of order, overlapping or beyond the recording's {n_times} samples")]
    Run {
        index: usize,
        start: usize,
        end: usize,
        n_times: usize,
    },
}

/// The formats [`crate::read`] knows, for messages.
const KNOWN_FORMATS: &str =
    ".dat (BCI2000), .csv, .edf, .bdf, .easy (NIC), .xdf (LSL), .mat (MATLAB v5/v7), .vhdr (BrainVision), .set (EEGLAB), .fif (MNE), .gdf";

fn extension_text(extension: &Option<String>) -> String {
    match extension {
        Some(e) => format!("extension .{e}"),
        None => "no extension".into(),
    }
}

fn recordings_text(recordings: &[String]) -> String {
    if recordings.is_empty() {
        format!(" (it holds no {KNOWN_FORMATS} file)")
    } else {
        format!(" inside it, e.g. {}", recordings.join(", "))
    }
}

/// A BIDS layout or sidecar that cannot be written or read, with the file and place at fault.
#[derive(Debug, thiserror::Error)]
pub enum BidsError {
    /// A subject, session or task label that BIDS does not allow (letters and digits only).
    #[error("{entity} label {value:?}: BIDS labels are letters and digits only (A-Z, a-z, 0-9), at least one")]
    Label {
        /// `sub`, `ses` or `task`.
        entity: &'static str,
        value: String,
    },
    /// A run's file is already there.
    #[error("{path} exists: a run is not overwritten unless asked to")]
    Exists { path: PathBuf },
    /// Two inputs would become the same run.
    #[error("{first} and {second} would both be written as {run}")]
    SameRun {
        first: PathBuf,
        second: PathBuf,
        run: String,
    },
    /// A TSV cell (or its header) that does not hold what the column means.
    #[error("{path}: line {line}, column {column:?}: {what}")]
    Table {
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        column: String,
        what: String,
    },
    /// A JSON sidecar that is not JSON, or a field of the wrong kind.
    #[error("{path}: {what}")]
    Json { path: PathBuf, what: String },
    /// A sidecar larger than [`crate::bids::MAX_SIDECAR_BYTES`].
    #[error("{path}: {len} bytes, more than the {limit} read from a BIDS sidecar")]
    TooLarge { path: PathBuf, len: u64, limit: u64 },
    /// A folder that is not a BIDS data set, or one holding no EEG run.
    #[error("{path}: {what}")]
    Dataset { path: PathBuf, what: String },
}

impl BidsError {
    /// The file or folder the error is about (the first, for [`BidsError::SameRun`]; an empty
    /// path for a label).
    pub fn path(&self) -> &Path {
        match self {
            BidsError::Label { .. } => Path::new(""),
            BidsError::SameRun { first: path, .. }
            | BidsError::Exists { path }
            | BidsError::Table { path, .. }
            | BidsError::Json { path, .. }
            | BidsError::TooLarge { path, .. }
            | BidsError::Dataset { path, .. } => path,
        }
    }
}
