//! Reading a `.easy` file: its layout, its cells, its events and timestamps.

use std::path::{Path, PathBuf};

use ndarray::Array2;
use oddball_signal::Event;

use crate::csv::{csv_err, marker_event, next_line};
use crate::files::read_file;
use crate::{Details, Format, IoError, Recording};

use super::info::*;
use super::types::*;

/// Reads a `.easy` recording and the `.info` beside it with default options.
pub fn read_easy(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_easy_with(path, &EasyOptions::default())
}

/// Reads a `.easy` recording with the given options.
pub fn read_easy_with(path: impl AsRef<Path>, options: &EasyOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    let info_path = match &options.info {
        EasyInfoFile::Beside => {
            let p = info_path_for(path);
            p.is_file().then_some(p)
        }
        EasyInfoFile::At(p) => Some(p.clone()),
        EasyInfoFile::Ignore => None,
    };
    let info_bytes = info_path.as_deref().map(read_file).transpose()?;
    let info = info_path.as_deref().zip(info_bytes.as_deref());
    let mut rec = parse_easy(&bytes, path, info.map(|(p, b)| (b, p)), options)?;
    label_oddball_session(&mut rec)?;
    Ok(rec)
}

/// `.info` key naming the paradigm of an oddball session's `.easy` (`four-bulb`).
pub const ODDBALL_PARADIGM_KEY: &str = "Oddball paradigm";
/// Trigger offset of attended flashes in an oddball session's `.easy` (NIC triggers carry one
/// number: bulb `C` attended is `C + 10`).
pub const ODDBALL_ATTENDED_OFFSET: u32 = 10;

/// An oddball session's `.easy` (its `.info` names the paradigm) reads as a labelled recording:
/// a trigger `C + 10` is bulb `C` attended (target), `C` not; other files are left as they are.
fn label_oddball_session(rec: &mut Recording) -> Result<(), IoError> {
    let session = rec
        .easy()
        .and_then(|e| e.info_value(ODDBALL_PARADIGM_KEY))
        .is_some_and(|v| v == "four-bulb");
    if !session {
        return Ok(());
    }
    let events: Vec<Event> = rec
        .raw
        .events()
        .iter()
        .map(|e| {
            let attended = e.code > ODDBALL_ATTENDED_OFFSET;
            Event {
                code: if attended {
                    e.code - ODDBALL_ATTENDED_OFFSET
                } else {
                    e.code
                },
                target: Some(attended),
                ..e.clone()
            }
        })
        .collect();
    rec.raw
        .set_events(oddball_signal::Events::new(events))
        .map_err(|source| IoError::Signal {
            path: rec.path.clone(),
            source,
        })
}

/// The `.info` file that belongs to a `.easy` file: same stem, extension `.info`.
pub fn info_path_for(easy: &Path) -> PathBuf {
    easy.with_extension("info")
}

/// The layout of a first line of `n_cols` cells (see the module documentation).
pub(super) fn resolve_layout(
    n_cols: usize,
    info: Option<(&ParsedInfo, &Path)>,
    options: &EasyOptions,
    path: &Path,
    line: usize,
) -> Result<EasyLayout, IoError> {
    let found = format!("{n_cols} cells");
    let fixed = |c: usize, why: String| {
        EasyLayout::for_columns(n_cols, c).ok_or_else(|| {
            csv_err(
                path,
                line,
                1,
                "layout",
                format!(
                    "{}, {}, {} or {} cells for {c} EEG channels ({why})",
                    c + 2,
                    c + 3,
                    c + 5,
                    c + 6
                ),
                found.clone(),
            )
        })
    };
    if let Some(c) = options.n_channels {
        return fixed(c, "EasyOptions::n_channels".into());
    }
    if let Some((info, info_path)) = info {
        if let Some(c) = info.total_channels.or(info.eeg_channels) {
            return fixed(c.value, format!("{} line {}", info_path.display(), c.line));
        }
        if let Some(acc) = info.accelerometer {
            let add = info.add_sensor.unwrap_or(false);
            let extra = 2 + 3 * usize::from(acc) + usize::from(add);
            return match n_cols.checked_sub(extra).filter(|&c| c > 0) {
                Some(c) => Ok(EasyLayout {
                    n_eeg: c,
                    accelerometer: acc,
                    add_sensor: add,
                }),
                None => Err(csv_err(
                    path,
                    line,
                    1,
                    "layout",
                    format!(
                        "more than {extra} cells (accelerometer {}, AddSensor {} in {})",
                        if acc { "on" } else { "off" },
                        if add { "on" } else { "off" },
                        info_path.display()
                    ),
                    found,
                )),
            };
        }
    }
    STANDARD_CHANNEL_COUNTS
        .iter()
        .find_map(|&c| EasyLayout::for_columns(n_cols, c))
        .ok_or_else(|| {
            csv_err(
                path,
                line,
                1,
                "layout",
                "10, 11, 13 or 14 cells (8 EEG channels), 22, 23, 25 or 26 (20 channels), \
                 34, 35, 37 or 38 (32 channels); other channel counts need a .info or \
                 EasyOptions::n_channels",
                found,
            )
        })
}

