//! Reading the chunks of an XDF file into its streams ([`XdfFile`]).

use std::collections::BTreeMap;
use std::path::Path;

use ndarray::Array2;

use crate::files::read_file;
use crate::IoError;

use super::acc::{Acc, Ctx};
use super::chunk::*;
use super::cut::{check_cut_chunk, check_footer_count};
use super::types::*;

/// A stream's values.
#[derive(Debug, Clone, PartialEq)]
pub enum XdfValues {
    /// `(n_channels, n_samples)`, as stored (no unit conversion).
    Numeric(Array2<f64>),
    /// `[sample][channel]`.
    Strings(Vec<Vec<String>>),
}

/// One stream with its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfStreamData {
    pub info: XdfStreamInfo,
    /// One per sample, as in the file (or deduced; see the module documentation).
    pub timestamps: Vec<f64>,
    pub values: XdfValues,
}

/// Every chunk of an XDF file, by stream.
#[derive(Debug, Clone, PartialEq)]
pub struct XdfFile {
    /// The FileHeader XML, when the file has one.
    pub header_xml: Option<String>,
    /// The FileHeader's `version`.
    pub version: Option<String>,
    /// In the order of their StreamHeaders.
    pub streams: Vec<XdfStreamData>,
    /// Complete chunks read (all tags).
    pub n_chunks: usize,
    pub n_boundaries: usize,
    /// Complete chunks with a tag this reader does not know (skipped).
    pub n_unknown_chunks: usize,
    /// The file ends inside a chunk (or inside the magic code).
    pub truncated: bool,
    /// Where the incomplete chunk starts.
    pub truncated_at: Option<u64>,
    pub file_len: u64,
}

impl XdfFile {
    /// The stream with this id.
    pub fn stream(&self, id: u32) -> Option<&XdfStreamData> {
        self.streams.iter().find(|s| s.info.id == id)
    }

    /// The first stream with this name.
    pub fn stream_named(&self, name: &str) -> Option<&XdfStreamData> {
        self.streams.iter().find(|s| s.info.name == name)
    }
}

pub(super) fn parse_f64_text(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok()
}

pub(super) fn parse_stream_header(
    ctx: &Ctx<'_>,
    id: u32,
    xml: &[u8],
    base: usize,
) -> Result<XdfStreamInfo, IoError> {
    let (text, root) = ctx.xml(xml, base, "StreamHeader")?;
    let field = |name: &str| format!("StreamHeader (stream {id}) {name}");
    if root.name != "info" {
        return Err(ctx.invalid(
            base,
            field("root element"),
            "<info>",
            format!("<{}>", root.name),
        ));
    }
    let required = |name: &str| {
        root.child(name)
            .ok_or_else(|| ctx.invalid(base, field(name), format!("a <{name}> element"), "none"))
    };
    let cc = required("channel_count")?;
    let channel_count = cc
        .text
        .trim()
        .parse::<usize>()
        .ok()
        .filter(|&n| (1..=MAX_CHANNELS).contains(&n))
        .ok_or_else(|| {
            ctx.invalid(
                base + cc.text_offset,
                field("channel_count"),
                format!("a whole number from 1 to {MAX_CHANNELS}"),
                cc.text.trim(),
            )
        })?;
    let sr = required("nominal_srate")?;
    let nominal_srate = parse_f64_text(&sr.text)
        .filter(|r| r.is_finite() && *r >= 0.0)
        .ok_or_else(|| {
            ctx.invalid(
                base + sr.text_offset,
                field("nominal_srate"),
                "a finite rate >= 0 (0 = irregular)",
                sr.text.trim(),
            )
        })?;
    let cf = required("channel_format")?;
    let format = XdfFormat::from_name(&cf.text).ok_or_else(|| {
        ctx.invalid(
            base + cf.text_offset,
            field("channel_format"),
            "int8, int16, int32, int64, float32, double64 or string",
            cf.text.trim(),
        )
    })?;
    let text_of = |name: &str| root.child_text(name).unwrap_or("").to_string();
    let mut labels = Vec::new();
    let mut units = Vec::new();
    let mut types = Vec::new();
    if let Some(chs) = root.child("desc").and_then(|d| d.child("channels")) {
        for ch in chs.children_named("channel") {
            labels.push(ch.child_text("label").unwrap_or("").to_string());
            units.push(ch.child_text("unit").unwrap_or("").to_string());
            types.push(ch.child_text("type").unwrap_or("").to_string());
        }
    }
    Ok(XdfStreamInfo {
        id,
        name: text_of("name"),
        stream_type: text_of("type"),
        channel_count,
        nominal_srate,
        format,
        source_id: text_of("source_id"),
        created_at: root.child_text("created_at").and_then(parse_f64_text),
        channel_labels: labels,
        channel_units: units,
        channel_types: types,
        header_xml: text,
        n_samples: 0,
        n_sample_chunks: 0,
        first_timestamp: None,
        last_timestamp: None,
        clock_offsets: Vec::new(),
        clock_fit: None,
        footer: None,
    })
}

