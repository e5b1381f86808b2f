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
    let (epochs, _dropped) = pre
        .params()
        .epochs(&rec.raw)
        .with_context(|| format!("epoching {}", rec.path.display()))?;
    Ok(EpochedRecording {
        name: rec.path.display().to_string(),
        n_events: rec.raw.events().len(),
        speller: rec.speller,
        epochs,
    })
}

/// Reads, labels (see [`EventArgs`]; `texts`: the spelled text of each file, for speller runs
/// recorded without labels) and epochs each recording; a recording whose events carry no
/// labels is an error saying how to label them.
pub fn load_epochs(
    paths: &[PathBuf],
    pre: &Preprocess,
    events: &EventArgs,
    texts: &[String],
) -> Result<Vec<EpochedRecording>> {
    if !texts.is_empty() && texts.len() != paths.len() {
        anyhow::bail!(
            "--test-text gives {} texts for {} test files (one per file)",
            texts.len(),
            paths.len()
        );
    }
    let mapping = events.mapping()?;
    paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut rec = read_mapped(p, mapping.as_ref())?;
            if let Some(text) = texts.get(i) {
                rec.label_from_text(text)
                    .with_context(|| format!("labelling {} from the text {text:?}", p.display()))?;
            }
            check_labelled(&rec)?;
            epoch(rec, pre)
        })
        .collect()
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}
