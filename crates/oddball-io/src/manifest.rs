//! Data sets as files: a TOML manifest naming subjects, their runs and roles, the event mapping
//! and the speller geometry.
//!
//! ```toml
//! name = "bnci-like"
//! root = "../data"         # optional: run paths are relative to this folder (itself relative
//!                          # to the manifest's folder); `oddball benchmark --data DIR` replaces it
//! [events]                 # codes or annotation texts; not needed when the files flag targets
//! target = [2]
//! nontarget = [1]
//! [read]                   # optional: what CSV/MAT files do not say themselves
//! sfreq = 256.0            # Hz; also: channels, time_column, events (CSV column or MAT
//!                          # variable of codes), data (MAT variable of samples)
//! [speller]                # optional
//! matrix = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"]
//! columns = [1, 2, 3, 4, 5, 6]
//! rows = [7, 8, 9, 10, 11, 12]
//! repetitions = 15         # sequences per character
//! [[subject]]
//! id = "s1"
//! train = ["s1_train.bdf"] # paths relative to the manifest
//! test = ["s1_test.bdf"]
//! test_text = ["WATER"]    # optional, one per test file without labels
//! [subject.sessions]       # optional: runs recorded together, for within-session evaluation
//! "1" = ["s1_train.bdf"]   # (without it, all of a subject's runs are one session)
//! "2" = ["s1_test.bdf"]
//! ```
//!
//! [`Manifest::load`] checks everything that can be checked before any EEG is read: unknown keys
//! (a typo is an error, not a silently ignored setting), every file present, subject ids unique,
//! the speller's codes distinct and matching its matrix, one `test_text` per test file. serde +
//! `toml` do the parsing; the checks are ours.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::events::{EventMapError, EventMapping};

/// A speller's geometry: its matrix and which stimulus codes flash which rows and columns.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpellerSpec {
    /// Rows of one-character symbols, top to bottom.
    pub matrix: Vec<String>,
    /// The code that flashes each column, left to right.
    pub columns: Vec<u32>,
    /// The code that flashes each row, top to bottom.
    pub rows: Vec<u32>,
    /// Sequences (each row and column flashed once) per character.
    pub repetitions: Option<usize>,
}

impl SpellerSpec {
    /// Flashes per character: `repetitions × (n_rows + n_cols)`, when the repetitions are given.
    pub fn flashes_per_character(&self) -> Option<usize> {
        self.repetitions
            .map(|r| r * (self.rows.len() + self.columns.len()))
    }

    /// The [`crate::Speller`] of this geometry: its codes must be the rows then the columns, or
    /// the columns then the rows, numbered from 1 (the two layouts BCI2000 and the BCI
    /// Competitions use).
    pub fn speller(&self) -> Result<crate::Speller, String> {
        use crate::CodeOrder;
        let mut speller = crate::Speller::from_rows(&self.matrix)
            .ok_or_else(|| "the matrix has no symbols or rows of different lengths".to_string())?;
        let (n_rows, n_cols) = (self.rows.len() as u32, self.columns.len() as u32);
        let seq = |from: u32, n: u32| (from..from + n).collect::<Vec<u32>>();
        if self.rows == seq(1, n_rows) && self.columns == seq(n_rows + 1, n_cols) {
            speller.code_order = CodeOrder::RowsFirst;
        } else if self.columns == seq(1, n_cols) && self.rows == seq(n_cols + 1, n_rows) {
            speller.code_order = CodeOrder::ColumnsFirst;
        } else {
            return Err(format!(
                "rows {:?} and columns {:?}: the codes must be 1..{} for the rows then the \
                 columns, or for the columns then the rows",
                self.rows,
                self.columns,
                n_rows + n_cols
            ));
        }
        speller.flashes_per_character = self.flashes_per_character();
        Ok(speller)
    }

