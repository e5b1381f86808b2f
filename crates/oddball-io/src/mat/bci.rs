//! The BCI Competition layout of a MAT file as a [`Recording`]: BCI Competition II data set IIb
//! and BCI Competition III data set II (Wadsworth's P300 speller, recorded with BCI2000).
//!
//! # Layout
//! * `signal`: `n_times × n_channels` samples (any numeric class and stored type). Channel names
//!   are BCI2000's standard 64-channel order ([`STANDARD_64_CHANNELS`], as in `eeg64.loc`) for
//!   64 channels, else `ch1..chN`, unless [`MatOptions::ch_names`] says otherwise.
//! * One value per sample for each BCI2000 state, e.g. `StimulusCode`, `Flashing`,
//!   `StimulusType`, `PhaseInSequence`, `trialnr`; all kept in [`MatInfo::states`].
//! * The competition files do **not** store the sampling rate. The competitions' rate is 240 Hz,
//!   which is this reader's default ([`BCI_COMPETITION_SFREQ`]); a file with a real scalar
//!   variable named one of [`SFREQ_VARIABLES`] (`sfreq`, `fs`, `srate`, `SamplingRate`) gives its
//!   own, and [`MatOptions::sfreq`] overrides both; [`MatInfo::sfreq_given`] records whether the
//!   rate came from the file or the options.
//! * The files store raw amplifier units and no gain; the samples are passed on unscaled (the
//!   [`Recording`]'s "µV" are these units here; [`MatInfo::units`] says so).
//!
//! * BCI Competition III data set II's files, one block per character (`Signal`
//!   `n_characters × n_times × n_channels`, states `n_characters × n_times`, `TargetChar`), are
//!   read as the blocks one after the other (`competition3.rs`); the flashes per character and,
//!   for training files, the spelled text come from the blocks and `TargetChar`.
//!
//! # Events and the speller
//! * An event where `Flashing` goes 0 → 1 (a first sample of 1 counts); its code is
//!   `StimulusCode` there (must be a whole number ≥ 1), its target flag `StimulusType != 0` there
//!   when the file has `StimulusType` (training runs), else `None` (test runs).
//!   Without `Flashing`, events are where `StimulusCode` goes 0 → non-zero (BCI2000's rule);
//!   without either, the recording has no events and no speller.
//! * The speller, when the flashes' codes are exactly 1–12 (other files, e.g. an oddball with
//!   codes 1 and 2, are not spellers): the 6 × 6 matrix `ABCDEF / GHIJKL / MNOPQR / STUVWX / YZ1234 / 56789_`
//!   (`_` = space) with codes 1–6 for the columns and 7–12 for the rows
//!   ([`CodeOrder::ColumnsFirst`], the opposite of BCI2000's P3Speller files). Flashes per
//!   character from [`MatOptions::flashes_per_character`], else from the pauses between
//!   characters (a gap over three times the median gap between onsets ends a character) when
//!   every character has the same number of flashes. `text_to_spell` is
//!   [`MatOptions::text_to_spell`] (the only way to know it for a test run without labels).

use std::collections::BTreeMap;
use std::path::Path;

use ndarray::Array2;
use oddball_signal::Event;

use super::competition3::PerCharacter;
use super::file::{MatArray, MatFile, MatValue, MatVariable};
pub use super::info::{MatInfo, MatVarSummary};
use super::parse::parse_mat_file;
use crate::bci2000::STANDARD_64_CHANNELS;
use crate::files::read_file;
use crate::speller::{CodeOrder, Speller};
use crate::{Details, Format, IoError, Recording};

/// The sampling rate of BCI Competition II data set IIb and III data set II, Hz (the files do
/// not store it).
pub const BCI_COMPETITION_SFREQ: f64 = 240.0;

/// Scalar variables that give a file's sampling rate (Hz), looked for in this order.
pub const SFREQ_VARIABLES: [&str; 4] = ["sfreq", "fs", "srate", "SamplingRate"];

/// The speller matrix of the BCI Competitions' P300 data sets, `_` for space.
pub const BCI_COMPETITION_MATRIX: [&str; 6] =
    ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"];

/// What the units of the samples are, for [`MatInfo::units`].
pub const RAW_UNITS: &str =
    "raw amplifier units as stored (the file gives no gain to µV); not scaled";

/// Options of [`read_mat_with`].
#[derive(Debug, Clone, PartialEq)]
pub struct MatOptions {
    /// The sampling rate, Hz; `None` means [`BCI_COMPETITION_SFREQ`].
    pub sfreq: Option<f64>,
    /// The variable holding the samples, `n_times × n_channels`.
    pub signal: String,
    /// The variable holding each sample's stimulus code (0 = none), `StimulusCode` by default.
    pub code: String,
    /// Channel names (one per column of the signal); `None`: see the module documentation.
    pub ch_names: Option<Vec<String>>,
    /// The text the user spelled (for runs without `StimulusType`).
    pub text_to_spell: Option<String>,
    /// Flashes per character; `None`: found from the pauses between characters.
    pub flashes_per_character: Option<usize>,
}