/// What each cell of a line holds.
#[derive(Debug, Clone, Copy)]
pub(super) enum Role {
    Eeg(usize),
    Acc(usize),
    AddSensor,
    Trigger,
    Timestamp,
}

pub(super) fn roles(layout: &EasyLayout) -> Vec<Role> {
    let mut r: Vec<Role> = (0..layout.n_eeg).map(Role::Eeg).collect();
    if layout.accelerometer {
        r.extend((0..3).map(Role::Acc));
    }
    if layout.add_sensor {
        r.push(Role::AddSensor);
    }
    r.push(Role::Trigger);
    r.push(Role::Timestamp);
    r
}

pub(super) fn parse_trigger(cell: &str) -> Option<u32> {
    cell.parse::<u32>().ok().or_else(|| {
        let v: f64 = cell.parse().ok()?;
        (v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX)).then_some(v as u32)
    })
}

pub(super) fn parse_timestamp(cell: &str) -> Option<u64> {
    let v = cell.parse::<u64>().ok().or_else(|| {
        let v: f64 = cell.parse().ok()?;
        (v >= 0.0 && v.fract() == 0.0 && v <= MAX_TIMESTAMP_MS as f64).then_some(v as u64)
    })?;
    (v <= MAX_TIMESTAMP_MS).then_some(v)
}

/// The rate the timestamps give, unrounded: `None` for fewer than two samples or timestamps
/// that do not strictly increase.
pub fn estimate_sfreq(timestamps_ms: &[u64]) -> Option<f64> {
    let mut d: Vec<u64> = timestamps_ms
        .windows(2)
        .map(|w| w[1].checked_sub(w[0]).filter(|&d| d > 0))
        .collect::<Option<_>>()?;
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let m = *d.select_nth_unstable(mid).1 as f64;
    let (sum, count) = d
        .iter()
        .map(|&x| x as f64)
        .filter(|&x| x >= m / 2.0 && x <= 1.5 * m)
        .fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    Some(1000.0 * count as f64 / sum)
}

/// The estimate rounded to whole Hz (left as it is below 1 Hz).
pub(super) fn round_sfreq(f: f64) -> f64 {
    if f >= 1.0 {
        f.round()
    } else {
        f
    }
}

