//! Reading a BrainVision recording: the header's settings and channels, the binary data file,
//! the markers as events.

use std::path::{Component, Path, PathBuf};

use crate::files::read_file;
use crate::units::microvolts_per;
use crate::{Details, Format, IoError, Recording};
use ndarray::Array2;

use super::ini::{self, Ini};
use super::types::*;

const COMMON: &str = "Common Infos";

/// Reads a BrainVision recording from its header (`.vhdr`), with the data file and the marker
/// file the header names, both beside it.
pub fn read_brainvision(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let header = read_file(path)?;
    let ini = ini::parse(&header, path, "Header")?;
    let data_path = data_file(&ini)?;
    let data = read_file(&data_path)?;
    let markers = match linked_file(&ini, "MarkerFile")? {
        Some(p) => Some(read_file(&p)?),
        None => None,
    };
    build(&ini, &data, markers.as_deref())
}

/// Parses a BrainVision recording from the bytes of its header, data file and marker file
/// (`None`: no markers); `path` is the header's path, which the header's file names are
/// relative to (used in messages and in the result only: nothing is read).
pub fn parse_brainvision(
    header: &[u8],
    path: &Path,
    data: &[u8],
    markers: Option<&[u8]>,
) -> Result<Recording, IoError> {
    let ini = ini::parse(header, path, "Header")?;
    build(&ini, data, markers)
}

/// The data file the header names; an absent or empty `DataFile` is an error.
fn data_file(ini: &Ini<'_>) -> Result<PathBuf, IoError> {
    match linked_file(ini, "DataFile")? {
        Some(p) => Ok(p),
        None => Err(match ini.get(COMMON, "DataFile") {
            Some(e) => ini.invalid(
                format!("[{COMMON}] DataFile"),
                e.value_at,
                "a file name",
                "",
            ),
            None => ini.missing(COMMON, "DataFile"),
        }),
    }
}

/// The file a `[Common Infos]` entry names (`DataFile`, `MarkerFile`), relative to the
/// header's folder; `None` when the entry is absent or empty. A name that leaves the folder
/// (absolute, or with a `..` part) is refused.
fn linked_file(ini: &Ini<'_>, key: &str) -> Result<Option<PathBuf>, IoError> {
    let Some(e) = ini.get(COMMON, key) else {
        return Ok(None);
    };
    let name = ini.text(e);
    if name.is_empty() {
        return Ok(None);
    }
    let rel = Path::new(&name);
    if !rel.components().all(|c| matches!(c, Component::Normal(_))) {
        return Err(ini.invalid(
            format!("[{COMMON}] {key}"),
            e.value_at,
            "a file name relative to the header's folder (no root, no `..`)",
            name,
        ));
    }
    let dir = ini.path.parent().unwrap_or(Path::new(""));
    Ok(Some(dir.join(rel)))
}

