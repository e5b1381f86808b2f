//! Reading an EEGLAB `.set` (and its `.fdt`): the `EEG` fields from the MAT container, the
//! samples, the channel names and the events.

use std::path::{Component, Path, PathBuf};

use ndarray::Array2;
use oddball_signal::Event;

use crate::edf::parse_event_text;
use crate::events::LabelCodes;
use crate::files::read_file;
use crate::mat::{parse_mat_file, MatArray, MatFile, MatValue};
use crate::{Details, Format, IoError, Recording};

use super::types::*;

/// Reads an EEGLAB `.set` file, and the `.fdt` beside it when `EEG.data` names one.
pub fn read_eeglab(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    let bytes = read_file(path)?;
    let mat = parse_mat_file(&bytes, path)?;
    let eeg = Eeg::new(&mat, path)?;
    match eeg.data()? {
        Data::Embedded(_) => build(&mat, &eeg, None),
        Data::File(name) => {
            let (fdt_path, stale) = resolve_fdt(&eeg, &name)?;
            let fdt = read_file(&fdt_path)?;
            build(&mat, &eeg, Some((&fdt, fdt_path, stale)))
        }
    }
}

/// Parses an EEGLAB `.set` from its bytes, with the bytes of the `.fdt` its `EEG.data` names
/// (`None` when the data are in the `.set`); `path` is the `.set`'s path, used in messages and
/// the result only (nothing is read).
pub fn parse_eeglab(set: &[u8], path: &Path, fdt: Option<&[u8]>) -> Result<Recording, IoError> {
    let mat = parse_mat_file(set, path)?;
    let eeg = Eeg::new(&mat, path)?;
    match (eeg.data()?, fdt) {
        (Data::Embedded(_), _) => build(&mat, &eeg, None),
        (Data::File(name), Some(bytes)) => {
            let dir = path.parent().unwrap_or(Path::new(""));
            build(&mat, &eeg, Some((bytes, dir.join(name), None)))
        }
        (Data::File(name), None) => Err(IoError::Missing {
            path: path.to_path_buf(),
            what: "EEGLAB data file",
            name,
            available: Vec::new(),
        }),
    }
}

/// The `.fdt` that `EEG.data` names, beside the `.set` (a name leaving that folder is refused);
/// when it is not there, the `.fdt` with the `.set`'s own name (renamed recordings), as MNE does.
fn resolve_fdt(eeg: &Eeg<'_>, name: &str) -> Result<(PathBuf, Option<String>), IoError> {
    let rel = Path::new(name);
    if name.is_empty() || !rel.components().all(|c| matches!(c, Component::Normal(_))) {
        return Err(eeg.invalid(
            "data",
            "a data file name relative to the .set's folder (no root, no `..`)",
            name.to_string(),
        ));
    }
    let dir = eeg.path.parent().unwrap_or(Path::new(""));
    let named = dir.join(rel);
    if !named.is_file() {
        let own = eeg.path.with_extension("fdt");
        if own != named && own.is_file() {
            return Ok((own, Some(name.to_string())));
        }
    }
    Ok((named, None))
}

/// Where the `EEG` fields are: top-level variables, or the fields of a 1 × 1 struct `EEG`.
enum Source<'a> {
    Top(&'a MatFile),
    Struct {
        offset: u64,
        fields: &'a [String],
        values: &'a [MatArray],
    },
}

/// The `EEG` structure of a `.set` file, with the byte offsets errors name.
struct Eeg<'a> {
    path: &'a Path,
    source: Source<'a>,
}

/// `EEG.data`: the samples, or the name of the `.fdt` holding them.
enum Data<'a> {
    Embedded(&'a MatArray),
    File(String),
}

impl<'a> Eeg<'a> {
    fn new(mat: &'a MatFile, path: &'a Path) -> Result<Self, IoError> {
        let source = match mat.get("EEG") {
            None => Source::Top(mat),
            Some(v) => match &v.array.value {
                MatValue::Struct { fields, values } if v.array.len() == 1 => Source::Struct {
                    offset: v.offset,
                    fields,
                    values,
                },
                _ => {
                    return Err(IoError::invalid_field(
                        path,
                        "variable EEG",
                        v.offset,
                        "a 1 × 1 struct (one continuous data set)",
                        format!("{:?} of dimensions {:?}", kind(&v.array), v.array.dims),
                    ))
                }
            },
        };
        Ok(Self { path, source })
    }

