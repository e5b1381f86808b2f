//! The BCI2000 `.dat` writer: format v1.1 with float32 samples in µV.
//!
//! No maintained Rust crate writes (or reads) BCI2000 files, and the format is small, so the
//! writer lives here beside the reader; `tests/bci2000_writer.rs` reads its files back with
//! [`crate::read`], and `tools/golden/io/check_written_bci2000.py` with the independent Python
//! reader `shared/peer/bci2000.py`.
//!
//! # What is written
//! * First line `BCI2000V= 1.1 HeaderLen= N SourceCh= C StatevectorLen= S DataFormat= float32`;
//!   every header line ends with CRLF and an empty CRLF line ends the header, as BCI2000 does.
//!   `HeaderLen` counts the whole header, itself included.
//! * `[ State Vector Definition ]`: one `Name Length Value ByteLocation BitLocation` line per
//!   state, packed bit by bit in the order given. BCI2000 always records the system state
//!   `Running`; when the caller gives none, a 1-bit `Running` that is 1 on every sample comes
//!   first. `Value` is the state's value at the first sample (the file format says the header
//!   value matches the first sample).
//! * `[ Parameter Definition ]`: `SourceCh`, `SampleBlockSize`, `SamplingRate` (`<rate>Hz`),
//!   `ChannelNames`, `SourceChOffset` (all 0) and `SourceChGain` (all 1, i.e. µV per unit, so a
//!   stored float32 *is* the µV value) in section `Source:Signal%20Properties:DataIOFilter`,
//!   `StateVectorLength` in `System:State%20Vector`, then the caller's
//!   [`Bci2000WriteOptions::extra_parameters`].
//! * The body: per sample, `C` little-endian float32 samples, then the `S` state-vector bytes.
//!
//! Values are URL-encoded as BCI2000 does ([`encode_value`]): a space is `%20`, an empty value
//! is a lone `%`. The file is written to a temporary file in the same directory and renamed
//! into place, so a failed write never leaves a partial file under the final name.

use std::collections::HashMap;
use std::io::{BufWriter, Write};
use std::path::Path;

use oddball_signal::{Events, Raw};

use super::params::parse_parameter_line;
use crate::error::StateProblem;
use crate::samples::{for_each_block, SampleBlocks};
use crate::writing::{check_writable_blocks, read_error, TempFile};
use crate::IoError;

/// One state (a BCI2000 state-vector variable): one value per sample.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateColumn {
    /// Printable ASCII without whitespace, e.g. `StimulusCode`.
    pub name: String,
    /// Width in bits, 1..=32.
    pub bits: u32,
    /// One value per sample, each below `2^bits`.
    pub values: Vec<u64>,
}

impl StateColumn {
    pub fn new(name: impl Into<String>, bits: u32, values: Vec<u64>) -> Self {
        Self {
            name: name.into(),
            bits,
            values,
        }
    }
}

/// Options of [`write_bci2000`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Bci2000WriteOptions {
    /// Whole BCI2000 parameter lines (`Section Type Name= value ... // comment`, values
    /// URL-encoded, see [`encode_value`]), written after the writer's own parameters, e.g.
    /// `Application:Oddball string Paradigm= four-bulb // stimulus layout`. A
    /// `SampleBlockSize` line replaces the writer's; the other parameters the writer writes
    /// (`SourceCh`, `SamplingRate`, `ChannelNames`, `SourceChOffset`, `SourceChGain`,
    /// `StateVectorLength`) cannot be given here.
    pub extra_parameters: Vec<String>,
}

/// What [`write_bci2000`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Bci2000WriteSummary {
    pub n_samples: usize,
    pub n_channels: usize,
    /// File size in bytes.
    pub bytes: u64,
    /// The largest `|f32(x) − x|` over all samples, in µV.
    pub max_rounding_uv: f64,
}

/// The parameters the writer defines itself; only `SampleBlockSize` may be replaced.
const OWN_PARAMETERS: [&str; 7] = [
    "SourceCh",
    "SampleBlockSize",
    "SamplingRate",
    "ChannelNames",
    "SourceChOffset",
    "SourceChGain",
    "StateVectorLength",
];

