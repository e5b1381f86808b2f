//! The measurement info (`FIFFB_MEAS_INFO`: channel count, rate, channel records, date) and the
//! MNE annotations (`FIFFB_MNE_ANNOTATIONS`) of a FIF file.

use crate::IoError;

use super::tags::*;
use super::types::FifChannel;

/// Size of a `fiffChInfoRec`: scanNo, logNo, kind (i32), range, cal (f32), coil_type (i32),
/// loc[12] (f32), unit, unit_mul (i32), ch_name[16].
const CH_INFO_SIZE: usize = 96;

/// What the measurement info gives the reader.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Meas {
    pub sfreq: f64,
    pub channels: Vec<FifChannel>,
    /// Byte offset of each channel's `FIFF_CH_INFO` tag, for messages.
    pub channel_pos: Vec<usize>,
    /// Byte offset of each channel's range and cal: in its record, or the extended block's
    /// `FIFF_CH_CAL` / `FIFF_CH_RANGE` tag that replaced them.
    pub scale_pos: Vec<usize>,
    /// (seconds, microseconds).
    pub meas_date: Option<(i64, i64)>,
}

/// The one `FIFFB_MEAS` block and its one `FIFFB_MEAS_INFO` (MNE refuses none or several).
pub(super) fn meas_blocks<'a>(
    ctx: &Ctx<'_>,
    root: &'a Node,
) -> Result<(&'a Node, &'a Node), IoError> {
    let one = |parent: &'a Node, k: i32, what: &str| -> Result<&'a Node, IoError> {
        match parent.find(k)[..] {
            [n] => Ok(n),
            ref found => Err(ctx.invalid(
                block_name(k),
                found.get(1).map(|n| n.start).unwrap_or(parent.start),
                format!("one {what} block"),
                format!("{} blocks", found.len()),
            )),
        }
    };
    let meas = one(root, block::MEAS, "measurement (FIFFB_MEAS)")?;
    let info = one(meas, block::MEAS_INFO, "measurement info (FIFFB_MEAS_INFO)")?;
    Ok((meas, info))
}

/// Reads the channel count, rate, channel records (with the extended `FIFFB_CH_INFO` blocks MNE
/// writes for names longer than 15 characters) and measurement date.
pub(super) fn read_meas_info(ctx: &Ctx<'_>, info: &Node) -> Result<Meas, IoError> {
    let mut nchan: Option<(i32, usize)> = None;
    let mut sfreq: Option<(f32, usize)> = None;
    let mut channels = Vec::new();
    let mut channel_pos = Vec::new();
    let mut meas_date = None;
    for t in &info.tags {
        match t.kind {
            kind::NCHAN => nchan = Some((ctx.int(t, "FIFF_NCHAN")?, t.data_pos())),
            kind::SFREQ => {
                let (v, single) = ctx.floats(t, "FIFF_SFREQ")?;
                if !single || v.len() != 1 {
                    return Err(ctx.invalid(
                        "FIFF_SFREQ",
                        t.pos,
                        "one float32",
                        format!("{} bytes of type {}", t.size, t.ty),
                    ));
                }
                sfreq = Some((v[0] as f32, t.data_pos()));
            }
            kind::CH_INFO => {
                channels.push(channel_record(ctx, t, channels.len())?);
                channel_pos.push(t.pos);
            }
            kind::MEAS_DATE => {
                let v = ctx.ints(t, "FIFF_MEAS_DATE")?;
                meas_date = match v[..] {
                    [s] => Some((s as i64, 0)),
                    [s, us] => Some((s as i64, us as i64)),
                    _ => {
                        return Err(ctx.invalid(
                            "FIFF_MEAS_DATE",
                            t.pos + 8,
                            "4 or 8 bytes (seconds, microseconds)",
                            t.size.to_string(),
                        ))
                    }
                };
            }
            _ => {}
        }
    }
    let Some((nchan, nchan_at)) = nchan else {
        return Err(missing(ctx, info, "FIFF_NCHAN (the number of channels)"));
    };
    let Some((sfreq, sfreq_at)) = sfreq else {
        return Err(missing(ctx, info, "FIFF_SFREQ (the sampling rate)"));
    };
    if nchan <= 0 || nchan as usize != channels.len() {
        return Err(ctx.invalid(
            "FIFF_NCHAN",
            nchan_at,
            format!(
                "a positive count equal to the {} FIFF_CH_INFO records",
                channels.len()
            ),
            nchan.to_string(),
        ));
    }
    let sfreq = sfreq as f64;
    if oddball_signal::check_sfreq(sfreq).is_err() {
        return Err(ctx.invalid(
            "FIFF_SFREQ",
            sfreq_at,
            "a sampling rate from 0.1 Hz to 1 MHz",
            sfreq.to_string(),
        ));
    }
    let mut scale_pos: Vec<usize> = channel_pos.iter().map(|p| p + 16 + 12).collect();
    extended_channels(ctx, info, &mut channels, &mut scale_pos)?;
    Ok(Meas {
        sfreq,
        channels,
        channel_pos,
        scale_pos,
        meas_date,
    })
}

