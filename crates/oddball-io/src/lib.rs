//! EEG file readers for the oddball P300 BCI, and BCI2000 and EDF+ writers.
//!
//! [`read`] picks the reader from the file extension and returns a [`Recording`]: the samples
//! as an [`oddball_signal::Raw`] in µV `(n_channels, n_times)` with their stimulus events, the
//! [`Format`], a [`Speller`] layout for P300-speller files, and the format's own [`Details`]
//! (BCI2000 parameters and states, CSV timestamps, EDF headers and annotations, NIC timestamps
//! and accelerometer).
//!
//! | extension | reader | events |
//! |---|---|---|
//! | `.dat` | [`bci2000`]: BCI2000 v1.0/v1.1; written by [`write_bci2000`] (v1.1, float32 µV, states from [`stimulus_states`] and the caller) | `StimulusCode` 0 → non-zero, target from `StimulusType` |
//! | `.csv` | [`csv`]: time / channel / marker columns ([`CsvOptions::detect`]) | non-zero marker |
//! | `.edf`, `.bdf` | [`edf`]: EDF, EDF+, BDF, BDF+ | EDF+ annotations |
//! | `.easy` | [`easy`]: Neuroelectrics NIC (Enobio, Starstim) text + the `.info` beside it; written by [`write_easy`] (whole nV, `.info` in NIC 2's form) | non-zero trigger differing from the sample before (255, NIC's lost-packet flag, skipped) |
//! | `.mat` | [`mat`]: MATLAB v5/v7 (uncompressed and zlib); a recording from the BCI Competition layout (`signal` + BCI2000 states, 240 Hz unless given) | `Flashing` 0 → 1 (else `StimulusCode` 0 → non-zero), target from `StimulusType` |
//! | `.xdf` (or any file starting with `XDF:`) | [`xdf`]: Lab Streaming Layer XDF 1.0, the EEG stream; written live by [`XdfWriter`] or offline by [`write_xdf`]; files cut by a killed recorder are read up to their last complete chunk | string (and numeric marker) stream samples at the nearest EEG sample |
//!
//! All six readers are written from scratch in this crate (each module says why). They share
//! one error rule: corrupt or truncated input gives an [`IoError`] naming the file, the field and
//! the byte offset (CSV and `.easy`/`.info`: line and column), never a panic and never a silently
//! shortened recording; header counts are checked against the file length before anything is
//! allocated.
//!
//! # Example
//! A CSV recording parsed from memory (the path only names it in messages):
//! ```
//! use std::path::Path;
//! use oddball_io::{csv::parse_csv, CsvOptions, Format};
//!
//! let text = "time,Cz,Pz,marker\n0.000,1.5,2.0,0\n0.004,1.0,2.5,7\n0.008,0.5,3.0,0\n";
//! let options = CsvOptions::detect(&["time", "Cz", "Pz", "marker"]);
//! let rec = parse_csv(text.as_bytes(), Path::new("mem.csv"), &options)?;
//! assert_eq!(rec.format, Format::Csv);
//! assert_eq!(rec.raw.ch_names(), ["Cz", "Pz"]);
//! assert_eq!(rec.raw.n_times(), 3);
//! assert_eq!(rec.raw.data()[[1, 2]], 3.0);
//! assert_eq!(rec.raw.events().len(), 1);
//! # Ok::<(), oddball_io::IoError>(())
//! ```

pub mod bci2000;
pub mod csv;
pub mod easy;
pub mod edf;
mod error;
pub mod events;
pub mod manifest;
pub mod mat;
pub mod montage;
pub mod nic;
pub mod read_options;
pub mod speller;
pub mod units;
mod writing;
pub mod xdf;

use std::path::{Path, PathBuf};

use oddball_signal::Raw;
use serde::{Deserialize, Serialize};

pub use bci2000::{
    read_bci2000, read_bci2000_with, stimulus_states, write_bci2000, Bci2000Header, Bci2000Info,
    Bci2000Options, Bci2000WriteOptions, Bci2000WriteSummary, DataFormat, Parameter, Parameters,
    StateColumn, StateDef, States,
};
pub use csv::{read_csv, read_csv_auto, CsvInfo, CsvOptions};
pub use easy::{
    read_easy, read_easy_with, write_easy, EasyInfo, EasyInfoFile, EasyLayout, EasyOptions,
    EasySfreqSource, EasyWriteOptions, EasyWriteSummary, InfoIndex,
};
pub use edf::{
    read_edf, read_edf_with, write_edf_plus, write_edf_plus_with, Annotation, EdfHeader, EdfInfo,
    EdfOptions, EdfSignal, EdfWriteOptions, EdfWriteSummary,
};
pub use error::{bounded, IoError, StateProblem, MAX_ECHO_CHARS};
pub use events::{EventKey, EventMapError, EventMapping, LabelError, MappingReport};
pub use manifest::{Manifest, ManifestError, SpellerSpec};
pub use mat::{
    parse_mat, parse_mat_file, read_mat, read_mat_file, read_mat_with, MatFile, MatInfo, MatOptions,
};
pub use read_options::{read_with, ReadOptions};
pub use speller::{CodeOrder, Speller, TextLabelError};
pub use writing::{write_atomic, AtomicFile};
pub use xdf::{
    parse_xdf, parse_xdf_file, parse_xdf_with, read_xdf, read_xdf_file, read_xdf_with, write_xdf,
    XdfFile, XdfFormat, XdfInfo, XdfMarker, XdfOptions, XdfStream, XdfStreamData, XdfStreamInfo,
    XdfValues, XdfWriteOptions, XdfWriteSummary, XdfWriter,
};

