//! Reading an EDF/EDF+/BDF/BDF+ file: header, data records, annotations as events.

use std::path::Path;

use ndarray::Array2;
use oddball_signal::Event;

use crate::files::read_file;
use crate::units::microvolts_per;
use crate::{Details, Format, IoError, Recording};

use super::annotations::*;
use super::header::*;
use super::types::*;

/// Reads an EDF, EDF+, BDF or BDF+ file with default options.
pub fn read_edf(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_edf_with(path, &EdfOptions::default())
}

/// Reads an EDF, EDF+, BDF or BDF+ file (the kind is taken from the header, not the extension).
pub fn read_edf_with(path: impl AsRef<Path>, options: &EdfOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_edf(&bytes, path, options)
}

/// Parses the bytes of an EDF/EDF+/BDF/BDF+ file; `path` is used in error messages and the result.
pub fn parse_edf(bytes: &[u8], path: &Path, options: &EdfOptions) -> Result<Recording, IoError> {
    let ctx = Ctx { path, bytes };
    let (header, is_bdf) = parse_header(&ctx)?;
    let bps = if is_bdf { 3 } else { 2 };
    let reserved = header.reserved.as_str();
    let plus = reserved.starts_with("EDF+") || reserved.starts_with("BDF+");
    let discontinuous = reserved.starts_with("EDF+D") || reserved.starts_with("BDF+D");
    let format = match (is_bdf, plus) {
        (false, false) => Format::Edf,
        (false, true) => Format::EdfPlus,
        (true, false) => Format::Bdf,
        (true, true) => Format::BdfPlus,
    };

    // Which signals become channels.
    let mut dropped = Vec::new();
    let mut chosen: Vec<usize> = Vec::new();
    let mut rate: Option<(usize, usize)> = None; // (signal index, samples per record)
    for (i, s) in header.signals.iter().enumerate() {
        if s.is_annotation() || options.exclude.iter().any(|e| e == &s.label) {
            continue;
        }
        match rate {
            None => {
                rate = Some((i, s.samples_per_record));
                chosen.push(i);
            }
            Some((_, spr)) if spr == s.samples_per_record => chosen.push(i),
            Some(_) if options.drop_mismatched_rates => dropped.push(s.label.clone()),
            Some((first, spr)) => {
                return Err(IoError::Unsupported {
                    path: path.to_path_buf(),
                    what: format!(
                        "signal {} ({}) has {} samples per data record but signal {} ({}) has {spr}: \
                         mixed sample rates (set EdfOptions::drop_mismatched_rates to drop the others)",
                        i + 1,
                        s.label,
                        s.samples_per_record,
                        first + 1,
                        header.signals[first].label
                    ),
                })
            }
        }
    }
    let Some((_, spr)) = rate else {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "no data signals (only annotations or excluded signals)".to_string(),
        });
    };
    let sfreq = spr as f64 / header.record_duration;
    if oddball_signal::check_sfreq(sfreq).is_err() {
        return Err(ctx.invalid(
            "duration of a data record",
            244,
            format!("a duration giving 0.1 Hz to 1 MHz with {spr} samples per record"),
            header.record_duration.to_string(),
        ));
    }

    // Scaling per chosen channel.
    let mut non_voltage = Vec::new();
    let scales: Vec<(f64, f64, f64)> = chosen
        .iter()
        .map(|&i| {
            let s = &header.signals[i];
            let unit = microvolts_per(&s.dimension).unwrap_or_else(|| {
                non_voltage.push(s.label.clone());
                1.0
            });
            let gain = (s.physical_max - s.physical_min) / (s.digital_max - s.digital_min) as f64;
            (s.digital_min as f64, gain, unit)
        })
        .collect();

    // Byte offset of each signal inside a record.
    let mut sig_off = Vec::with_capacity(header.signals.len());
    let mut acc = 0usize;
    for s in &header.signals {
        sig_off.push(acc);
        acc += s.samples_per_record * bps;
    }
    let record_bytes = acc;
    let n_times = header.n_records * spr;
    let n_ch = chosen.len();
    let mut data = vec![0.0f64; n_ch * n_times];
    let ann_signals: Vec<usize> = (0..header.signals.len())
        .filter(|&i| header.signals[i].is_annotation())
        .collect();
    let mut tals_all: Vec<(usize, Tal)> = Vec::new(); // (record, tal)
    let mut record_starts: Vec<f64> = Vec::new();
    // Byte offset of each record's time-keeping annotation.
    let mut stamp_offsets: Vec<usize> = Vec::new();

    for r in 0..header.n_records {
        let base = header.header_bytes + r * record_bytes;
        for (c, &i) in chosen.iter().enumerate() {
            let (dmin, gain, unit) = scales[c];
            let pmin = header.signals[i].physical_min;
            let start = base + sig_off[i];
            let src = &bytes[start..start + spr * bps];
            let dst = &mut data[c * n_times + r * spr..c * n_times + (r + 1) * spr];
            if is_bdf {
                for (d, s) in dst.iter_mut().zip(src.chunks_exact(3)) {
                    let dig = (i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8) as f64;
                    *d = ((dig - dmin) * gain + pmin) * unit;
                }
            } else {
                for (d, s) in dst.iter_mut().zip(src.chunks_exact(2)) {
                    let dig = i16::from_le_bytes([s[0], s[1]]) as f64;
                    *d = ((dig - dmin) * gain + pmin) * unit;
                }
            }
        }
        for (k, &i) in ann_signals.iter().enumerate() {
            let start = base + sig_off[i];
            let len = header.signals[i].samples_per_record * bps;
            let mut tals = parse_tals(&ctx, &bytes[start..start + len], start, r)?;
            if k == 0 && plus {
                // The first TAL of the first annotation signal is the record's time stamp.
                if tals.is_empty() || tals[0].2.first().is_none_or(|t| !t.is_empty()) {
                    return Err(ctx.invalid(
                        format!("time-keeping annotation of data record {r}"),
                        start,
                        "a first TAL `+seconds\\x14\\x14`",
                        tals.first()
                            .map(|t| format!("{:?}", t.2))
                            .unwrap_or_else(|| "no TAL".into()),
                    ));
                }
                let mut stamp = tals.remove(0);
                record_starts.push(stamp.0);
                stamp_offsets.push(start);
                stamp.2.remove(0);
                if !stamp.2.is_empty() {
                    tals.insert(0, stamp);
                }
            }
            tals_all.extend(tals.into_iter().map(|t| (r, t)));
        }
    }

    let start_offset = record_starts.first().copied().unwrap_or(0.0);
    if !discontinuous {
        // EDF+C: every record starts where the one before ended. A stamp that says otherwise
        // is corrupt, and the events timed from it would silently fall outside the recording.
        let half = 0.5 / sfreq;
        for (r, (&t, &at)) in record_starts.iter().zip(&stamp_offsets).enumerate() {
            let expected = start_offset + r as f64 * header.record_duration;
            if !t.is_finite() || t.abs() > 1e9 || (t - expected).abs() > half {
                return Err(ctx.invalid(
                    format!("time stamp of data record {r}"),
                    at,
                    if r == 0 {
                        "a start time in seconds (EDF+C: contiguous records)".to_string()
                    } else {
                        format!("+{expected} (EDF+C: contiguous records)")
                    },
                    format!("{t}"),
                ));
            }
        }
    }
    if discontinuous {
        let half = 0.5 / sfreq;
        for (r, &t) in record_starts.iter().enumerate() {
            let expected = start_offset + r as f64 * header.record_duration;
            if (t - expected).abs() > half {
                return Err(IoError::Unsupported {
                    path: path.to_path_buf(),
                    what: format!(
                        "EDF+D with a gap: data record {r} starts at {t} s, not {expected} s"
                    ),
                });
            }
        }
    }

    // Annotations and events.
    let annotations: Vec<Annotation> = tals_all
        .iter()
        .flat_map(|(_, (onset, duration, texts))| {
            texts.iter().map(move |t| Annotation {
                onset: *onset,
                duration: *duration,
                text: t.clone(),
            })
        })
        .collect();
    let (texts, label_codes) = text_codes(annotations.iter().map(|a| a.text.as_str()), 0);
    let mut events = Vec::new();
    for (a, (code, target, label)) in annotations.iter().zip(texts) {
        let pos = ((a.onset - start_offset) * sfreq).round();
        if pos >= 0.0 && pos < n_times as f64 {
            events.push(Event {
                onset: pos as usize,
                code,
                target,
                label,
            });
        }
    }

    let ch_names: Vec<String> = chosen
        .iter()
        .map(|&i| header.signals[i].label.clone())
        .collect();
    let data = Array2::from_shape_vec((n_ch, n_times), data).map_err(|e| IoError::Unsupported {
        path: path.to_path_buf(),
        what: format!("data layout: {e}"),
    })?;
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, events)?;
    Ok(Recording {
        raw,
        format,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Edf(Box::new(EdfInfo {
            header,
            annotations,
            label_codes,
            start_offset,
            dropped_signals: dropped,
            non_voltage_signals: non_voltage,
        })),
    })
}
