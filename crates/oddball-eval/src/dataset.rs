//! Recordings into labelled epochs, the one place that does it for `train`, `evaluate` and
//! `benchmark`: read ([`oddball_io::read_with`] and its [`ReadOptions`]), label (an [`EventMapping`], MNE's `event_id`; or the
//! text a speller run spelled), give a speller geometry to recordings that lack one (a
//! manifest's `[speller]`), and cut epochs with the [`Preprocess`] of the model.
//!
//! A recording with events of which none says target or non-target is an error that says how
//! to label them (an event mapping, or the spelled text). [`load_epochs`] does it for every
//! file of a run, each matched to the run's one [`Layout`].

use std::path::{Path, PathBuf};

use oddball_io::events::{describe_events, LabelError};
use oddball_io::manifest::{Manifest, SpellerSpec, Subject};
use oddball_io::{EventMapping, IoError, ReadOptions, Recording, Speller};
use oddball_signal::SignalError;
use thiserror::Error;

use crate::evaluate::EpochedRecording;
use crate::layout::{Layout, Resampled};
use oddball_decode::preprocess::Preprocess;

/// Why a recording could not become labelled epochs; every variant names the file.
#[derive(Debug, Error)]
pub enum DatasetError {
    #[error("reading {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: Box<IoError>,
    },
    #[error("labelling the events of {}", path.display())]
    Label {
        path: PathBuf,
        #[source]
        source: Box<LabelError>,
    },
    #[error("labelling {} from the text {text:?}", path.display())]
    Text {
        path: PathBuf,
        text: String,
        #[source]
        source: Box<LabelError>,
    },
    #[error(
        "{} has {n_events} events but none is labelled target or non-target (its events: \
         {events}); say which events are targets and which non-targets (codes or marker texts; \
         an [events] table in a dataset manifest), or for a speller run give the text it spelled \
         (test_text in a manifest)",
        path.display()
    )]
    Unlabelled {
        path: PathBuf,
        n_events: usize,
        /// The codes and texts present, e.g. `code 1 ×192, code 2 ×48`.
        events: String,
    },
    #[error("{}: the speller geometry does not fit: {what}", path.display())]
    Speller { path: PathBuf, what: String },
    #[error("{}: every one of its {n_epochs} epochs was dropped: {why}", path.display())]
    AllDropped {
        path: PathBuf,
        n_epochs: usize,
        /// The drop log's summary: which rule dropped how many, on which channels.
        why: String,
    },
    /// A run's channels or rate could not be matched to its subject's first run's.
    #[error(transparent)]
    Layout(Box<crate::layout::LayoutError>),
    /// Resampling a recording to the rate asked for failed.
    #[error("resampling {} to {to} Hz", path.display())]
    Resample {
        path: PathBuf,
        to: f64,
        #[source]
        source: SignalError,
    },
    #[error("epoching {}", path.display())]
    Epoch {
        path: PathBuf,
        #[source]
        source: SignalError,
    },
}

/// How to label one recording.
#[derive(Debug, Clone, Copy, Default)]
pub struct Labelling<'a> {
    /// Which events are targets; replaces the file's own flags.
    pub mapping: Option<&'a EventMapping>,
    /// The text a speller run spelled (runs recorded without labels).
    pub text: Option<&'a str>,
    /// The speller geometry, for recordings that do not carry one.
    pub speller: Option<&'a SpellerSpec>,
    /// What the reader cannot find in the file (CSV columns, MAT variables, sampling rate).
    pub read: Option<&'a ReadOptions>,
}

impl<'a> Labelling<'a> {
    /// How manifest `m` labels `run` of its `subject`: the manifest's event mapping, speller
    /// geometry and `[read]` options, and the text the run spelled (a test run's `test_text`).
    pub fn of_run(m: &'a Manifest, subject: &'a Subject, run: &Path) -> Self {
        Self {
            mapping: m.events.as_ref(),
            text: subject.text_of(run),
            speller: m.speller.as_ref(),
            read: m.read.as_ref(),
        }
    }
}

/// The [`Speller`] of a manifest's geometry ([`SpellerSpec::speller`]).
pub fn speller_of(spec: &SpellerSpec) -> Result<Speller, String> {
    spec.speller()
}

/// Reads a recording with `options` and applies `mapping`, if any: its events may stay
/// unlabelled (what a look at a file needs, not an evaluation).
pub fn read_mapped(
    path: &Path,
    mapping: Option<&EventMapping>,
    options: &ReadOptions,
) -> Result<Recording, DatasetError> {
    let mut rec = read(path, options)?;
    if let Some(m) = mapping {
        map_events(&mut rec, path, m)?;
    }
    Ok(rec)
}

/// Reads a recording with `options` (as read, not yet labelled).
pub fn read(path: &Path, options: &ReadOptions) -> Result<Recording, DatasetError> {
    oddball_io::read_with(path, options).map_err(|source| DatasetError::Read {
        path: path.to_path_buf(),
        source: Box::new(source),
    })
}

fn map_events(rec: &mut Recording, path: &Path, m: &EventMapping) -> Result<(), DatasetError> {
    rec.map_events(m).map_err(|source| DatasetError::Label {
        path: path.to_path_buf(),
        source: Box::new(source),
    })?;
    Ok(())
}