/// URL-encodes one parameter value the way BCI2000 does: the empty string becomes `%`;
/// whitespace, control and non-ASCII bytes, `%`, `{` and `}` become `%xx` (UTF-8 bytes). `/` is
/// encoded too, so a value can never start a `//` comment for a reader that looks for `//`
/// anywhere on the line.
pub fn encode_value(s: &str) -> String {
    if s.is_empty() {
        return "%".to_string();
    }
    let mut out = String::with_capacity(s.len());
    for &b in s.as_bytes() {
        if b.is_ascii_graphic() && !matches!(b, b'%' | b'{' | b'}' | b'/') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02x}"));
        }
    }
    out
}

/// One run of a state given by runs ([`StateRuns`]): `value` over the samples `[start, end)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateRun {
    pub start: usize,
    pub end: usize,
    pub value: u64,
}

/// One state given by its runs, 0 on every sample outside them: what a long recording's
/// states cost grows with its events, not its samples ([`write_bci2000_blocks`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateRuns {
    /// Printable ASCII without whitespace, e.g. `TrialNumber`.
    pub name: String,
    /// Width in bits, 1..=32.
    pub bits: u32,
    /// Non-empty, in order, not overlapping, within the recording.
    pub runs: Vec<StateRun>,
}

impl StateRuns {
    pub fn new(name: impl Into<String>, bits: u32, runs: Vec<StateRun>) -> Self {
        Self {
            name: name.into(),
            bits,
            runs,
        }
    }

    /// The state as one value per sample, for `n_times` samples.
    pub fn to_column(&self, n_times: usize) -> StateColumn {
        let mut values = vec![0u64; n_times];
        for r in &self.runs {
            for v in &mut values[r.start.min(n_times)..r.end.min(n_times)] {
                *v = r.value;
            }
        }
        StateColumn::new(self.name.clone(), self.bits, values)
    }
}

/// `StimulusCode` and `StimulusType` columns for `n_times` samples from `events`
/// ([`stimulus_runs`], one value per sample).
pub fn stimulus_states(events: &Events, n_times: usize, duration: usize) -> Vec<StateColumn> {
    stimulus_runs(events.as_slice(), n_times, duration)
        .iter()
        .map(|r| r.to_column(n_times))
        .collect()
}

/// `StimulusCode` and `StimulusType` as runs for `n_times` samples from `events` (in order of
/// onset).
///
/// Each event's code is held for `duration` samples (at least 1) from its onset, clipped at the
/// end of the recording and one sample before the next later onset, so that `StimulusCode`
/// returns to 0 between events and the reader (which finds events where `StimulusCode` goes
/// from 0 to non-zero) gets every event back; events one sample apart cannot be told apart in
/// a BCI2000 file and merge. `StimulusType` is 1 over the same samples for events whose
/// `target` is `Some(true)` (the reader reports every event of a file with `StimulusType` as
/// `Some(true)` or `Some(false)`). Events at or after `n_times` are left out; of events at the
/// same sample the later one wins; an event with code 0 marks nothing. `StimulusCode` has 8
/// bits, or as many as the largest code needs.
pub fn stimulus_runs(
    events: &[oddball_signal::Event],
    n_times: usize,
    duration: usize,
) -> Vec<StateRuns> {
    let mut ev: Vec<_> = events.iter().filter(|e| e.onset < n_times).collect();
    ev.sort_by_key(|e| e.onset);
    let duration = duration.max(1);
    let mut code: Vec<StateRun> = Vec::new();
    let mut kind: Vec<StateRun> = Vec::new();
    let mut i = 0;
    while i < ev.len() {
        // Of events at one sample, the later one wins.
        let mut j = i;
        while j + 1 < ev.len() && ev[j + 1].onset == ev[i].onset {
            j += 1;
        }
        let e = ev[j];
        let mut end = e.onset.saturating_add(duration).min(n_times);
        if let Some(next) = ev.get(j + 1).map(|f| f.onset) {
            end = end.min(next - 1).max(e.onset + 1);
        }
        if e.code != 0 {
            code.push(StateRun {
                start: e.onset,
                end,
                value: u64::from(e.code),
            });
        }
        if e.target == Some(true) {
            kind.push(StateRun {
                start: e.onset,
                end,
                value: 1,
            });
        }
        i = j + 1;
    }
    let max_code = ev.iter().map(|e| e.code).max().unwrap_or(0);
    let bits = (u32::BITS - max_code.leading_zeros()).max(8);
    vec![
        StateRuns::new("StimulusCode", bits, code),
        StateRuns::new("StimulusType", 1, kind),
    ]
}

