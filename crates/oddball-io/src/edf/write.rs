//! Writing EDF+ (`write_edf_plus`).

use std::path::Path;

use oddball_signal::Raw;

use crate::IoError;

use super::annotations::*;

// ---------------------------------------------------------------------------------------------
// Writer

/// Start date and time written into an EDF+ header (local time of the recording).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdfStart {
    /// 1985..=2084 (EDF stores two digits).
    pub year: u16,
    pub month: u8,
    pub day: u8,
    pub hour: u8,
    pub minute: u8,
    pub second: u8,
}

/// Header text of [`write_edf_plus_with`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdfWriteOptions {
    /// EDF+ patient field: `code sex birthdate name`, `X` for unknown subfields.
    pub patient: String,
    /// EDF+ recording subfields after the start date: `admincode technician equipment`.
    pub recording: String,
    /// Start of the recording; `None` writes EDF+'s "unknown" date 01.01.85 00.00.00.
    pub start: Option<EdfStart>,
}

impl Default for EdfWriteOptions {
    fn default() -> Self {
        Self {
            patient: "X X X X".to_string(),
            recording: "X X oddball".to_string(),
            start: None,
        }
    }
}

/// What [`write_edf_plus`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct EdfWriteSummary {
    pub n_records: usize,
    /// Seconds per data record.
    pub record_duration: f64,
    pub samples_per_record: usize,
    /// Samples appended after the last real sample to fill the last record (copies of the
    /// last sample of each channel); a reader gets `n_times + padded_samples` samples back.
    pub padded_samples: usize,
    /// Bytes of the `EDF Annotations` signal per record.
    pub annotation_bytes: usize,
}

/// Formats `v` in at most 8 characters, rounded down (`up == false`) or up, so that the
/// written value still bounds `v`.
pub(super) fn fmt8_outward(v: f64, up: bool) -> Option<String> {
    for prec in (0..=7usize).rev() {
        let scale = 10f64.powi(prec as i32);
        let r = if up {
            (v * scale).ceil() / scale
        } else {
            (v * scale).floor() / scale
        };
        let s = format!("{r:.prec$}");
        if s.len() > 8 {
            continue;
        }
        let back: f64 = s.parse().ok()?;
        if (up && back >= v) || (!up && back <= v) {
            return Some(s);
        }
    }
    None
}

pub(super) fn put(buf: &mut Vec<u8>, text: &str, width: usize) {
    let mut b: Vec<u8> = text.bytes().take(width).collect();
    b.resize(width, b' ');
    buf.extend_from_slice(&b);
}

/// Writes `raw` as an EDF+C file with its events as annotations (see [`write_edf_plus_with`]).
pub fn write_edf_plus(path: impl AsRef<Path>, raw: &Raw) -> Result<EdfWriteSummary, IoError> {
    write_edf_plus_with(path, raw, &EdfWriteOptions::default())
}

