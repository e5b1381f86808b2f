//! Reading a FIF raw file: its data buffers and skips, split parts, and the [`Recording`].

use std::path::{Path, PathBuf};

use ndarray::Array2;

use crate::files::read_file;
use crate::{Details, Format, IoError, Recording};

use super::events::*;
use super::meas::*;
use super::tags::*;
use super::types::*;

/// MNE writes at most 100 split parts.
const MAX_PARTS: usize = 100;

/// Acquisition skips are read as zeros; more zeros than this many times the samples stored are
/// refused.
const MAX_GAP_RATIO: usize = 16;

/// Reads a FIF raw file and, when it names a next split part (`FIFFB_REF`), every part after it
/// (in the same folder; each checked to continue the one before).
pub fn read_fif(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    refuse_gzip_name(path)?;
    let bytes = read_file(path)?;
    let mut parts = vec![parse_part(&bytes, path)?];
    let mut paths = vec![path.to_path_buf()];
    while let Some((name, at)) = parts.last().and_then(|p| p.next.clone()) {
        let current = paths.last().expect("one part").clone();
        let next_path = current
            .parent()
            .unwrap_or_else(|| Path::new(""))
            .join(&name);
        if parts.len() >= MAX_PARTS || paths.contains(&next_path) {
            return Err(IoError::invalid_field(
                &current,
                "next split part (FIFF_REF_FILE_NAME)",
                at as u64,
                format!("a part not read before, at most {MAX_PARTS} parts"),
                name,
            ));
        }
        if !next_path.exists() {
            return Err(IoError::Unsupported {
                path: current,
                what: format!(
                    "split FIF recording: its next part {name:?} (named at byte {at}) is not in \
                     the same folder; keep all the parts together, as MNE writes them"
                ),
            });
        }
        let bytes = read_file(&next_path)?;
        let part = parse_part(&bytes, &next_path)?;
        check_continues(parts.last().expect("one part"), &part, &next_path)?;
        parts.push(part);
        paths.push(next_path);
    }
    assemble(parts, paths)
}

/// Parses the bytes of one FIF raw file; `path` names it in messages and in the result. A file
/// that continues in a next split part is refused (read it with [`read_fif`]).
pub fn parse_fif(bytes: &[u8], path: &Path) -> Result<Recording, IoError> {
    let part = parse_part(bytes, path)?;
    if let Some((name, at)) = &part.next {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "split FIF recording: it continues in {name:?} (named at byte {at}); read it \
                 from its folder with read_fif"
            ),
        });
    }
    assemble(vec![part], vec![path.to_path_buf()])
}

/// `.fif.gz` (which MNE reads through gzip): refused, naming what to do.
pub(super) fn refuse_gzip_name(path: &Path) -> Result<(), IoError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.ends_with(".fif.gz") {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "gzip-compressed FIF (.fif.gz); decompress it first (gunzip) and read the .fif"
                .into(),
        });
    }
    Ok(())
}

/// One file of a recording.
struct Part {
    meas: Meas,
    first_samp: i64,
    n_times: usize,
    /// Which channels are EEG (kept), trigger (events), or dropped.
    eeg: Vec<usize>,
    stim: Vec<usize>,
    /// µV (or unscaled, for a non-volt unit), one row per EEG channel.
    eeg_data: Vec<Vec<f64>>,
    /// Trigger values, one row per STIM channel.
    stim_data: Vec<Vec<u32>>,
    skips: Vec<FifSkip>,
    data_type: FifDataType,
    annotations: Option<StoredAnnotations>,
    /// The next split part's file name and the byte of the tag naming it.
    next: Option<(String, usize)>,
}

/// A data buffer: its tag, samples, the first sample it fills.
struct Buffer {
    tag: Tag,
    nsamp: usize,
    start: usize,
}

