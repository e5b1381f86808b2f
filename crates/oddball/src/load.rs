//! Reading recordings and models for the commands: the files, with the path in every error.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use oddball_decode::evaluate::EpochedRecording;
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_io::Recording;

/// The formats [`oddball_io::read`] takes (by extension; XDF also by its magic bytes), for help
/// texts.
macro_rules! formats {
    () => {
        "BCI2000 .dat (v1.0/v1.1), CSV (e.g. Muse), EDF/EDF+/BDF (annotations as events), NIC \
         .easy (with its .info), XDF"
    };
}
pub(crate) use formats;

/// Reads a recording.
pub fn read(path: &Path) -> Result<Recording> {
    oddball_io::read(path).with_context(|| format!("reading {}", path.display()))
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

/// Reads and epochs each recording.
pub fn load_epochs(paths: &[PathBuf], pre: &Preprocess) -> Result<Vec<EpochedRecording>> {
    paths.iter().map(|p| epoch(read(p)?, pre)).collect()
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}
