//! Writing a `.easy` file and the `.info` beside it.

use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use oddball_signal::{Event, Raw};

use crate::samples::{for_each_block, SampleBlocks};
use crate::writing::{check_writable_blocks, read_error, TempFile};
use crate::IoError;

use super::read::*;
use super::types::*;

/// Options of [`write_easy`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EasyWriteOptions {
    /// Unix time of the first sample in ms (`StartDate` in the `.info`); default 0.
    pub start_ms: u64,
    /// `Device class` in the `.info`; default `STARSTIM`. One line of printable text.
    pub device_class: String,
    /// More `key: value` lines for the end of the `.info` (one line each, no line breaks);
    /// the reader returns them with the others in [`EasyInfo::info`].
    pub extra_info: Vec<(String, String)>,
}

impl Default for EasyWriteOptions {
    fn default() -> Self {
        Self {
            start_ms: 0,
            device_class: "STARSTIM".into(),
            extra_info: Vec::new(),
        }
    }
}

/// What [`write_easy`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct EasyWriteSummary {
    pub n_samples: usize,
    pub n_channels: usize,
    /// Size of the `.easy` file in bytes.
    pub bytes: u64,
    /// The `.info` file written beside it.
    pub info_path: PathBuf,
    /// The largest `|round(x × 1000) / 1000 − x|` over all samples, in µV (at most 0.0005).
    pub max_rounding_uv: f64,
    /// Samples with a non-zero trigger.
    pub n_triggers: usize,
    /// Events of the [`Raw`] that [`read_easy`] with default options does not give back: code 0,
    /// code 255 (NIC's lost-packet flag), another event at the same sample (the later one is
    /// written), or the same code on the sample before (read back as one held trigger).
    pub events_lost: usize,
}

/// The timestamp [`write_easy`] writes for `sample`: `start_ms + round(sample × 1000 / sfreq)`,
/// rounded to the nearest ms with halves away from zero.
pub fn timestamp_ms(start_ms: u64, sample: usize, sfreq: f64) -> u64 {
    start_ms.saturating_add((sample as f64 * 1000.0 / sfreq).round() as u64)
}

/// Whether `s` is one line of printable text without surrounding whitespace.
pub(super) fn text_problem(s: &str) -> Option<&'static str> {
    if s.is_empty() {
        Some("empty")
    } else if s.chars().any(char::is_control) {
        Some("contains a control character (TAB, line end, ...)")
    } else if s.trim() != s {
        Some("starts or ends with whitespace")
    } else {
        None
    }
}

/// Writes `raw` as a `.easy` file at `path` and a `.info` file beside it (see the module
/// documentation for what is written).
///
/// Refused with an [`IoError`] before anything is written: an empty recording; a channel name or
/// device class that is empty, has surrounding whitespace or a control character; a `path` that
/// is its own `.info` path; timestamps beyond 2⁵³ ms; a sample that is not finite or whose nV
/// value is beyond the int32 range ([`IoError::UnwritableSample`], naming channel and sample).
pub fn write_easy(
    path: impl AsRef<Path>,
    raw: &Raw,
    options: &EasyWriteOptions,
) -> Result<EasyWriteSummary, IoError> {
    write_easy_blocks(
        path,
        &raw.data().view(),
        raw.sfreq(),
        raw.ch_names(),
        raw.events().as_slice(),
        options,
    )
}