fn parse_part(bytes: &[u8], path: &Path) -> Result<Part, IoError> {
    let ctx = Ctx { path, bytes };
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "gzip-compressed FIF; decompress it first (gunzip) and read the .fif".into(),
        });
    }
    let tags = walk(&ctx)?;
    let root = tree(&ctx, tags)?;
    let (meas_node, info_node) = meas_blocks(&ctx, &root)?;
    let meas = read_meas_info(&ctx, info_node)?;
    let annotations = read_annotations(&ctx, &root)?;
    if let (Some(a), None) = (&annotations, meas.meas_date) {
        if a.orig_time_us.is_some() {
            return Err(ctx.invalid(
                "annotations orig_time (FIFF_MEAS_DATE)",
                a.orig_time_pos,
                "no orig_time in a file without a measurement date (MNE refuses these too)",
                "an orig_time",
            ));
        }
    }
    let raw = raw_block(&ctx, meas_node)?;
    let nchan = meas.channels.len();

    // Which channels are read.
    let stim = stim_channels(&meas.channels);
    let eeg: Vec<usize> = (0..nchan)
        .filter(|i| meas.channels[*i].kind == FifChannel::EEG && !stim.contains(i))
        .collect();
    if eeg.is_empty() {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "no EEG channel (kind 2) among the {nchan} channels ({}); oddball reads EEG only",
                kinds_present(&meas.channels)
            ),
        });
    }
    let scale = |i: usize| -> Result<f64, IoError> {
        let c = &meas.channels[i];
        let at = meas.scale_pos[i];
        if !(c.range.is_finite() && c.cal.is_finite()) {
            return Err(ctx.invalid(
                format!("range and cal of channel {:?}", c.name),
                at,
                "finite numbers",
                format!("{} and {}", c.range, c.cal),
            ));
        }
        Ok(c.range as f64 * c.cal as f64)
    };
    let eeg_cal: Vec<f64> = eeg.iter().map(|&i| scale(i)).collect::<Result<_, _>>()?;
    let stim_cal: Vec<f64> = stim.iter().map(|&i| scale(i)).collect::<Result<_, _>>()?;
    let mut eeg_unit = Vec::with_capacity(eeg.len());
    for &i in &eeg {
        let c = &meas.channels[i];
        if !(-30..=30).contains(&c.unit_mul) {
            return Err(ctx.invalid(
                format!("unit_mul of channel {:?}", c.name),
                meas.channel_pos[i] + 16 + 76,
                "a unit exponent from -30 to 30",
                c.unit_mul.to_string(),
            ));
        }
        let volt = if c.unit == FifChannel::VOLT { 1e6 } else { 1.0 };
        eeg_unit.push(volt * 10f64.powi(c.unit_mul));
    }

    // The buffers and skips, then the samples.
    let (first_samp, buffers, skips, n_times) = layout(&ctx, raw, nchan)?;
    let mut eeg_data = vec![vec![0.0f64; n_times]; eeg.len()];
    let mut stim_data = vec![vec![0u32; n_times]; stim.len()];
    let mut data_type = None;
    for b in &buffers {
        let (dt, width) = match b.tag.ty {
            ty::SHORT | ty::DAU_PACK16 => (FifDataType::Short, 2),
            ty::INT => (FifDataType::Int, 4),
            ty::FLOAT => (FifDataType::Float, 4),
            _ => (FifDataType::Double, 8),
        };
        data_type.get_or_insert(dt);
        let d = ctx.data(&b.tag);
        let value = |s: usize, ch: usize| -> f64 {
            let at = (s * nchan + ch) * width;
            let x = &d[at..at + width];
            match dt {
                FifDataType::Short => i16::from_be_bytes([x[0], x[1]]) as f64,
                FifDataType::Int => i32::from_be_bytes([x[0], x[1], x[2], x[3]]) as f64,
                FifDataType::Float => f32::from_be_bytes([x[0], x[1], x[2], x[3]]) as f64,
                FifDataType::Double => f64::from_be_bytes(x.try_into().expect("8 bytes")),
            }
        };
        for (k, &ch) in eeg.iter().enumerate() {
            let (cal, unit) = (eeg_cal[k], eeg_unit[k]);
            let row = &mut eeg_data[k][b.start..b.start + b.nsamp];
            for (s, out) in row.iter_mut().enumerate() {
                let v = value(s, ch) * cal;
                *out = if unit == 1.0 { v } else { v * unit };
            }
        }
        for (k, &ch) in stim.iter().enumerate() {
            let row = &mut stim_data[k][b.start..b.start + b.nsamp];
            for (s, out) in row.iter_mut().enumerate() {
                let v = (value(s, ch) * stim_cal[k]).trunc().abs();
                if v.is_nan() || v > u32::MAX as f64 {
                    let name = &meas.channels[ch].name;
                    return Err(ctx.invalid(
                        format!("trigger channel {name:?} at sample {}", b.start + s),
                        b.tag.data_pos() + (s * nchan + ch) * width,
                        "a finite trigger value below 2^32",
                        format!("{}", value(s, ch) * stim_cal[k]),
                    ));
                }
                *out = v as u32;
            }
        }
    }
    let next = next_part(&ctx, &root)?;
    Ok(Part {
        meas,
        first_samp,
        n_times,
        eeg,
        stim,
        eeg_data,
        stim_data,
        skips,
        data_type: data_type.unwrap_or(FifDataType::Float),
        annotations,
        next,
    })
}