fn missing(ctx: &Ctx<'_>, node: &Node, what: &str) -> IoError {
    ctx.invalid(
        block_name(node.kind),
        node.start,
        format!("a {what} tag"),
        "none",
    )
}

/// One `fiffChInfoRec`.
fn channel_record(ctx: &Ctx<'_>, t: &Tag, index: usize) -> Result<FifChannel, IoError> {
    let field = format!("FIFF_CH_INFO of channel {index}");
    if t.ty != ty::CH_INFO_STRUCT || t.size < CH_INFO_SIZE {
        return Err(ctx.invalid(
            field,
            t.pos + 4,
            format!("type FIFFT_CH_INFO_STRUCT (30) of {CH_INFO_SIZE} bytes"),
            format!("type {}, {} bytes", t.ty, t.size),
        ));
    }
    let d = ctx.data(t);
    let i = |at: usize| i32::from_be_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]);
    let f = |at: usize| f32::from_be_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]);
    let raw_name = &d[80..96];
    let end = raw_name.iter().position(|&b| b == 0).unwrap_or(16);
    let name = std::str::from_utf8(&raw_name[..end])
        .map_err(|_| {
            ctx.invalid(
                format!("{field} name"),
                t.data_pos() + 80,
                "UTF-8 text",
                String::from_utf8_lossy(&raw_name[..end]).into_owned(),
            )
        })?
        .to_string();
    Ok(FifChannel {
        name,
        kind: i(8),
        scan_no: i(0),
        logical_no: i(4),
        range: f(12),
        cal: f(16),
        coil_type: i(20),
        unit: i(72),
        unit_mul: i(76),
    })
}

/// Applies the `FIFFB_CH_INFO` blocks (one per channel, in channel order, as MNE reads them).
fn extended_channels(
    ctx: &Ctx<'_>,
    info: &Node,
    channels: &mut [FifChannel],
    scale_pos: &mut [usize],
) -> Result<(), IoError> {
    let blocks = info.find(block::CH_INFO);
    if blocks.is_empty() {
        return Ok(());
    }
    if blocks.len() != channels.len() {
        return Err(ctx.invalid(
            "FIFFB_CH_INFO blocks",
            blocks[0].start,
            format!("one per channel ({})", channels.len()),
            blocks.len().to_string(),
        ));
    }
    for ((b, ch), scale_at) in blocks.iter().zip(channels.iter_mut()).zip(scale_pos) {
        for t in &b.tags {
            let f32_of = |name: &str| -> Result<f32, IoError> {
                match ctx.floats(t, name)? {
                    (v, true) if v.len() == 1 => Ok(v[0] as f32),
                    _ => Err(ctx.invalid(name, t.pos + 8, "one float32", t.size.to_string())),
                }
            };
            match t.kind {
                kind::CH_SCAN_NO => ch.scan_no = ctx.int(t, "FIFF_CH_SCAN_NO")?,
                kind::CH_LOGICAL_NO => ch.logical_no = ctx.int(t, "FIFF_CH_LOGICAL_NO")?,
                kind::CH_KIND => ch.kind = ctx.int(t, "FIFF_CH_KIND")?,
                kind::CH_RANGE => {
                    ch.range = f32_of("FIFF_CH_RANGE")?;
                    *scale_at = t.data_pos();
                }
                kind::CH_CAL => {
                    ch.cal = f32_of("FIFF_CH_CAL")?;
                    *scale_at = t.data_pos();
                }
                kind::CH_COIL_TYPE => ch.coil_type = ctx.int(t, "FIFF_CH_COIL_TYPE")?,
                kind::CH_UNIT => ch.unit = ctx.int(t, "FIFF_CH_UNIT")?,
                kind::CH_UNIT_MUL => ch.unit_mul = ctx.int(t, "FIFF_CH_UNIT_MUL")?,
                kind::CH_DACQ_NAME => ch.name = ctx.string(t, "FIFF_CH_DACQ_NAME")?,
                _ => {}
            }
        }
    }
    Ok(())
}