/// [`write_easy`] for samples read a block at a time (a session's samples spilled to disk,
/// [`crate::SampleSpill`]) and their `events`: memory stays one block and the events, however
/// long the recording.
pub fn write_easy_blocks(
    path: impl AsRef<Path>,
    samples: &dyn SampleBlocks,
    sfreq: f64,
    ch_names: &[String],
    events: &[Event],
    options: &EasyWriteOptions,
) -> Result<EasyWriteSummary, IoError> {
    let path = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    let (n_ch, n_times) = (samples.n_channels(), samples.n_times());
    crate::writing::check_not_empty_counts(path, n_ch, n_times, ".easy")?;
    for (c, name) in ch_names.iter().enumerate() {
        if let Some(problem) = text_problem(name) {
            return Err(unsupported(format!(
                "channel {c} name {name:?} {problem} (it goes on a .info line)"
            )));
        }
    }
    if let Some(problem) = text_problem(&options.device_class) {
        return Err(unsupported(format!(
            "device class {:?} {problem}",
            options.device_class
        )));
    }
    let info_path = info_path_for(path);
    if info_path == path {
        return Err(unsupported(
            "a .easy path that is its own .info path (give the file another extension)".into(),
        ));
    }
    let last = timestamp_ms(options.start_ms, n_times - 1, sfreq);
    if options.start_ms > MAX_TIMESTAMP_MS || last > MAX_TIMESTAMP_MS {
        return Err(unsupported(format!(
            "timestamps from {} to {last} ms (at most 2^53 ms)",
            options.start_ms
        )));
    }

    // Samples: finite and within int32 nV; the largest rounding is reported.
    let nv = |x: f64| (x * 1000.0).round();
    let max_rounding = check_writable_blocks(
        path,
        samples,
        ch_names,
        "beyond ±2147483647 nV, the int32 range of .easy samples",
        |x| (nv(x).abs() <= f64::from(i32::MAX)).then(|| nv(x) / 1000.0),
    )?;

    // Triggers: each event's code at its onset only (the later of two at one sample wins), as
    // (sample, code) in order.
    let mut order: Vec<&Event> = events.iter().filter(|e| e.onset < n_times).collect();
    order.sort_by_key(|e| e.onset);
    let mut trig: Vec<(usize, u32)> = Vec::with_capacity(order.len());
    for e in order {
        match trig.last_mut() {
            Some(last) if last.0 == e.onset => last.1 = e.code,
            _ => trig.push((e.onset, e.code)),
        }
    }
    trig.retain(|&(_, c)| c != 0);
    let n_triggers = trig.len();
    let readable = trig
        .iter()
        .enumerate()
        .filter(|&(i, &(t, c))| {
            let held = i > 0 && trig[i - 1] == (t.wrapping_sub(1), c);
            c != NIC_PACKET_LOSS_CODE && !held
        })
        .count();
    let events_lost = events.len().saturating_sub(readable);

    // The .info (NIC 2's form).
    let mut info = String::new();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let _ = writeln!(info, "Step Details");
    let _ = writeln!(info, "Step name: {}", stem.replace(['\r', '\n'], " "));
    let _ = writeln!(info, "StartDate (firstEEGtimestamp): {}", options.start_ms);
    let _ = writeln!(info, "Device class: {}", options.device_class);
    let _ = writeln!(
        info,
        "Software's version: oddball-io {}",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(info, "Additional channel: NONE");
    let _ = writeln!(info);
    let _ = writeln!(info, "EEG Settings");
    let _ = writeln!(info, "Total number of channels: {n_ch}");
    let _ = writeln!(info, "Number of EEG channels: {n_ch}");
    let _ = writeln!(info, "Number of records of EEG: {n_times}");
    let _ = writeln!(info, "EEG sampling rate: {sfreq} Samples/second");
    let _ = writeln!(info, "EEG units: nV");
    let _ = writeln!(info, "Accelerometer data: OFF");
    let _ = writeln!(info, "EEG montage:");
    for (k, name) in ch_names.iter().enumerate() {
        let _ = writeln!(info, "\tChannel {}: {name}", k + 1);
    }
    if !options.extra_info.is_empty() {
        let _ = writeln!(info);
        for (key, value) in &options.extra_info {
            let clean = |t: &str| t.replace(['\r', '\n'], " ");
            let _ = writeln!(info, "{}: {}", clean(key).replace(':', ";"), clean(value));
        }
    }

    // The .easy, then both renamed into place (.info first).
    let (easy_tmp, file) = TempFile::create(path)?;
    let write_err = |p: &Path, source| IoError::Io {
        path: p.to_path_buf(),
        action: "write",
        source,
    };
    let mut w = BufWriter::with_capacity(1 << 16, file);
    let mut line = String::with_capacity(12 * (n_ch + 2));
    let mut bytes = 0u64;
    let mut next_trig = trig.iter().peekable();
    for_each_block(
        samples,
        |start, block| {
            for (k, column) in block.columns().into_iter().enumerate() {
                let t = start + k;
                line.clear();
                for x in column {
                    let _ = write!(line, "{}\t", nv(*x) as i32);
                }
                let code = match next_trig.peek() {
                    Some(&&(at, c)) if at == t => {
                        next_trig.next();
                        c
                    }
                    _ => 0,
                };
                let _ = writeln!(line, "{code}\t{}", timestamp_ms(options.start_ms, t, sfreq));
                w.write_all(line.as_bytes())
                    .map_err(|e| write_err(&easy_tmp.path, e))?;
                bytes += line.len() as u64;
            }
            Ok(())
        },
        |source| read_error(path, source),
    )?;
    let file = w
        .into_inner()
        .map_err(|e| write_err(&easy_tmp.path, e.into_error()))?;
    crate::writing::sync(&file).map_err(|e| write_err(&easy_tmp.path, e))?;
    drop(file);

    let (info_tmp, mut file) = TempFile::create(&info_path)?;
    file.write_all(info.as_bytes())
        .and_then(|()| crate::writing::sync(&file))
        .map_err(|e| write_err(&info_tmp.path, e))?;
    drop(file);
    info_tmp.persist(&info_path)?;
    easy_tmp.persist(path)?;
    Ok(EasyWriteSummary {
        n_samples: n_times,
        n_channels: n_ch,
        bytes,
        info_path,
        max_rounding_uv: max_rounding,
        n_triggers,
        events_lost,
    })
}
