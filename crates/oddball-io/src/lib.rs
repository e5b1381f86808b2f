//! EEG file readers for the oddball P300 BCI, and BCI2000, EDF+ and BrainVision writers.
//!
//! [`read`] picks the reader from the file extension and returns a [`Recording`]: the samples
//! as an [`oddball_signal::Raw`] in µV `(n_channels, n_times)` with their stimulus events, the
//! [`Format`], a [`Speller`] layout for P300-speller files, and the format's own [`Details`]
//! (BCI2000 parameters and states, CSV timestamps, EDF headers and annotations, NIC timestamps
//! and accelerometer, FIF channel records and annotations, GDF event tables).
//!
//! | extension | reader | events |
//! |---|---|---|
//! | `.dat` | [`bci2000`]: BCI2000 v1.0/v1.1; written by [`write_bci2000`] (v1.1, float32 µV, states from [`stimulus_states`] and the caller) | `StimulusCode` 0 → non-zero, target from `StimulusType` |
//! | `.csv` | [`csv`]: time / channel / marker columns ([`CsvOptions::detect`]) | non-zero marker |
//! | `.edf`, `.bdf` | [`edf`]: EDF, EDF+, BDF, BDF+ | EDF+ annotations |
//! | `.easy` | [`easy`]: Neuroelectrics NIC (Enobio, Starstim) text + the `.info` beside it; written by [`write_easy`] (whole nV, `.info` in NIC 2's form) | non-zero trigger differing from the sample before (255, NIC's lost-packet flag, skipped) |
//! | `.mat` | [`mat`]: MATLAB v5/v7 (uncompressed and zlib); a recording from the BCI Competition layout (`signal` + BCI2000 states, 240 Hz unless given) | `Flashing` 0 → 1 (else `StimulusCode` 0 → non-zero), target from `StimulusType` |
//! | `.vhdr` | [`brainvision`]: BrainVision 1.0 header + `.vmrk` markers + binary data (INT_16, INT_32, IEEE_FLOAT_32; multiplexed or vectorized); written by [`write_brainvision`] (IEEE_FLOAT_32 µV, multiplexed, as pybv) | `Stimulus` `S n` → n, `Response` `R n` → 1000 + n |
//! | `.set` | [`eeglab`]: EEGLAB continuous data set (MAT v5/v7, `EEG` as variables or a struct), samples inside or in the `.fdt` | `EEG.event`: numeric `type` → code, text `type` → EDF+ annotation rule |
//! | `.fif` | [`fif`]: MNE / Neuromag FIF raw (`*_raw.fif`, `*_eeg.fif`; split parts followed; EEG channels kept) | STIM channel steps up (MNE's `find_events`), MNE annotations |
//! | `.gdf` | [`gdf`]: GDF 1.x and 2.x (all integer and float types, 24-bit included) | the event table; OpenViBE label codes 0x8101… as flashes 1…, target from 0x8205/0x8206 within 2 samples; other tables: their codes |
//! | `.xdf` (or any file starting with `XDF:`) | [`xdf`]: Lab Streaming Layer XDF 1.0, the EEG stream; written live by [`XdfWriter`] or offline by [`write_xdf`]; files cut by a killed recorder are read up to their last complete chunk | string (and numeric marker) stream samples at the nearest EEG sample |
//!
//! A BIDS-EEG run (`sub-…_eeg.<edf|bdf|vhdr|set>` with its `_events.tsv` beside it) is read by
//! its format's reader with the events, channels and speller of its sidecars ([`bids`], which
//! also writes recordings as BIDS-EEG).
//!
//! All ten readers are written from scratch in this crate (each module says why). They share
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
pub mod bids;
pub mod brainvision;
mod bytes;
pub mod csv;
mod dispatch;
pub mod easy;
pub mod edf;
pub mod eeglab;
mod error;
pub mod events;
pub mod fif;
mod files;
pub mod gdf;
pub mod manifest;
pub mod mat;
pub mod montage;
pub mod nic;
pub mod paradigm;
pub mod read_options;
mod recording;
pub mod samples;
pub mod speller;
pub mod units;
mod writing;
pub mod xdf;

pub use bci2000::{
    read_bci2000, read_bci2000_with, stimulus_runs, stimulus_states, write_bci2000,
    write_bci2000_blocks, Bci2000Header, Bci2000Info, Bci2000Options, Bci2000WriteOptions,
    Bci2000WriteSummary, DataFormat, Parameter, Parameters, StateColumn, StateDef, StateRun,
    StateRuns, States,
};
pub use brainvision::{
    parse_brainvision, read_brainvision, write_brainvision, BrainVisionInfo, BvWriteSummary,
};
pub use csv::{read_csv, read_csv_auto, CsvInfo, CsvOptions};
pub use dispatch::read;
pub use easy::{
    read_easy, read_easy_with, write_easy, write_easy_blocks, EasyInfo, EasyInfoFile, EasyLayout,
    EasyOptions, EasySfreqSource, EasyWriteOptions, EasyWriteSummary, InfoIndex,
};
pub use edf::{
    read_edf, read_edf_with, write_edf_plus, write_edf_plus_with, Annotation, EdfHeader, EdfInfo,
    EdfOptions, EdfSignal, EdfWriteOptions, EdfWriteSummary,
};
pub use eeglab::{parse_eeglab, read_eeglab, EeglabInfo};
pub use error::{bounded, IoError, StateProblem, MAX_ECHO_CHARS};
pub use events::{EventKey, EventMapError, EventMapping, LabelError, MappingReport};
pub use fif::{parse_fif, read_fif, FifAnnotation, FifChannel, FifDataType, FifInfo, FifSkip};
pub use files::{check_file, RECORDING_EXTENSIONS};
pub use gdf::{parse_gdf, read_gdf, read_gdf_with, GdfInfo, GdfOptions};
pub use manifest::{Manifest, ManifestError, SpellerSpec};
pub use mat::{
    parse_mat, parse_mat_file, read_mat, read_mat_file, read_mat_with, MatFile, MatInfo, MatOptions,
};
pub use paradigm::{MarkerKind, Paradigm, ParadigmError};
pub use read_options::{read_with, ReadOptions};
pub use recording::{Details, Format, Recording};
pub use samples::{SampleBlocks, SampleSpill, SpilledSamples};
pub use speller::{CodeOrder, Speller, TextLabelError};
pub use writing::{write_atomic, AtomicFile};
pub use xdf::{
    parse_xdf, parse_xdf_file, parse_xdf_with, read_xdf, read_xdf_file, read_xdf_with, write_xdf,
    XdfFile, XdfFormat, XdfInfo, XdfMarker, XdfOptions, XdfStream, XdfStreamData, XdfStreamInfo,
    XdfValues, XdfWriteOptions, XdfWriteSummary, XdfWriter,
};