    fn get(&self, name: &str) -> Option<&'a MatArray> {
        match &self.source {
            Source::Top(mat) => mat.get(name).map(|v| &v.array),
            Source::Struct { fields, values, .. } => {
                fields.iter().position(|f| f == name).map(|i| &values[i])
            }
        }
    }

    /// The byte offset an error about field `name` names: its variable's, or `EEG`'s.
    fn at(&self, name: &str) -> u64 {
        match &self.source {
            Source::Top(mat) => mat.get(name).map_or(0, |v| v.offset),
            Source::Struct { offset, .. } => *offset,
        }
    }

    fn what(&self, name: &str) -> String {
        match &self.source {
            Source::Top(_) => format!("EEG.{name} (top-level variable {name})"),
            Source::Struct { .. } => format!("EEG.{name} (field of the struct variable EEG)"),
        }
    }

    fn invalid(&self, name: &str, expected: &str, found: String) -> IoError {
        IoError::invalid_field(self.path, self.what(name), self.at(name), expected, found)
    }

    fn require(&self, name: &str) -> Result<&'a MatArray, IoError> {
        self.get(name).ok_or_else(|| IoError::Missing {
            path: self.path.to_path_buf(),
            what: "EEGLAB field",
            name: format!("EEG.{name}"),
            available: match &self.source {
                Source::Top(mat) => mat.names(),
                Source::Struct { fields, .. } => fields.to_vec(),
            },
        })
    }

    /// A whole number ≥ 1 (`nbchan`, `pnts`, `trials`); `default` when the field is absent.
    fn count(&self, name: &str, default: Option<usize>) -> Result<usize, IoError> {
        let a = match (self.get(name), default) {
            (None, Some(d)) => return Ok(d),
            (None, None) => self.require(name)?,
            (Some(a), _) => a,
        };
        scalar(a)
            .filter(|v| v.fract() == 0.0 && *v >= 1.0 && *v <= u32::MAX as f64)
            .map(|v| v as usize)
            .ok_or_else(|| self.invalid(name, "a whole number from 1", describe(a)))
    }

    fn text(&self, name: &str) -> Option<String> {
        self.get(name).and_then(text)
    }

    fn data(&self) -> Result<Data<'a>, IoError> {
        let a = self.require("data")?;
        match &a.value {
            MatValue::Numeric { imag: None, .. } => Ok(Data::Embedded(a)),
            MatValue::Char(_) => Ok(Data::File(text(a).unwrap_or_default().trim().to_string())),
            _ => Err(self.invalid(
                "data",
                "a real numeric matrix or the name of a .fdt file",
                describe(a),
            )),
        }
    }
}

/// A numeric or logical array of one element, as `f64`.
fn scalar(a: &MatArray) -> Option<f64> {
    match &a.value {
        MatValue::Numeric { real, .. } if real.len() == 1 => real.get_f64(0),
        _ => None,
    }
}

/// A char array as one string (its rows joined by newlines; an empty array is "").
fn text(a: &MatArray) -> Option<String> {
    a.char_rows().map(|rows| rows.join("\n"))
}

fn kind(a: &MatArray) -> &'static str {
    match &a.value {
        MatValue::Numeric { imag: Some(_), .. } => "complex numeric",
        MatValue::Numeric { .. } => "numeric",
        MatValue::Char(_) => "char",
        MatValue::Cell(_) => "cell",
        MatValue::Struct { .. } => "struct",
        MatValue::Unsupported { .. } => "unsupported class",
    }
}

fn describe(a: &MatArray) -> String {
    match (scalar(a), text(a)) {
        (Some(v), _) => format!("{v}"),
        (None, Some(t)) => format!("char {t:?}"),
        _ => format!("{} array of dimensions {:?}", kind(a), a.dims),
    }
}

/// Element `i` of a struct array's field `name`.
fn field<'a>(a: &'a MatArray, i: usize, name: &str) -> Option<&'a MatArray> {
    match &a.value {
        MatValue::Struct { fields, values } => {
            let f = fields.iter().position(|x| x == name)?;
            values.get(i * fields.len() + f)
        }
        _ => None,
    }
}

