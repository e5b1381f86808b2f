//! Reading recordings and models for the commands: the files, with the path in every error.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use oddball_decode::evaluate::EpochedRecording;
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_io::events::describe_events;
use oddball_io::{EventMapping, Recording};

/// The formats [`oddball_io::read`] takes (by extension; XDF also by its magic bytes), for help
/// texts.
macro_rules! formats {
    () => {
        "BCI2000 .dat (v1.0/v1.1), CSV (e.g. Muse), EDF/EDF+/BDF (annotations as events), NIC \
         .easy (with its .info), XDF, MATLAB .mat v5/v7 (BCI Competition speller layout)"
    };
}
pub(crate) use formats;

/// Which events are targets, for recordings that do not flag them (MNE's `event_id`).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct EventArgs {
    /// The target events: stimulus codes or marker/annotation texts, comma-separated (e.g. 2 or
    /// Target). With --nontarget-events; replaces the file's own target flags, and events that
    /// match neither list are left out.
    #[arg(long, value_name = "KEYS", requires = "nontarget_events")]
    pub target_events: Option<String>,
    /// The non-target events, as --target-events (e.g. 1 or NonTarget).
    #[arg(long, value_name = "KEYS", requires = "target_events")]
    pub nontarget_events: Option<String>,
}

impl EventArgs {
    /// The mapping, checked (both lists, no key in both), or `None` when not given.
    pub fn mapping(&self) -> Result<Option<EventMapping>> {
        match (&self.target_events, &self.nontarget_events) {
            (Some(t), Some(n)) => Ok(Some(
                EventMapping::parse(t, n).context("--target-events/--nontarget-events")?,
            )),
            _ => Ok(None),
        }
    }
}

/// Reads a recording.
pub fn read(path: &Path) -> Result<Recording> {
    oddball_io::read(path).with_context(|| format!("reading {}", path.display()))
}

/// Reads a recording and applies the event mapping, if any.
pub fn read_mapped(path: &Path, mapping: Option<&EventMapping>) -> Result<Recording> {
    let mut rec = read(path)?;
    if let Some(m) = mapping {
        rec.map_events(m)
            .with_context(|| format!("labelling the events of {}", path.display()))?;
    }
    Ok(rec)
}

/// An error when a recording has events but none says whether it is a target, telling how to
/// label them.
fn check_labelled(rec: &Recording) -> Result<()> {
    let events = rec.raw.events();
    if !events.is_empty() && events.iter().all(|e| e.target.is_none()) {
        anyhow::bail!(
            "{} has {} events but none is labelled target or non-target (its events: {}); say \
             which are with --target-events and --nontarget-events (codes or marker texts, e.g. \
             --target-events 2 --nontarget-events 1), or for a speller run give the text it \
             spelled with --test-text",
            rec.path.display(),
            events.len(),
            describe_events(events)
        );
    }
    Ok(())
}

/// The epochs of one recording cut by `pre` (the one preprocessing path,
/// [`Preprocess::params`]).
pub fn epoch(rec: Recording, pre: &Preprocess) -> Result<EpochedRecording> {
    let name = rec.path.display().to_string();
    let n_events = rec.raw.events().len();
    let (epochs, dropped) = pre
        .params()
        .epochs_owned(rec.raw)
        .with_context(|| format!("epoching {name}"))?;
    if epochs.is_empty() && !dropped.is_empty() {
        // Name the real cause here, not later as "0 targets and 0 non-targets".
        anyhow::bail!(
            "{name}: every one of its {} epochs was dropped: {}",
            dropped.len(),
            dropped.summary()
        );
    }
    Ok(EpochedRecording {
        name,
        n_events,
        speller: rec.speller,
        epochs,
    })
}

/// The channels (by name, in order) and the rate every recording of a run must have: a model's,
/// or the first training file's. Recordings are matched to it by channel name (any order, extra
/// channels left out) before anything is filtered; a missing channel or another rate is an
/// error naming it.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub ch_names: Vec<String>,
    pub sfreq: f64,
    /// What it is, for messages ("model.json", "the training file a.dat").
    pub of: String,
}

impl Layout {
    pub fn of_model(model: &Model, path: &Path) -> Self {
        Self {
            ch_names: model.ch_names.clone(),
            sfreq: model.sfreq,
            of: format!("the model {}", path.display()),
        }
    }

    fn of_recording(rec: &Recording) -> Self {
        Self {
            ch_names: rec.raw.ch_names().to_vec(),
            sfreq: rec.raw.sfreq(),
            of: format!("the training file {}", rec.path.display()),
        }
    }

    /// `rec` with this layout's channels in its order.
    fn fit(&self, mut rec: Recording) -> Result<Recording> {
        let raw = &rec.raw;
        let what = || {
            format!(
                "matching the channels of {} to those of {}",
                rec.path.display(),
                self.of
            )
        };
        if (raw.sfreq() - self.sfreq).abs() > 1e-9 * self.sfreq {
            anyhow::bail!(
                "{} is sampled at {} Hz, {} at {} Hz",
                rec.path.display(),
                raw.sfreq(),
                self.of,
                self.sfreq
            );
        }
        if raw.ch_names() == self.ch_names.as_slice() {
            return Ok(rec);
        }
        oddball_decode::model::match_channels(&self.ch_names, raw.ch_names()).with_context(what)?;
        rec.raw = raw.pick_channels(&self.ch_names).with_context(what)?;
        Ok(rec)
    }
}

/// Reads, labels (see [`EventArgs`]; `texts`: the spelled text of each file, for speller runs
/// recorded without labels) and epochs each recording; a recording whose events carry no
/// labels is an error saying how to label them. Every file's channels are matched by name to
/// the first's ([`Layout`]).
pub fn load_epochs(
    paths: &[PathBuf],
    pre: &Preprocess,
    events: &EventArgs,
    texts: &[String],
) -> Result<Vec<EpochedRecording>> {
    load_epochs_in(paths, pre, events, texts, None).map(|(e, _)| e)
}

/// [`load_epochs`] with every file matched to `layout` (else to the first file's), returned.
pub fn load_epochs_in(
    paths: &[PathBuf],
    pre: &Preprocess,
    events: &EventArgs,
    texts: &[String],
    layout: Option<&Layout>,
) -> Result<(Vec<EpochedRecording>, Option<Layout>)> {
    if !texts.is_empty() && texts.len() != paths.len() {
        anyhow::bail!(
            "--test-text gives {} texts for {} test files (one per file)",
            texts.len(),
            paths.len()
        );
    }
    let mapping = events.mapping()?;
    let mut layout = layout.cloned();
    let epochs = paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut rec = read_mapped(p, mapping.as_ref())?;
            rec = match &layout {
                Some(l) => l.fit(rec)?,
                None => {
                    layout = Some(Layout::of_recording(&rec));
                    rec
                }
            };
            if let Some(text) = texts.get(i) {
                rec.label_from_text(text)
                    .with_context(|| format!("labelling {} from the text {text:?}", p.display()))?;
            }
            check_labelled(&rec)?;
            epoch(rec, pre)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((epochs, layout))
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}