/// Writes `raw` as an EDF+C file: 16-bit samples in µV with each channel's physical range set
/// to its own data range (rounded outward to fit the 8-character fields), so the quantisation
/// step is `(max − min) / 65535` per channel; one `EDF Annotations` signal with each event as
/// [`event_annotation_text`]. Data records last the shortest whole number of seconds (1..=60)
/// that holds a whole number of samples; the last record is padded by repeating the last sample.
pub fn write_edf_plus_with(
    path: impl AsRef<Path>,
    raw: &Raw,
    options: &EdfWriteOptions,
) -> Result<EdfWriteSummary, IoError> {
    let path = path.as_ref();
    let unsupported = |what: String| IoError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    crate::writing::check_not_empty(path, raw, "EDF+")?;
    let (n_ch, n_times) = (raw.n_channels(), raw.n_times());
    let sfreq = raw.sfreq();
    let (duration, spr) = (1..=60u32)
        .find_map(|d| {
            let n = sfreq * d as f64;
            let r = n.round();
            ((n - r).abs() <= 1e-9 * n.max(1.0) && r >= 1.0).then_some((d, r as usize))
        })
        .ok_or_else(|| {
            unsupported(format!(
                "sampling rate {sfreq} Hz: no record of 1 to 60 s holds a whole number of samples"
            ))
        })?;
    let n_records = n_times.div_ceil(spr);
    let padded = n_records * spr - n_times;
    let data = raw.data();

    // Channel headers.
    let mut ranges = Vec::with_capacity(n_ch);
    for (c, name) in raw.ch_names().iter().enumerate() {
        if name.len() > 16 || !name.bytes().all(|b| (32..127).contains(&b)) {
            return Err(unsupported(format!(
                "channel name {name:?}: EDF labels are at most 16 printable ASCII characters"
            )));
        }
        let row = data.row(c);
        if let Some(t) = row.iter().position(|v| !v.is_finite()) {
            return Err(unsupported(format!(
                "channel {name} sample {t} is {}: EDF stores finite values only",
                row[t]
            )));
        }
        let (lo, hi) = row
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 1.0, hi + 1.0)
        };
        let (Some(lo_s), Some(hi_s)) = (fmt8_outward(lo, false), fmt8_outward(hi, true)) else {
            return Err(unsupported(format!(
                "channel {name} range {lo}..{hi} µV does not fit EDF's 8-character fields"
            )));
        };
        let (pmin, pmax): (f64, f64) = (lo_s.parse().unwrap_or(lo), hi_s.parse().unwrap_or(hi));
        ranges.push((lo_s, hi_s, pmin, pmax));
    }

    // Annotations per record.
    let mut tal_bytes: Vec<Vec<u8>> = vec![Vec::new(); n_records];
    for (r, tb) in tal_bytes.iter_mut().enumerate() {
        tb.extend_from_slice(format!("+{}\x14\x14\x00", r as u64 * duration as u64).as_bytes());
    }
    for e in raw.events() {
        let text = event_annotation_text(e);
        if text.bytes().any(|b| b < 32 && b != b'\t') {
            return Err(unsupported(format!(
                "event at sample {} has a control character in its text {text:?}",
                e.onset
            )));
        }
        let onset = e.onset as f64 / sfreq;
        let tb = &mut tal_bytes[e.onset / spr];
        tb.extend_from_slice(format!("+{onset}\x14{text}\x14\x00").as_bytes());
    }
    let ann_bytes = tal_bytes
        .iter()
        .map(Vec::len)
        .max()
        .unwrap_or(0)
        .div_ceil(2)
        * 2;
    let ann_spr = ann_bytes / 2;

    // Header.
    let ns = n_ch + 1;
    let fits = |what: &str, text: &str, width: usize| {
        if text.len() <= width && text.bytes().all(|b| (32..127).contains(&b)) {
            Ok(())
        } else {
            Err(unsupported(format!(
                "{what} {text:?}: EDF allows at most {width} printable ASCII characters here"
            )))
        }
    };
    fits("number of signals", &ns.to_string(), 4)?;
    fits("samples per data record", &spr.max(ann_spr).to_string(), 8)?;
    fits("patient", &options.patient, 80)?;
    let mut buf: Vec<u8> =
        Vec::with_capacity(256 * (ns + 1) + n_records * (n_ch * spr + ann_spr) * 2);
    put(&mut buf, "0", 8);
    put(&mut buf, &options.patient, 80);
    let (date, time, rec_date) = match options.start {
        None => (
            "01.01.85".to_string(),
            "00.00.00".to_string(),
            "X".to_string(),
        ),
        Some(s) => {
            let valid = (1985..=2084).contains(&s.year)
                && (1..=12).contains(&s.month)
                && (1..=31).contains(&s.day)
                && s.hour < 24
                && s.minute < 60
                && s.second < 60;
            if !valid {
                return Err(unsupported(format!("start date/time {s:?}")));
            }
            const MONTHS: [&str; 12] = [
                "JAN", "FEB", "MAR", "APR", "MAY", "JUN", "JUL", "AUG", "SEP", "OCT", "NOV", "DEC",
            ];
            (
                format!("{:02}.{:02}.{:02}", s.day, s.month, s.year % 100),
                format!("{:02}.{:02}.{:02}", s.hour, s.minute, s.second),
                format!("{:02}-{}-{}", s.day, MONTHS[s.month as usize - 1], s.year),
            )
        }
    };
    let recording = format!("Startdate {rec_date} {}", options.recording);
    fits("recording", &recording, 80)?;
    put(&mut buf, &recording, 80);
    put(&mut buf, &date, 8);
    put(&mut buf, &time, 8);
    put(&mut buf, &(256 * (ns + 1)).to_string(), 8);
    put(&mut buf, "EDF+C", 44);
    let n_rec_s = n_records.to_string();
    if n_rec_s.len() > 8 {
        return Err(unsupported(format!(
            "{n_records} data records (EDF allows 8 digits)"
        )));
    }
    put(&mut buf, &n_rec_s, 8);
    put(&mut buf, &duration.to_string(), 8);
    put(&mut buf, &ns.to_string(), 4);
    let ann_label = "EDF Annotations";
    for name in raw.ch_names() {
        put(&mut buf, name, 16);
    }
    put(&mut buf, ann_label, 16);
    for _ in 0..ns {
        put(&mut buf, "", 80);
    }
    for _ in 0..n_ch {
        put(&mut buf, "uV", 8);
    }
    put(&mut buf, "", 8);
    for r in &ranges {
        put(&mut buf, &r.0, 8);
    }
    put(&mut buf, "-1", 8);
    for r in &ranges {
        put(&mut buf, &r.1, 8);
    }
    put(&mut buf, "1", 8);
    for _ in 0..ns {
        put(&mut buf, "-32768", 8);
    }
    for _ in 0..ns {
        put(&mut buf, "32767", 8);
    }
    for _ in 0..ns {
        put(&mut buf, "", 80);
    }
    for _ in 0..n_ch {
        put(&mut buf, &spr.to_string(), 8);
    }
    put(&mut buf, &ann_spr.to_string(), 8);
    for _ in 0..ns {
        put(&mut buf, "", 32);
    }

    // Records.
    for (r, tb) in tal_bytes.iter().enumerate() {
        for (c, &(_, _, pmin, pmax)) in ranges.iter().enumerate() {
            let row = data.row(c);
            let k = 65535.0 / (pmax - pmin);
            for t in r * spr..(r + 1) * spr {
                let v = row[t.min(n_times - 1)];
                let dig = ((v - pmin) * k).round() - 32768.0;
                let dig = dig.clamp(-32768.0, 32767.0) as i16;
                buf.extend_from_slice(&dig.to_le_bytes());
            }
        }
        let start = buf.len();
        buf.extend_from_slice(tb);
        buf.resize(start + ann_bytes, 0);
    }
    crate::write_atomic(path, &buf)?;
    Ok(EdfWriteSummary {
        n_records,
        record_duration: duration as f64,
        samples_per_record: spr,
        padded_samples: padded,
        annotation_bytes: ann_bytes,
    })
}