/// A state's values, one per sample or by runs.
#[derive(Clone, Copy)]
enum Values<'a> {
    Dense(&'a [u64]),
    Runs(&'a [StateRun]),
    /// `Running`, added when the caller gives none.
    One,
}

/// A state's place in the state vector.
struct Placed<'a> {
    name: &'a str,
    bits: u32,
    values: Values<'a>,
    /// Bit offset from the start of the state vector.
    first_bit: usize,
    /// The run a [`Values::Runs`] state is at, samples being visited in order.
    cursor: usize,
}

impl Placed<'_> {
    /// The value at sample `t`; `t` never decreases between calls.
    fn value_at(&mut self, t: usize) -> u64 {
        match self.values {
            Values::Dense(v) => v[t],
            Values::One => 1,
            Values::Runs(runs) => {
                while self.cursor < runs.len() && runs[self.cursor].end <= t {
                    self.cursor += 1;
                }
                match runs.get(self.cursor) {
                    Some(r) if r.start <= t => r.value,
                    _ => 0,
                }
            }
        }
    }
}

/// Writes `raw` and `states` as a BCI2000 v1.1 `.dat` file with float32 samples in µV (see the
/// module documentation for the layout).
///
/// The events of `raw` are not written by themselves: pass them as states, usually
/// [`stimulus_states`] plus the caller's own. Refused with an [`IoError`] before anything is
/// written: an empty recording; an empty channel name (channel
/// names are otherwise URL-encoded, spaces included); a sample that is not finite or beyond
/// float32 ([`IoError::UnwritableSample`]); a state whose length is not `n_times`, whose value
/// does not fit its bits, whose bits are outside 1..=32, whose name is not printable ASCII
/// without whitespace, or that is given twice ([`IoError::InvalidState`]); an extra parameter
/// line the reader cannot parse or that repeats a parameter ([`IoError::InvalidParameterLine`]).
pub fn write_bci2000(
    path: impl AsRef<Path>,
    raw: &Raw,
    states: &[StateColumn],
    options: &Bci2000WriteOptions,
) -> Result<Bci2000WriteSummary, IoError> {
    let path = path.as_ref();
    let n_times = raw.n_times();
    for s in states {
        if s.values.len() != n_times {
            return Err(IoError::InvalidState {
                path: path.to_path_buf(),
                state: s.name.clone(),
                problem: StateProblem::Length {
                    len: s.values.len(),
                    n_times,
                },
            });
        }
    }
    let states: Vec<_> = states
        .iter()
        .map(|s| (s.name.as_str(), s.bits, Values::Dense(&s.values)))
        .collect();
    write_core(
        path,
        &raw.data().view(),
        raw.sfreq(),
        raw.ch_names(),
        states,
        options,
    )
}

/// [`write_bci2000`] for samples read a block at a time (a session's samples spilled to disk,
/// [`crate::SampleSpill`]) and states given by runs: memory stays one block and the runs,
/// however long the recording. A run that is empty, out of order, overlapping the one before or
/// beyond the recording is refused ([`StateProblem::Run`]), before anything is written.
pub fn write_bci2000_blocks(
    path: impl AsRef<Path>,
    samples: &dyn SampleBlocks,
    sfreq: f64,
    ch_names: &[String],
    states: &[StateRuns],
    options: &Bci2000WriteOptions,
) -> Result<Bci2000WriteSummary, IoError> {
    let path = path.as_ref();
    let n_times = samples.n_times();
    for s in states {
        let mut prev_end = 0;
        for (index, r) in s.runs.iter().enumerate() {
            if r.start >= r.end || r.start < prev_end || r.end > n_times {
                return Err(IoError::InvalidState {
                    path: path.to_path_buf(),
                    state: s.name.clone(),
                    problem: StateProblem::Run {
                        index,
                        start: r.start,
                        end: r.end,
                        n_times,
                    },
                });
            }
            prev_end = r.end;
        }
    }
    let states: Vec<_> = states
        .iter()
        .map(|s| (s.name.as_str(), s.bits, Values::Runs(&s.runs)))
        .collect();
    write_core(path, samples, sfreq, ch_names, states, options)
}

