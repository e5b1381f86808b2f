//! The EDF/BDF header: the fixed part and the signal headers, each field checked.

use crate::IoError;

use super::types::*;

pub(super) const FIXED: usize = 256;
/// Signal header fields: name, width.
pub(super) const SIGNAL_FIELDS: [(&str, usize); 10] = [
    ("label", 16),
    ("transducer type", 80),
    ("physical dimension", 8),
    ("physical minimum", 8),
    ("physical maximum", 8),
    ("digital minimum", 8),
    ("digital maximum", 8),
    ("prefiltering", 80),
    ("samples per data record", 8),
    ("reserved", 32),
];

/// The file's bytes and path ([`crate::bytes::FileBytes`]: its errors and reads).
pub(super) type Ctx<'a> = crate::bytes::FileBytes<'a>;

impl Ctx<'_> {
    /// An ASCII header field (Latin-1, trailing spaces and NULs trimmed).
    pub(super) fn ascii(&self, off: usize, len: usize) -> String {
        self.bytes[off..off + len]
            .iter()
            .map(|&b| b as char)
            .collect::<String>()
            .trim_end_matches([' ', '\0'])
            .trim_start()
            .to_string()
    }

    /// A numeric field: printable ASCII, parsed after trimming.
    pub(super) fn number<T: std::str::FromStr>(
        &self,
        field: &str,
        off: usize,
        len: usize,
        expected: &str,
    ) -> Result<T, IoError> {
        let raw = &self.bytes[off..off + len];
        let text: String = raw.iter().map(|&b| b as char).collect();
        if raw.iter().any(|&b| !(b == 0 || (32..127).contains(&b))) {
            return Err(self.invalid(field, off, expected, text));
        }
        text.trim_end_matches([' ', '\0'])
            .trim()
            .parse::<T>()
            .map_err(|_| self.invalid(field, off, expected, text.trim_end().to_string()))
    }
}