fn build(
    mat: &MatFile,
    eeg: &Eeg<'_>,
    fdt: Option<(&[u8], PathBuf, Option<String>)>,
) -> Result<Recording, IoError> {
    let path = eeg.path;
    let n_ch = eeg.count("nbchan", None)?;
    let n_times = eeg.count("pnts", None)?;
    let trials = eeg.count("trials", Some(1))?;
    if trials > 1 {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "epoched EEGLAB data set (EEG.trials = {trials}); only continuous data sets \
                 (one trial) are read"
            ),
        });
    }
    let srate_array = eeg.require("srate")?;
    let sfreq = scalar(srate_array)
        .filter(|v| v.is_finite() && *v > 0.0)
        .ok_or_else(|| eeg.invalid("srate", "a positive rate in Hz", describe(srate_array)))?;

    // The samples, µV, channels × points column-major.
    let mut values = vec![0.0f64; 0];
    let data_file = match fdt {
        None => {
            let Data::Embedded(a) = eeg.data()? else {
                return Err(eeg.invalid("data", "a numeric matrix", "a file name".into()));
            };
            let (rows, cols) = (a.dims.first().copied().unwrap_or(0), a.len());
            if rows != n_ch || Some(cols) != n_ch.checked_mul(n_times) {
                return Err(eeg.invalid(
                    "data",
                    &format!("an EEG.nbchan × EEG.pnts = {n_ch} × {n_times} matrix"),
                    format!("dimensions {:?}", a.dims),
                ));
            }
            let real = a.numbers().map(|n| n.to_f64()).unwrap_or_default();
            values.resize(n_ch * n_times, 0.0);
            for (k, v) in real.into_iter().enumerate() {
                values[(k % n_ch) * n_times + k / n_ch] = v;
            }
            None
        }
        Some((bytes, fdt_path, stale)) => {
            let frame = n_ch * 4;
            let needed = (frame as u64).saturating_mul(n_times as u64);
            let len = bytes.len() as u64;
            if len < needed {
                let whole = len / frame as u64;
                return Err(IoError::Truncated {
                    path: fdt_path,
                    field: format!(
                        "sample {whole} of {n_times} (EEG.nbchan = {n_ch} float32 values each)"
                    ),
                    offset: whole * frame as u64,
                    needed,
                    file_len: len,
                });
            }
            if len > needed {
                return Err(IoError::invalid_field(
                    &fdt_path,
                    format!("end of the data (EEG.nbchan × EEG.pnts = {n_ch} × {n_times} float32)"),
                    needed,
                    "the end of the file",
                    format!("{} more bytes", len - needed),
                ));
            }
            values.resize(n_ch * n_times, 0.0);
            for (k, c) in bytes.chunks_exact(4).enumerate() {
                let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                values[(k % n_ch) * n_times + k / n_ch] = f64::from(v);
            }
            Some((fdt_path, stale))
        }
    };

    // After the data, which bound nbchan: names are only made for channels there are.
    let ch_names = channel_names(eeg, n_ch)?;
    let (events, eeglab_events, label_codes) = events(eeg, n_times)?;
    let values =
        Array2::from_shape_vec((n_ch, n_times), values).map_err(|e| IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!("data layout: {e}"),
        })?;
    let raw = crate::error::new_raw(path, values, sfreq, ch_names, events)?;
    let in_eeg_struct = matches!(eeg.source, Source::Struct { .. });
    let (data_file, stale_data_name) = match data_file {
        Some((p, stale)) => (Some(p), stale),
        None => (None, None),
    };
    Ok(Recording {
        raw,
        format: Format::Eeglab,
        path: path.to_path_buf(),
        speller: None,
        details: Details::Eeglab(Box::new(EeglabInfo {
            header: mat.header.clone(),
            in_eeg_struct,
            setname: eeg.text("setname"),
            data_file,
            stale_data_name,
            events: eeglab_events,
            label_codes,
            reference: eeg.text("ref"),
        })),
    })
}

