//! BCI2000 `.dat` files, format versions 1.0 and 1.1, read from scratch; and written (v1.1,
//! float32) by [`write_bci2000`], see `write.rs`.
//!
//! There is no maintained Rust crate for BCI2000 files, and the format is small, so this reader
//! is written here (checked against the independent Python reader `shared/peer/bci2000.py` by the
//! golden test `tests/bci2000_golden.rs`).
//!
//! # Format
//! * An ASCII header of `HeaderLen` bytes, CRLF lines. First line, v1.0:
//!   `HeaderLen= N SourceCh= C StatevectorLen= S`; v1.1: `BCI2000V= 1.1 HeaderLen= N SourceCh= C
//!   StatevectorLen= S DataFormat= int16|int32|float32`. Without `DataFormat`, samples are int16.
//! * `[ State Vector Definition ]`: `Name Length DefaultValue ByteLocation BitLocation` per line.
//! * `[ Parameter Definition ]`: `Section Type Name= value ... // comment` (see [`params`]).
//! * The body: per sample, `C` little-endian samples of the data format, then `S` state-vector
//!   bytes. A state's value is the `Length`-bit little-endian unsigned integer starting at bit
//!   `ByteLocation*8 + BitLocation` of the state vector.
//!
//! # What the reader makes of it
//! * Samples in µV: `(raw − SourceChOffset[c]) × SourceChGain[c]`. A gain may carry a voltage
//!   unit (`0.033muV`, `1e-3mV`; see [`crate::units::microvolts_per`]); without one it is µV
//!   per A/D unit, BCI2000's convention. A list
//!   with one value applies to every channel; missing parameters mean gain 1 and offset 0.
//! * Channel names from `ChannelNames` when it names every channel; else `ch1..chN`, or, with
//!   [`Bci2000Options::standard_64_names`], [`STANDARD_64_CHANNELS`] for 64-channel files.
//! * Events where the `StimulusCode` state goes from 0 to non-zero (a non-zero first sample
//!   counts); `target` is `StimulusType != 0` at the onset (`None` without that state).
//! * A [`Speller`] when the file has `TargetDefinitions` (P3Speller files): the matrix size from
//!   `NumMatrixRows`/`NumMatrixColumns` (first menu), symbols from the `TargetDefinitions`
//!   display column, `TextToSpell`, and `NumberOfSequences × (rows + cols)` flashes per character.
//! * All parameters ([`Parameters`]) and all states ([`States`], decoded on request from the
//!   stored state-vector bytes).
//!
//! Every size in the header is checked against the file length before anything is allocated;
//! a body that is not a whole number of sample records is reported as truncated at the offset
//! of the incomplete record.

mod info;
pub mod params;
mod write;

use std::path::Path;

use ndarray::Array2;
use oddball_signal::Event;

pub use info::{Bci2000Header, Bci2000Info, DataFormat, StateDef, States};
pub use params::{ParamCell, ParamValue, Parameter, Parameters};
pub use write::{
    encode_value, stimulus_runs, stimulus_states, write_bci2000, write_bci2000_blocks,
    Bci2000WriteOptions, Bci2000WriteSummary, StateColumn, StateRun, StateRuns,
};

use crate::files::read_file;
use crate::speller::Speller;
use crate::units::{hz_factor, microvolts_per, split_number_unit};
use crate::{Details, Format, IoError, Recording};

/// The BCI2000 standard 64-channel order (the 10-10 subset of the Wadsworth cap), as in
/// `eeg64.loc` beside the sample files and in BCI Competition II data set IIb.
pub const STANDARD_64_CHANNELS: [&str; 64] = [
    "Fc5", "Fc3", "Fc1", "Fcz", "Fc2", "Fc4", "Fc6", "C5", "C3", "C1", "Cz", "C2", "C4", "C6",
    "Cp5", "Cp3", "Cp1", "Cpz", "Cp2", "Cp4", "Cp6", "Fp1", "Fpz", "Fp2", "Af7", "Af3", "Afz",
    "Af4", "Af8", "F7", "F5", "F3", "F1", "Fz", "F2", "F4", "F6", "F8", "Ft7", "Ft8", "T7", "T8",
    "T9", "T10", "Tp7", "Tp8", "P7", "P5", "P3", "P1", "Pz", "P2", "P4", "P6", "P8", "Po7", "Po3",
    "Poz", "Po4", "Po8", "O1", "Oz", "O2", "Iz",
];

