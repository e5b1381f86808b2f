//! Writing BrainVision ([`write_brainvision`]): a recording as the three files pybv writes for
//! float data, which this crate's reader, MNE and BrainVision Analyzer read.
//!
//! # Why no crate
//! No Rust crate writes BrainVision (pybv, the reference writer, is Python), and the format is
//! three small files whose every rule (the `\1` comma, the marker codes, the header's keys) the
//! reader beside this file already holds; the writer is their inverse, so one rule serves both.
//!
//! # What is written
//! For `NAME.vhdr` ([`write_brainvision`]'s path), beside it:
//! * `NAME.eeg`: the samples as little-endian `IEEE_FLOAT_32`, `MULTIPLEXED` (all channels of
//!   sample 0, then of sample 1, …), in µV: each value is the recording's rounded to the nearest
//!   `f32` (a relative error of at most 2⁻²⁴, 6·10⁻⁸);
//! * `NAME.vmrk`: one marker per event, `Mk<i>=<Type>,<Description>,<onset + 1>,1,0`, the type
//!   and description those the reader turns back into the event's code (`Stimulus` `S  n` for
//!   codes 0–999 and from 2000, `Response` `R  n` for 1000 + n; the reader's rule, MNE's
//!   numbering, pybv's `S{:>3}` padding). An event's label and target flag are not stored (a
//!   marker has a type and a description only; a BIDS export keeps them in `_events.tsv`).
//! * `NAME.vhdr`: `Codepage=UTF-8`, the two file names, `DataFormat=BINARY`,
//!   `DataOrientation=MULTIPLEXED`, `NumberOfChannels`, `DataPoints` (so that a cut data file
//!   is an error on reading, not a shorter recording), `SamplingInterval` (10⁶ / rate µs, the
//!   shortest decimal that reads back as that `f64`), `BinaryFormat=IEEE_FLOAT_32`, and
//!   `ChN=Name,,1,µV` (resolution 1, unit µV, no reference: what pybv writes for float data in
//!   µV), a comma in a name written `\1`.
//!
//! Refused before anything is written: an empty recording; a non-finite sample or one beyond
//! `f32`'s range (the channel and sample named); a channel name the header cannot carry back
//! identically (empty, with a control character, with leading or trailing white space, or with
//! the text `\1` itself); a header path not ending in `.vhdr` or not UTF-8. Each file is written
//! atomically ([`crate::AtomicFile`]), the header last, so a header never names files not yet
//! complete.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use oddball_signal::Raw;

use crate::writing::{check_not_empty, check_writable};
use crate::{AtomicFile, IoError};

use super::markers::marker_of_code;

/// What [`write_brainvision`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct BvWriteSummary {
    /// The header (`.vhdr`), the one a reader is given.
    pub vhdr: PathBuf,
    /// The marker file (`.vmrk`).
    pub vmrk: PathBuf,
    /// The data file (`.eeg`).
    pub eeg: PathBuf,
    pub n_channels: usize,
    pub n_times: usize,
    /// Markers written (one per event).
    pub n_markers: usize,
    /// The largest |stored − given| over all samples, µV (the `f32` rounding).
    pub max_rounding: f64,
}

/// Writes `raw` as a BrainVision recording: the header at `path` (`….vhdr`), the data file and
/// the marker file beside it with the same stem (`.eeg`, `.vmrk`). See the module doc for what
/// each holds and what is refused.
pub fn write_brainvision(path: impl AsRef<Path>, raw: &Raw) -> Result<BvWriteSummary, IoError> {
    let vhdr = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: vhdr.to_path_buf(),
        what,
    };
    let is_vhdr = vhdr
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vhdr"));
    let stem = vhdr.file_stem().and_then(|s| s.to_str());
    let Some(stem) = stem.filter(|s| is_vhdr && !s.is_empty() && is_header_text(s)) else {
        return Err(unsupported(
            "a BrainVision header path: NAME.vhdr, NAME UTF-8 text without commas or control \
             characters"
                .into(),
        ));
    };
    check_not_empty(vhdr, raw, "BrainVision")?;
    for (c, name) in raw.ch_names().iter().enumerate() {
        if let Some(why) = unwritable_name(name) {
            return Err(unsupported(format!(
                "channel {c} name {name:?}: {why}, which a BrainVision header cannot carry back"
            )));
        }
    }
    let max_rounding = check_writable(vhdr, raw, "beyond IEEE float32's range", |x| {
        let f = x as f32;
        f.is_finite().then_some(f64::from(f))
    })?;

    let (eeg_name, vmrk_name) = (format!("{stem}.eeg"), format!("{stem}.vmrk"));
    let eeg = vhdr.with_file_name(&eeg_name);
    let vmrk = vhdr.with_file_name(&vmrk_name);
    write_data(&eeg, raw)?;
    let n_markers = raw.events().len();
    crate::write_atomic(&vmrk, marker_text(raw, &eeg_name))?;
    crate::write_atomic(vhdr, header_text(raw, &eeg_name, &vmrk_name))?;
    Ok(BvWriteSummary {
        vhdr: vhdr.to_path_buf(),
        vmrk,
        eeg,
        n_channels: raw.n_channels(),
        n_times: raw.n_times(),
        n_markers,
        max_rounding,
    })
}