/// A StreamFooter, and the file offset of its `sample_count` text when it has one.
pub(super) fn parse_footer(
    ctx: &Ctx<'_>,
    id: u32,
    xml: &[u8],
    base: usize,
) -> Result<(XdfFooter, Option<usize>), IoError> {
    let (text, root) = ctx.xml(xml, base, "StreamFooter")?;
    let num = |name: &str| -> Result<Option<f64>, IoError> {
        match root.child(name) {
            None => Ok(None),
            Some(n) => parse_f64_text(&n.text).map(Some).ok_or_else(|| {
                ctx.invalid(
                    base + n.text_offset,
                    format!("StreamFooter (stream {id}) {name}"),
                    "a number",
                    n.text.trim(),
                )
            }),
        }
    };
    let first_timestamp = num("first_timestamp")?;
    let last_timestamp = num("last_timestamp")?;
    let sample_count = match root.child("sample_count") {
        None => None,
        Some(n) => Some(n.text.trim().parse::<u64>().map_err(|_| {
            ctx.invalid(
                base + n.text_offset,
                format!("StreamFooter (stream {id}) sample_count"),
                "a whole number",
                n.text.trim(),
            )
        })?),
    };
    let count_at = root.child("sample_count").map(|n| base + n.text_offset);
    Ok((
        XdfFooter {
            first_timestamp,
            last_timestamp,
            sample_count,
            xml: text,
        },
        count_at,
    ))
}

/// Parses a Samples chunk's content (after the stream id, which starts at file offset `base`).
pub(super) fn parse_samples(
    ctx: &Ctx<'_>,
    content: &[u8],
    base: usize,
    acc: &mut Acc,
) -> Result<(), IoError> {
    let id = acc.info.id;
    let field = |what: String| format!("Samples (stream {id}) {what}");
    let (n, mut p) = varlen(content, 4).map_err(|(at, found)| {
        ctx.invalid(
            base + at,
            field("NumSamples".into()),
            "a varlen integer (1, 4 or 8 bytes)",
            found,
        )
    })?;
    let n_ch = acc.info.channel_count;
    let format = acc.info.format;
    let min_per_sample = 1 + n_ch * format.value_bytes().unwrap_or(2);
    let room = (content.len() - p) / min_per_sample;
    if n > room as u64 {
        return Err(ctx.invalid(
            base + 4,
            field("NumSamples".into()),
            format!(
                "at most {room} samples of {n_ch} {} channels in the {} bytes left in the chunk",
                format.name(),
                content.len() - p
            ),
            n.to_string(),
        ));
    }
    let n = n as usize;
    acc.timestamps.reserve(n);
    if format.is_numeric() {
        acc.numeric.reserve(n * n_ch);
    } else {
        acc.strings.reserve(n);
    }
    let vb = format.value_bytes().unwrap_or(0);
    for k in 0..n {
        let tsb = content[p];
        let ts = match tsb {
            0 => {
                p += 1;
                acc.last_ts + acc.tdiff
            }
            8 => {
                if p + 9 > content.len() {
                    return Err(ctx.invalid(
                        base + p,
                        field(format!("sample {k} timestamp")),
                        "8 bytes inside the chunk",
                        "the end of the chunk",
                    ));
                }
                let t = le_f64(content, p + 1);
                p += 9;
                t
            }
            other => {
                return Err(ctx.invalid(
                    base + p,
                    field(format!("sample {k} TimeStampBytes")),
                    "0 or 8",
                    other.to_string(),
                ))
            }
        };
        acc.last_ts = ts;
        acc.timestamps.push(ts);
        if format.is_numeric() {
            let need = n_ch * vb;
            let vals = content.get(p..p + need).ok_or_else(|| {
                ctx.invalid(
                    base + p,
                    field(format!("sample {k} values")),
                    format!("{need} bytes inside the chunk"),
                    format!("{} bytes", content.len() - p),
                )
            })?;
            for v in vals.chunks_exact(vb) {
                let x = match format {
                    XdfFormat::Int8 => f64::from(v[0] as i8),
                    XdfFormat::Int16 => f64::from(i16::from_le_bytes([v[0], v[1]])),
                    XdfFormat::Int32 => f64::from(i32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                    XdfFormat::Int64 => le_u64(v) as i64 as f64,
                    XdfFormat::Float32 => f64::from(f32::from_le_bytes([v[0], v[1], v[2], v[3]])),
                    _ => le_f64(v, 0),
                };
                acc.numeric.push(x);
            }
            p += need;
        } else {
            let mut sample = Vec::with_capacity(n_ch);
            for c in 0..n_ch {
                let (len, q) = varlen(content, p).map_err(|(at, found)| {
                    ctx.invalid(
                        base + at,
                        field(format!("sample {k} channel {c} string length")),
                        "a varlen integer (1, 4 or 8 bytes)",
                        found,
                    )
                })?;
                let left = content.len() - q;
                if len > left as u64 {
                    return Err(ctx.invalid(
                        base + p,
                        field(format!("sample {k} channel {c} string length")),
                        format!("at most the {left} bytes left in the chunk"),
                        len.to_string(),
                    ));
                }
                let len = len as usize;
                sample.push(String::from_utf8_lossy(&content[q..q + len]).into_owned());
                p = q + len;
            }
            acc.strings.push(sample);
        }
        if k + 1 < n && p >= content.len() {
            return Err(ctx.invalid(
                base + p,
                field(format!("sample {}", k + 1)),
                format!("{n} samples inside the chunk"),
                "the end of the chunk",
            ));
        }
    }
    if p != content.len() {
        return Err(ctx.invalid(
            base + p,
            field("end".into()),
            format!("the chunk to end after its {n} samples"),
            format!("{} more bytes", content.len() - p),
        ));
    }
    acc.info.n_samples += n;
    acc.info.n_sample_chunks += 1;
    Ok(())
}

/// Reads an XDF file (every stream with its samples).
pub fn read_xdf_file(path: impl AsRef<Path>) -> Result<XdfFile, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    parse_xdf_file(&bytes, path)
}