/// Parses the bytes of a `.easy` file and, when given, of its `.info` file (`(bytes, path)`);
/// the paths are used in error messages and the result.
pub fn parse_easy(
    bytes: &[u8],
    path: &Path,
    info: Option<(&[u8], &Path)>,
    options: &EasyOptions,
) -> Result<Recording, IoError> {
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    if let Some(f) = options.sfreq.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(unsupported(format!(
            "sampling rate {f} Hz in EasyOptions::sfreq"
        )));
    }
    if options.n_channels == Some(0) {
        return Err(unsupported("EasyOptions::n_channels = 0".into()));
    }
    if let Some(f) = options
        .scale_to_uv
        .filter(|f| !(f.is_finite() && *f != 0.0))
    {
        return Err(unsupported(format!("EasyOptions::scale_to_uv = {f}")));
    }
    let parsed = info.map(|(b, p)| parse_info(b, p)).transpose()?;
    // The parsed .info with its path, for errors that name it.
    let info_ref = parsed.as_ref().zip(info.map(|(_, p)| p));
    let scale = options
        .scale_to_uv
        .map(Scale::from_factor)
        .or(parsed.as_ref().and_then(|i| i.scale))
        .unwrap_or(Scale::DivideBy(1000.0));

    let ends_with_newline = bytes.last() == Some(&b'\n');
    let mut lines = bytes.split(|&b| b == b'\n').enumerate().peekable();

    // Set from the first data line.
    let mut layout: Option<EasyLayout> = None;
    let mut role: Vec<Role> = Vec::new();
    let mut fields: Vec<String> = Vec::new();
    let mut ch_names: Vec<String> = Vec::new();
    let mut first_line = 0usize;

    let mut eeg: Vec<Vec<f64>> = Vec::new();
    let mut acc: [Vec<f64>; 3] = Default::default();
    let mut add: Vec<f64> = Vec::new();
    let mut triggers: Vec<u32> = Vec::new();
    let mut timestamps: Vec<u64> = Vec::new();
    let mut events: Vec<Event> = Vec::new();
    let mut prev_trigger = 0u32;
    // The first line whose timestamp does not exceed the one before: (line, column, before, now).
    let mut not_increasing: Option<(usize, usize, u64, u64)> = None;
    let mut last_line = 0usize;

    let line_end_required = !ends_with_newline && options.require_final_newline;
    let truncated = |line_no, text: &str| {
        csv_err(
            path,
            line_no,
            text.split('\t').count(),
            "line end",
            "a line end after the last line (the file looks cut inside it)",
            shorten(text),
        )
    };
    while let Some((line_no, text)) =
        next_line(&mut lines, path, cell_column, line_end_required, truncated)?
    {
        let text = text.trim_end();
        last_line = line_no;
        let lay = match layout {
            Some(l) => l,
            None => {
                let l = resolve_layout(text.split('\t').count(), info_ref, options, path, line_no)?;
                ch_names = channel_names(&l, info_ref)?;
                role = roles(&l);
                fields = role
                    .iter()
                    .map(|r| match *r {
                        Role::Eeg(c) => format!("EEG channel {} ({})", c + 1, ch_names[c]),
                        Role::Acc(k) => format!("accelerometer {}", ["x", "y", "z"][k]),
                        Role::AddSensor => "AddSensor".into(),
                        Role::Trigger => "trigger".into(),
                        Role::Timestamp => "timestamp (ms)".into(),
                    })
                    .collect();
                let hint = bytes.len() / (8 * l.n_columns() + 1) + 1;
                eeg = (0..l.n_eeg).map(|_| Vec::with_capacity(hint)).collect();
                first_line = line_no;
                layout = Some(l);
                l
            }
        };
        let n_cols = lay.n_columns();
        let mut n_cells = 0usize;
        for (j, cell) in text.split('\t').enumerate() {
            n_cells += 1;
            if j >= n_cols {
                return Err(csv_err(
                    path,
                    line_no,
                    j + 1,
                    "line",
                    format!("{n_cols} cells, as on line {first_line}"),
                    format!("{} cells", text.split('\t').count()),
                ));
            }
            let cell = cell.trim();
            let bad = |expected: &str| {
                csv_err(
                    path,
                    line_no,
                    j + 1,
                    fields[j].clone(),
                    expected,
                    shorten(cell),
                )
            };
            match role[j] {
                Role::Eeg(c) => {
                    let v: f64 = cell
                        .parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?;
                    let uv = scale.to_uv(v);
                    if uv.abs() > MAX_ABS_UV {
                        return Err(bad(
                            "an EEG value within ±2147483647 nV (the int32 range, ±2.1 V)",
                        ));
                    }
                    eeg[c].push(uv);
                }
                Role::Acc(k) => acc[k].push(
                    cell.parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?,
                ),
                Role::AddSensor => add.push(
                    cell.parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad("a finite number"))?,
                ),
                Role::Trigger => {
                    let code = parse_trigger(cell)
                        .ok_or_else(|| bad("an integer trigger from 0 to 4294967295"))?;
                    if code != 0 && code != prev_trigger && !options.ignore_codes.contains(&code) {
                        events.push(marker_event(
                            triggers.len(),
                            code,
                            &options.target_codes,
                            &options.nontarget_codes,
                        ));
                    }
                    prev_trigger = code;
                    triggers.push(code);
                }
                Role::Timestamp => {
                    let ts = parse_timestamp(cell)
                        .ok_or_else(|| bad("an integer Unix time in ms from 0 to 2^53"))?;
                    if let Some(&prev) = timestamps.last() {
                        if ts <= prev && not_increasing.is_none() {
                            not_increasing = Some((line_no, j + 1, prev, ts));
                        }
                    }
                    timestamps.push(ts);
                }
            }
        }
        if n_cells < n_cols {
            return Err(csv_err(
                path,
                line_no,
                n_cells + 1,
                "line",
                format!("{n_cols} cells, as on line {first_line} (the line is too short)"),
                format!("{n_cells} cells"),
            ));
        }
    }
    let Some(layout) = layout else {
        return Err(csv_err(
            path,
            1,
            1,
            "data",
            "at least one sample line",
            if bytes.is_empty() {
                "an empty file"
            } else {
                "only blank lines"
            },
        ));
    };
    let n_times = timestamps.len();

    if let (true, Some((info, info_path))) = (options.check_record_count, info_ref) {
        if let Some(n) = info.n_records.filter(|n| n.value != n_times) {
            return Err(csv_err(
                path,
                last_line + 1,
                1,
                "data",
                format!(
                    "{} sample lines (\"Number of records of EEG\" in {} line {}; the .easy \
                     may be cut short)",
                    n.value,
                    info_path.display(),
                    n.line
                ),
                format!("{n_times} sample lines"),
            ));
        }
    }

    let estimated_sfreq = estimate_sfreq(&timestamps);
    let (sfreq, sfreq_source) = if let Some(f) = options.sfreq {
        (f, EasySfreqSource::Options)
    } else if let Some(f) = parsed.as_ref().and_then(|i| i.sfreq) {
        (f.value, EasySfreqSource::Info)
    } else if let Some(f) = estimated_sfreq {
        (round_sfreq(f), EasySfreqSource::Timestamps)
    } else {
        let ts_col = layout.n_columns();
        let why = "(no EasyOptions::sfreq and no \"EEG sampling rate\" in a .info, so the rate \
                   comes from the timestamps)";
        return Err(match not_increasing {
            Some((line, col, before, now)) => csv_err(
                path,
                line,
                col,
                "timestamp (ms)",
                format!("a timestamp after the previous line's {before} {why}"),
                now.to_string(),
            ),
            None => csv_err(
                path,
                last_line,
                ts_col,
                "timestamp (ms)",
                format!("at least two samples {why}"),
                format!("{n_times} sample"),
            ),
        });
    };

    let flat: Vec<f64> = eeg.into_iter().flatten().collect();
    let data = Array2::from_shape_vec((layout.n_eeg, n_times), flat).map_err(|e| {
        IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(".easy layout: {e}"),
        }
    })?;
    let accelerometer = if layout.accelerometer {
        let flat: Vec<f64> = acc.into_iter().flatten().collect();
        Some(
            Array2::from_shape_vec((3, n_times), flat).map_err(|e| IoError::Unsupported {
                path: path.to_path_buf(),
                what: format!(".easy accelerometer layout: {e}"),
            })?,
        )
    } else {
        None
    };
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    let (device_class, entries) = match parsed {
        Some(p) => (p.device_class, p.entries),
        None => (None, Vec::new()),
    };
    Ok(Recording {
        raw,
        format: Format::Easy,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Easy(EasyInfo {
            layout,
            device_class,
            accelerometer,
            add_sensor: layout.add_sensor.then_some(add),
            triggers,
            timestamps_ms: timestamps,
            sfreq_source,
            estimated_sfreq,
            info_path: info.map(|(_, p)| p.to_path_buf()),
            info: entries,
        }),
    })
}

/// `Ch1` … `ChN`, replaced by the `.info`'s names; a `.info` channel beyond `N` is an error.
pub(super) fn channel_names(
    layout: &EasyLayout,
    info: Option<(&ParsedInfo, &Path)>,
) -> Result<Vec<String>, IoError> {
    let mut names: Vec<String> = (1..=layout.n_eeg).map(|k| format!("Ch{k}")).collect();
    if let Some((info, info_path)) = info {
        for (k, name, line) in &info.names {
            if *k > layout.n_eeg {
                return Err(csv_err(
                    info_path,
                    *line,
                    1,
                    format!("Channel {k}"),
                    format!(
                        "a channel number from 1 to {} (the EEG columns of the .easy)",
                        layout.n_eeg
                    ),
                    format!("channel {k}"),
                ));
            }
            names[k - 1] = name.clone();
        }
    }
    Ok(names)
}