/// Options of [`read_bci2000_with`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Bci2000Options {
    /// Name the channels of a 64-channel file without `ChannelNames` with
    /// [`STANDARD_64_CHANNELS`] instead of `ch1..ch64`. Off by default: the file itself does not
    /// say which cap was used.
    pub standard_64_names: bool,
}

/// Reads a BCI2000 `.dat` file (v1.0 or v1.1) with default options.
pub fn read_bci2000(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_bci2000_with(path, &Bci2000Options::default())
}

/// Reads a BCI2000 `.dat` file (v1.0 or v1.1).
pub fn read_bci2000_with(
    path: impl AsRef<Path>,
    options: &Bci2000Options,
) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_bci2000(&bytes, path, options)
}

struct Ctx<'a> {
    path: &'a Path,
    file_len: u64,
}

impl Ctx<'_> {
    fn invalid(
        &self,
        field: impl Into<String>,
        offset: u64,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> IoError {
        IoError::invalid_field(self.path, field, offset, expected, found)
    }

    fn truncated(&self, field: impl Into<String>, offset: u64, needed: u64) -> IoError {
        IoError::Truncated {
            path: self.path.to_path_buf(),
            field: field.into(),
            offset,
            needed,
            file_len: self.file_len,
        }
    }
}

fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

/// Parses the first header line into its header, given the line's text.
fn parse_first_line(ctx: &Ctx<'_>, line: &str) -> Result<Bci2000Header, IoError> {
    // Key/value pairs: `Key= value` (or `Key=value`), with the byte offset of each value.
    let mut pairs: Vec<(&str, &str, u64)> = Vec::new();
    let mut words = Vec::new();
    let mut pos = 0;
    for w in line.split_whitespace() {
        let at = pos + line[pos..].find(w).unwrap_or(0);
        words.push((w, at as u64));
        pos = at + w.len();
    }
    let mut i = 0;
    while i < words.len() {
        let (w, at) = words[i];
        match w.find('=') {
            Some(eq) if eq + 1 < w.len() => {
                pairs.push((&w[..eq], &w[eq + 1..], at + eq as u64 + 1));
                i += 1;
            }
            Some(eq) => {
                let (v, vat) = words
                    .get(i + 1)
                    .copied()
                    .unwrap_or(("", at + w.len() as u64));
                pairs.push((&w[..eq], v, vat));
                i += 2;
            }
            None => {
                return Err(ctx.invalid(
                    "first header line",
                    at,
                    "`Key= value` pairs (HeaderLen, SourceCh, StatevectorLen, ...)",
                    w,
                ))
            }
        }
    }
    let get = |key: &str| pairs.iter().find(|p| p.0 == key).copied();
    let count = |key: &str| -> Result<usize, IoError> {
        let (_, v, at) = get(key).ok_or_else(|| {
            ctx.invalid(
                key,
                0,
                format!("`{key}= <count>` on the first header line"),
                line.chars().take(120).collect::<String>(),
            )
        })?;
        v.parse::<usize>()
            .map_err(|_| ctx.invalid(key, at, "a non-negative integer", v))
    };
    let version = match get("BCI2000V") {
        None => "1.0".to_string(),
        Some((_, v, at)) => {
            if v != "1.0" && v != "1.1" {
                return Err(ctx.invalid("BCI2000V", at, "1.0 or 1.1", v));
            }
            v.to_string()
        }
    };
    let data_format = match get("DataFormat") {
        None => DataFormat::Int16,
        Some((_, "int16", _)) => DataFormat::Int16,
        Some((_, "int32", _)) => DataFormat::Int32,
        Some((_, "float32", _)) => DataFormat::Float32,
        Some((_, v, at)) => {
            return Err(ctx.invalid("DataFormat", at, "int16, int32 or float32", v))
        }
    };
    Ok(Bci2000Header {
        version,
        header_len: count("HeaderLen")?,
        source_ch: count("SourceCh")?,
        statevector_len: count("StatevectorLen")?,
        data_format,
    })
}