fn build(ini: &Ini<'_>, data: &[u8], markers: Option<&[u8]>) -> Result<Recording, IoError> {
    let path = ini.path;
    let (format_text, at) = ini.require(COMMON, "DataFormat")?;
    if format_text.eq_ignore_ascii_case("ASCII") {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "BrainVision ASCII data (DataFormat=ASCII); only BINARY is read".into(),
        });
    }
    if !format_text.eq_ignore_ascii_case("BINARY") {
        return Err(ini.invalid(format!("[{COMMON}] DataFormat"), at, "BINARY", format_text));
    }
    let orientation = match ini.get(COMMON, "DataOrientation") {
        None => BvOrientation::Multiplexed,
        Some(e) => match ini.text(e).to_ascii_uppercase().as_str() {
            "MULTIPLEXED" => BvOrientation::Multiplexed,
            "VECTORIZED" => BvOrientation::Vectorized,
            other => {
                return Err(ini.invalid(
                    format!("[{COMMON}] DataOrientation"),
                    e.value_at,
                    "MULTIPLEXED or VECTORIZED",
                    other,
                ))
            }
        },
    };
    let (bf, at) = ini.require("Binary Infos", "BinaryFormat")?;
    let binary_format = match bf.to_ascii_uppercase().as_str() {
        "INT_16" => BvBinaryFormat::Int16,
        "INT_32" => BvBinaryFormat::Int32,
        "IEEE_FLOAT_32" => BvBinaryFormat::Float32,
        _ => {
            return Err(ini.invalid(
                "[Binary Infos] BinaryFormat",
                at,
                "INT_16, INT_32 or IEEE_FLOAT_32",
                bf,
            ))
        }
    };
    if let Some(e) = ini.get("Binary Infos", "UseBigEndianOrder") {
        if ini.text(e).eq_ignore_ascii_case("YES") {
            return Err(IoError::Unsupported {
                path: path.to_path_buf(),
                what: "big-endian BrainVision data (UseBigEndianOrder=YES)".into(),
            });
        }
    }
    let (interval_text, at) = ini.require(COMMON, "SamplingInterval")?;
    let interval: f64 = interval_text
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && *v > 0.0)
        .ok_or_else(|| {
            ini.invalid(
                format!("[{COMMON}] SamplingInterval"),
                at,
                "a positive number of microseconds",
                interval_text.clone(),
            )
        })?;
    let channels = channels(ini)?;
    let n_ch = channels.len();

    // The data file: exactly n_channels × n_times values.
    let frame = n_ch * binary_format.size();
    let data_points = match ini.get(COMMON, "DataPoints") {
        None => None,
        Some(e) => Some(ini.text(e).parse::<usize>().map_err(|_| {
            ini.invalid(
                format!("[{COMMON}] DataPoints"),
                e.value_at,
                "a whole number of samples",
                ini.text(e),
            )
        })?),
    };
    let n_times = data.len() / frame;
    let data_name = data_file(ini)?;
    let short = |n_times: usize, needed: u64| IoError::Truncated {
        path: data_name.clone(),
        field: match orientation {
            BvOrientation::Multiplexed => format!(
                "sample {n_times} ({n_ch} channels × {} bytes of {})",
                binary_format.size(),
                binary_format.name()
            ),
            BvOrientation::Vectorized => format!(
                "VECTORIZED data of {n_ch} channels × {} bytes of {}",
                binary_format.size(),
                binary_format.name()
            ),
        },
        offset: match orientation {
            BvOrientation::Multiplexed => (n_times * frame) as u64,
            BvOrientation::Vectorized => data.len() as u64,
        },
        needed,
        file_len: data.len() as u64,
    };
    let n_times = match data_points {
        Some(dp) => {
            let needed = (dp as u64).saturating_mul(frame as u64);
            if (data.len() as u64) < needed {
                return Err(short(n_times, needed));
            }
            if (data.len() as u64) > needed {
                return Err(IoError::invalid_field(
                    &data_name,
                    format!("end of the data ([{COMMON}] DataPoints={dp})"),
                    needed,
                    "the end of the file",
                    format!("{} more bytes", data.len() as u64 - needed),
                ));
            }
            dp
        }
        None => {
            if data.len() % frame != 0 {
                return Err(short(n_times, ((n_times + 1) * frame) as u64));
            }
            n_times
        }
    };

    let mut non_voltage = Vec::new();
    let scales: Vec<f64> = channels
        .iter()
        .map(|c| {
            let unit = if c.unit.trim().is_empty() {
                1.0
            } else {
                microvolts_per(&c.unit).unwrap_or_else(|| {
                    non_voltage.push(c.name.clone());
                    1.0
                })
            };
            c.resolution * unit
        })
        .collect();
    let mut values = vec![0.0f64; n_ch * n_times];
    let size = binary_format.size();
    for (k, chunk) in data.chunks_exact(size).enumerate() {
        let v = match binary_format {
            BvBinaryFormat::Int16 => f64::from(i16::from_le_bytes([chunk[0], chunk[1]])),
            BvBinaryFormat::Int32 => {
                f64::from(i32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]))
            }
            BvBinaryFormat::Float32 => {
                f64::from(f32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]))
            }
        };
        let (c, t) = match orientation {
            BvOrientation::Multiplexed => (k % n_ch, k / n_ch),
            BvOrientation::Vectorized => (k / n_times, k % n_times),
        };
        values[c * n_times + t] = v * scales[c];
    }

    let marker_file = linked_file(ini, "MarkerFile")?;
    let (markers, events, label_codes) = match markers {
        None => (Vec::new(), Vec::new(), Default::default()),
        Some(bytes) => {
            let mpath = marker_file
                .clone()
                .unwrap_or_else(|| path.with_extension("vmrk"));
            super::markers::parse_markers(bytes, &mpath, n_times)?
        }
    };

    let sfreq = rate_of_interval(interval);
    let ch_names: Vec<String> = channels.iter().map(|c| c.name.clone()).collect();
    let values =
        Array2::from_shape_vec((n_ch, n_times), values).map_err(|e| IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!("data layout: {e}"),
        })?;
    let raw = crate::error::new_raw(path, values, sfreq, ch_names, events)?;
    Ok(Recording {
        raw,
        format: Format::BrainVision,
        path: path.to_path_buf(),
        speller: None,
        details: Details::BrainVision(Box::new(BrainVisionInfo {
            version_line: ini.first_line.clone(),
            encoding: ini.encoding.name().to_string(),
            data_file: data_name,
            marker_file,
            binary_format,
            orientation,
            sampling_interval_us: interval,
            channels,
            markers,
            label_codes,
            non_voltage_channels: non_voltage,
        })),
    })
}

