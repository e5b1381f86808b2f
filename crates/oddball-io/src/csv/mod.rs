//! CSV recordings: a time column, channel columns and a marker column, read from scratch.
//!
//! The files this project meets (Muse/muse-lsl exports: `timestamps,TP9,AF7,AF8,TP10,Right AUX,
//! Marker`) are plain numeric tables without quoting, so a small reader that knows where each
//! value came from (1-based line and column in every error) serves better than a general CSV
//! crate. Header names may be wrapped in double quotes; data cells may not.
//!
//! * Channel values are multiplied by [`CsvOptions::scale_to_uv`] (1 by default: the values are
//!   taken to be µV, as in Muse files).
//! * Sampling rate: [`CsvOptions::sfreq`] when given; else estimated from the time column as
//!   `(n − 1) / (t_last − t_first)`, the mean rate, and taken as the nominal rate within 0.1 % of
//!   it ([`oddball_signal::rate::nominal_sfreq`]: 240.0000073 Hz is 240 Hz). (The median interval is useless for Muse files:
//!   their timestamps are rounded to 1 ms, so intervals are 3 or 4 ms and the median gives 250 Hz
//!   instead of 256 Hz.) The estimate is kept in [`CsvInfo::estimated_sfreq`] either way.
//! * Events: at each sample whose marker is non-zero and differs from the previous sample's
//!   marker (a marker held over several samples is one event, at its first sample). The code
//!   is the marker value; `target` is `Some(true)` for [`CsvOptions::target_codes`],
//!   `Some(false)` for [`CsvOptions::nontarget_codes`], else `None`.
//! * Every cell that is read must be a finite number; markers must be non-negative integers.
//!   Rows must have as many cells as the header. Blank lines are skipped. By default the last row
//!   must end with a line end, so a file cut inside its last row is reported, not read short.

mod info;

use std::iter::Peekable;
use std::path::Path;

use ndarray::Array2;
use oddball_signal::Event;

pub use info::CsvInfo;

use crate::files::read_file;
use crate::{Details, Format, IoError, Recording};

/// Which columns are what, and how to turn them into µV samples and events.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvOptions {
    /// The time column (seconds); used for the sampling rate when `sfreq` is `None`.
    pub time_column: Option<String>,
    /// The marker column (0 = no event).
    pub marker_column: Option<String>,
    /// The EEG channel columns, in this order. `None`: every column except the time column,
    /// the marker column and `drop_columns`, in file order.
    pub channels: Option<Vec<String>>,
    /// Columns left out when `channels` is `None` (names absent from the file are ignored).
    pub drop_columns: Vec<String>,
    /// Sampling rate in Hz; `None` estimates it from the time column.
    pub sfreq: Option<f64>,
    /// Marker values whose events are targets.
    pub target_codes: Vec<u32>,
    /// Marker values whose events are non-targets.
    pub nontarget_codes: Vec<u32>,
    /// Cell separator.
    pub delimiter: u8,
    /// Factor from the file's channel values to µV.
    pub scale_to_uv: f64,
    /// Reject a file whose last row has no line end (a sign of truncation).
    pub require_final_newline: bool,
}

impl Default for CsvOptions {
    fn default() -> Self {
        Self {
            time_column: None,
            marker_column: None,
            channels: None,
            drop_columns: Vec::new(),
            sfreq: None,
            target_codes: Vec::new(),
            nontarget_codes: Vec::new(),
            delimiter: b',',
            scale_to_uv: 1.0,
            require_final_newline: true,
        }
    }
}

/// The column names that [`CsvOptions::detect`] takes for a time column (compared in lower case).
const TIME_NAMES: [&str; 6] = ["time", "times", "timestamp", "timestamps", "t", "time_s"];
/// The column names that [`CsvOptions::detect`] takes for a marker column (lower case).
const MARKER_NAMES: [&str; 7] = [
    "marker", "markers", "marker0", "stim", "trigger", "triggers", "event",
];