fn parse_state_line(
    ctx: &Ctx<'_>,
    line: &str,
    offset: u64,
    statevector_len: usize,
) -> Result<StateDef, IoError> {
    let f: Vec<&str> = line.split_whitespace().collect();
    let field = |what: &str| match f.first() {
        Some(name) => format!("state {name} {what}"),
        None => format!("state {what}"),
    };
    if f.len() < 5 {
        return Err(ctx.invalid(
            field("definition"),
            offset,
            "`Name Length DefaultValue ByteLocation BitLocation`",
            line,
        ));
    }
    let num = |k: usize, what: &str| -> Result<u64, IoError> {
        f[k].parse::<u64>()
            .map_err(|_| ctx.invalid(field(what), offset, "a non-negative integer", f[k]))
    };
    let length = num(1, "Length")?;
    let default = num(2, "DefaultValue")?;
    let byte_location = num(3, "ByteLocation")?;
    let bit_location = num(4, "BitLocation")?;
    if !(1..=64).contains(&length) {
        return Err(ctx.invalid(field("Length"), offset, "1 to 64 bits", f[1]));
    }
    if bit_location > 7 {
        return Err(ctx.invalid(field("BitLocation"), offset, "0 to 7", f[4]));
    }
    let end_bit = byte_location
        .checked_mul(8)
        .and_then(|b| b.checked_add(bit_location + length));
    match end_bit {
        Some(e) if e <= (statevector_len as u64).saturating_mul(8) => {}
        _ => {
            return Err(ctx.invalid(
                field("ByteLocation"),
                offset,
                format!("a state inside the {statevector_len}-byte state vector"),
                format!("byte {} bit {} length {}", f[3], f[4], f[1]),
            ))
        }
    }
    Ok(StateDef {
        name: f[0].to_string(),
        length: length as u32,
        default,
        byte_location: byte_location as usize,
        bit_location: bit_location as u32,
    })
}

/// The per-channel values of a numeric list parameter (`SourceChGain`, `SourceChOffset`):
/// one value for all channels, or at least `n` values of which the first `n` are used.
fn per_channel(
    ctx: &Ctx<'_>,
    params: &Parameters,
    name: &str,
    n: usize,
    default: f64,
    to_value: impl Fn(f64, &str) -> Option<f64>,
    expected: &str,
) -> Result<Vec<f64>, IoError> {
    let Some(p) = params.get(name) else {
        return Ok(vec![default; n]);
    };
    let items = p.values();
    if items.len() != 1 && items.len() < n {
        return Err(ctx.invalid(
            format!("parameter {name}"),
            p.offset,
            format!("1 or at least {n} values (one per channel)"),
            format!("{} values", items.len()),
        ));
    }
    let parsed = items
        .iter()
        .take(n)
        .enumerate()
        .map(|(i, s)| {
            split_number_unit(s)
                .and_then(|(v, unit)| to_value(v, unit))
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    ctx.invalid(format!("parameter {name}[{i}]"), p.offset, expected, *s)
                })
        })
        .collect::<Result<Vec<f64>, IoError>>()?;
    Ok(if parsed.len() == 1 {
        vec![parsed[0]; n]
    } else {
        parsed
    })
}

fn first_count(p: &Parameter) -> Option<usize> {
    let v = p.values().first().copied()?;
    let (x, unit) = split_number_unit(v)?;
    (unit.is_empty() && x >= 1.0 && x.fract() == 0.0 && x <= 1e6).then_some(x as usize)
}