/// Reads and labels a recording (see [`Labelling`]); not yet epoched.
pub fn read_labelled(path: &Path, how: Labelling<'_>) -> Result<Recording, DatasetError> {
    let mut rec = read(path, &how.read.cloned().unwrap_or_default())?;
    if let Some(spec) = how.speller {
        let speller = speller_of(spec).map_err(|what| DatasetError::Speller {
            path: path.to_path_buf(),
            what,
        })?;
        match &rec.speller {
            // The file's own geometry must agree with the manifest's.
            Some(own)
                if own.matrix() != speller.matrix() || own.code_order != speller.code_order =>
            {
                return Err(DatasetError::Speller {
                    path: path.to_path_buf(),
                    what: "the file's own speller matrix or code order differs from the \
                           manifest's"
                        .into(),
                })
            }
            Some(_) => {}
            None => rec.speller = Some(speller),
        }
    }
    if let Some(m) = how.mapping {
        map_events(&mut rec, path, m)?;
    }
    if let Some(text) = how.text {
        rec.label_from_text(text)
            .map_err(|source| DatasetError::Text {
                path: path.to_path_buf(),
                text: text.to_string(),
                source: Box::new(source),
            })?;
    }
    let events = rec.raw.events();
    if !events.is_empty() && events.iter().all(|e| e.target.is_none()) {
        return Err(DatasetError::Unlabelled {
            path: path.to_path_buf(),
            n_events: events.len(),
            events: describe_events(events),
        });
    }
    Ok(rec)
}

/// The epochs of a labelled recording, cut by `pre` (the one preprocessing path, filtering the
/// recording in place); a recording whose every epoch is dropped is an error naming the cause
/// (not, later, "0 targets and 0 non-targets").
pub fn epoch(rec: Recording, pre: &Preprocess) -> Result<EpochedRecording, DatasetError> {
    let n_events = rec.raw.events().len();
    let path = rec.path;
    let speller = rec.speller;
    let (epochs, dropped) = match pre.params().epochs_owned(rec.raw) {
        Ok(e) => e,
        Err(source) => return Err(DatasetError::Epoch { path, source }),
    };
    if epochs.is_empty() && !dropped.is_empty() {
        return Err(DatasetError::AllDropped {
            path,
            n_epochs: dropped.len(),
            why: dropped.summary(),
        });
    }
    Ok(EpochedRecording {
        name: path.display().to_string(),
        n_events,
        speller,
        epochs,
    })
}

/// Reads and labels each run (a path and its [`Labelling`]), resamples it to `resample` Hz when
/// given, matches it to `layout` (else to the first run's, which is returned) and epochs it with
/// `pre`; `on_resampled(path, resampled, layout.of)` hears of every run resampled to the
/// layout's rate.
pub fn load_epochs<'a>(
    runs: impl IntoIterator<Item = (&'a Path, Labelling<'a>)>,
    pre: &Preprocess,
    resample: Option<f64>,
    layout: Option<&Layout>,
    on_resampled: &mut dyn FnMut(&Path, Resampled, &str),
) -> Result<(Vec<EpochedRecording>, Option<Layout>), DatasetError> {
    let mut layout = layout.cloned();
    let mut epoched = Vec::new();
    for (path, how) in runs {
        let mut rec = read_labelled(path, how)?;
        if let Some(to) =
            resample.filter(|&f| !oddball_signal::rate::same_sfreq(rec.raw.sfreq(), f))
        {
            rec.raw = oddball_signal::resample::resample_raw(&rec.raw, to).map_err(|source| {
                DatasetError::Resample {
                    path: path.to_path_buf(),
                    to,
                    source,
                }
            })?;
        }
        let rec = match &layout {
            Some(l) => {
                let (rec, resampled) = l.fit(rec).map_err(|e| DatasetError::Layout(Box::new(e)))?;
                if let Some(r) = resampled {
                    on_resampled(path, r, &l.of);
                }
                rec
            }
            None => {
                layout = Some(Layout::of_recording(&rec));
                rec
            }
        };
        epoched.push(epoch(rec, pre)?);
    }
    Ok((epoched, layout))
}

#[cfg(test)]
mod tests {
    use super::*;
    use oddball_io::CodeOrder;

    fn spec(rows: &[u32], columns: &[u32]) -> SpellerSpec {
        SpellerSpec {
            matrix: vec!["AB".into(), "CD".into(), "EF".into()],
            rows: rows.to_vec(),
            columns: columns.to_vec(),
            repetitions: Some(5),
        }
    }

    #[test]
    fn speller_codes_in_either_order_and_nothing_else() {
        let s = speller_of(&spec(&[1, 2, 3], &[4, 5])).unwrap();
        assert_eq!(s.code_order, CodeOrder::RowsFirst);
        assert_eq!((s.code_of_row(2), s.code_of_col(0)), (3, 4));
        assert_eq!(s.flashes_per_character, Some(25));
        let s = speller_of(&spec(&[3, 4, 5], &[1, 2])).unwrap();
        assert_eq!(s.code_order, CodeOrder::ColumnsFirst);
        assert_eq!((s.code_of_row(0), s.code_of_col(1)), (3, 2));
        let err = speller_of(&spec(&[1, 3, 5], &[2, 4])).unwrap_err();
        assert!(err.contains("1..5"), "{err}");
    }
}