fn write_core(
    path: &Path,
    samples: &dyn SampleBlocks,
    sfreq: f64,
    ch_names: &[String],
    states: Vec<(&str, u32, Values<'_>)>,
    options: &Bci2000WriteOptions,
) -> Result<Bci2000WriteSummary, IoError> {
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    let (n_ch, n_times) = (samples.n_channels(), samples.n_times());
    crate::writing::check_not_empty_counts(path, n_ch, n_times, "BCI2000")?;
    if let Some(c) = ch_names.iter().position(String::is_empty) {
        return Err(unsupported(format!(
            "channel {c} has an empty name (a BCI2000 reader would then rename every channel)"
        )));
    }

    // States: checked, then packed bit by bit in the given order (`Running` first if absent).
    let add_running = !states.iter().any(|s| s.0 == "Running");
    let mut cols: Vec<(&str, u32, Values<'_>)> = Vec::with_capacity(states.len() + 1);
    if add_running {
        cols.push(("Running", 1, Values::One));
    }
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, &(name, bits, values)) in states.iter().enumerate() {
        let bad = |problem: StateProblem| IoError::InvalidState {
            path: path.to_path_buf(),
            state: name.to_string(),
            problem,
        };
        if let Some(reason) = state_name_problem(name) {
            return Err(bad(StateProblem::Name { reason }));
        }
        if let Some(&first) = seen.get(name) {
            return Err(bad(StateProblem::Duplicate { first, second: i }));
        }
        seen.insert(name, i);
        if !(1..=32).contains(&bits) {
            return Err(bad(StateProblem::Bits { bits }));
        }
        let too_wide = match values {
            Values::Dense(v) => v
                .iter()
                .enumerate()
                .find(|(_, &v)| v >> bits != 0)
                .map(|(sample, &value)| (sample, value)),
            Values::Runs(runs) => runs
                .iter()
                .find(|r| r.value >> bits != 0)
                .map(|r| (r.start, r.value)),
            Values::One => None,
        };
        if let Some((sample, value)) = too_wide {
            return Err(bad(StateProblem::ValueTooWide {
                sample,
                value,
                bits,
            }));
        }
        cols.push((name, bits, values));
    }
    let mut placed = Vec::with_capacity(cols.len());
    let mut next_bit = 0usize;
    for (name, bits, values) in cols {
        placed.push(Placed {
            name,
            bits,
            values,
            first_bit: next_bit,
            cursor: 0,
        });
        next_bit += bits as usize;
    }
    let sv_len = next_bit.div_ceil(8);

    // Samples: finite and within float32; the largest rounding is reported.
    let max_rounding =
        check_writable_blocks(path, samples, ch_names, "beyond the float32 range", |x| {
            let f = x as f32;
            f.is_finite().then(|| f64::from(f))
        })?;

    // Parameters.
    let extras = check_extra_parameters(path, &options.extra_parameters)?;
    let block = if extras.block_size_given {
        None
    } else {
        Some(default_block_size(n_times, sfreq))
    };
    let props = "Source:Signal%20Properties:DataIOFilter";
    let mut params = vec![format!(
        "{props} int SourceCh= {n_ch} // number of digitized and stored channels"
    )];
    if let Some(b) = block {
        params.push(format!(
            "{props} int SampleBlockSize= {b} // number of samples transmitted at a time"
        ));
    }
    params.push(format!(
        "{props} float SamplingRate= {sfreq}Hz // sample rate"
    ));
    let names: Vec<String> = ch_names.iter().map(|n| encode_value(n)).collect();
    params.push(format!(
        "{props} list ChannelNames= {n_ch} {} // list of channel names",
        names.join(" ")
    ));
    params.push(format!(
        "{props} floatlist SourceChOffset= {n_ch}{} // offset for channels in A/D units",
        " 0".repeat(n_ch)
    ));
    params.push(format!(
        "{props} floatlist SourceChGain= {n_ch}{} // gain for each channel (A/D units -> muV)",
        " 1".repeat(n_ch)
    ));
    params.push(format!(
        "System:State%20Vector int StateVectorLength= {sv_len} // length of the state vector in bytes"
    ));
    params.extend(extras.lines);

    // Header: everything after the first line, then the first line, whose length depends on
    // the `HeaderLen` it states (found by fixed-point iteration).
    let mut rest = String::from("[ State Vector Definition ]\r\n");
    for p in &mut placed {
        let first = p.value_at(0);
        p.cursor = 0;
        rest.push_str(&format!(
            "{} {} {} {} {}\r\n",
            p.name,
            p.bits,
            first,
            p.first_bit / 8,
            p.first_bit % 8
        ));
    }
    rest.push_str("[ Parameter Definition ]\r\n");
    for p in &params {
        rest.push_str(p);
        rest.push_str("\r\n");
    }
    rest.push_str("\r\n");
    let first_line = |header_len: usize| {
        format!(
            "BCI2000V= 1.1 HeaderLen= {header_len} SourceCh= {n_ch} StatevectorLen= {sv_len} DataFormat= float32\r\n"
        )
    };
    let mut header_len = rest.len();
    loop {
        let n = rest.len() + first_line(header_len).len();
        if n == header_len {
            break;
        }
        header_len = n;
    }
    let header = first_line(header_len) + &rest;
    debug_assert_eq!(header.len(), header_len);

    // Body, into a temporary file renamed into place.
    let record_len = n_ch * 4 + sv_len;
    let bytes = header_len as u64 + (n_times as u64) * (record_len as u64);
    let (tmp, file) = TempFile::create(path)?;
    let write_err = |source| IoError::Io {
        path: tmp.path.clone(),
        action: "write",
        source,
    };
    let mut w = BufWriter::with_capacity(1 << 16, file);
    w.write_all(header.as_bytes()).map_err(write_err)?;
    let mut record = vec![0u8; record_len];
    for_each_block(
        samples,
        |start, block| {
            for (k, column) in block.columns().into_iter().enumerate() {
                let t = start + k;
                record.fill(0);
                for (c, x) in column.iter().enumerate() {
                    record[4 * c..4 * c + 4].copy_from_slice(&(*x as f32).to_le_bytes());
                }
                let sv = &mut record[4 * n_ch..];
                for p in &mut placed {
                    let shifted = p.value_at(t) << (p.first_bit % 8);
                    let first_byte = p.first_bit / 8;
                    let n_bytes = (p.first_bit % 8 + p.bits as usize).div_ceil(8);
                    for (k, b) in sv[first_byte..first_byte + n_bytes].iter_mut().enumerate() {
                        *b |= (shifted >> (8 * k)) as u8;
                    }
                }
                w.write_all(&record).map_err(write_err)?;
            }
            Ok(())
        },
        |source| read_error(path, source),
    )?;
    let file = w.into_inner().map_err(|e| write_err(e.into_error()))?;
    crate::writing::sync(&file).map_err(write_err)?;
    drop(file);
    tmp.persist(path)?;
    Ok(Bci2000WriteSummary {
        n_samples: n_times,
        n_channels: n_ch,
        bytes,
        max_rounding_uv: max_rounding,
    })
}

/// Why `name` cannot be a state name, if it cannot.
fn state_name_problem(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("empty")
    } else if name.chars().any(char::is_whitespace) {
        Some("contains whitespace")
    } else if !name.bytes().all(|b| b.is_ascii_graphic()) {
        Some("not printable ASCII")
    } else if name.starts_with('[') {
        Some("starts with `[` (a header section line)")
    } else {
        None
    }
}