/// Text a header value can hold: no control character and no comma (a file name).
fn is_header_text(s: &str) -> bool {
    !s.contains(',') && !s.chars().any(char::is_control) && s.trim() == s
}

/// Why a channel name would not read back identically from `ChN=Name,…`, if it would not.
fn unwritable_name(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("empty")
    } else if name.chars().any(char::is_control) {
        Some("a control character")
    } else if name.trim() != name {
        Some("leading or trailing white space")
    } else if name.contains("\\1") {
        Some("the text `\\1` (a comma when read)")
    } else {
        None
    }
}

/// The samples as little-endian f32, multiplexed.
fn write_data(eeg: &Path, raw: &Raw) -> Result<(), IoError> {
    let io = |path: &Path, source| IoError::Io {
        path: path.to_path_buf(),
        action: "write",
        source,
    };
    let mut file = AtomicFile::create(eeg)?;
    let temp = file.temp_path().to_path_buf();
    {
        let mut out = BufWriter::with_capacity(1 << 16, file.file());
        let data = raw.data();
        for column in data.columns() {
            for &v in column {
                out.write_all(&(v as f32).to_le_bytes())
                    .map_err(|e| io(&temp, e))?;
            }
        }
        out.flush().map_err(|e| io(&temp, e))?;
    }
    file.commit()
}

fn header_text(raw: &Raw, eeg_name: &str, vmrk_name: &str) -> String {
    let mut h = String::new();
    let mut line = |s: &str| {
        h.push_str(s);
        h.push('\n');
    };
    line("Brain Vision Data Exchange Header File Version 1.0");
    line(&format!(
        "; Written by oddball {} (IEEE_FLOAT_32 in µV, as pybv writes float data)",
        env!("CARGO_PKG_VERSION")
    ));
    line("");
    line("[Common Infos]");
    line("Codepage=UTF-8");
    line(&format!("DataFile={eeg_name}"));
    line(&format!("MarkerFile={vmrk_name}"));
    line("DataFormat=BINARY");
    line("; Data orientation: MULTIPLEXED=ch1,pt1, ch2,pt1 ...");
    line("DataOrientation=MULTIPLEXED");
    line(&format!("NumberOfChannels={}", raw.n_channels()));
    line(&format!("DataPoints={}", raw.n_times()));
    line("; Sampling interval in microseconds");
    line(&format!("SamplingInterval={}", 1e6 / raw.sfreq()));
    line("");
    line("[Binary Infos]");
    line("BinaryFormat=IEEE_FLOAT_32");
    line("");
    line("[Channel Infos]");
    line("; Each entry: Ch<Channel number>=<Name>,<Reference channel name>,");
    line("; <Resolution in \"Unit\">,<Unit>, Future extensions..");
    line("; Fields are delimited by commas, some fields might be omitted (empty).");
    line("; Commas in channel names are coded as \"\\1\".");
    for (i, name) in raw.ch_names().iter().enumerate() {
        line(&format!("Ch{}={},,1,µV", i + 1, name.replace(',', "\\1")));
    }
    h
}

fn marker_text(raw: &Raw, eeg_name: &str) -> String {
    let mut m = String::new();
    let mut line = |s: &str| {
        m.push_str(s);
        m.push('\n');
    };
    line("Brain Vision Data Exchange Marker File, Version 1.0");
    line(&format!(
        "; Written by oddball {}",
        env!("CARGO_PKG_VERSION")
    ));
    line("");
    line("[Common Infos]");
    line("Codepage=UTF-8");
    line(&format!("DataFile={eeg_name}"));
    line("");
    line("[Marker Infos]");
    line("; Each entry: Mk<Marker number>=<Type>,<Description>,<Position in data points>,");
    line(";             <Size in data points>, <Channel number (0 = marker is related to all channels)>");
    line("; Fields are delimited by commas, some fields might be omitted (empty).");
    line("; Commas in type or description text are coded as \"\\1\".");
    for (i, e) in raw.events().iter().enumerate() {
        let (kind, description) = marker_of_code(e.code);
        line(&format!(
            "Mk{}={kind},{description},{},1,0",
            i + 1,
            e.onset + 1
        ));
    }
    m
}
