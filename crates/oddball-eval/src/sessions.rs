//! Session files (`session.dat` of `oddball demo`) re-decided offline: every online decision
//! recomputed from the raw EEG by a model ([`oddball_session::record::reevaluate`]) and
//! compared with the recorded one.

use std::path::{Path, PathBuf};

use oddball_arm::Command;
use oddball_decode::model::Model;
use oddball_io::ReadOptions;
use oddball_session::record::{read_session, reevaluate};
use oddball_session::report::SessionResult;
use oddball_session::SessionError;
use thiserror::Error;

use crate::dataset::{self, DatasetError};

/// Why a session file could not be re-decided; every variant names the file.
#[derive(Debug, Error)]
pub enum SessionFileError {
    #[error(transparent)]
    Read(#[from] DatasetError),
    #[error("reading {}", path.display())]
    Session {
        path: PathBuf,
        #[source]
        source: Box<SessionError>,
    },
    #[error("re-evaluating {} with {}", path.display(), model.display())]
    Reevaluate {
        path: PathBuf,
        model: PathBuf,
        #[source]
        source: Box<SessionError>,
    },
}

/// A session file's decisions re-made and scored, with the commands of its four bulbs.
#[derive(Debug, Clone)]
pub struct Redecided {
    pub result: SessionResult,
    pub bulbs: [Command; 4],
}

/// Re-decides every online decision of the session file at `path` with `model` (saved at
/// `model_path`, named in errors).
pub fn redecide(
    path: &Path,
    model: &Model,
    model_path: &Path,
) -> Result<Redecided, SessionFileError> {
    let rec = dataset::read(path, &ReadOptions::default())?;
    let saved = read_session(&rec).map_err(|source| SessionFileError::Session {
        path: path.to_path_buf(),
        source: Box::new(source),
    })?;
    let decisions =
        reevaluate(&rec, &saved, model).map_err(|source| SessionFileError::Reevaluate {
            path: path.to_path_buf(),
            model: model_path.to_path_buf(),
            source: Box::new(source),
        })?;
    Ok(Redecided {
        result: SessionResult::new(path.to_path_buf(), decisions),
        bulbs: saved.bulbs,
    })
}
