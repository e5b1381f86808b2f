//! EEGLAB data sets (`.set`, with the samples in the `.set` or in a `.fdt` beside it), read
//! with this crate's own MAT reader.
//!
//! # Why no crate
//! A `.set` is a MATLAB MAT v5/v7 file, which [`crate::mat`] already reads from scratch (structs,
//! struct arrays, char arrays, zlib), with byte-offset errors; the `.fdt` is bare float32. What
//! is left is EEGLAB's `EEG` structure, a few dozen lines: no crate is needed.
//!
//! # Format
//! The `EEG` fields are either top-level variables (EEGLAB ≥ 2019, eeglabio, MNE's
//! `export_raw(fmt="eeglab")`) or the fields of a 1 × 1 struct variable `EEG` (older EEGLAB);
//! both are read ([`EeglabInfo::in_eeg_struct`]). The fields used:
//! * `nbchan`, `pnts` (whole numbers ≥ 1), `srate` (Hz), `trials` (1 when absent). An
//!   **epoched** data set (`trials` > 1) is refused: only continuous recordings are read, as
//!   MNE's `read_raw_eeglab` reads them.
//! * `data`: the samples in µV, an `nbchan × pnts` numeric matrix (any class, column-major), or
//!   a char array naming the `.fdt` file: `nbchan × pnts` little-endian float32, channels
//!   varying fastest, exactly `nbchan × pnts × 4` bytes long (a shorter file is an
//!   [`IoError::Truncated`](crate::IoError::Truncated) naming the first incomplete sample and
//!   its byte offset). The name is relative to the `.set`'s folder (a name with a root or a `..`
//!   part is refused); when that file is missing, the `.fdt` with the `.set`'s own name is read
//!   instead (a renamed recording, as MNE does; [`EeglabInfo::stale_data_name`]).
//! * `chanlocs(k).labels`: the channel names; with no `chanlocs`, `EEG 000`, `EEG 001` … (MNE's).
//! * `event(k).type` (text or a number) and `event(k).latency` (1-based samples, possibly
//!   fractional; an empty latency is NaN and makes no event, as MNE drops it). The onset is
//!   `latency − 1` rounded half to even (numpy's rounding, which MNE uses). A numeric type that
//!   is a whole number is the code; a text type is read as an EDF+ annotation text (`7`,
//!   `3 target`, `12 nontarget: A`) or else gets a code per distinct text in order of first
//!   appearance from one above the largest numeric code ([`EeglabInfo::label_codes`], the rule
//!   of EDF+ annotations). EEGLAB's `boundary` events are events like any other text.
//!
//! A MAT file holds no count of its variables: a `.set` of top-level variables cut exactly
//! between two variables after the ones needed still reads (with all its samples, which
//! `nbchan × pnts` checks, but without the variables cut off, `event` among them). A struct
//! `EEG` is one variable, so any cut of it is an error.
//!
//! MAT v7.3 (HDF5) `.set` files are refused with an error naming the version (no HDF5 reader
//! here). Every error names the `.set` (or `.fdt`), the `EEG` field, and the byte offset of the
//! variable holding it (for a struct `EEG`, that variable's offset). Values are checked against
//! MNE 1.13.2's `read_raw_eeglab` on files written by eeglabio and by `scipy.io.savemat`
//! (`tools/golden/eeglab/`).
//!
//! # Layout
//! `types.rs` holds what a recording keeps ([`EeglabInfo`]), `read.rs` reads the `EEG` fields,
//! the samples and the events.

mod read;
mod types;

pub use read::{parse_eeglab, read_eeglab};
pub use types::{EeglabEvent, EeglabEventType, EeglabInfo};
