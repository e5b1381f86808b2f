//! Reading a GDF 1.x / 2.x file: header, data records, event table into a
//! [`Recording`].

use std::path::Path;

use ndarray::Array2;

use crate::files::read_file;
use crate::units::microvolts_per;
use crate::{Details, Format, IoError, Recording};

use super::events::{parse_event_table, table_events};
use super::header::*;
use super::types::*;

/// Reads a GDF 1.x or 2.x file with default options.
pub fn read_gdf(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    read_gdf_with(path, &GdfOptions::default())
}

/// Reads a GDF 1.x or 2.x file.
pub fn read_gdf_with(path: impl AsRef<Path>, options: &GdfOptions) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_gdf(&bytes, path, options)
}

/// Parses the bytes of a GDF file; `path` is used in error messages and the result.
pub fn parse_gdf(bytes: &[u8], path: &Path, options: &GdfOptions) -> Result<Recording, IoError> {
    let ctx = Ctx { path, bytes };
    let header = parse_header(&ctx)?;

    // Which channels are kept: one rate for all.
    let mut dropped = Vec::new();
    let mut chosen: Vec<usize> = Vec::new();
    let mut rate: Option<(usize, usize)> = None; // (channel index, samples per record)
    for (i, ch) in header.channels.iter().enumerate() {
        if options.exclude.iter().any(|e| e == &ch.label) {
            continue;
        }
        let spr = ch.samples_per_record;
        match rate {
            None if spr > 0 => {
                rate = Some((i, spr));
                chosen.push(i);
            }
            Some((_, first)) if first == spr => chosen.push(i),
            _ if options.drop_mismatched_rates => dropped.push(ch.label.clone()),
            None => {
                return Err(IoError::Unsupported {
                    path: path.to_path_buf(),
                    what: format!(
                        "channel {} ({}) has 0 samples per data record \
                         (set GdfOptions::drop_mismatched_rates to drop it)",
                        i + 1,
                        ch.label
                    ),
                })
            }
            Some((first, spr0)) => {
                return Err(IoError::Unsupported {
                    path: path.to_path_buf(),
                    what: format!(
                        "channel {} ({}) has {spr} samples per data record but channel {} ({}) has \
                         {spr0}: mixed sample rates (set GdfOptions::drop_mismatched_rates to drop \
                         the others)",
                        i + 1,
                        ch.label,
                        first + 1,
                        header.channels[first].label
                    ),
                })
            }
        }
    }
    let Some((_, spr)) = rate else {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "no channel with samples left (all excluded or dropped)".to_string(),
        });
    };
    let (num, den) = header.record_duration;
    let sfreq = spr as f64 * f64::from(den) / f64::from(num);
    if oddball_signal::check_sfreq(sfreq).is_err() {
        return Err(ctx.invalid(
            "duration of a data record",
            244,
            format!("a duration giving 0.1 Hz to 1 MHz with {spr} samples per record"),
            format!("{num}/{den} s"),
        ));
    }

    // The layout of a record: every channel, kept or not, in turn.
    let mut ch_off = Vec::with_capacity(header.channels.len());
    let mut record_bytes: u64 = 0;
    for ch in &header.channels {
        ch_off.push(record_bytes as usize);
        // ≤ 2³² samples × 8 bytes per channel, ≤ 2³² channels: no u64 overflow.
        record_bytes += ch.samples_per_record as u64 * ch.data_type.bytes() as u64;
    }
    let data_end = (header.n_records as u64)
        .checked_mul(record_bytes)
        .and_then(|d| d.checked_add(header.header_bytes as u64))
        .filter(|&end| end <= bytes.len() as u64)
        .ok_or_else(|| {
            ctx.truncated(
                format!("data records ({} × {record_bytes} bytes)", header.n_records),
                header.header_bytes,
                (header.n_records as u128 * record_bytes as u128 + header.header_bytes as u128)
                    .min(u64::MAX as u128) as u64,
            )
        })? as usize;
    // The data fit in the file, so neither product below can overflow or be absurd: each kept
    // sample takes at least one byte of it.
    let record_bytes = record_bytes as usize;
    let n_times = header.n_records * spr;
    let n_ch = chosen.len();

    // Scaling per kept channel: ((digital − dmin) × gain + pmin) × µV per unit.
    let mut non_voltage = Vec::new();
    let scales: Vec<(f64, f64, f64, f64)> = chosen
        .iter()
        .map(|&i| {
            let ch = &header.channels[i];
            let unit = microvolts_per(&ch.dimension).unwrap_or_else(|| {
                non_voltage.push(ch.label.clone());
                1.0
            });
            let gain = (ch.physical_max - ch.physical_min) / (ch.digital_max - ch.digital_min);
            (ch.digital_min, gain, ch.physical_min, unit)
        })
        .collect();

    let mut data = vec![0.0f64; n_ch * n_times];
    for (c, &i) in chosen.iter().enumerate() {
        let (dmin, gain, pmin, unit) = scales[c];
        let ty = header.channels[i].data_type;
        let w = ty.bytes();
        let row = &mut data[c * n_times..(c + 1) * n_times];
        for r in 0..header.n_records {
            let start = header.header_bytes + r * record_bytes + ch_off[i];
            let src = &bytes[start..start + spr * w];
            for (d, s) in row[r * spr..(r + 1) * spr]
                .iter_mut()
                .zip(src.chunks_exact(w))
            {
                *d = ((ty.decode(s) - dmin) * gain + pmin) * unit;
            }
        }
    }

    let (event_table, trailing_bytes) = parse_event_table(&ctx, header.major, data_end)?;
    let made = table_events(event_table.as_ref(), sfreq, n_times);

    let ch_names: Vec<String> = chosen
        .iter()
        .map(|&i| header.channels[i].label.clone())
        .collect();
    let data = Array2::from_shape_vec((n_ch, n_times), data).map_err(|e| IoError::Unsupported {
        path: path.to_path_buf(),
        what: format!("data layout: {e}"),
    })?;
    let raw = crate::error::new_raw(path, data, sfreq, ch_names, made.events)?;
    Ok(Recording {
        raw,
        format: Format::Gdf,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Gdf(Box::new(GdfInfo {
            header,
            event_table,
            events_outside: made.outside,
            openvibe: made.openvibe,
            trailing_bytes,
            dropped_channels: dropped,
            non_voltage_channels: non_voltage,
        })),
    })
}
