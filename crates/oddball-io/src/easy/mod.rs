//! Neuroelectrics NIC `.easy` recordings (Enobio, Starstim) and their `.info` files: a reader and
//! a writer, written from scratch.
//!
//! # Why here
//! One Rust crate reads `.easy` files, `easy-rs` (0.0.6, early 2025): its errors are
//! `anyhow` text, not a typed error carrying file, line and column; it depends on the `cargo`
//! crate, `chrono`, `regex`, `csv` and `flate2`; and it writes nothing. The format is one table
//! of integers, so a small reader that knows where each value came from (1-based line and column
//! in every error, like [`crate::csv`]) and a writer beside it serve this crate's error rule
//! better, without new dependencies.
//!
//! # The `.easy` file
//! NIC's plain-text recording: one line per sample, TAB-separated cells:
//!
//! ```text
//! Ch1 … ChN (nV) [aX aY aZ] [AddSensor] trigger timestamp
//! ```
//!
//! The `N` EEG channels are integers in nanovolts (`N` is 8, 20 or 32 on Neuroelectrics
//! devices), then optionally three accelerometer columns, optionally the external "AddSensor"
//! column, then the trigger/flags column (uint32; 0 = no marker; NIC writes 255 when packets
//! were lost), then a Unix timestamp in milliseconds. So an 8-channel file has 10 cells per line
//! (no accelerometer, no AddSensor), 11 (AddSensor), 13 (accelerometer) or 14 (both); 20
//! channels: 22, 23, 25, 26; 32 channels: 34, 35, 37, 38.
//!
//! # The `.info` file
//! A text file with the same stem, one `Key: value` per line, for example (NIC 1 and NIC 2 write
//! somewhat different sets of keys; each line is trimmed, keys are compared case-insensitively
//! with runs of spaces collapsed, and lines this reader does not know are kept in
//! [`EasyInfo::info`] and otherwise ignored):
//!
//! ```text
//! Device class: STARSTIM
//! Total number of channels: 8
//! Number of EEG channels: 8
//! Number of records of EEG: 15000
//! EEG sampling rate: 500 Samples/second
//! EEG units: nV
//! Accelerometer data: ON
//! Channel 1: Position: C3        (NIC 1 also puts "Position: C3" on the line after "Channel 1:")
//! Channel 2: C4                  (NIC 2)
//! ```
//!
//! # Reading ([`read_easy`], [`read_easy_with`], [`parse_easy`])
//! * **Layout.** The number of cells on the first line decides, given the EEG channel count `N`:
//!   `N + 2`, `+ 3` (AddSensor), `+ 5` (accelerometer) or `+ 6` (both). `N` comes from
//!   [`EasyOptions::n_channels`]; else from the `.info`'s `Total number of channels` (a Starstim
//!   that stimulates on some channels records all of them; `Number of EEG channels` counts only
//!   the recording ones) or, without it, `Number of EEG channels`; else, when the `.info` says
//!   `Accelerometer data: ON/OFF` (and `Additional channel status: ON/OFF` or
//!   `Additional channel: NONE`), from those flags; else from the device sizes 8, 20 and 32 (the
//!   cell counts above do not overlap). The `.info`'s accelerometer flag does not override a
//!   layout the channel count gives. Every later line must have as many cells as the first.
//! * **Samples.** EEG cells are numbers (NIC writes integers) in nV, divided by 1000 to µV (so a
//!   whole number of nV reads back as the `f64` nearest to its µV value); `EEG units` in the
//!   `.info` (`nV`, `uV`, `mV`, `V`; see [`crate::units::microvolts_per`]) or
//!   [`EasyOptions::scale_to_uv`] change the factor. A value
//!   beyond ±2 147 483 647 nV (the int32 range, ±2.1 V) is refused as absurd. Accelerometer and
//!   AddSensor values are kept as written in [`EasyInfo::accelerometer`] and
//!   [`EasyInfo::add_sensor`] (NIC documents the accelerometer in mm/s²).
//! * **Channel names** from the `.info`'s `Channel k:` lines (`Channel k: Position: X`,
//!   `Channel k: X`, or `Channel k:` followed by a `Position: X` line). Channels without one are
//!   named `Ch1` … `ChN`: that is what NIC itself writes for an electrode without a position (and
//!   what Neuroelectrics' EEGLAB plugin treats as an unused channel). No default montage is
//!   assumed: an Enobio/Starstim 8 has none (the electrodes go wherever the cap is set up), so a
//!   guessed list of positions would be wrong as often as right.
//! * **Sampling rate:** [`EasyOptions::sfreq`] when given; else the `.info`'s
//!   `EEG sampling rate`; else from the timestamps: the median interval `m`, then the mean of the
//!   intervals within `[m/2, 3m/2]` (which ignores the gaps of lost packets and averages out
//!   timestamps rounded to 1 ms), `1000 / mean` rounded to whole Hz (device rates are whole Hz; the
//!   unrounded estimate is kept in [`EasyInfo::estimated_sfreq`]). Deriving the rate needs at least
//!   two samples with strictly increasing timestamps; otherwise the reader refuses, naming the
//!   line where the time stands still or goes back.
//! * **Events** at each sample whose trigger is non-zero and differs from the previous sample's
//!   (a trigger held over several samples is one event, at its first sample; a change from one
//!   code straight to another is a new event). The code is the trigger value; `target` is
//!   `Some(true)`/`Some(false)` for [`EasyOptions::target_codes`] /
//!   [`EasyOptions::nontarget_codes`], else `None`. Codes in [`EasyOptions::ignore_codes`]
//!   (by default 255, NIC's lost-packet flag) give no event but still count as the previous
//!   sample's value (`5 255 5` gives two events). The whole trigger column is kept in
//!   [`EasyInfo::triggers`].
//! * **Errors** ([`IoError::Csv`](crate::IoError::Csv), the crate's line-and-column variant, with the path of the
//!   `.easy` or `.info` file at fault; lines count from 1, blank lines included; in a `.easy`
//!   the column is the 1-based TAB-separated cell, in a `.info` the character where the value
//!   starts): a cell that is not a number, an integer trigger
//!   (0 ..= 4 294 967 295) or an integer timestamp (0 ..= 2⁵³ ms); an absurd value; a line with
//!   more or fewer cells than the first; a first line that fits no layout; invalid UTF-8; an empty
//!   file; a last line without a line end (a file cut inside its last line; see
//!   [`EasyOptions::require_final_newline`]); fewer or more lines than the `.info`'s
//!   `Number of records of EEG` (a file cut at a line end; see
//!   [`EasyOptions::check_record_count`]); a `.info` value this reader needs that it cannot read.
//!   Blank lines are skipped, `\r\n` line ends and a UTF-8 byte-order mark are accepted, and
//!   spaces around cells and trailing whitespace (a trailing TAB) are ignored.
//!
//! # Writing ([`write_easy`])
//! The `.easy` and a `.info` beside it (same stem, extension `.info`), each written to a
//! temporary file in the same directory and renamed into place (`.info` first): a failed write
//! never leaves a partial file under either name (should the second rename fail, the new
//! `.info` sits beside the old `.easy`; the reader refuses that pair unless their sample counts
//! agree). The `.easy` holds, per sample, the EEG in whole nV (`round(µV × 1000)`, halves away
//! from zero; the largest rounding is reported), no accelerometer or AddSensor columns, the
//! trigger and the timestamp. The trigger is the code of each of the [`Raw`](oddball_signal::Raw)'s events at its
//! onset sample only, 0 elsewhere. Timestamp of sample `i`: `start_ms + round(i × 1000 /
//! sfreq)` ms, rounded to the nearest ms (halves away from zero) and computed from `i` each
//! time, so the error never exceeds 0.5 ms and does not accumulate (above 1000 Hz successive
//! timestamps can be equal; the `.info` carries the exact rate). The `.info` is in NIC 2's form
//! (`Channel k: NAME` lines, which Neuroelectrics' EEGLAB plugin reads) with the device class
//! (`STARSTIM` by default), channel count, record count, the rate (Rust's shortest round-trip
//! decimal, so it reads back bit-exact), `EEG units: nV` and `Accelerometer data: OFF`.

