//! FIF raw files (`*_raw.fif`, `*_eeg.fif`): MNE-Python's and Elekta/MEGIN Neuromag's recording
//! format, read from scratch.
//!
//! # Why not a crate
//! Two crates read FIF (judged from their docs.rs pages and sources, not built here): `fiff`
//! 0.1.0 documents the tag tree, tags and measurement info (its docs send anything further to
//! MNE-Python), and `exg` 0.0.6 carries a FIF reader (`open_raw`, `read_all_data`) inside an
//! EEG preprocessing pipeline (RustFFT and more), with `anyhow` string errors. Neither gives this
//! crate's errors (the file, the field and the byte offset of what is wrong) nor MNE's
//! annotations and trigger events, and the raw layout is small, so it is read here. It was
//! learnt from MNE-Python 1.13.2 (`mne/_fiff/tag.py`, `open.py`, `tree.py`, `meas_info.py`,
//! `mne/io/fiff/raw.py`, `mne/annotations.py`, `mne/event.py`) and is checked against files MNE
//! writes and what `mne.io.read_raw_fif` reads from them (`tools/golden/fif/`).
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

#[cfg(test)]
mod tests {
    use super::events::*;
    use super::tags::decode_string;

    #[test]
    fn strings_decode_as_mne_decodes_them() {
        assert_eq!(decode_string(b"Fz"), "Fz");
        assert_eq!(decode_string(b"caf\xe9"), "café");
        // MNE writes characters beyond Latin-1 as decimal references; they are decoded when
        // one has six digits (MNE's test), as `html.unescape` would.
        assert_eq!(decode_string(b"&#128512; ok &#233;"), "😀 ok é");
        assert_eq!(decode_string(b"&#233; alone"), "&#233; alone");
        assert_eq!(
            decode_string(b"&#128512;&#;&#x41;&#99999999999;"),
            "😀&#;A&#99999999999;"
        );
    }

    #[test]
    fn trigger_steps_follow_find_events_defaults() {
        let ch = vec![2, 2, 0, 3, 5, 4, 0, 0, 1, 1, 7];
        assert_eq!(
            stim_events(std::slice::from_ref(&ch)),
            [(3, 3), (4, 5), (8, 1), (10, 7)]
        );
        // A second channel with a step at the same sample and code: one event.
        let other = vec![0, 0, 0, 3, 0, 0, 0, 0, 0, 0, 0];
        assert_eq!(stim_events(&[ch, other]).len(), 4);
        assert!(stim_events(&[vec![]]).is_empty());
    }

    #[test]
    fn annotation_samples_are_cropped_and_rounded_as_mne_does() {
        // MNE 1.13.2, by hand: a 400-sample RawArray at 250 Hz, meas_date 1700000000.5, cropped
        // from 0.4 s (first_samp 100), annotations (onset, duration) (0.41, 0), (0.414, 0),
        // (0.35, 0.02), (0.35, 0.1), (0.4 + 300/250, 0), (0.4 + 299/250, 0):
        // `events_from_annotations` gives samples 2, 3, –, 0, 300, 299 (from first_samp).
        let m = 1_700_000_000_500_000;
        let t = Timing {
            sfreq: 250.0,
            first_samp: 100,
            n_times: 300,
            meas_us: Some(m),
        };
        let at = |onset: f64, duration: f64| annotation_sample(&t, onset, duration, Some(m));
        assert_eq!(at(0.41, 0.0), Some(2)); // 2.5 samples: half to even
        assert_eq!(at(0.414, 0.0), Some(3)); // 3.4999…
        assert_eq!(at(0.35, 0.02), None); // ends before the first sample
        assert_eq!(at(0.35, 0.1), Some(0)); // reaches it: clipped
        assert_eq!(at(0.4 + 300.0 / 250.0, 0.0), None); // MNE's 300 is past the data
        assert_eq!(at(0.4 + 299.0 / 250.0, 0.0), Some(299));
        assert_eq!(at(f64::NAN, 0.0), None);
        assert_eq!(at(1e300, 0.0), None);
        // Another orig_time (0.4 s later): onsets count from it; MNE (by hand, as above) gives
        // 3 and 8 for 0.01 and 0.03 (0.01 + 0.4 − 0.4 is 2.5000000000000107 samples).
        assert_eq!(annotation_sample(&t, 0.01, 0.0, Some(m + 400_000)), Some(3));
        assert_eq!(annotation_sample(&t, 0.03, 0.0, Some(m + 400_000)), Some(8));
        // No dates: onsets count from acquisition sample 0. MNE (by hand: the same raw without
        // meas_date, saved and read back) stores 0.4099999964237213 and 0.414000004529953
        // (float32) and gives samples 3 and 4.
        let t = Timing { meas_us: None, ..t };
        assert_eq!(
            annotation_sample(&t, 0.4099999964237213, f64::NAN, None),
            Some(3)
        );
        assert_eq!(annotation_sample(&t, 0.414000004529953, 0.0, None), Some(4));
        assert_eq!(annotation_sample(&t, 0.2, 0.0, None), None);
    }
}