    pub(crate) fn validate(&self) -> Result<(), String> {
        let n_rows = self.matrix.len();
        if n_rows == 0 {
            return Err("speller.matrix has no rows".into());
        }
        let n_cols = self.matrix[0].chars().count();
        if let Some((i, r)) = self
            .matrix
            .iter()
            .enumerate()
            .find(|(_, r)| r.chars().count() != n_cols)
        {
            return Err(format!(
                "speller.matrix row {} ({r:?}) has {} symbols, row 1 has {n_cols}",
                i + 1,
                r.chars().count()
            ));
        }
        if self.rows.len() != n_rows {
            return Err(format!(
                "speller.rows lists {} codes for a matrix of {n_rows} rows",
                self.rows.len()
            ));
        }
        if self.columns.len() != n_cols {
            return Err(format!(
                "speller.columns lists {} codes for a matrix of {n_cols} columns",
                self.columns.len()
            ));
        }
        let mut seen = BTreeSet::new();
        for c in self.rows.iter().chain(&self.columns) {
            if !seen.insert(*c) {
                return Err(format!("speller code {c} is listed twice"));
            }
        }
        if self.repetitions == Some(0) {
            return Err("speller.repetitions must be at least 1".into());
        }
        Ok(())
    }
}

/// One subject's runs. Paths are resolved against the manifest's folder by [`Manifest::load`].
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Subject {
    pub id: String,
    /// Labelled runs to fit on.
    #[serde(default)]
    pub train: Vec<PathBuf>,
    /// Runs to test on (labelled, or unlabelled with `test_text`).
    #[serde(default)]
    pub test: Vec<PathBuf>,
    /// The text spelled in each test run whose file carries no labels, in the order of `test`.
    pub test_text: Option<Vec<String>>,
    /// Sessions (runs recorded together), each a list of this subject's runs; `None`: all runs
    /// are one session.
    pub sessions: Option<BTreeMap<String, Vec<PathBuf>>>,
}

impl Subject {
    /// Every run, training runs first.
    pub fn runs(&self) -> impl Iterator<Item = &PathBuf> {
        self.train.iter().chain(&self.test)
    }

    /// The spelled text of a run, for test runs recorded without labels.
    pub fn text_of(&self, run: &Path) -> Option<&str> {
        let i = self.test.iter().position(|r| r == run)?;
        self.test_text.as_ref()?.get(i).map(String::as_str)
    }

    /// The sessions and their runs, in name order; all runs as one session `"all"` when the
    /// manifest names none.
    pub fn session_runs(&self) -> Vec<(String, Vec<PathBuf>)> {
        match &self.sessions {
            Some(s) => s.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
            None => vec![("all".to_string(), self.runs().cloned().collect())],
        }
    }
}

/// A data set: subjects and runs, how to read their events.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub name: String,
    /// The folder run paths are relative to, itself relative to the manifest's folder.
    pub root: Option<PathBuf>,
    /// Which events are targets; `None` when the files flag targets themselves.
    pub events: Option<EventMapping>,
    pub speller: Option<SpellerSpec>,
    /// How to read files that do not say everything themselves (CSV columns, MAT variables,
    /// the sampling rate).
    pub read: Option<crate::ReadOptions>,
    #[serde(rename = "subject")]
    pub subjects: Vec<Subject>,
    /// The manifest file (set by [`Manifest::load`]).
    #[serde(skip)]
    pub path: PathBuf,
}

/// A manifest that cannot be used, with the file and the field at fault.
#[derive(Debug, Error)]
pub enum ManifestError {
    /// The manifest's path is not a readable regular file (missing, a folder, a device).
    #[error(transparent)]
    File(Box<crate::IoError>),
    #[error("{path}: cannot read the manifest: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Parse {
        path: PathBuf,
        source: Box<toml::de::Error>,
    },
    #[error("{path}: [events]: {source}")]
    Events {
        path: PathBuf,
        source: EventMapError,
    },
    #[error("{path}: {what}")]
    Invalid { path: PathBuf, what: String },
    #[error("{path}: subject {subject:?}: run {run} does not exist")]
    MissingRun {
        path: PathBuf,
        subject: String,
        run: PathBuf,
    },
}

