//! Making a [`Recording`] of an XDF file: the EEG stream, clock synchronisation, markers as events.

use std::path::Path;

use oddball_signal::Event;

use crate::files::read_file;
use crate::units::stream_microvolts_per;
use crate::{Details, Format, IoError, Recording};

use super::info::{XdfInfo, XdfMarker};
use super::read::*;

/// How to read an XDF file into a [`Recording`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct XdfOptions {
    /// The name of the stream to read as EEG (default: see the module documentation).
    pub eeg_stream: Option<String>,
    /// Apply each stream's ClockOffsets (default true).
    pub synchronize_clocks: bool,
    /// Read a file that ends inside a chunk up to its last complete chunk (default true);
    /// otherwise such a file is an [`IoError::Truncated`].
    pub allow_truncated: bool,
}

impl Default for XdfOptions {
    fn default() -> Self {
        Self {
            eeg_stream: None,
            synchronize_clocks: true,
            allow_truncated: true,
        }
    }
}

/// Reads an XDF recording with default options (see the module documentation).
pub fn read_xdf(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_xdf_with(path, &XdfOptions::default())
}

/// Reads an XDF recording with the given options.
pub fn read_xdf_with(path: impl AsRef<Path>, options: &XdfOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_xdf_with(&bytes, path, options)
}

/// Parses the bytes of an XDF recording with default options; `path` is used in error messages
/// and the result.
pub fn parse_xdf(bytes: &[u8], path: &Path) -> Result<Recording, IoError> {
    parse_xdf_with(bytes, path, &XdfOptions::default())
}

/// `(a, b)` of the least-squares line `offset = a + b·t` through the finite clock offsets.
pub(super) fn clock_fit(offsets: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = offsets
        .iter()
        .copied()
        .filter(|(t, v)| t.is_finite() && v.is_finite())
        .collect();
    if pts.is_empty() {
        return None;
    }
    let n = pts.len() as f64;
    let mt = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let mv = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let stt: f64 = pts.iter().map(|p| (p.0 - mt) * (p.0 - mt)).sum();
    let stv: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
    let b = if stt > 0.0 { stv / stt } else { 0.0 };
    let (a, b) = (mv - b * mt, b);
    (a.is_finite() && b.is_finite()).then_some((a, b))
}

/// The number a text ends in, after a space, `_`, `:`, `=` or `#` (`flash 3` → 3).
pub(super) fn trailing_code(text: &str) -> Option<u32> {
    let t = text.trim_end();
    let digits = t.len() - t.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 || digits == t.len() {
        return None;
    }
    let before = t[..t.len() - digits].chars().next_back()?;
    if !(before.is_whitespace() || matches!(before, '_' | ':' | '=' | '#')) {
        return None;
    }
    t[t.len() - digits..].parse().ok()
}

pub(super) fn is_marker_type(t: &str) -> bool {
    let t = t.to_ascii_lowercase();
    ["marker", "event", "trigger", "stim"]
        .iter()
        .any(|k| t.contains(k))
}

/// The sample whose timestamp is nearest `t`; `None` outside the span (± half a sample).
pub(super) fn nearest_sample(times: &[f64], monotonic: bool, sfreq: f64, t: f64) -> Option<usize> {
    let (&first, &last) = (times.first()?, times.last()?);
    if !t.is_finite() {
        return None;
    }
    let half = 0.5 / sfreq;
    if monotonic {
        if t < first - half || t > last + half {
            return None;
        }
        let i = times.partition_point(|&x| x < t);
        if i == 0 {
            return Some(0);
        }
        if i == times.len() {
            return Some(times.len() - 1);
        }
        Some(if t - times[i - 1] <= times[i] - t {
            i - 1
        } else {
            i
        })
    } else {
        let pos = ((t - first) * sfreq).round();
        (pos >= 0.0 && pos < times.len() as f64).then_some(pos as usize)
    }
}