impl CsvOptions {
    /// Muse / muse-lsl exports (NeuroTechX eeg-notebooks): `timestamps` time column, `Marker`
    /// column with 2 = target and 1 = non-target, channels TP9 AF7 AF8 TP10 in µV (`Right AUX`
    /// dropped), 256 Hz (the Muse 2016 rate; the timestamps give 256.02 Hz on average).
    pub fn muse() -> Self {
        Self {
            time_column: Some("timestamps".into()),
            marker_column: Some("Marker".into()),
            channels: None,
            drop_columns: vec!["Right AUX".into()],
            sfreq: Some(256.0),
            target_codes: vec![2],
            nontarget_codes: vec![1],
            ..Self::default()
        }
    }

    /// Options guessed from the header's column names: a Muse header
    /// (`timestamps,TP9,AF7,AF8,TP10,...`) gets [`CsvOptions::muse`] (with `Marker0` when the
    /// file names its marker column that way); otherwise the first column is the time column when
    /// it is named like `time`/`timestamp(s)`, and a column named `Marker`, `stim`, `trigger` (any
    /// case) is the marker column. Target codes are not guessed outside the Muse preset.
    pub fn detect<S: AsRef<str>>(header: &[S]) -> Self {
        let names: Vec<&str> = header.iter().map(|s| s.as_ref().trim()).collect();
        let lower: Vec<String> = names.iter().map(|s| s.to_ascii_lowercase()).collect();
        let marker = lower
            .iter()
            .position(|n| MARKER_NAMES.contains(&n.as_str()))
            .map(|i| names[i].to_string());
        if names.len() >= 5 && names[..5] == ["timestamps", "TP9", "AF7", "AF8", "TP10"] {
            let mut o = Self::muse();
            if marker.is_some() {
                o.marker_column = marker;
            }
            return o;
        }
        Self {
            time_column: lower
                .first()
                .filter(|n| TIME_NAMES.contains(&n.as_str()))
                .map(|_| names[0].to_string()),
            marker_column: marker,
            ..Self::default()
        }
    }
}

/// Reads a CSV recording with the given column roles.
pub fn read_csv(path: impl AsRef<Path>, options: &CsvOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_csv(&bytes, path, options)
}

/// Reads a CSV recording with options from [`CsvOptions::detect`] on its header.
pub fn read_csv_auto(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    parse_csv_with_detected(path.as_ref(), |o| o)
}

/// Reads a CSV recording with the options `adjust` makes of [`CsvOptions::detect`]'s.
pub(crate) fn parse_csv_with_detected(
    path: &Path,
    adjust: impl FnOnce(CsvOptions) -> CsvOptions,
) -> Result<Recording, IoError> {
    let bytes = read_file(path)?;
    let header_end = bytes
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(bytes.len());
    let header = split_header(&bytes[..header_end], b',', path)?;
    parse_csv(&bytes, path, &adjust(CsvOptions::detect(&header)))
}

/// A text-file error (CSV, `.easy`, `.info`): file, line, column, field, expected, found.
pub(crate) fn csv_err(
    path: &Path,
    line: usize,
    column: usize,
    field: impl Into<String>,
    expected: impl Into<String>,
    found: impl Into<String>,
) -> IoError {
    IoError::Csv {
        path: path.to_path_buf(),
        line,
        column,
        field: field.into(),
        expected: expected.into(),
        found: crate::error::bounded(&found.into()),
    }
}

/// A line's text without its `\r`. A byte that is not UTF-8 is an error at the column
/// `column(valid)` gives from the valid bytes before it.
pub(crate) fn line_text<'a>(
    raw: &'a [u8],
    path: &Path,
    line: usize,
    column: fn(&[u8]) -> usize,
) -> Result<&'a str, IoError> {
    let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
    std::str::from_utf8(raw).map_err(|e| {
        csv_err(
            path,
            line,
            column(&raw[..e.valid_up_to()]),
            "text",
            "UTF-8 text",
            format!("byte 0x{:02x}", raw[e.valid_up_to()]),
        )
    })
}

/// The event of the marker `code` at sample `onset`: a target when `code` is one of `targets`, a
/// non-target when one of `nontargets`, otherwise unlabelled.
pub(crate) fn marker_event(onset: usize, code: u32, targets: &[u32], nontargets: &[u32]) -> Event {
    let target = if targets.contains(&code) {
        Some(true)
    } else if nontargets.contains(&code) {
        Some(false)
    } else {
        None
    };
    Event {
        onset,
        code,
        target,
        label: None,
    }
}