/// `EEG.chanlocs(k).labels`; with no `chanlocs` (absent or empty), `EEG 000` … as MNE names
/// them.
fn channel_names(eeg: &Eeg<'_>, n_ch: usize) -> Result<Vec<String>, IoError> {
    let Some(locs) = eeg.get("chanlocs").filter(|a| !a.is_empty()) else {
        return Ok((0..n_ch).map(|i| format!("EEG {i:03}")).collect());
    };
    if !matches!(locs.value, MatValue::Struct { .. }) || locs.len() != n_ch {
        return Err(eeg.invalid(
            "chanlocs",
            &format!("a struct array of EEG.nbchan = {n_ch} channels with a field `labels`"),
            describe(locs),
        ));
    }
    (0..n_ch)
        .map(|i| {
            field(locs, i, "labels").and_then(text).ok_or_else(|| {
                eeg.invalid(
                    "chanlocs",
                    &format!("a char `labels` for channel {}", i + 1),
                    field(locs, i, "labels").map_or("no `labels` field".into(), describe),
                )
            })
        })
        .collect()
}

type Events = (
    Vec<Event>,
    Vec<EeglabEvent>,
    std::collections::BTreeMap<String, u32>,
);

/// `EEG.event`: numeric types → codes; text types read as EDF+ annotation texts
/// (`CODE [target|nontarget][: LABEL]`) or else coded by [`LabelCodes`].
fn events(eeg: &Eeg<'_>, n_times: usize) -> Result<Events, IoError> {
    let Some(ev) = eeg.get("event").filter(|a| !a.is_empty()) else {
        return Ok(Default::default());
    };
    if !matches!(ev.value, MatValue::Struct { .. }) {
        return Err(eeg.invalid(
            "event",
            "a struct array with fields `type` and `latency`",
            describe(ev),
        ));
    }
    // Each element's type and latency, and what its text says.
    let mut parsed = Vec::with_capacity(ev.len());
    for i in 0..ev.len() {
        let bad = |what: &str, a: Option<&MatArray>| {
            eeg.invalid(
                "event",
                &format!("EEG.event({}).{what}", i + 1),
                a.map_or("no such field".into(), describe),
            )
        };
        let t = field(ev, i, "type");
        let kind = match t {
            Some(a) if matches!(a.value, MatValue::Char(_)) => {
                EeglabEventType::Text(text(a).unwrap_or_default())
            }
            Some(a) if matches!(a.value, MatValue::Numeric { .. }) && a.is_empty() => {
                EeglabEventType::Text(String::new())
            }
            Some(a) => {
                EeglabEventType::Number(scalar(a).ok_or_else(|| bad("type: text or a number", t))?)
            }
            None => return Err(bad("type: text or a number", t)),
        };
        let l = field(ev, i, "latency");
        let latency = match l {
            Some(a) if matches!(a.value, MatValue::Numeric { .. }) && a.is_empty() => f64::NAN,
            Some(a) => scalar(a).ok_or_else(|| bad("latency: a number of samples", l))?,
            None => return Err(bad("latency: a number of samples", l)),
        };
        let code_text = match &kind {
            EeglabEventType::Number(v)
                if v.fract() == 0.0 && *v >= 0.0 && *v <= u32::MAX as f64 =>
            {
                Ok((*v as u32, None, None))
            }
            EeglabEventType::Number(v) => Err(format!("{v}")),
            EeglabEventType::Text(s) => parse_event_text(s).ok_or_else(|| s.clone()),
        };
        parsed.push((kind, latency, code_text));
    }
    let max = parsed
        .iter()
        .filter_map(|p| p.2.as_ref().ok().map(|c| c.0))
        .max()
        .unwrap_or(0);
    let mut labels = LabelCodes::after(max);
    let mut events = Vec::new();
    let mut all = Vec::with_capacity(parsed.len());
    for (kind, latency, code_text) in parsed {
        let (code, target, label) = match code_text {
            Ok(c) => c,
            Err(text) => (labels.code(&text), None, Some(text)),
        };
        let pos = (latency - 1.0).round_ties_even();
        let onset = (pos >= 0.0 && pos < n_times as f64).then_some(pos as usize);
        if let Some(onset) = onset {
            events.push(Event {
                onset,
                code,
                target,
                label,
            });
        }
        all.push(EeglabEvent {
            kind,
            latency,
            onset,
            code,
        });
    }
    Ok((events, all, labels.into_map()))
}