/// Parses the bytes of an XDF file; `path` is used in error messages. A file that ends inside a
/// chunk gives every complete chunk and [`XdfFile::truncated`].
pub fn parse_xdf_file(bytes: &[u8], path: &Path) -> Result<XdfFile, IoError> {
    let ctx = Ctx { path };
    let len = bytes.len();
    let mut out = XdfFile {
        header_xml: None,
        version: None,
        streams: Vec::new(),
        n_chunks: 0,
        n_boundaries: 0,
        n_unknown_chunks: 0,
        truncated: false,
        truncated_at: None,
        file_len: len as u64,
    };
    if len < MAGIC.len() && MAGIC.starts_with(bytes) {
        out.truncated = true;
        out.truncated_at = Some(0);
        return Ok(out);
    }
    if len < MAGIC.len() || &bytes[..4] != MAGIC {
        return Err(ctx.invalid(
            0,
            "magic code",
            "\"XDF:\"",
            String::from_utf8_lossy(&bytes[..len.min(4)]),
        ));
    }
    let mut accs: Vec<Acc> = Vec::new();
    let mut index: BTreeMap<u32, usize> = BTreeMap::new();
    let mut pos = MAGIC.len();
    while pos < len {
        let start = pos;
        let nlb = bytes[pos];
        if !matches!(nlb, 1 | 4 | 8) {
            return Err(ctx.invalid(pos, "chunk NumLengthBytes", "1, 4 or 8", nlb.to_string()));
        }
        let nlb = nlb as usize;
        let header_end = pos + 1 + nlb;
        if header_end + 2 > len {
            out.truncated = true;
            out.truncated_at = Some(start as u64);
            break;
        }
        let length = le_u64(&bytes[pos + 1..header_end]);
        if length < 2 {
            return Err(ctx.invalid(
                pos + 1,
                "chunk Length",
                "at least 2 (the tag)",
                length.to_string(),
            ));
        }
        if length > (len - header_end) as u64 {
            // A chunk the file's end cuts: a recorder stopped while writing it, unless its
            // bytes say the file goes on past it (then its Length is corrupt).
            check_cut_chunk(&ctx, bytes, start, header_end, length, &index, &accs)?;
            out.truncated = true;
            out.truncated_at = Some(start as u64);
            break;
        }
        let end = header_end + length as usize;
        let tag = u16::from_le_bytes([bytes[header_end], bytes[header_end + 1]]);
        let cbase = header_end + 2;
        let content = &bytes[cbase..end];
        let stream_id = |what: &str| -> Result<u32, IoError> {
            if content.len() < 4 {
                return Err(ctx.invalid(
                    cbase,
                    format!("{what} StreamId"),
                    "4 bytes inside the chunk",
                    format!("{} bytes", content.len()),
                ));
            }
            Ok(le_u32(content, 0))
        };
        let known = |id: u32, what: &str, index: &BTreeMap<u32, usize>| -> Result<usize, IoError> {
            index.get(&id).copied().ok_or_else(|| {
                ctx.invalid(
                    cbase,
                    format!("{what} StreamId"),
                    "the id of a stream whose StreamHeader came before",
                    id.to_string(),
                )
            })
        };
        match tag {
            TAG_FILE_HEADER => {
                if out.header_xml.is_some() {
                    return Err(ctx.invalid(
                        start,
                        "FileHeader",
                        "one FileHeader chunk",
                        "a second one",
                    ));
                }
                let (text, root) = ctx.xml(content, cbase, "FileHeader")?;
                out.version = root.child_text("version").map(str::to_string);
                out.header_xml = Some(text);
            }
            TAG_STREAM_HEADER => {
                let id = stream_id("StreamHeader")?;
                if index.contains_key(&id) {
                    return Err(ctx.invalid(
                        cbase,
                        "StreamHeader StreamId",
                        "one StreamHeader per stream",
                        format!("a second one for stream {id}"),
                    ));
                }
                let info = parse_stream_header(&ctx, id, &content[4..], cbase + 4)?;
                let tdiff = if info.nominal_srate > 0.0 {
                    1.0 / info.nominal_srate
                } else {
                    0.0
                };
                index.insert(id, accs.len());
                accs.push(Acc {
                    info,
                    timestamps: Vec::new(),
                    numeric: Vec::new(),
                    strings: Vec::new(),
                    last_ts: 0.0,
                    tdiff,
                    footer_count_at: None,
                });
            }
            TAG_SAMPLES => {
                let id = stream_id("Samples")?;
                let k = known(id, "Samples", &index)?;
                parse_samples(&ctx, content, cbase, &mut accs[k])?;
            }
            TAG_CLOCK_OFFSET => {
                let id = stream_id("ClockOffset")?;
                let k = known(id, "ClockOffset", &index)?;
                if content.len() != 20 {
                    return Err(ctx.invalid(
                        start,
                        "ClockOffset chunk Length",
                        "22 (tag, StreamId, two f64)",
                        (content.len() + 2).to_string(),
                    ));
                }
                accs[k]
                    .info
                    .clock_offsets
                    .push((le_f64(content, 4), le_f64(content, 12)));
            }
            TAG_BOUNDARY => {
                if content != BOUNDARY_UUID {
                    return Err(ctx.invalid(
                        cbase,
                        "Boundary chunk",
                        "the 16 Boundary bytes 43 A5 46 DC …",
                        format!("{} other bytes", content.len()),
                    ));
                }
                out.n_boundaries += 1;
            }
            TAG_STREAM_FOOTER => {
                let id = stream_id("StreamFooter")?;
                let k = known(id, "StreamFooter", &index)?;
                if accs[k].info.footer.is_some() {
                    return Err(ctx.invalid(
                        cbase,
                        "StreamFooter StreamId",
                        "one StreamFooter per stream",
                        format!("a second one for stream {id}"),
                    ));
                }
                let (footer, count_at) = parse_footer(&ctx, id, &content[4..], cbase + 4)?;
                accs[k].info.footer = Some(footer);
                accs[k].footer_count_at = count_at;
            }
            _ => out.n_unknown_chunks += 1,
        }
        out.n_chunks += 1;
        pos = end;
    }

    for acc in &accs {
        check_footer_count(&ctx, acc)?;
    }
    for acc in accs {
        let Acc {
            mut info,
            timestamps,
            numeric,
            strings,
            ..
        } = acc;
        info.first_timestamp = timestamps.first().copied();
        info.last_timestamp = timestamps.last().copied();
        let values = if info.format.is_numeric() {
            let n_ch = info.channel_count;
            let n_s = timestamps.len();
            let a = Array2::from_shape_vec((n_s, n_ch), numeric)
                .map_err(|e| ctx.invalid(0, "Samples", "whole samples", e.to_string()))?;
            XdfValues::Numeric(a.reversed_axes().as_standard_layout().into_owned())
        } else {
            XdfValues::Strings(strings)
        };
        out.streams.push(XdfStreamData {
            info,
            timestamps,
            values,
        });
    }
    Ok(out)
}