impl Default for MatOptions {
    fn default() -> Self {
        Self {
            sfreq: None,
            signal: "signal".into(),
            code: "StimulusCode".into(),
            ch_names: None,
            text_to_spell: None,
            flashes_per_character: None,
        }
    }
}

/// Reads a MAT file in the BCI Competition layout with default options.
pub fn read_mat(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_mat_with(path, &MatOptions::default())
}

/// Reads a MAT file in the BCI Competition layout.
pub fn read_mat_with(path: impl AsRef<Path>, options: &MatOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    parse_mat(&read_file(path)?, path, options)
}

/// Parses the bytes of a MAT file in the BCI Competition layout; `path` names it in errors.
pub fn parse_mat(bytes: &[u8], path: &Path, options: &MatOptions) -> Result<Recording, IoError> {
    let mut file = parse_mat_file(bytes, path)?;
    let per_char = super::competition3::flatten(&mut file, &options.signal, path)?;
    recording(file, path, options, per_char)
}

fn kind(a: &MatArray) -> String {
    match &a.value {
        MatValue::Numeric { class, real, imag } => format!(
            "{}{class:?} stored as {:?}",
            if imag.is_some() { "complex " } else { "" },
            real.stored_type()
        ),
        MatValue::Char(_) => "char".into(),
        MatValue::Cell(_) => "cell".into(),
        MatValue::Struct { .. } => "struct".into(),
        MatValue::Unsupported { class } => format!("unsupported class {class}"),
    }
}

fn invalid(path: &Path, v: &MatVariable, field: &str, expected: &str, found: String) -> IoError {
    let found = crate::error::bounded(&found);
    IoError::InvalidField {
        path: path.to_path_buf(),
        field: format!("variable {:?}: {field}", v.name),
        offset: v.offset,
        expected: expected.into(),
        found,
    }
}