/// Parses the header of an EDF/BDF file: `(header, is_bdf)`.
pub(super) fn parse_header(ctx: &Ctx<'_>) -> Result<(EdfHeader, bool), IoError> {
    let b = ctx.bytes;
    if b.len() < FIXED {
        return Err(ctx.truncated("fixed header (256 bytes)", 0, FIXED as u64));
    }
    let is_bdf = b[0] == 0xFF && &b[1..8] == b"BIOSEMI";
    if !is_bdf && ctx.ascii(0, 8) != "0" {
        return Err(ctx.invalid(
            "version",
            0,
            "`0` (EDF) or `\\xFFBIOSEMI` (BDF)",
            ctx.ascii(0, 8),
        ));
    }
    let header_bytes: usize = ctx.number("number of bytes in header", 184, 8, "an integer")?;
    let n_records: i64 = ctx.number(
        "number of data records",
        236,
        8,
        "an integer (-1 if unknown)",
    )?;
    let record_duration: f64 =
        ctx.number("duration of a data record", 244, 8, "seconds as a number")?;
    let ns: usize = ctx.number("number of signals", 252, 4, "a positive integer")?;
    if ns == 0 {
        return Err(ctx.invalid("number of signals", 252, "a positive integer", "0"));
    }
    let needed = ns
        .checked_add(1)
        .and_then(|n| n.checked_mul(FIXED))
        .ok_or_else(|| ctx.invalid("number of signals", 252, "a signal count", ns.to_string()))?;
    if header_bytes != needed {
        return Err(ctx.invalid(
            "number of bytes in header",
            184,
            format!("256 × (1 + {ns} signals) = {needed}"),
            header_bytes.to_string(),
        ));
    }
    if b.len() < needed {
        return Err(ctx.truncated(
            format!("signal headers ({ns} signals × 256 bytes)"),
            FIXED,
            needed as u64,
        ));
    }
    if !(record_duration.is_finite() && record_duration > 0.0) {
        return Err(ctx.invalid(
            "duration of a data record",
            244,
            "a positive number of seconds",
            ctx.ascii(244, 8),
        ));
    }
    if n_records < -1 || n_records == 0 {
        return Err(ctx.invalid(
            "number of data records",
            236,
            "a positive count, or -1 while recording",
            n_records.to_string(),
        ));
    }

    let (dig_lo, dig_hi) = if is_bdf {
        (-8_388_608, 8_388_607)
    } else {
        (-32_768, 32_767)
    };
    let mut starts = [0usize; 10];
    let mut acc = FIXED;
    for (k, &(_, w)) in SIGNAL_FIELDS.iter().enumerate() {
        starts[k] = acc;
        acc += ns * w;
    }
    let at = |k: usize, i: usize| starts[k] + i * SIGNAL_FIELDS[k].1;
    let mut signals = Vec::with_capacity(ns);
    for i in 0..ns {
        let label = ctx.ascii(at(0, i), 16);
        let name = |k: usize| format!("signal {} ({label}) {}", i + 1, SIGNAL_FIELDS[k].0);
        let physical_min: f64 = ctx.number(&name(3), at(3, i), 8, "a number")?;
        let physical_max: f64 = ctx.number(&name(4), at(4, i), 8, "a number")?;
        let digital_min: i32 = ctx.number(&name(5), at(5, i), 8, "an integer")?;
        let digital_max: i32 = ctx.number(&name(6), at(6, i), 8, "an integer")?;
        let spr: usize = ctx.number(&name(8), at(8, i), 8, "a positive integer")?;
        if !(physical_min.is_finite() && physical_max.is_finite()) || physical_min == physical_max {
            return Err(ctx.invalid(
                name(4),
                at(4, i),
                format!("a finite number different from the physical minimum {physical_min}"),
                ctx.ascii(at(4, i), 8),
            ));
        }
        if !(dig_lo..=dig_hi).contains(&digital_min) {
            return Err(ctx.invalid(
                name(5),
                at(5, i),
                format!("an integer in {dig_lo}..={dig_hi}"),
                digital_min.to_string(),
            ));
        }
        if !(dig_lo..=dig_hi).contains(&digital_max) || digital_max <= digital_min {
            return Err(ctx.invalid(
                name(6),
                at(6, i),
                format!("an integer above the digital minimum {digital_min}, at most {dig_hi}"),
                digital_max.to_string(),
            ));
        }
        if spr == 0 {
            return Err(ctx.invalid(name(8), at(8, i), "a positive integer", "0"));
        }
        signals.push(EdfSignal {
            transducer: ctx.ascii(at(1, i), 80),
            dimension: ctx.ascii(at(2, i), 8),
            physical_min,
            physical_max,
            digital_min,
            digital_max,
            prefiltering: ctx.ascii(at(7, i), 80),
            samples_per_record: spr,
            reserved: ctx.ascii(at(9, i), 32),
            label,
        });
    }

    // Record layout against the file length.
    let bps = if is_bdf { 3 } else { 2 };
    let record_bytes = signals
        .iter()
        .try_fold(0usize, |a, s| a.checked_add(s.samples_per_record))
        .and_then(|n| n.checked_mul(bps))
        .ok_or_else(|| {
            ctx.invalid(
                "samples per data record",
                starts[8],
                "sizes that fit in memory",
                "overflow",
            )
        })?;
    let data_len = b.len() - header_bytes;
    // The data record the file cuts short (of `n` when the header says how many there are).
    let cut_record = |n: Option<usize>| {
        let k = data_len / record_bytes;
        let off = header_bytes + k * record_bytes;
        let what = match n {
            None => format!("data record {k} ({record_bytes} bytes)"),
            Some(n) => format!("data record {k} of {n} ({record_bytes} bytes)"),
        };
        ctx.truncated(what, off, (off + record_bytes) as u64)
    };
    let n_records = if n_records == -1 {
        if data_len == 0 || data_len % record_bytes != 0 {
            return Err(cut_record(None));
        }
        data_len / record_bytes
    } else {
        let n = n_records as usize;
        let expected = n.checked_mul(record_bytes);
        match expected {
            Some(e) if e == data_len => n,
            Some(e) if e < data_len => {
                return Err(ctx.invalid(
                    "number of data records",
                    236,
                    format!(
                        "{n} records × {record_bytes} bytes = {e} bytes after the header, as the file has"
                    ),
                    format!("{data_len} bytes after the header"),
                ))
            }
            _ => return Err(cut_record(Some(n))),
        }
    };
    Ok((
        EdfHeader {
            version: if is_bdf {
                "BIOSEMI".to_string()
            } else {
                "0".to_string()
            },
            patient: ctx.ascii(8, 80),
            recording: ctx.ascii(88, 80),
            start_date: ctx.ascii(168, 8),
            start_time: ctx.ascii(176, 8),
            header_bytes,
            reserved: ctx.ascii(192, 44),
            n_records,
            record_duration,
            signals,
        },
        is_bdf,
    ))
}