/// Parses the bytes of an XDF recording with the given options.
pub fn parse_xdf_with(
    bytes: &[u8],
    path: &Path,
    options: &XdfOptions,
) -> Result<Recording, IoError> {
    let mut file = parse_xdf_file(bytes, path)?;
    if file.truncated && !options.allow_truncated {
        let at = file.truncated_at.unwrap_or(0);
        return Err(IoError::Truncated {
            path: path.to_path_buf(),
            field: "chunk".into(),
            offset: at,
            needed: at + 1,
            file_len: file.file_len,
        });
    }
    let names: Vec<String> = file.streams.iter().map(|s| s.info.name.clone()).collect();
    let numeric = |s: &&XdfStreamData| s.info.format.is_numeric();
    let first_max = |it: &mut dyn Iterator<Item = usize>| -> Option<usize> {
        let mut best: Option<usize> = None;
        for k in it {
            if best.is_none_or(|b| {
                file.streams[k].info.channel_count > file.streams[b].info.channel_count
            }) {
                best = Some(k);
            }
        }
        best
    };
    let eeg = match &options.eeg_stream {
        Some(name) => file
            .streams
            .iter()
            .position(|s| &s.info.name == name && s.info.format.is_numeric())
            .ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "numeric XDF stream",
                name: name.clone(),
                available: names.clone(),
            })?,
        None => {
            let typed = first_max(
                &mut file
                    .streams
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| numeric(s) && s.info.stream_type.eq_ignore_ascii_case("EEG"))
                    .map(|(k, _)| k),
            );
            let regular = || {
                first_max(
                    &mut file
                        .streams
                        .iter()
                        .enumerate()
                        .filter(|(_, s)| numeric(s) && s.info.nominal_srate > 0.0)
                        .map(|(k, _)| k),
                )
            };
            typed.or_else(regular).ok_or_else(|| IoError::Missing {
                path: path.to_path_buf(),
                what: "XDF EEG stream",
                name: "type EEG or a regular-rate numeric stream".into(),
                available: names.clone(),
            })?
        }
    };
    let sfreq = file.streams[eeg].info.nominal_srate;
    if sfreq <= 0.0 {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "stream {:?} as EEG: its rate is irregular (nominal_srate 0)",
                file.streams[eeg].info.name
            ),
        });
    }

    // Clock synchronization.
    let mut synced: Vec<Vec<f64>> = Vec::with_capacity(file.streams.len());
    for s in &mut file.streams {
        let fit = if options.synchronize_clocks {
            clock_fit(&s.info.clock_offsets)
        } else {
            None
        };
        s.info.clock_fit = fit;
        synced.push(match fit {
            Some((a, b)) => s.timestamps.iter().map(|&t| t + a + b * t).collect(),
            None => s.timestamps.clone(),
        });
    }

    // The EEG.
    let eeg_stream = &file.streams[eeg];
    let n_ch = eeg_stream.info.channel_count;
    let XdfValues::Numeric(values) = &eeg_stream.values else {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "a string stream as EEG".into(),
        });
    };
    let mut data = values.clone();
    let mut eeg_units = Vec::with_capacity(n_ch);
    let mut scale_to_uv = Vec::with_capacity(n_ch);
    let mut ch_names = Vec::with_capacity(n_ch);
    for c in 0..n_ch {
        let label = eeg_stream
            .info
            .channel_labels
            .get(c)
            .map(|l| l.trim())
            .unwrap_or("");
        ch_names.push(if label.is_empty() {
            format!("Ch{}", c + 1)
        } else {
            label.to_string()
        });
        let unit = eeg_stream
            .info
            .channel_units
            .get(c)
            .cloned()
            .unwrap_or_default();
        let f = stream_microvolts_per(&unit).unwrap_or(1.0);
        if f != 1.0 {
            data.row_mut(c).mapv_inplace(|x| x * f);
        }
        eeg_units.push(unit);
        scale_to_uv.push(f);
    }
    let eeg_times = &synced[eeg];
    // Markers are placed by the EEG's timestamps: a non-finite one would drop every event.
    if let Some(i) = eeg_times.iter().position(|t| !t.is_finite()) {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "stream {:?} (EEG), sample {i}: timestamp {} is not a finite number, so no marker can be placed on it",
                file.streams[eeg].info.name, eeg_times[i]
            ),
        });
    }
    let monotonic = eeg_times.windows(2).all(|w| w[0] <= w[1]);

    // Markers.
    struct Raw1 {
        stream_id: u32,
        timestamp: f64,
        synced: f64,
        text: String,
    }
    let mut raw_markers = Vec::new();
    for (k, s) in file.streams.iter().enumerate() {
        if k == eeg {
            continue;
        }
        match &s.values {
            XdfValues::Strings(v) => {
                for (i, sample) in v.iter().enumerate() {
                    raw_markers.push(Raw1 {
                        stream_id: s.info.id,
                        timestamp: s.timestamps[i],
                        synced: synced[k][i],
                        text: sample.join("\t"),
                    });
                }
            }
            XdfValues::Numeric(a)
                if s.info.channel_count == 1
                    && s.info.nominal_srate == 0.0
                    && is_marker_type(&s.info.stream_type) =>
            {
                for (i, &x) in a.row(0).iter().enumerate() {
                    raw_markers.push(Raw1 {
                        stream_id: s.info.id,
                        timestamp: s.timestamps[i],
                        synced: synced[k][i],
                        text: format!("{x}"),
                    });
                }
            }
            XdfValues::Numeric(_) => {}
        }
    }
    // An oddball session's recording: its flashes carry their code and flag, and its other
    // markers (cues, decisions, trial records) are not stimuli (kept as markers, not events).
    let session = raw_markers
        .iter()
        .any(|m| super::session_markers::parse_flash_marker(&m.text).is_some());
    let parsed: Vec<Option<crate::edf::EventText>> = raw_markers
        .iter()
        .map(|m| {
            if let Some((code, attended)) = super::session_markers::parse_flash_marker(&m.text) {
                return Some((code, Some(attended), Some(m.text.clone())));
            }
            crate::edf::parse_event_text(&m.text)
                .or_else(|| trailing_code(&m.text).map(|c| (c, None, Some(m.text.clone()))))
        })
        .collect();
    let max_code = parsed.iter().flatten().map(|p| p.0).max().unwrap_or(0);
    let mut text_codes = crate::events::LabelCodes::after(max_code);
    let mut markers = Vec::with_capacity(raw_markers.len());
    let mut events = Vec::new();
    for (m, p) in raw_markers.into_iter().zip(parsed) {
        let (code, target, label) = match p {
            Some(p) => p,
            None => (text_codes.code(&m.text), None, Some(m.text.clone())),
        };
        if !m.synced.is_finite() {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                what: format!(
                    "marker {:?} of stream {}: timestamp {} is not a finite number",
                    crate::error::bounded(&m.text),
                    m.stream_id,
                    m.synced
                ),
            });
        }
        let sample = nearest_sample(eeg_times, monotonic, sfreq, m.synced);
        let stimulus = !session || target.is_some();
        if let (Some(onset), true) = (sample, stimulus) {
            events.push(Event {
                onset,
                code,
                target,
                label,
            });
        }
        markers.push(XdfMarker {
            stream_id: m.stream_id,
            timestamp: m.timestamp,
            text: m.text,
            code,
            target,
            sample,
        });
    }

    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    let eeg_timestamps = synced.swap_remove(eeg);
    let info = XdfInfo {
        version: file.version,
        header_xml: file.header_xml,
        streams: file.streams.into_iter().map(|s| s.info).collect(),
        eeg_stream: eeg,
        eeg_timestamps,
        eeg_units,
        scale_to_uv,
        markers,
        truncated: file.truncated,
        truncated_at: file.truncated_at,
        n_chunks: file.n_chunks,
        n_boundaries: file.n_boundaries,
        n_unknown_chunks: file.n_unknown_chunks,
    };
    Ok(Recording {
        raw,
        format: Format::Xdf,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Xdf(Box::new(info)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marker_texts() {
        assert_eq!(
            crate::edf::parse_event_text("3 target: Ä b"),
            Some((3, Some(true), Some("Ä b".into())))
        );
        assert_eq!(crate::edf::parse_event_text("12"), Some((12, None, None)));
        assert_eq!(crate::edf::parse_event_text("flash 3"), None);
        assert_eq!(trailing_code("flash 3"), Some(3));
        assert_eq!(trailing_code("S  12"), Some(12));
        assert_eq!(trailing_code("stim:7"), Some(7));
        assert_eq!(trailing_code("P300"), None);
        assert_eq!(trailing_code("-1"), None);
        assert_eq!(trailing_code("42"), None);
        assert_eq!(trailing_code("flash 99999999999"), None);
    }

    #[test]
    fn clock_fits() {
        assert_eq!(clock_fit(&[]), None);
        assert_eq!(clock_fit(&[(5.0, 0.25)]), Some((0.25, 0.0)));
        let (a, b) = clock_fit(&[(0.0, 1.0), (10.0, 2.0), (20.0, 3.0)]).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 0.1).abs() < 1e-12);
    }

    #[test]
    fn nearest() {
        let t = [1.0, 1.5, 2.0, 3.0];
        assert_eq!(nearest_sample(&t, true, 2.0, 1.2), Some(0));
        assert_eq!(nearest_sample(&t, true, 2.0, 1.3), Some(1));
        assert_eq!(nearest_sample(&t, true, 2.0, 2.6), Some(3));
        assert_eq!(nearest_sample(&t, true, 2.0, 0.75), Some(0));
        assert_eq!(nearest_sample(&t, true, 2.0, 0.7499), None);
        assert_eq!(nearest_sample(&t, true, 2.0, 3.3), None);
        assert_eq!(nearest_sample(&t, true, 2.0, f64::NAN), None);
        assert_eq!(nearest_sample(&[], true, 2.0, 1.0), None);
        assert_eq!(nearest_sample(&[2.0, 1.0], false, 1.0, 2.0), Some(0));
    }
}