/// The annotations as stored: onsets and durations in seconds, texts, `orig_time` in µs.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct StoredAnnotations {
    pub onset: Vec<f64>,
    pub duration: Vec<f64>,
    pub description: Vec<String>,
    pub orig_time_us: Option<i64>,
    /// Byte of the `FIFF_MEAS_DATE` tag giving `orig_time`.
    pub orig_time_pos: usize,
}

/// Reads the first `FIFFB_MNE_ANNOTATIONS` block, as MNE does: onsets (`FIFF_MNE_BASELINE_MIN`),
/// ends (`FIFF_MNE_BASELINE_MAX`; duration = end − onset in the stored precision), texts
/// (`FIFF_COMMENT`, `:`-separated, `{COLON}` for a colon), `orig_time` (`FIFF_MEAS_DATE`: float64
/// seconds and microseconds, or old-style float64 seconds).
pub(super) fn read_annotations(
    ctx: &Ctx<'_>,
    root: &Node,
) -> Result<Option<StoredAnnotations>, IoError> {
    let Some(node) = root.find(block::MNE_ANNOTATIONS).into_iter().next() else {
        return Ok(None);
    };
    let mut out = StoredAnnotations::default();
    let mut ends: Option<(Vec<f64>, bool)> = None;
    let mut onset_single = true;
    for t in &node.tags {
        match t.kind {
            kind::MNE_BASELINE_MIN => {
                let (v, single) = ctx.floats(t, "annotation onsets (FIFF_MNE_BASELINE_MIN)")?;
                out.onset = v;
                onset_single = single;
            }
            kind::MNE_BASELINE_MAX => {
                ends = Some(ctx.floats(t, "annotation ends (FIFF_MNE_BASELINE_MAX)")?);
            }
            kind::COMMENT => {
                let text = ctx.string(t, "annotation texts (FIFF_COMMENT)")?;
                out.description = if text.is_empty() {
                    Vec::new()
                } else {
                    text.split(':').map(|s| s.replace("{COLON}", ":")).collect()
                };
            }
            kind::MEAS_DATE => {
                let field = "annotations orig_time (FIFF_MEAS_DATE)";
                let (v, _) = ctx.floats(t, field)?;
                let us = match v[..] {
                    [s] if s.is_finite() && s.abs() < 1e13 => (s * 1e6).round_ties_even() as i64,
                    [s, us]
                        if s.is_finite() && us.is_finite() && s.abs() < 1e13 && us.abs() < 1e13 =>
                    {
                        s as i64 * 1_000_000 + us as i64
                    }
                    _ => {
                        return Err(ctx.invalid(
                            field,
                            t.data_pos(),
                            "finite seconds (and microseconds)",
                            format!("{v:?}"),
                        ))
                    }
                };
                out.orig_time_us = Some(us);
                out.orig_time_pos = t.pos;
            }
            _ => {}
        }
    }
    let n = out.onset.len();
    let (ends, end_single) = ends.unwrap_or((Vec::new(), true));
    if ends.len() != n || out.description.len() != n {
        return Err(ctx.invalid(
            "FIFFB_MNE_ANNOTATIONS",
            node.start,
            "as many onsets, ends and texts",
            format!(
                "{n} onsets, {} ends, {} texts",
                ends.len(),
                out.description.len()
            ),
        ));
    }
    out.duration = ends
        .iter()
        .zip(&out.onset)
        .map(|(&e, &o)| {
            if end_single && onset_single {
                (e as f32 - o as f32) as f64
            } else {
                e - o
            }
        })
        .collect();
    Ok(Some(out))
}