//!
//! # Layout
//! By job: `types.rs` holds the options and what a file held, `info.rs` parses the `.info`,
//! `read.rs` the `.easy`, `write.rs` writes both.

mod info;
mod read;
mod types;
mod write;

pub use read::{
    estimate_sfreq, info_path_for, parse_easy, read_easy, read_easy_with, ODDBALL_ATTENDED_OFFSET,
    ODDBALL_PARADIGM_KEY,
};
pub use types::{
    EasyInfo, EasyInfoFile, EasyLayout, EasyOptions, EasySfreqSource, InfoIndex, MAX_TIMESTAMP_MS,
    NIC_PACKET_LOSS_CODE, STANDARD_CHANNEL_COUNTS,
};
pub use write::{timestamp_ms, write_easy, write_easy_blocks, EasyWriteOptions, EasyWriteSummary};

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::info::*;
    use super::read::*;
    use super::*;
    use crate::IoError;

    #[test]
    fn layouts() {
        let l = |n, c| EasyLayout::for_columns(n, c).map(|l| (l.accelerometer, l.add_sensor));
        assert_eq!(l(10, 8), Some((false, false)));
        assert_eq!(l(11, 8), Some((false, true)));
        assert_eq!(l(13, 8), Some((true, false)));
        assert_eq!(l(14, 8), Some((true, true)));
        assert_eq!(l(12, 8), None);
        assert_eq!(l(9, 8), None);
        assert_eq!(l(15, 8), None);
        assert_eq!(l(2, 0), None);
        assert_eq!(l(26, 20), Some((true, true)));
        for n in [10, 11, 13, 14, 22, 23, 25, 26, 34, 35, 37, 38] {
            let found: Vec<_> = STANDARD_CHANNEL_COUNTS
                .iter()
                .filter_map(|&c| EasyLayout::for_columns(n, c))
                .collect();
            assert_eq!(found.len(), 1, "{n} columns");
            assert_eq!(found[0].n_columns(), n);
        }
    }

    #[test]
    fn rate_estimates() {
        let ts = |steps: &[u64]| {
            let mut t = vec![1_000u64];
            for s in steps {
                t.push(t.last().unwrap() + s);
            }
            t
        };
        assert_eq!(estimate_sfreq(&ts(&[2; 9])), Some(500.0));
        // A lost-packet gap is left out of the mean.
        assert_eq!(estimate_sfreq(&ts(&[2, 2, 2, 10, 2, 2])), Some(500.0));
        // 256 Hz with timestamps rounded to 1 ms: steps of 3.90625 ms on average.
        let t: Vec<u64> = (0..513)
            .map(|i| (i as f64 * 1000.0 / 256.0).round() as u64)
            .collect();
        let f = estimate_sfreq(&t).unwrap();
        assert!((f - 256.0).abs() < 0.01, "{f}");
        assert_eq!(round_sfreq(f), 256.0);
        assert_eq!(estimate_sfreq(&[5]), None);
        assert_eq!(estimate_sfreq(&[]), None);
        assert_eq!(estimate_sfreq(&[5, 5]), None);
        assert_eq!(estimate_sfreq(&[5, 7, 6]), None);
        assert_eq!(round_sfreq(0.25), 0.25);
    }

    #[test]
    fn scales_keep_whole_nanovolts_exact() {
        assert_eq!(Scale::from_factor(1e-3), Scale::DivideBy(1000.0));
        assert_eq!(Scale::from_factor(1.0), Scale::Times(1.0));
        assert_eq!(Scale::from_factor(1e3), Scale::Times(1e3));
        for k in [1234i64, -1, 7, 2_147_483_647, -999_999_999] {
            let s = format!("{}", k as f64 / 1000.0);
            assert_eq!(
                Scale::DivideBy(1000.0).to_uv(k as f64),
                s.parse::<f64>().unwrap()
            );
        }
    }

    #[test]
    fn info_lines() {
        let text = "\u{feff}Device CLASS :  STARSTIM \r\n\
            Device Mac: 00:07:80:58:9C:1A\r\n\
            total   number of channels: 8\r\n\
            EEG sampling rate: 500 Samples/second\r\n\
            eeg units: nV\r\n\
            Accelerometer data: on\r\n\
            Channel 1:\r\n Position: C3\r\n Type: EEG Recording\r\n\
            Channel 2: Position: C4\r\n\
            \tChannel 3: Pz\r\n\
            Channel 4:\r\nTrigger information:\r\n1 Subject moved\r\n";
        let p = parse_info(text.as_bytes(), Path::new("x.info")).unwrap();
        assert_eq!(p.device_class.as_deref(), Some("STARSTIM"));
        assert_eq!(p.total_channels.unwrap().value, 8);
        assert_eq!(p.total_channels.unwrap().line, 3);
        assert_eq!(p.sfreq.unwrap().value, 500.0);
        assert_eq!(p.accelerometer, Some(true));
        assert_eq!(p.scale, Some(Scale::DivideBy(1000.0)));
        let names: Vec<_> = p.names.iter().map(|n| (n.0, n.1.as_str())).collect();
        assert_eq!(names, vec![(1, "C3"), (2, "C4"), (3, "Pz")]);
        assert_eq!(p.entries[0], ("Device CLASS".into(), "STARSTIM".into()));
        assert_eq!(p.entries[1].1, "00:07:80:58:9C:1A");
        assert!(p
            .entries
            .iter()
            .any(|(k, v)| k == "Channel 4" && v.is_empty()));

        let err = |text: &str| match parse_info(text.as_bytes(), Path::new("x.info")) {
            Err(IoError::Csv { line, column, .. }) => (line, column),
            other => panic!("{other:?}"),
        };
        assert_eq!(err("a: b\nEEG sampling rate: fast\n"), (2, 20));
        assert_eq!(err("EEG sampling rate:   -5 Hz\n"), (1, 22));
        assert_eq!(err("Total number of channels: 0\n"), (1, 27));
        assert_eq!(err("Number of EEG channels: many\n"), (1, 25));
        assert_eq!(err("Number of records of EEG: -1\n"), (1, 27));
        assert_eq!(err("EEG units: degC\n"), (1, 12));
        assert_eq!(err("Channel 0: Fz\n"), (1, 1));
    }
}