fn recording(
    file: MatFile,
    path: &Path,
    options: &MatOptions,
    per_char: Option<PerCharacter>,
) -> Result<Recording, IoError> {
    let Some(sig) = file.get(&options.signal) else {
        return Err(IoError::Missing {
            path: path.to_path_buf(),
            what: "MAT variable (the samples, n_times × n_channels)",
            name: options.signal.clone(),
            available: file.names(),
        });
    };
    let (n_times, n_channels) = match sig.array.dims.as_slice() {
        [t, c] => (*t, *c),
        d => {
            return Err(invalid(
                path,
                sig,
                "dimensions",
                "n_times × n_channels",
                format!("{d:?}"),
            ))
        }
    };
    let real = match &sig.array.value {
        MatValue::Numeric {
            real, imag: None, ..
        } => real,
        _ => {
            return Err(invalid(
                path,
                sig,
                "type",
                "a real numeric array",
                kind(&sig.array),
            ))
        }
    };
    // Column-major n_times × n_channels is channel after channel: row-major (n_channels, n_times).
    let data = Array2::from_shape_vec((n_channels, n_times), real.to_f64()).map_err(|e| {
        invalid(
            path,
            sig,
            "values",
            "n_times × n_channels values",
            e.to_string(),
        )
    })?;
    let ch_names = match &options.ch_names {
        Some(names) => names.clone(),
        None if n_channels == STANDARD_64_CHANNELS.len() => {
            STANDARD_64_CHANNELS.iter().map(|s| s.to_string()).collect()
        }
        None => (1..=n_channels).map(|i| format!("ch{i}")).collect(),
    };

    let mut states = BTreeMap::new();
    let mut strings = BTreeMap::new();
    for v in &file.variables {
        match &v.array.value {
            MatValue::Numeric {
                real, imag: None, ..
            } if v.name != options.signal && real.len() == n_times => {
                states.insert(v.name.clone(), real.to_f64());
            }
            MatValue::Char(_) => {
                let rows = v.array.char_rows().unwrap_or_default();
                strings.insert(v.name.clone(), rows.join("\n"));
            }
            _ => {}
        }
    }
    let state_var = |name: &str| -> Result<Option<(&MatVariable, &Vec<f64>)>, IoError> {
        let Some(v) = file.get(name) else {
            return Ok(None);
        };
        match states.get(name) {
            Some(values) => Ok(Some((v, values))),
            None => Err(invalid(
                path,
                v,
                "values",
                &format!(
                    "{n_times} real numbers, one per sample of {:?}",
                    options.signal
                ),
                format!("{} with dimensions {:?}", kind(&v.array), v.array.dims),
            )),
        }
    };
    let code = state_var(&options.code)?;
    let flashing = state_var("Flashing")?;
    let stype = state_var("StimulusType")?;

    let mut events = Vec::new();
    let onset_var = flashing.or(code);
    if let Some((ov, on)) = onset_var {
        let Some((cv, codes)) = code else {
            return Err(IoError::Missing {
                path: path.to_path_buf(),
                what: "MAT variable (the code of each flash)",
                name: options.code.clone(),
                available: file.names(),
            });
        };
        for t in 0..n_times {
            if on[t] == 0.0 || (t > 0 && on[t - 1] != 0.0) {
                continue;
            }
            let c = codes[t];
            if !(c >= 1.0 && c <= f64::from(u32::MAX) && c.fract() == 0.0) {
                return Err(invalid(
                    path,
                    cv,
                    &format!("value at sample {t} (where {:?} turns on)", ov.name),
                    "a whole stimulus code ≥ 1",
                    format!("{c}"),
                ));
            }
            let mut e = Event::new(t, c as u32);
            if let Some((_, ty)) = stype {
                e = e.with_target(ty[t] != 0.0);
            }
            events.push(e);
        }
    }

    let codes_present: std::collections::BTreeSet<u32> = events.iter().map(|e| e.code).collect();
    let speller = if code.is_some() && codes_present.iter().copied().eq(1..=12) {
        let mut sp = Speller::from_rows(&BCI_COMPETITION_MATRIX);
        if let Some(sp) = sp.as_mut() {
            sp.code_order = CodeOrder::ColumnsFirst;
            let (blocks, target_chars) = per_char
                .map(|p| (p.flashes_per_character, p.text))
                .unwrap_or_default();
            sp.text_to_spell = options.text_to_spell.clone().or(target_chars);
            sp.flashes_per_character = options
                .flashes_per_character
                .or(blocks)
                .or_else(|| flashes_per_character(&events));
        }
        sp
    } else {
        None
    };

    let file_sfreq = SFREQ_VARIABLES.iter().find_map(|name| {
        let v = file.get(name)?;
        match &v.array.value {
            MatValue::Numeric {
                real, imag: None, ..
            } if real.len() == 1 => Some((v.name.clone(), v.offset, real.to_f64()[0])),
            _ => None,
        }
    });
    if let Some((name, offset, f)) = &file_sfreq {
        if options.sfreq.is_none() && !(f.is_finite() && *f > 0.0) {
            return Err(IoError::InvalidField {
                path: path.to_path_buf(),
                field: format!("variable {name:?}: value"),
                offset: *offset,
                expected: "a sampling rate in Hz (finite, > 0)".into(),
                found: format!("{f}"),
            });
        }
    }
    let sfreq = options
        .sfreq
        .or(file_sfreq.as_ref().map(|(_, _, f)| *f))
        .unwrap_or(BCI_COMPETITION_SFREQ);
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    let variables = file
        .variables
        .iter()
        .map(|v| MatVarSummary {
            name: v.name.clone(),
            dims: v.array.dims.clone(),
            kind: kind(&v.array),
            offset: v.offset,
            compressed: v.compressed,
        })
        .collect();
    Ok(Recording {
        raw,
        format: Format::Mat,
        path: path.to_path_buf(),
        speller,
        details: Details::Mat(Box::new(MatInfo {
            header: file.header,
            variables,
            states,
            strings,
            sfreq_given: options.sfreq.is_some() || file_sfreq.is_some(),
            units: RAW_UNITS,
        })),
    })
}

/// The number of flashes of every character, when all characters have the same: characters are
/// separated by gaps between onsets of more than three times the median gap.
fn flashes_per_character(events: &[Event]) -> Option<usize> {
    if events.len() < 2 {
        return None;
    }
    let mut gaps: Vec<usize> = events.windows(2).map(|w| w[1].onset - w[0].onset).collect();
    let mut sorted = gaps.clone();
    sorted.sort_unstable();
    let median = sorted[sorted.len() / 2];
    let mut sizes = Vec::new();
    let mut n = 1;
    for g in gaps.drain(..) {
        if g > 3 * median {
            sizes.push(n);
            n = 1;
        } else {
            n += 1;
        }
    }
    sizes.push(n);
    sizes.iter().all(|&s| s == sizes[0]).then_some(sizes[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flashes_per_character_from_pauses() {
        let mut ev = Vec::new();
        let mut t = 100;
        for _ in 0..3 {
            for i in 0..24 {
                ev.push(Event::new(t, (i % 12) + 1));
                t += 42;
            }
            t += 1254;
        }
        assert_eq!(flashes_per_character(&ev), Some(24));
        ev.pop();
        assert_eq!(flashes_per_character(&ev), None);
        assert_eq!(flashes_per_character(&ev[..1]), None);
    }
}
