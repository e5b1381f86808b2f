//! The closed loop of the oddball BCI: what the panel shows, who looks at it, and the engine that
//! turns their EEG into arm commands.
//!
//! * [`paradigm`]: stimulus schedules, (onset time, stimulus code) pairs shared by the panel and
//!   the decoder: the paper's four-bulb panel and the 6 × 6 row/column speller.
//! * [`subject`]: a simulated subject who attends one stimulus and produces 8-channel EEG: 1/f
//!   background, alpha, mains, drift, blinks, a visual response to every flash and a P300 to the
//!   attended ones (presets easy, typical, hard).
//! * [`roles`]: what a session talks to, one trait per role: the EEG stream, the stimulus
//!   presenter, the observer (a [`roles::Subject`] is all three).
//! * [`engine`]: the session: calibration, training, online decisions driving the arm.
//! * [`task`]: tasks people do with a pilot (copy, tracking, drawing).
//! * [`timing`]: the paradigm's timing meeting the bit rate: the stopping rule chosen from the
//!   calibration for the most bits per minute, and where a decision's time went.
//! * [`report`]: what a copy task's run reports: decision rows, accuracy and ITR, the pen's
//!   corners, and their text.
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

pub mod engine;
mod error;
pub mod online;
pub mod paradigm;
pub mod record;
pub mod replay;
pub mod report;
pub mod roles;
pub mod subject;
pub mod task;
pub mod timing;

pub use error::SessionError;
pub use subject::{SimulatedSubject, SubjectParams, SubjectPreset};
