//! The runs behind oddball's commands, for any front end (the command line, a GUI, Python): a
//! run is built from plain settings, checked before any EEG work, run, and says what it does on
//! a writer the front end gives (the command line gives standard output). Errors carry the facts
//! and name no command-line flag ([`SettingError`] for settings a front end maps back to its own
//! option names).
//!
//! Layers, bottom up:
//! - [`error`]: [`SettingError`], [`AppError`];
//! - [`settings`]: [`SessionSettings`] and [`SourceSettings`] → decision rules, session
//!   parameters, how the session starts, a live [`oddball_live::plan::SessionPlan`], opened;
//! - [`replayed`]: a replayed speller subject's files and calibration;
//! - [`panel`]: the browser panel served and a page waited for;
//! - [`pilot`]: the calibrated pilot of the demo and the tasks (replayed or live);
//! - [`report`]: the report folder's files;
//! - the runs: [`demo::Demo`], [`task::TaskRun`] (track, draw), [`online::Online`].

// A run's error is returned once, at its end, never in a loop: its size costs nothing, and boxing
// every library error it carries would only hide the facts behind one more indirection.
#![allow(clippy::result_large_err)]

pub mod demo;
pub mod error;
pub mod online;
pub mod panel;
pub mod pilot;
pub mod replayed;
pub mod report;
pub mod settings;
pub mod task;

pub use error::{AppError, SettingError, StartKind};
pub use settings::{CalibrationSpec, SessionSettings, SourceSettings, SubjectSpec};