/// The column (1-based, in bytes) after the bytes `valid`.
fn byte_column(valid: &[u8]) -> usize {
    valid.len() + 1
}

/// The next line of a text recording read row by row from `lines` (each line's index and bytes,
/// split at `\n`): its line number and text ([`line_text`], `column` locating a byte that is not
/// UTF-8; a UTF-8 byte-order mark before the file's first line left out), blank lines skipped.
/// `None` at the end, the text after the final line end included. With `line_end_required` (the
/// reader asks for a line end after the last line and the file has none), the last line is the
/// error `truncated(line, text)`.
pub(crate) fn next_line<'a>(
    lines: &mut Peekable<impl Iterator<Item = (usize, &'a [u8])>>,
    path: &Path,
    column: fn(&[u8]) -> usize,
    line_end_required: bool,
    truncated: impl Fn(usize, &str) -> IoError,
) -> Result<Option<(usize, &'a str)>, IoError> {
    while let Some((idx, raw)) = lines.next() {
        let line_no = idx + 1;
        let is_last = lines.peek().is_none();
        if is_last && raw.is_empty() {
            break; // the text after the final line end
        }
        let raw = if idx == 0 {
            raw.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(raw)
        } else {
            raw
        };
        let text = line_text(raw, path, line_no, column)?;
        if text.trim().is_empty() {
            continue;
        }
        if is_last && line_end_required {
            return Err(truncated(line_no, text));
        }
        return Ok(Some((line_no, text)));
    }
    Ok(None)
}

fn split_header(raw: &[u8], delimiter: u8, path: &Path) -> Result<Vec<String>, IoError> {
    let raw = raw.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(raw);
    let text = line_text(raw, path, 1, byte_column)?;
    Ok(text
        .split(delimiter as char)
        .map(|s| {
            let s = s.trim();
            s.strip_prefix('"')
                .and_then(|s| s.strip_suffix('"'))
                .unwrap_or(s)
                .to_string()
        })
        .collect())
}