fn kinds_present(channels: &[FifChannel]) -> String {
    let mut kinds: Vec<String> = channels.iter().map(FifChannel::kind_name).collect();
    kinds.sort();
    kinds.dedup();
    kinds.join(", ")
}

/// The raw data block: `FIFFB_RAW_DATA`, else `FIFFB_CONTINUOUS_DATA` (MaxShield
/// `FIFFB_IAS_RAW_DATA` refused, as MNE refuses it by default).
fn raw_block<'a>(ctx: &Ctx<'_>, meas: &'a Node) -> Result<&'a Node, IoError> {
    for k in [block::RAW_DATA, block::CONTINUOUS_DATA] {
        match meas.find(k)[..] {
            [] => continue,
            [one] => return Ok(one),
            ref several => {
                return Err(ctx.invalid(
                    block_name(k),
                    several[1].start,
                    "one raw data block",
                    format!("{} blocks", several.len()),
                ))
            }
        }
    }
    if let Some(ias) = meas.find(block::IAS_RAW_DATA).first() {
        return Err(IoError::Unsupported {
            path: ctx.path.to_path_buf(),
            what: format!(
                "MaxShield (internal active shielding) raw data ({} at byte {}): process it with \
                 SSS/tSSS (MaxFilter) first",
                block_name(ias.kind),
                ias.start
            ),
        });
    }
    Err(ctx.invalid(
        "raw data",
        meas.start,
        "a FIFFB_RAW_DATA (102) or FIFFB_CONTINUOUS_DATA (112) block (epochs, evoked and \
         other FIF files are not recordings)",
        "none",
    ))
}