impl Manifest {
    /// Reads and checks a manifest; run paths become paths relative to the manifest's folder
    /// joined with its `root` (absolute paths are kept).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ManifestError> {
        Self::load_with_root(path, None)
    }

    /// As [`Manifest::load`], with run paths relative to `root` instead of the manifest's own
    /// `root` (e.g. the data kept in another folder).
    pub fn load_with_root(
        path: impl AsRef<Path>,
        root: Option<&Path>,
    ) -> Result<Self, ManifestError> {
        let path = path.as_ref();
        crate::check_file(path).map_err(|e| ManifestError::File(Box::new(e)))?;
        let text = std::fs::read_to_string(path).map_err(|source| ManifestError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let mut m = Self::parse(&text, path)?;
        let dir = match (root, &m.root) {
            (Some(r), _) => r.to_path_buf(),
            (None, Some(r)) => path.parent().unwrap_or(Path::new(".")).join(r),
            (None, None) => path.parent().unwrap_or(Path::new(".")).to_path_buf(),
        };
        m.root = Some(dir.clone());
        // A montage file named by `[read]` is data too: relative to the root, as the runs.
        if let Some(montage) = m.read.as_mut().and_then(|r| r.montage.as_mut()) {
            *montage = dir.join(&*montage);
        }
        for s in &mut m.subjects {
            let sessions = s.sessions.iter_mut().flat_map(|t| t.values_mut().flatten());
            for run in sessions {
                *run = dir.join(&*run);
            }
            for run in s.train.iter_mut().chain(s.test.iter_mut()) {
                *run = dir.join(&*run);
                if !run.is_file() {
                    return Err(ManifestError::MissingRun {
                        path: path.to_path_buf(),
                        subject: s.id.clone(),
                        run: run.clone(),
                    });
                }
            }
        }
        Ok(m)
    }

    /// The spelled text of a run given by path (any subject's test run with a `test_text`);
    /// paths are compared as the file system resolves them, so `data/../data/x.mat` is `x.mat`.
    pub fn text_of(&self, run: &Path) -> Option<&str> {
        let canonical = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        let run = canonical(run);
        self.subjects.iter().find_map(|s| {
            let i = s.test.iter().position(|r| canonical(r) == run)?;
            s.test_text.as_ref()?.get(i).map(String::as_str)
        })
    }

    /// Parses and checks manifest text; `path` names it in errors. Run paths are left as written.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ManifestError> {
        let mut m: Manifest = toml::from_str(text).map_err(|e| ManifestError::Parse {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
        m.path = path.to_path_buf();
        m.validate()?;
        Ok(m)
    }

    fn invalid(&self, what: impl Into<String>) -> ManifestError {
        ManifestError::Invalid {
            path: self.path.clone(),
            what: what.into(),
        }
    }

    fn validate(&self) -> Result<(), ManifestError> {
        if self.name.trim().is_empty() {
            return Err(self.invalid("name is empty"));
        }
        if let Some(events) = &self.events {
            events.validate().map_err(|source| ManifestError::Events {
                path: self.path.clone(),
                source,
            })?;
        }
        if let Some(sp) = &self.speller {
            sp.validate().map_err(|w| self.invalid(w))?;
        }
        if let Some(r) = &self.read {
            r.check()
                .map_err(|w| self.invalid(format!("[read]: {w}")))?;
        }
        if self.subjects.is_empty() {
            return Err(self.invalid("no [[subject]] entries"));
        }
        let mut ids = BTreeSet::new();
        for s in &self.subjects {
            if s.id.trim().is_empty() {
                return Err(self.invalid("a subject has an empty id"));
            }
            if !ids.insert(s.id.as_str()) {
                return Err(self.invalid(format!("subject id {:?} is used twice", s.id)));
            }
            if s.train.is_empty() && s.test.is_empty() {
                return Err(self.invalid(format!("subject {:?} has no runs", s.id)));
            }
            if let Some(texts) = &s.test_text {
                if texts.len() != s.test.len() {
                    return Err(self.invalid(format!(
                        "subject {:?}: test_text has {} entries for {} test runs",
                        s.id,
                        texts.len(),
                        s.test.len()
                    )));
                }
                if self.speller.is_none() {
                    return Err(self.invalid(format!(
                        "subject {:?}: test_text needs a [speller] table",
                        s.id
                    )));
                }
            }
            if let Some(sessions) = &s.sessions {
                let mut seen = BTreeSet::new();
                for (name, runs) in sessions {
                    if runs.is_empty() {
                        return Err(self
                            .invalid(format!("subject {:?}: session {name:?} has no runs", s.id)));
                    }
                    for run in runs {
                        if !s.runs().any(|r| r == run) {
                            return Err(self.invalid(format!(
                                "subject {:?}: session {name:?} names {}, which is not one of \
                                 the subject's train or test runs",
                                s.id,
                                run.display()
                            )));
                        }
                        if !seen.insert(run) {
                            return Err(self.invalid(format!(
                                "subject {:?}: run {} is in two sessions",
                                s.id,
                                run.display()
                            )));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::EventKey;

    const MINIMAL: &str = r#"
name = "bnci-like"
[events]
target = [2]
nontarget = [1]
[speller]
matrix = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"]
columns = [1, 2, 3, 4, 5, 6]
rows = [7, 8, 9, 10, 11, 12]
repetitions = 15
[[subject]]
id = "s1"
train = ["s1_train.bdf"]
test = ["s1_test.bdf"]
test_text = ["WATER"]
"#;

    #[test]
    fn the_minimal_form_parses() {
        let m = Manifest::parse(MINIMAL, Path::new("m.toml")).unwrap();
        assert_eq!(m.name, "bnci-like");
        assert_eq!(m.events.as_ref().unwrap().target, vec![EventKey::Code(2)]);
        let sp = m.speller.as_ref().unwrap();
        assert_eq!(sp.flashes_per_character(), Some(180));
        assert_eq!(
            m.subjects[0].test_text.as_deref(),
            Some(&["WATER".to_string()][..])
        );
        assert_eq!(m.subjects[0].runs().count(), 2);
    }

    #[test]
    fn load_resolves_runs_and_refuses_missing_ones() {
        let dir = std::env::temp_dir().join(format!("oddball-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("s1_train.bdf"), b"x").unwrap();
        std::fs::write(dir.join("m.toml"), MINIMAL).unwrap();
        let err = Manifest::load(dir.join("m.toml")).unwrap_err();
        assert!(
            matches!(&err, ManifestError::MissingRun { run, .. } if run.ends_with("s1_test.bdf")),
            "{err}"
        );
        std::fs::write(dir.join("s1_test.bdf"), b"x").unwrap();
        let m = Manifest::load(dir.join("m.toml")).unwrap();
        assert_eq!(m.subjects[0].train[0], dir.join("s1_train.bdf"));
        // A test run's text, by the path as given (another spelling of it too); none for others.
        let sub = dir.join("sub");
        std::fs::create_dir_all(&sub).unwrap();
        assert_eq!(m.text_of(&sub.join("../s1_test.bdf")), Some("WATER"));
        assert_eq!(m.text_of(&dir.join("s1_train.bdf")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn mistakes_are_named() {
        let bad = |from: &str, to: &str| {
            let text = MINIMAL.replace(from, to);
            Manifest::parse(&text, Path::new("m.toml"))
                .unwrap_err()
                .to_string()
        };
        assert!(bad("repetitions", "repetitons").contains("repetitons"));
        assert!(bad("rows = [7, 8, 9, 10, 11, 12]", "rows = [7, 8, 9]").contains("3 codes"));
        assert!(bad(
            "rows = [7, 8, 9, 10, 11, 12]",
            "rows = [1, 8, 9, 10, 11, 12]"
        )
        .contains("code 1 is listed twice"));
        assert!(bad("\"YZ1234\"", "\"YZ123\"").contains("row 5"));
        assert!(bad("test_text = [\"WATER\"]", "test_text = [\"A\", \"B\"]").contains("2 entries"));
        assert!(bad("nontarget = [1]", "nontarget = [2]").contains("both as a target"));
        let twice = format!("{MINIMAL}\n[[subject]]\nid = \"s1\"\ntrain = [\"x.bdf\"]\n");
        assert!(Manifest::parse(&twice, Path::new("m.toml"))
            .unwrap_err()
            .to_string()
            .contains("used twice"));
    }
}