/// The default `SampleBlockSize`: the largest divisor of `n_times` not above 40 ms of samples
/// (BCI2000 records whole blocks; a typical block is 20 to 50 ms).
fn default_block_size(n_times: usize, sfreq: f64) -> usize {
    let cap = ((sfreq * 0.04).round() as usize).clamp(1, n_times);
    (1..=cap).rev().find(|b| n_times % b == 0).unwrap_or(1)
}

struct Extras {
    lines: Vec<String>,
    block_size_given: bool,
}

/// Checks the caller's parameter lines: one printable-ASCII line each, parsed by the reader's
/// parser, no parameter twice and none of the writer's own (except `SampleBlockSize`).
fn check_extra_parameters(path: &Path, lines: &[String]) -> Result<Extras, IoError> {
    let mut out = Extras {
        lines: Vec::with_capacity(lines.len()),
        block_size_given: false,
    };
    let mut seen: HashMap<String, usize> = HashMap::new();
    for (index, line) in lines.iter().enumerate() {
        let bad = |expected: &str, found: String| IoError::InvalidParameterLine {
            path: path.to_path_buf(),
            index,
            line: line.chars().take(200).collect(),
            expected: expected.to_string(),
            found,
        };
        if let Some(ch) = line
            .chars()
            .find(|&c| c != '\t' && !(' '..='~').contains(&c))
        {
            return Err(bad(
                "one line of printable ASCII (URL-encode other characters, see encode_value)",
                ch.to_string(),
            ));
        }
        let text = line.trim();
        if text.starts_with('[') {
            return Err(bad(
                "a parameter line, not a section header",
                text.to_string(),
            ));
        }
        let p = parse_parameter_line(text, 0).map_err(|e| bad(&e.expected, e.found))?;
        if let Some(&first) = seen.get(&p.name) {
            return Err(bad(
                "a parameter not defined by an earlier extra line",
                format!("{} again (first in line {first})", p.name),
            ));
        }
        if p.name == "SampleBlockSize" {
            out.block_size_given = true;
        } else if OWN_PARAMETERS.contains(&p.name.as_str()) {
            return Err(bad(
                "a parameter the writer does not write itself (it writes SourceCh, SamplingRate, ChannelNames, SourceChOffset, SourceChGain, StateVectorLength)",
                p.name,
            ));
        }
        seen.insert(p.name, index);
        out.lines.push(text.to_string());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use oddball_signal::Event;

    #[test]
    fn encodes_like_bci2000() {
        assert_eq!(encode_value(""), "%");
        assert_eq!(encode_value("Fz"), "Fz");
        assert_eq!(encode_value("a b"), "a%20b");
        assert_eq!(encode_value("100%"), "100%25");
        assert_eq!(encode_value("{x}"), "%7bx%7d");
        assert_eq!(encode_value("µV"), "%c2%b5V");
        assert_eq!(encode_value("a//b"), "a%2f%2fb");
        for s in ["", "a b", "%", "%20", "é t\té", "{ } //"] {
            assert_eq!(super::super::params::url_decode(&encode_value(s)), s);
        }
    }

    #[test]
    fn stimulus_codes_are_held_and_separated() {
        let events = Events::new(vec![
            Event::new(1, 3).with_target(true),
            Event::new(4, 5),
            Event::new(5, 300).with_target(false),
            Event::new(20, 1),
        ]);
        let s = stimulus_states(&events, 9, 3);
        assert_eq!(s[0].name, "StimulusCode");
        assert_eq!(s[0].bits, 9);
        // Event 1 stops before the onset at 4; the events at 4 and 5 are adjacent and merge.
        assert_eq!(s[0].values, vec![0, 3, 3, 0, 5, 300, 300, 300, 0]);
        assert_eq!(s[1].values, vec![0, 1, 1, 0, 0, 0, 0, 0, 0]);
        // A long hold stops one sample before the next onset.
        let s = stimulus_states(
            &Events::new(vec![Event::new(0, 1), Event::new(3, 2)]),
            6,
            10,
        );
        assert_eq!(s[0].values, vec![1, 1, 0, 2, 2, 2]);
        assert_eq!(s[0].bits, 8);
        assert_eq!(
            stimulus_states(&Events::default(), 2, 0)[0].values,
            vec![0, 0]
        );
    }

    #[test]
    fn block_sizes_divide_the_recording() {
        assert_eq!(default_block_size(56840, 256.0), 10);
        assert_eq!(default_block_size(1000, 500.0), 20);
        assert_eq!(default_block_size(7, 500.0), 7);
        assert_eq!(default_block_size(1009, 500.0), 1);
        assert_eq!(default_block_size(5, 1.0), 1);
    }
}