/// The speller layout of a P3Speller file, `None` for files without `TargetDefinitions`.
fn speller_from(ctx: &Ctx<'_>, params: &Parameters) -> Result<Option<Speller>, IoError> {
    let Some(defs) = params.get("TargetDefinitions") else {
        return Ok(None);
    };
    let ParamValue::Matrix {
        rows, col_labels, ..
    } = &defs.value
    else {
        return Err(ctx.invalid(
            "parameter TargetDefinitions",
            defs.offset,
            "a matrix",
            defs.kind.clone(),
        ));
    };
    let display_col = col_labels
        .as_ref()
        .and_then(|l| l.iter().position(|s| s.eq_ignore_ascii_case("display")))
        .unwrap_or(0);
    let symbols: Vec<String> = rows
        .iter()
        .map(|r| {
            r.get(display_col)
                .and_then(|c| c.as_str())
                .unwrap_or("")
                .to_string()
        })
        .collect();
    let dim = |name: &str| -> Result<Option<usize>, IoError> {
        match params.get(name) {
            None => Ok(None),
            Some(p) => first_count(p).map(Some).ok_or_else(|| {
                ctx.invalid(
                    format!("parameter {name}"),
                    p.offset,
                    "a positive integer count",
                    p.values().first().copied().unwrap_or(""),
                )
            }),
        }
    };
    if symbols.is_empty() {
        return Err(ctx.invalid(
            "parameter TargetDefinitions",
            defs.offset,
            "at least one target",
            "0 targets",
        ));
    }
    let (n_rows, n_cols) = match (dim("NumMatrixRows")?, dim("NumMatrixColumns")?) {
        (Some(r), Some(c)) => (r, c),
        (r, c) => {
            let side = (symbols.len() as f64).sqrt().round() as usize;
            match (r, c) {
                (Some(r), None) if r > 0 && symbols.len() % r == 0 => (r, symbols.len() / r),
                (None, Some(c)) if c > 0 && symbols.len() % c == 0 => (symbols.len() / c, c),
                (None, None) if side * side == symbols.len() && side > 0 => (side, side),
                _ => {
                    return Err(ctx.invalid(
                        "parameter TargetDefinitions",
                        defs.offset,
                        "NumMatrixRows/NumMatrixColumns, or a square number of targets",
                        format!("{} targets", symbols.len()),
                    ))
                }
            }
        }
    };
    if n_rows.checked_mul(n_cols).is_none_or(|n| n > symbols.len()) {
        return Err(ctx.invalid(
            "parameter TargetDefinitions",
            defs.offset,
            format!("at least NumMatrixRows × NumMatrixColumns = {n_rows} × {n_cols} targets"),
            format!("{} targets", symbols.len()),
        ));
    }
    let matrix: Vec<Vec<String>> = symbols[..n_rows * n_cols]
        .chunks(n_cols)
        .map(|r| r.to_vec())
        .collect();
    let text_to_spell = params
        .get("TextToSpell")
        .and_then(|p| p.as_str())
        .filter(|s| !s.is_empty())
        .map(str::to_string);
    let flashes = match params.get("NumberOfSequences") {
        None => None,
        Some(p) => Some(
            first_count(p).ok_or_else(|| {
                ctx.invalid(
                    "parameter NumberOfSequences",
                    p.offset,
                    "a positive integer",
                    p.as_str().unwrap_or(""),
                )
            })? * (n_rows + n_cols),
        ),
    };
    Ok(Speller::new(matrix, text_to_spell, flashes))
}

