//! FIF raw files (`*_raw.fif`, `*_eeg.fif`): MNE-Python's and Elekta/MEGIN Neuromag's recording
//! format, read from scratch.
//!
//! # Why not a crate
//! No Rust crate reads FIF (crates.io has none for MNE/Neuromag files as of 2026-11). The layout
//! is a plain chain of tagged records, so it is read here; it was learnt from MNE-Python 1.13.2
//! (`mne/_fiff/tag.py`, `open.py`, `tree.py`, `meas_info.py`, `mne/io/fiff/raw.py`,
//! `mne/annotations.py`) and is checked against files MNE writes and what `mne.io.read_raw_fif`
//! reads from them (`tools/golden/fif/`).
//!
//! # Format
//! A FIF file is a chain of tags. Each tag is a 16-byte big-endian header — `kind` (i32),
//! `type` (u32), `size` (i32, bytes of data), `next` (i32) — then its data. `next` is 0 when the
//! next tag follows, -1 for the last tag, else the byte offset of the next tag; the reader only
//! accepts offsets after the tag's end, so the chain moves forward and cannot loop. The file
//! starts with a `FIFF_FILE_ID` tag (type `FIFFT_ID_STRUCT`, 20 bytes) and a `FIFF_DIR_POINTER`.
//! Tags `FIFF_BLOCK_START` / `FIFF_BLOCK_END` (data: the block kind) nest the others in blocks;
//! a block left open where the chain ends is a cut file and an error. The directory MNE can use
//! to find the tags (`FIFF_DIR`) is not needed: the chain is followed from the start.
//!
//! What is read:
//! * `FIFFB_MEAS` › `FIFFB_MEAS_INFO`: `FIFF_NCHAN`, `FIFF_SFREQ` (float32), `FIFF_MEAS_DATE`
//!   (seconds, microseconds), one `FIFF_CH_INFO` per channel (96 bytes: scanNo, logNo, kind,
//!   range, cal, coil_type, loc\[12\], unit, unit_mul, ch_name\[16\]), and the `FIFFB_CH_INFO`
//!   blocks MNE adds for names longer than 15 characters (`FIFF_CH_DACQ_NAME` and the others).
//! * `FIFFB_RAW_DATA` (else `FIFFB_CONTINUOUS_DATA`): an optional `FIFF_FIRST_SAMPLE`
//!   (first_samp, the acquisition sample of the first sample), an optional initial
//!   `FIFF_DATA_SKIP` (first_samp moves by that many buffers), then `FIFF_DATA_BUFFER` tags
//!   holding `n_samples × n_channels` values, sample-major, of type short / dau_pack16 (i16),
//!   int (i32), float (f32) or double (f64), buffer by buffer (the type may change between
//!   buffers). A `FIFF_DATA_SKIP` between buffers leaves that many buffers (of the next buffer's
//!   size) that MNE reads as zeros; so does this reader, listing them in [`FifInfo::skips`]
//!   (MNE also annotates them `BAD_ACQ_SKIP`; here they are not events). Zeros beyond 16 times
//!   the samples stored are refused. MaxShield (`FIFFB_IAS_RAW_DATA`) data and complex buffers
//!   are refused.
//! * `FIFFB_MNE_ANNOTATIONS`: onsets (`FIFF_MNE_BASELINE_MIN`), ends (`FIFF_MNE_BASELINE_MAX`),
//!   texts (`FIFF_COMMENT`, `:`-separated, `{COLON}` standing for a colon) and `orig_time`
//!   (`FIFF_MEAS_DATE`).
//! * `FIFFB_REF` blocks of role 2 (`FIFFV_ROLE_NEXT_FILE`): the next part of a split recording
//!   (`FIFF_REF_FILE_NAME`, a file name in the same folder; MNE names them `x_raw.fif`,
//!   `x_raw-1.fif`, …). [`read_fif`] reads every part and checks that each continues the one
//!   before (same channels, calibration and rate; first sample right after the previous part's
//!   last); a missing part is an error naming it. [`parse_fif`] reads one file from memory and
//!   refuses one that names a next part.
//!
//! `.fif.gz` files (MNE reads them through gzip) are refused: decompress them first.
//!
//! # Values and channels
//! A sample's value is `stored × range × cal` (in `f64`, as MNE computes it), times
//! `10^unit_mul` (0 in every file MNE writes; MNE itself ignores it). Only **EEG** channels
//! (kind 2) become the recording's channels, in µV (volts × 10⁶; an EEG channel whose unit is not
//! the volt is kept unscaled and listed in [`FifInfo::non_voltage_channels`]). The trigger
//! channels become events and are not data channels. Every other kind (EOG, ECG, EMG, MISC, MEG,
//! …) is dropped and listed in [`FifInfo::dropped_channels`]; every channel record is kept in
//! [`FifInfo::channels`].
//!
//! # Events
//! * **Trigger channels**, chosen as MNE's `find_events` chooses them by default: the channel
//!   named `STI101` if there is one, else `STI 014`, else every channel of kind STIM (3). Their
//!   calibrated values are truncated to integers (sign dropped), and an event is put at every
//!   sample whose value is above the sample before — MNE's default `consecutive="increasing"`:
//!   0 → 3 and 3 → 5 are events (codes 3 and 5), 5 → 4 and 4 → 0 are not, nor a non-zero first
//!   sample. The code is the value. (MNE's `shortest_event=2` refusal of one-sample events is
//!   not applied.) Steps on several channels are merged, sorted, duplicates dropped.
//! * **Annotations** of the first part, at the sample MNE gives them (`events_from_annotations`,
//!   after `read_raw_fif` cropped them to the data in whole microseconds, counted from the
//!   measurement date and the first sample; half samples round to even). Those outside the
//!   recording are kept in [`FifInfo::annotations`] only. An annotation text gives its event's
//!   code as EDF+ texts do: `CODE [target|nontarget][: LABEL]` gives the code, target flag and
//!   label; any other text is the label and gets a code from [`FifInfo::label_codes`] — one per
//!   distinct text, in order of first appearance, counting up from one above the largest
//!   numeric code, trigger codes included (so the two never share a code). MNE's
//!   `events_from_annotations` numbers the texts 1, 2, … in sorted order and leaves out `BAD_*`
//!   and `EDGE_*` texts by default; here every annotation in the recording is an event.
//!
//! # Limits and errors
//! Every tag's size is checked against the file length before it is read; buffer sizes must be
//! whole samples; a channel count must match the channel records; nothing is allocated beyond
//! what the file's tags hold (plus the bounded skips). Errors name the file, the tag or field,
//! and the byte offset. Epochs, evoked, forward and other FIF files hold no raw data block and
//! are refused as such.
//!
//! # Layout
//! By job: `tags.rs` (tag headers, the chain, the block tree, typed tag data), `meas.rs`
//! (measurement info, channel records, stored annotations), `events.rs` (trigger steps and
//! annotation samples), `read.rs` (buffers, skips, split parts, the
//! [`Recording`](crate::Recording)), `types.rs` ([`FifInfo`] and its parts).

mod events;
mod meas;
mod read;
mod tags;
mod types;

pub use read::{parse_fif, read_fif};
pub use types::{FifAnnotation, FifChannel, FifDataType, FifInfo, FifSkip};