/// Where each buffer goes, as MNE lays them out: an optional `FIFF_FIRST_SAMPLE` first, an
/// optional initial `FIFF_DATA_SKIP` (moving the first sample by that many buffers), then
/// buffers; a `FIFF_DATA_SKIP` between buffers leaves that many buffers (of the next buffer's
/// size) of zeros. Returns `(first_samp, buffers, skips, n_times)`.
fn layout(
    ctx: &Ctx<'_>,
    raw: &Node,
    nchan: usize,
) -> Result<(i64, Vec<Buffer>, Vec<FifSkip>, usize), IoError> {
    let mut first_samp = 0i64;
    let mut first_skip = 0usize;
    let mut pending_skip: Option<(usize, usize)> = None; // (count, tag byte)
    let mut buffers: Vec<Buffer> = Vec::new();
    let mut skips = Vec::new();
    let mut n_times = 0usize;
    let mut stored = 0usize;
    let mut skipped = 0usize;
    let mut longest: Option<(usize, usize, usize)> = None; // (samples, buffers, tag byte)
    for (i, t) in raw.tags.iter().enumerate() {
        match t.kind {
            kind::FIRST_SAMPLE if i == 0 => first_samp = ctx.int(t, "FIFF_FIRST_SAMPLE")? as i64,
            kind::FIRST_SAMPLE => {
                return Err(ctx.invalid(
                    "FIFF_FIRST_SAMPLE",
                    t.pos,
                    "the first sample number as the first tag of the raw data block",
                    format!("tag {i} of the block"),
                ))
            }
            kind::DATA_SKIP => {
                let n = ctx.int(t, "FIFF_DATA_SKIP")?;
                if n < 0 {
                    return Err(ctx.invalid(
                        "FIFF_DATA_SKIP",
                        t.data_pos(),
                        "a number of skipped buffers, 0 or more",
                        n.to_string(),
                    ));
                }
                let initial =
                    buffers.is_empty() && (i == 0 || raw.tags[i - 1].kind == kind::FIRST_SAMPLE);
                if initial {
                    first_skip = n as usize;
                } else {
                    pending_skip = Some((n as usize, t.pos)); // the last one counts, as in MNE
                }
            }
            kind::DATA_BUFFER => {
                let width = match t.ty {
                    ty::SHORT | ty::DAU_PACK16 => 2,
                    ty::INT | ty::FLOAT => 4,
                    ty::DOUBLE => 8,
                    ty::COMPLEX_FLOAT | ty::COMPLEX_DOUBLE => {
                        return Err(IoError::Unsupported {
                            path: ctx.path.to_path_buf(),
                            what: format!("complex-valued data buffer at byte {}", t.pos),
                        })
                    }
                    other => return Err(ctx.invalid(
                        format!("data buffer {}", buffers.len()),
                        t.pos + 4,
                        "data type short (2), int (3), float (4), double (5) or dau_pack16 (16)",
                        other.to_string(),
                    )),
                };
                let frame = nchan * width;
                if t.size % frame != 0 {
                    return Err(ctx.invalid(
                        format!("data buffer {} size", buffers.len()),
                        t.pos + 8,
                        format!("a multiple of {nchan} channels × {width} bytes"),
                        t.size.to_string(),
                    ));
                }
                let nsamp = t.size / frame;
                if first_skip > 0 {
                    first_samp += (nsamp * first_skip) as i64;
                    first_skip = 0;
                }
                if let Some((count, at)) = pending_skip.take() {
                    let len = count.saturating_mul(nsamp);
                    if len > 0 {
                        skips.push(FifSkip {
                            start: n_times,
                            len,
                        });
                        skipped = skipped.saturating_add(len);
                        n_times = n_times.saturating_add(len);
                        if longest.is_none_or(|(l, _, _)| len > l) {
                            longest = Some((len, count, at));
                        }
                    }
                }
                buffers.push(Buffer {
                    tag: *t,
                    nsamp,
                    start: n_times,
                });
                n_times = n_times.saturating_add(nsamp);
                stored += nsamp;
            }
            _ => {}
        }
    }
    if stored == 0 {
        return Err(ctx.invalid(
            block_name(raw.kind),
            raw.start,
            "at least one data buffer (FIFF_DATA_BUFFER) with samples",
            "none",
        ));
    }
    // Zeros cost memory the file does not pay for: skips adding up to more than
    // MAX_GAP_RATIO times the samples stored are taken for corruption.
    if let Some((len, count, at)) = longest {
        if skipped > MAX_GAP_RATIO.saturating_mul(stored) {
            return Err(ctx.invalid(
                "FIFF_DATA_SKIP",
                at + 16,
                format!("skips adding up to at most {MAX_GAP_RATIO} × the {stored} samples stored"),
                format!("{count} buffers ({len} samples) here, {skipped} samples in all"),
            ));
        }
    }
    Ok((first_samp, buffers, skips, n_times))
}

/// The next split part named by a `FIFFB_REF` block of role `FIFFV_ROLE_NEXT_FILE` (2): a file
/// name in the same folder.
fn next_part(ctx: &Ctx<'_>, root: &Node) -> Result<Option<(String, usize)>, IoError> {
    for r in root.find(block::REF) {
        let role = r.tags.iter().find(|t| t.kind == kind::REF_ROLE);
        let role = match role {
            Some(t) => ctx.int(t, "FIFF_REF_ROLE")?,
            None => continue,
        };
        if role != 2 {
            continue;
        }
        let Some(name_tag) = r.tags.iter().find(|t| t.kind == kind::REF_FILE_NAME) else {
            return Err(IoError::Unsupported {
                path: ctx.path.to_path_buf(),
                what: format!(
                    "split FIF recording whose next part is named only by number (FIFFB_REF at \
                     byte {}); rename the parts as MNE writes them and save again",
                    r.start
                ),
            });
        };
        let name = ctx.string(name_tag, "FIFF_REF_FILE_NAME")?;
        if name.is_empty() || name == "." || name == ".." || name.contains(['/', '\\', '\0']) {
            return Err(ctx.invalid(
                "next split part (FIFF_REF_FILE_NAME)",
                name_tag.data_pos(),
                "a file name in the same folder",
                name,
            ));
        }
        return Ok(Some((name, name_tag.data_pos())));
    }
    Ok(None)
}