/// The rate of a `SamplingInterval` of `interval` µs: the rate of at most six decimals whose
/// interval (10⁶ / rate, as a writer computes it) is exactly `interval`, the fewest decimals
/// first; else 10⁶ / `interval`. So the 240 Hz that pybv and oddball write as
/// `4166.666666666667` µs reads back as 240, not 239.99999999999997.
pub(super) fn rate_of_interval(interval: f64) -> f64 {
    let rate = 1e6 / interval;
    (0..=6)
        .map(|d| {
            let scale = 10f64.powi(d);
            (rate * scale).round() / scale
        })
        .find(|&r| r > 0.0 && 1e6 / r == interval)
        .unwrap_or(rate)
}

/// `[Channel Infos]`: `Ch1` … `ChN` for `NumberOfChannels` = N, each
/// `Name,Reference,Resolution,Unit`.
fn channels(ini: &Ini<'_>) -> Result<Vec<BvChannel>, IoError> {
    let (n_text, at) = ini.require(COMMON, "NumberOfChannels")?;
    let entries: Vec<_> = ini.section("Channel Infos").collect();
    let n = n_text
        .parse::<usize>()
        .ok()
        .filter(|&n| n >= 1 && n <= entries.len())
        .ok_or_else(|| {
            ini.invalid(
                format!("[{COMMON}] NumberOfChannels"),
                at,
                format!(
                    "a number of channels from 1 to the {} entries of [Channel Infos]",
                    entries.len()
                ),
                n_text.clone(),
            )
        })?;
    let mut out = Vec::with_capacity(n);
    for i in 1..=n {
        let key = format!("Ch{i}");
        let Some(e) = entries.iter().find(|e| e.key.eq_ignore_ascii_case(&key)) else {
            return Err(IoError::Missing {
                path: ini.path.to_path_buf(),
                what: "BrainVision channel",
                name: format!("[Channel Infos] {key} (NumberOfChannels={n})"),
                available: entries.iter().map(|e| e.key.clone()).take(20).collect(),
            });
        };
        let f = ini.fields(e);
        let name = f[0].text.clone();
        if name.trim().is_empty() {
            return Err(ini.invalid(
                format!("[Channel Infos] {key} name"),
                f[0].at,
                "a channel name",
                name,
            ));
        }
        let reference = f.get(1).map(|x| x.text.clone()).unwrap_or_default();
        let resolution = match f.get(2) {
            None => 1.0,
            Some(r) if r.text.trim().is_empty() => 1.0,
            Some(r) => r
                .text
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    ini.invalid(
                        format!("[Channel Infos] {key} resolution"),
                        r.at,
                        "a number (units per stored value)",
                        r.text.clone(),
                    )
                })?,
        };
        let unit = f
            .get(3)
            .map(|x| x.text.trim().to_string())
            .unwrap_or_default();
        out.push(BvChannel {
            name,
            reference,
            resolution,
            unit,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::rate_of_interval;

    #[test]
    fn a_written_interval_reads_back_as_its_rate() {
        for rate in [
            240.0,
            220.0,
            250.0,
            256.0,
            512.0,
            1000.0,
            7.0,
            119.5,
            2048.0,
            1e6 / 3.0,
        ] {
            assert_eq!(rate_of_interval(1e6 / rate), rate, "{rate}");
        }
        assert_eq!(1e6 / (1e6 / 240.0), 239.99999999999997);
        // An interval no short rate gives: 10⁶ / interval as it is.
        assert_eq!(rate_of_interval(1953.1249), 1e6 / 1953.1249);
        // A rate with more than six decimals is the division's.
        let odd = 123.123_456_789_f64;
        assert!((rate_of_interval(1e6 / odd) - odd).abs() < 1e-9);
    }
}