/// Parses the bytes of a CSV recording; `path` is used in error messages and the result.
pub fn parse_csv(bytes: &[u8], path: &Path, options: &CsvOptions) -> Result<Recording, IoError> {
    if !options.delimiter.is_ascii() || options.delimiter == b'\n' || options.delimiter == b'"' {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!("CSV delimiter byte 0x{:02x}", options.delimiter),
        });
    }
    let mut lines = bytes.split(|&b| b == b'\n').enumerate().peekable();
    let Some((_, header_raw)) = lines.next() else {
        return Err(csv_err(
            path,
            1,
            1,
            "header",
            "a header line",
            "an empty file",
        ));
    };
    if bytes.is_empty() {
        return Err(csv_err(
            path,
            1,
            1,
            "header",
            "a header line",
            "an empty file",
        ));
    }
    let columns = split_header(header_raw, options.delimiter, path)?;
    if lines.peek().is_none() && options.require_final_newline {
        return Err(csv_err(
            path,
            1,
            String::from_utf8_lossy(header_raw).chars().count() + 1,
            "line end",
            "a line end after the header (the file looks truncated)",
            String::from_utf8_lossy(&header_raw[..header_raw.len().min(80)]).into_owned(),
        ));
    }
    for (j, name) in columns.iter().enumerate() {
        if let Some(k) = columns[..j].iter().position(|n| n == name) {
            return Err(csv_err(
                path,
                1,
                j + 1,
                name.clone(),
                format!("unique column names (column {} has the same name)", k + 1),
                name.clone(),
            ));
        }
    }
    let find = |name: &str| -> Result<usize, IoError> {
        columns
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "CSV column",
                name: name.to_string(),
                available: columns.clone(),
            })
    };
    let time_idx = options.time_column.as_deref().map(find).transpose()?;
    let marker_idx = options.marker_column.as_deref().map(find).transpose()?;
    let ch_idx: Vec<usize> = match &options.channels {
        Some(names) => names.iter().map(|n| find(n)).collect::<Result<_, _>>()?,
        None => (0..columns.len())
            .filter(|&j| {
                Some(j) != time_idx
                    && Some(j) != marker_idx
                    && !options.drop_columns.iter().any(|d| d == &columns[j])
            })
            .collect(),
    };
    // A channel named among the time or marker columns would feed the clock or the labels in
    // as EEG (the probe's `--channels Marker,TP9` scored AUC 1.000 on its own labels).
    for &j in &ch_idx {
        if Some(j) == time_idx || Some(j) == marker_idx {
            return Err(csv_err(
                path,
                1,
                j + 1,
                "channels",
                format!(
                    "EEG columns, not the {} column",
                    if Some(j) == time_idx {
                        "time"
                    } else {
                        "marker"
                    }
                ),
                columns[j].clone(),
            ));
        }
    }
    if ch_idx.is_empty() {
        return Err(csv_err(
            path,
            1,
            1,
            "header",
            "at least one channel column besides the time and marker columns",
            columns.join(","),
        ));
    }
    if !(options.scale_to_uv.is_finite() && options.scale_to_uv != 0.0) {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!("scale_to_uv = {}", options.scale_to_uv),
        });
    }

    // Which column feeds what: 0 = unused, 1 = time, 2 = marker, 3+k = channel k.
    let mut role = vec![0usize; columns.len()];
    for (k, &j) in ch_idx.iter().enumerate() {
        role[j] = 3 + k;
    }
    if let Some(j) = time_idx {
        role[j] = 1;
    }
    if let Some(j) = marker_idx {
        role[j] = 2;
    }
    // (A channel is never the time or marker column: refused above.)
    let ch_of_col: Vec<Vec<usize>> = (0..columns.len())
        .map(|j| {
            ch_idx
                .iter()
                .enumerate()
                .filter(|(_, &c)| c == j)
                .map(|(k, _)| k)
                .collect()
        })
        .collect();

    let n_lines_hint = bytes.len() / 32 + 1;
    let mut channels: Vec<Vec<f64>> = (0..ch_idx.len())
        .map(|_| Vec::with_capacity(n_lines_hint))
        .collect();
    let mut times: Vec<f64> = Vec::new();
    let mut events: Vec<Event> = Vec::new();
    let mut prev_marker = 0u32;
    let mut n_times = 0usize;
    let ends_with_newline = bytes.last() == Some(&b'\n');

    let line_end_required = !ends_with_newline && options.require_final_newline;
    let truncated = |line_no, text: &str| {
        csv_err(
            path,
            line_no,
            text.chars().count() + 1,
            "line end",
            "a line end after the last row (the file looks truncated)",
            text.chars().take(80).collect::<String>(),
        )
    };
    while let Some((line_no, text)) =
        next_line(&mut lines, path, byte_column, line_end_required, truncated)?
    {
        let mut n_cells = 0usize;
        for (j, cell) in text.split(options.delimiter as char).enumerate() {
            n_cells += 1;
            if j >= columns.len() {
                continue;
            }
            let r = role[j];
            if r == 0 {
                continue;
            }
            let value: f64 = cell
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| {
                    csv_err(
                        path,
                        line_no,
                        j + 1,
                        columns[j].clone(),
                        "a finite number",
                        cell,
                    )
                })?;
            if r == 1 {
                times.push(value);
            } else if r == 2 {
                if value < 0.0 || value.fract() != 0.0 || value > u32::MAX as f64 {
                    return Err(csv_err(
                        path,
                        line_no,
                        j + 1,
                        columns[j].clone(),
                        "a non-negative integer marker",
                        cell,
                    ));
                }
                let code = value as u32;
                if code != 0 && code != prev_marker {
                    events.push(marker_event(
                        n_times,
                        code,
                        &options.target_codes,
                        &options.nontarget_codes,
                    ));
                }
                prev_marker = code;
            }
            for &k in &ch_of_col[j] {
                channels[k].push(value * options.scale_to_uv);
            }
        }
        if n_cells != columns.len() {
            return Err(csv_err(
                path,
                line_no,
                n_cells.min(columns.len()) + 1,
                "row",
                format!("{} cells, as in the header", columns.len()),
                format!("{n_cells} cells"),
            ));
        }
        n_times += 1;
    }
    if n_times == 0 {
        return Err(csv_err(path, 2, 1, "data", "at least one data row", "none"));
    }

    let estimated_sfreq = match times.as_slice() {
        [first, .., last] if last > first => Some((times.len() - 1) as f64 / (last - first)),
        _ => None,
    };
    let (sfreq, from_ts) = match options.sfreq {
        Some(f) if f.is_finite() && f > 0.0 => (f, false),
        Some(f) => {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                what: format!("sampling rate {f} Hz in CsvOptions::sfreq"),
            })
        }
        None => match (time_idx, estimated_sfreq) {
            (Some(_), Some(f)) => (oddball_signal::rate::nominal_sfreq(f), true),
            (Some(j), None) => return Err(csv_err(
                path,
                n_times + 1,
                j + 1,
                columns[j].clone(),
                "at least two rows with a last time after the first, to estimate the sampling rate",
                format!("{} rows", n_times),
            )),
            (None, _) => return Err(IoError::Missing {
                path: path.to_path_buf(),
                what:
                    "time column (needed for the sampling rate when CsvOptions::sfreq is not set)",
                name: String::new(),
                available: columns,
            }),
        },
    };

    let ch_names: Vec<String> = ch_idx.iter().map(|&j| columns[j].clone()).collect();
    let flat: Vec<f64> = channels.into_iter().flatten().collect();
    let data = Array2::from_shape_vec((ch_names.len(), n_times), flat).map_err(|e| {
        IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!("CSV layout: {e}"),
        }
    })?;
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    Ok(Recording {
        raw,
        format: Format::Csv,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Csv(CsvInfo {
            time_column: options.time_column.clone(),
            marker_column: options.marker_column.clone(),
            columns,
            timestamps: time_idx.map(|_| times),
            estimated_sfreq,
            sfreq_from_timestamps: from_ts,
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, o: &CsvOptions) -> Result<Recording, IoError> {
        parse_csv(text.as_bytes(), Path::new("t.csv"), o)
    }

    const MUSE: &str = "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n\
        10.000,1,2,3,4,5,0\n10.004,1.5,2,3,4,5,2\n10.008,1,2,3,4,5,0\n10.012,1,2,3,4,5,1\n10.016,1,2,3,4,5,1\n";

    #[test]
    fn muse_preset() {
        let r = parse(MUSE, &CsvOptions::muse()).unwrap();
        assert_eq!(r.raw.ch_names(), ["TP9", "AF7", "AF8", "TP10"]);
        assert_eq!(r.raw.sfreq(), 256.0);
        assert_eq!(r.raw.n_times(), 5);
        assert_eq!(r.raw.data()[[0, 1]], 1.5);
        let ev: Vec<_> = r
            .raw
            .events()
            .iter()
            .map(|e| (e.onset, e.code, e.target))
            .collect();
        // The held marker 1 on rows 4-5 is one event.
        assert_eq!(ev, vec![(1, 2, Some(true)), (3, 1, Some(false))]);
        let info = r.csv().unwrap();
        assert!(!info.sfreq_from_timestamps);
        assert!((info.estimated_sfreq.unwrap() - 250.0).abs() < 1e-9);
        assert_eq!(info.timestamps.as_ref().unwrap().len(), 5);
    }

    #[test]
    fn detection() {
        let h = [
            "timestamps",
            "TP9",
            "AF7",
            "AF8",
            "TP10",
            "Right AUX",
            "Marker0",
        ];
        let o = CsvOptions::detect(&h);
        assert_eq!(o.marker_column.as_deref(), Some("Marker0"));
        assert_eq!(o.sfreq, Some(256.0));
        let o = CsvOptions::detect(&["Time", "Cz", "Pz", "STIM"]);
        assert_eq!(o.time_column.as_deref(), Some("Time"));
        assert_eq!(o.marker_column.as_deref(), Some("STIM"));
        assert_eq!(o.sfreq, None);
        let o = CsvOptions::detect(&["Cz", "time"]);
        assert_eq!(o.time_column, None);
    }

    /// Issue #30: `--channels Marker,TP9` fed the labels in as EEG (AUC 1.000); a channel that
    /// is the time or the marker column is refused, naming the column.
    #[test]
    fn channels_that_are_the_time_or_marker_column_are_refused() {
        let text = "time,Cz,Pz,trigger\n0,1,2,0\n0.01,1,2,7\n0.02,1,2,0\n";
        let mut o = CsvOptions::detect(&["time", "Cz", "Pz", "trigger"]);
        for (pick, what) in [("trigger", "marker"), ("time", "time")] {
            o.channels = Some(vec![pick.into(), "Cz".into()]);
            let e = parse(text, &o).unwrap_err().to_string();
            assert!(
                e.contains(&format!("not the {what} column")) && e.contains(pick),
                "{e}"
            );
        }
    }

    #[test]
    fn estimates_rate_and_chooses_columns() {
        let text = "\u{feff}\"time\",Cz,Pz,trigger\r\n0,1,2,0\r\n0.01,1,2,7\r\n0.02,1,2,7\r\n0.03,1,2,0\r\n0.04,1,2,7\r\n";
        let mut o = CsvOptions::detect(&["time", "Cz", "Pz", "trigger"]);
        o.channels = Some(vec!["Pz".into()]);
        o.scale_to_uv = 1e3;
        let r = parse(text, &o).unwrap();
        assert!((r.raw.sfreq() - 100.0).abs() < 1e-9);
        assert!(r.csv().unwrap().sfreq_from_timestamps);
        assert_eq!(r.raw.ch_names(), ["Pz"]);
        assert_eq!(r.raw.data()[[0, 0]], 2000.0);
        let onsets: Vec<_> = r
            .raw
            .events()
            .iter()
            .map(|e| (e.onset, e.code, e.target))
            .collect();
        assert_eq!(onsets, vec![(1, 7, None), (4, 7, None)]);
    }

    fn csv_pos(e: &IoError) -> (usize, usize) {
        match e {
            IoError::Csv { line, column, .. } => (*line, *column),
            other => panic!("not a CSV error: {other}"),
        }
    }

    #[test]
    fn errors_name_line_and_column() {
        let o = CsvOptions::muse();
        // Short row.
        let e = parse("timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3\n", &o).unwrap_err();
        assert_eq!(csv_pos(&e), (2, 4));
        // Bad number.
        let e = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,x,4,5,6,0\n",
            &o,
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (2, 3));
        assert!(e.to_string().contains("AF7"), "{e}");
        // Non-finite value.
        let e = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3,inf,5,6,0\n",
            &o,
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (2, 4));
        // Fractional marker.
        let e = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3,4,5,6,1.5\n",
            &o,
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (2, 7));
        // Too many cells.
        let e = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3,4,5,6,0,9\n",
            &o,
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (2, 8));
        // Last line cut.
        let e = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3,4,5,6,0\n1,2,3,4,5,6,0",
            &o,
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (3, 14));
        let mut lax = o.clone();
        lax.require_final_newline = false;
        let r = parse(
            "timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n1,2,3,4,5,6,0\n1,2,3,4,5,6,0",
            &lax,
        )
        .unwrap();
        assert_eq!(r.raw.n_times(), 2);
        // Duplicate column names, missing column, no data, empty file, bad UTF-8.
        let e = parse(
            "a,b,a\n1,2,3\n",
            &CsvOptions {
                sfreq: Some(1.0),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (1, 3));
        let e = parse("a,b\n1,2\n", &o).unwrap_err();
        assert!(matches!(e, IoError::Missing { .. }), "{e}");
        let e = parse("timestamps,TP9,AF7,AF8,TP10,Right AUX,Marker\n", &o).unwrap_err();
        assert_eq!(csv_pos(&e), (2, 1));
        let e = parse("", &o).unwrap_err();
        assert_eq!(csv_pos(&e), (1, 1));
        let e = parse_csv(
            b"a,b\n1,\xff\n",
            Path::new("t.csv"),
            &CsvOptions {
                sfreq: Some(1.0),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert_eq!(csv_pos(&e), (2, 3));
        // No time column and no rate.
        let e = parse("a,b\n1,2\n", &CsvOptions::default()).unwrap_err();
        assert!(matches!(e, IoError::Missing { .. }), "{e}");
        // One row cannot give a rate.
        let e = parse("time,a\n1,2\n", &CsvOptions::detect(&["time", "a"])).unwrap_err();
        assert_eq!(csv_pos(&e), (2, 1));
    }
}
