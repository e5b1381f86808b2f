//! The closed loop of the oddball BCI: what the panel shows, who looks at it, and the engine that
//! turns their EEG into arm commands.
//!
//! The files in layers, each importing only those above it in this list:
//!
//! * [`paradigm`]: stimulus schedules, (onset time, stimulus code) pairs shared by the panel and
//!   the decoder: the paper's four-bulb panel and the 6 × 6 row/column speller.
//! * [`decision`]: the records: flashes shown, trials run, what calibration measured, and the
//!   one [`decision::Decision`] record the tasks, the replay and the reports share.
//! * [`online`]: the causal epocher a session streams its EEG through.
//! * [`subject`]: a simulated subject who attends one stimulus and produces 8-channel EEG: 1/f
//!   background, alpha, mains, drift, blinks, a visual response to every flash and a P300 to the
//!   attended ones (presets easy, typical, hard).
//! * [`roles`]: what a session talks to, one trait per role: the EEG stream, the stimulus
//!   presenter, the observer (a [`roles::Subject`] is all three).
//! * [`timing`]: the paradigm's timing meeting the bit rate: the stopping rule chosen from the
//!   calibration for the most bits per minute, and where a decision's time went.
//! * [`prequential`]: how sure an uncalibrated session can be: a score model of the latest
//!   fit's leave-one-trial-out scores, weighing the trial in progress as scored by the model
//!   fitted before it.
//! * `fit` (private): a session's model fitted on labelled epochs, its score model on
//!   cross-validated scores.
//! * [`decoder`]: how a session starts ([`decoder::Start`]) and the decoder it then decides
//!   with (calibrated, adapting, given, or unsupervised).
//! * [`listener`]: another program's session decoded: its markers read by a paradigm file,
//!   epochs cut at their times, a decision per trial (and a stop when sure).
//! * [`engine`]: the session loop: calibration trials, online decisions driving the arm.
//! * [`replay`] and [`record`]: speller recordings replayed as four-choice decisions; session
//!   files saved, read and re-decided.
//! * [`tasks`]: tasks people do with a pilot (copy, tracking, drawing) and the stroke font.
//! * [`report`]: on top, imported by nothing here: what a run reports: decision rows, accuracy
//!   and ITR, the pen's corners, and their text.
//!
//! # Example
//! The paper's four-bulb panel gives each command its own stimulus code:
//! ```
//! use oddball_arm::Command;
//! use oddball_session::paradigm::FourBulbParams;
//!
//! let panel = FourBulbParams::paper();
//! for c in [Command::Up, Command::Down, Command::Left, Command::Right] {
//!     assert_eq!(panel.command_of(panel.code_of(c)), Some(c));
//! }
//! assert_eq!(panel.command_of(0), None);
//! ```

pub mod decision;
pub mod decoder;
pub mod engine;
mod error;
mod fit;
pub mod listener;
pub mod online;
pub mod paradigm;
pub mod prequential;
pub mod record;
pub mod replay;
pub mod report;
pub mod roles;
pub mod subject;
pub mod tasks;
pub mod timing;

pub use error::SessionError;
pub use subject::{SimulatedSubject, SubjectParams, SubjectPreset};