/// The file format a recording was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    /// BCI2000 `.dat` (v1.0 or v1.1).
    Bci2000,
    Csv,
    Edf,
    EdfPlus,
    Bdf,
    BdfPlus,
    /// Neuroelectrics NIC `.easy` (with its `.info`).
    Easy,
    /// Lab Streaming Layer XDF.
    Xdf,
    /// MATLAB MAT v5/v7 (BCI Competition layout).
    Mat,
}

/// The format-specific contents of a recording.
#[derive(Debug, Clone, PartialEq)]
pub enum Details {
    Bci2000(Box<Bci2000Info>),
    Csv(CsvInfo),
    Edf(Box<EdfInfo>),
    Easy(EasyInfo),
    Xdf(Box<XdfInfo>),
    Mat(Box<MatInfo>),
}

/// A recording read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Samples in µV, `(n_channels, n_times)`, with the stimulus events.
    pub raw: Raw,
    pub format: Format,
    /// The file it was read from.
    pub path: PathBuf,
    /// The speller layout, for P300-speller recordings (BCI2000 files with `TargetDefinitions`).
    pub speller: Option<Speller>,
    pub details: Details,
}

impl Recording {
    /// BCI2000 parameters, states and header, for `.dat` files.
    pub fn bci2000(&self) -> Option<&Bci2000Info> {
        match &self.details {
            Details::Bci2000(b) => Some(b),
            _ => None,
        }
    }

    /// Column names and timestamps, for CSV files.
    pub fn csv(&self) -> Option<&CsvInfo> {
        match &self.details {
            Details::Csv(c) => Some(c),
            _ => None,
        }
    }

    /// Header and annotations, for EDF/BDF files.
    pub fn edf(&self) -> Option<&EdfInfo> {
        match &self.details {
            Details::Edf(e) => Some(e),
            _ => None,
        }
    }

    /// Layout, triggers, timestamps, accelerometer and `.info` entries, for `.easy` files.
    pub fn easy(&self) -> Option<&EasyInfo> {
        match &self.details {
            Details::Easy(e) => Some(e),
            _ => None,
        }
    }

    /// Streams, markers, timestamps and truncation, for XDF files.
    pub fn xdf(&self) -> Option<&XdfInfo> {
        match &self.details {
            Details::Xdf(x) => Some(x),
            _ => None,
        }
    }

    /// Header, variables, states and sampling-rate source, for MAT files.
    pub fn mat(&self) -> Option<&MatInfo> {
        match &self.details {
            Details::Mat(m) => Some(m),
            _ => None,
        }
    }
}

/// The extensions [`read`] dispatches on (any case), as `IoError::UnknownFormat` lists them.
pub const RECORDING_EXTENSIONS: [&str; 7] = ["dat", "csv", "edf", "bdf", "easy", "xdf", "mat"];

/// Refuses, before any reading, a path that does not exist or is a directory (naming the
/// recordings inside it).
pub fn check_file(path: &Path) -> Result<(), IoError> {
    let meta = std::fs::metadata(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => IoError::NotFound {
            path: path.to_path_buf(),
        },
        _ => IoError::Io {
            path: path.to_path_buf(),
            action: "read",
            source,
        },
    })?;
    if meta.is_dir() {
        let mut recordings: Vec<String> = std::fs::read_dir(path)
            .map(|entries| {
                entries
                    .filter_map(|e| e.ok())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|name| {
                        std::path::Path::new(name)
                            .extension()
                            .and_then(|e| e.to_str())
                            .is_some_and(|e| {
                                RECORDING_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                            })
                    })
                    .collect()
            })
            .unwrap_or_default();
        recordings.sort();
        recordings.truncate(3);
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
            recordings,
        });
    }
    Ok(())
}

/// Reads a recording, choosing the reader by extension (case-insensitive): `.dat` → BCI2000,
/// `.csv` → CSV with [`CsvOptions::detect`], `.edf`/`.bdf` → EDF/BDF (the header decides which),
/// `.easy` → NIC with the `.info` beside it ([`read_easy`]), `.xdf` → XDF ([`read_xdf`]),
/// `.mat` → MAT in the BCI Competition layout ([`read_mat`], 240 Hz); a file
/// with another extension that starts with the XDF magic code `XDF:` is read as XDF.
pub fn read(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    check_file(path)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("dat") => read_bci2000(path),
        Some("csv") => read_csv_auto(path),
        Some("edf") | Some("bdf") => read_edf(path),
        Some("easy") => read_easy(path),
        Some("xdf") => read_xdf(path),
        Some("mat") => read_mat(path),
        Some("xdfz") => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "gzip-compressed XDF (.xdfz); decompress it to .xdf first".into(),
        }),
        _ if xdf::has_magic(path) => read_xdf(path),
        _ => Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
            extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
        }),
    }
}