/// A split part must continue the one before: the same channels and rate, and its first sample
/// right after the last one before.
fn check_continues(prev: &Part, next: &Part, path: &Path) -> Result<(), IoError> {
    let same = |a: &FifChannel, b: &FifChannel| {
        a.name == b.name && a.kind == b.kind && a.range == b.range && a.cal == b.cal
    };
    let channels_match = prev.meas.channels.len() == next.meas.channels.len()
        && prev
            .meas
            .channels
            .iter()
            .zip(&next.meas.channels)
            .all(|(a, b)| same(a, b));
    if !channels_match || prev.meas.sfreq != next.meas.sfreq {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "split part with other channels (names, kinds, calibration) or another \
                   sampling rate than the part before"
                .into(),
        });
    }
    let expected = prev.first_samp + prev.n_times as i64;
    if next.first_samp != expected {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "split part starting at acquisition sample {}, not {expected} where the part \
                 before ends",
                next.first_samp
            ),
        });
    }
    Ok(())
}

/// The recording of one or more parts: EEG in µV, events from the trigger channels and the
/// first part's annotations.
fn assemble(parts: Vec<Part>, paths: Vec<PathBuf>) -> Result<Recording, IoError> {
    let path = paths[0].clone();
    let n_times: usize = parts.iter().map(|p| p.n_times).sum();
    let first = &parts[0];
    let n_eeg = first.eeg.len();
    let mut data = Vec::with_capacity(n_eeg * n_times);
    for k in 0..n_eeg {
        for p in &parts {
            data.extend_from_slice(&p.eeg_data[k]);
        }
    }
    let stim: Vec<Vec<u32>> = (0..first.stim.len())
        .map(|k| {
            parts
                .iter()
                .flat_map(|p| p.stim_data[k].iter().copied())
                .collect()
        })
        .collect();
    let mut skips = Vec::new();
    let mut offset = 0;
    for p in &parts {
        skips.extend(p.skips.iter().map(|s| FifSkip {
            start: s.start + offset,
            len: s.len,
        }));
        offset += p.n_times;
    }

    let meas = &first.meas;
    let steps = stim_events(&stim);
    let max_stim = steps.iter().map(|&(_, c)| c).max().unwrap_or(0);
    let mut events: Vec<oddball_signal::Event> = steps
        .iter()
        .map(|&(s, c)| oddball_signal::Event::new(s, c))
        .collect();
    let timing = Timing {
        sfreq: meas.sfreq,
        first_samp: first.first_samp,
        n_times,
        meas_us: meas.meas_date.map(|(s, us)| s * 1_000_000 + us),
    };
    let (annotations, label_codes, orig) = match &first.annotations {
        Some(stored) => {
            let (annotations, ann_events, codes) = annotation_events(stored, &timing, max_stim);
            events.extend(ann_events);
            (annotations, codes, stored.orig_time_us)
        }
        None => (Vec::new(), Default::default(), None),
    };

    let channels = &meas.channels;
    let ch_names: Vec<String> = first
        .eeg
        .iter()
        .map(|&i| channels[i].name.clone())
        .collect();
    let non_voltage_channels = first
        .eeg
        .iter()
        .filter(|&&i| channels[i].unit != FifChannel::VOLT)
        .map(|&i| channels[i].name.clone())
        .collect();
    let dropped_channels = (0..channels.len())
        .filter(|i| !first.eeg.contains(i) && !first.stim.contains(i))
        .map(|i| channels[i].name.clone())
        .collect();
    let data =
        Array2::from_shape_vec((n_eeg, n_times), data).map_err(|e| IoError::Unsupported {
            path: path.clone(),
            what: format!("data layout: {e}"),
        })?;
    let raw = crate::error::new_raw(&path, data, meas.sfreq, ch_names, events)?;
    let info = FifInfo {
        channels: channels.clone(),
        stim_channels: first
            .stim
            .iter()
            .map(|&i| channels[i].name.clone())
            .collect(),
        dropped_channels,
        non_voltage_channels,
        first_samp: first.first_samp,
        meas_date: meas.meas_date,
        annotations_orig_time: orig,
        annotations,
        label_codes,
        skips,
        data_type: first.data_type,
        parts: paths,
    };
    Ok(Recording {
        raw,
        format: Format::Fif,
        path,
        speller: None,
        details: Details::Fif(Box::new(info)),
    })
}
