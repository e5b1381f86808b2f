//! Reading recordings and models for the commands: the files, with the path in every error.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use oddball_decode::dataset;
use oddball_decode::evaluate::EpochedRecording;
use oddball_decode::pipeline::{Model, Preprocess};
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

/// Reads, labels (see [`EventArgs`]; `texts`: the spelled text of each file, for speller runs
/// recorded without labels) and epochs each recording
/// ([`oddball_decode::dataset::load_epochs`]); a recording whose events carry no labels is an
/// error saying how to label them.
pub fn load_epochs(
    paths: &[PathBuf],
    pre: &Preprocess,
    events: &EventArgs,
    texts: &[String],
) -> Result<Vec<EpochedRecording>> {
    let mapping = events.mapping()?;
    Ok(dataset::load_epochs(
        paths,
        pre,
        mapping.as_ref(),
        texts,
        None,
    )?)
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}