/// Parses the bytes of a BCI2000 `.dat` file; `path` is used in error messages and the result.
pub fn parse_bci2000(
    bytes: &[u8],
    path: &Path,
    options: &Bci2000Options,
) -> Result<Recording, IoError> {
    let ctx = Ctx {
        path,
        file_len: bytes.len() as u64,
    };
    // First line.
    let starts_ok = bytes.starts_with(b"HeaderLen=") || bytes.starts_with(b"BCI2000V=");
    if !starts_ok {
        return Err(ctx.invalid(
            "first header line",
            0,
            "a BCI2000 header starting with `HeaderLen=` or `BCI2000V=`",
            latin1(&bytes[..bytes.len().min(40)]),
        ));
    }
    let Some(eol) = bytes.iter().take(4096).position(|&b| b == b'\n') else {
        return Err(if bytes.len() < 4096 {
            ctx.truncated("first header line (no line end)", 0, bytes.len() as u64 + 1)
        } else {
            ctx.invalid(
                "first header line",
                0,
                "a line end within 4096 bytes",
                "none",
            )
        });
    };
    let first = latin1(&bytes[..eol]);
    let header = parse_first_line(&ctx, first.trim_end_matches('\r'))?;
    if header.header_len as u64 > ctx.file_len {
        return Err(ctx.truncated(
            format!("header (HeaderLen= {})", header.header_len),
            0,
            header.header_len as u64,
        ));
    }
    if header.header_len <= eol {
        return Err(ctx.invalid(
            "HeaderLen",
            0,
            format!("more than the {} bytes of the first line", eol + 1),
            header.header_len.to_string(),
        ));
    }

    // Header sections, line by line (offsets are byte offsets in the file).
    let head = &bytes[..header.header_len];
    let mut state_defs: Vec<StateDef> = Vec::new();
    let mut parameters = Parameters::default();
    #[derive(PartialEq)]
    enum Section {
        None,
        States,
        Params,
        Other,
    }
    let mut section = Section::None;
    let mut pos = eol + 1;
    while pos < head.len() {
        let end = head[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(head.len(), |i| pos + i);
        let line = latin1(&head[pos..end]);
        let offset = pos as u64;
        pos = end + 1;
        let s = line.trim();
        if s.is_empty() {
            continue;
        }
        if s.starts_with('[') && s.ends_with(']') {
            let name = s.trim_matches(|c: char| c == '[' || c == ']' || c.is_whitespace());
            section = if name.eq_ignore_ascii_case("State Vector Definition") {
                Section::States
            } else if name.eq_ignore_ascii_case("Parameter Definition") {
                Section::Params
            } else {
                Section::Other
            };
            continue;
        }
        match section {
            Section::States => {
                state_defs.push(parse_state_line(&ctx, s, offset, header.statevector_len)?)
            }
            Section::Params => {
                let p = params::parse_parameter_line(s, offset).map_err(|e| {
                    ctx.invalid(
                        match e.name {
                            Some(n) => format!("parameter {n}"),
                            None => "parameter line".to_string(),
                        },
                        offset,
                        e.expected,
                        e.found,
                    )
                })?;
                parameters.push(p);
            }
            Section::None => {
                return Err(ctx.invalid(
                    "header section",
                    offset,
                    "`[ State Vector Definition ]` or `[ Parameter Definition ]`",
                    s.chars().take(80).collect::<String>(),
                ))
            }
            Section::Other => {}
        }
    }

    // Body layout, checked against the file length before allocating.
    let bps = header.data_format.bytes();
    let record_len = header
        .source_ch
        .checked_mul(bps)
        .and_then(|n| n.checked_add(header.statevector_len))
        .ok_or_else(|| {
            ctx.invalid(
                "SourceCh",
                0,
                "a channel count whose sample record size fits in 64 bits",
                header.source_ch.to_string(),
            )
        })?;
    if header.source_ch == 0 {
        return Err(ctx.invalid("SourceCh", 0, "at least 1 channel", "0"));
    }
    let body_start = header.header_len;
    let body_len = bytes.len() - body_start;
    let record_desc = |i: usize| {
        format!(
            "sample record {i} ({} channels × {bps} bytes + {} state bytes = {record_len} bytes)",
            header.source_ch, header.statevector_len
        )
    };
    if body_len == 0 {
        return Err(ctx.truncated(
            record_desc(0),
            body_start as u64,
            body_start as u64 + record_len as u64,
        ));
    }
    let n_times = body_len / record_len;
    if body_len % record_len != 0 {
        let at = body_start + n_times * record_len;
        return Err(ctx.truncated(record_desc(n_times), at as u64, (at + record_len) as u64));
    }

    // Scaling and rate.
    let nch = header.source_ch;
    let gains = per_channel(
        &ctx,
        &parameters,
        "SourceChGain",
        nch,
        1.0,
        |v, unit| {
            if unit.is_empty() {
                Some(v)
            } else {
                microvolts_per(unit).map(|f| v * f)
            }
        },
        "a number, optionally with a voltage unit (muV, uV, mV, V)",
    )?;
    let offsets = per_channel(
        &ctx,
        &parameters,
        "SourceChOffset",
        nch,
        0.0,
        |v, unit| unit.is_empty().then_some(v),
        "a number (A/D units)",
    )?;
    let sfreq = {
        let p = parameters
            .get("SamplingRate")
            .ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "parameter",
                name: "SamplingRate".into(),
                available: parameters.names().iter().map(|s| s.to_string()).collect(),
            })?;
        let v = p.as_str().unwrap_or("");
        split_number_unit(v)
            .and_then(|(x, unit)| hz_factor(unit).map(|f| x * f))
            .filter(|f| oddball_signal::check_sfreq(*f).is_ok())
            .ok_or_else(|| {
                ctx.invalid(
                    "parameter SamplingRate",
                    p.offset,
                    "a rate in Hz within oddball_signal::check_sfreq's 0.1 Hz to 1 MHz",
                    v,
                )
            })?
    };

    // Samples.
    let mut data = vec![0.0f64; nch * n_times];
    let mut sv = vec![0u8; header.statevector_len * n_times];
    let body = &bytes[body_start..];
    for (t, rec) in body.chunks_exact(record_len).enumerate() {
        let (samples, states) = rec.split_at(nch * bps);
        match header.data_format {
            DataFormat::Int16 => {
                for (c, b) in samples.chunks_exact(2).enumerate() {
                    let raw = i16::from_le_bytes([b[0], b[1]]) as f64;
                    data[c * n_times + t] = (raw - offsets[c]) * gains[c];
                }
            }
            DataFormat::Int32 => {
                for (c, b) in samples.chunks_exact(4).enumerate() {
                    let raw = i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
                    data[c * n_times + t] = (raw - offsets[c]) * gains[c];
                }
            }
            DataFormat::Float32 => {
                for (c, b) in samples.chunks_exact(4).enumerate() {
                    let raw = f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
                    data[c * n_times + t] = (raw - offsets[c]) * gains[c];
                }
            }
        }
        sv[t * header.statevector_len..(t + 1) * header.statevector_len].copy_from_slice(states);
    }
    let data = Array2::from_shape_vec((nch, n_times), data).map_err(|e| {
        ctx.invalid(
            "data body",
            body_start as u64,
            "a rectangular array",
            e.to_string(),
        )
    })?;
    let states = States {
        defs: state_defs,
        record_len: header.statevector_len,
        n_samples: n_times,
        bytes: sv,
    };

    // Channel names.
    let ch_names: Vec<String> = match parameters.get("ChannelNames").and_then(|p| p.list_items()) {
        Some(names) if names.len() == nch && names.iter().all(|n| !n.is_empty()) => {
            names.iter().map(|s| s.to_string()).collect()
        }
        _ if nch == 64 && options.standard_64_names => {
            STANDARD_64_CHANNELS.iter().map(|s| s.to_string()).collect()
        }
        _ => (1..=nch).map(|i| format!("ch{i}")).collect(),
    };

    // Events.
    let mut events = Vec::new();
    if let Some(code_def) = states.def("StimulusCode") {
        let type_def = states.def("StimulusType");
        let mut prev = 0u64;
        for t in 0..n_times {
            let code = states.decode_at(code_def, t);
            if code != 0 && prev == 0 {
                let code32 = u32::try_from(code).map_err(|_| {
                    ctx.invalid(
                        "state StimulusCode",
                        (body_start + t * record_len + nch * bps) as u64,
                        "a stimulus code below 2^32",
                        code.to_string(),
                    )
                })?;
                let mut e = Event::new(t, code32);
                if let Some(td) = type_def {
                    e = e.with_target(states.decode_at(td, t) != 0);
                }
                events.push(e);
            }
            prev = code;
        }
    }

    let speller = speller_from(&ctx, &parameters)?;
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    Ok(Recording {
        raw,
        format: Format::Bci2000,
        path: path.to_path_buf(),
        speller,
        details: Details::Bci2000(Box::new(Bci2000Info {
            header,
            parameters,
            states,
            gains,
            offsets,
        })),
    })
}
