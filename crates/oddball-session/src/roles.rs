//! The roles a [`crate::engine::Session`] talks to, one trait each:
//!
//! * [`EegStream`]: where the EEG comes from (a simulated subject, an amplifier's stream, a
//!   recording played back);
//! * [`Presenter`]: what shows the stimuli (the panel a person looks at; for a simulated
//!   subject, its own eyes), and reports when each flash was really drawn;
//! * [`Observer`]: what is told how trials ended and where the arm is (markers, the
//!   recording, the panel's arm view).
//!
//! A [`Subject`] is all three: the person in front of the panel with their amplifier.
//!
//! Units: positions and onsets are sample indices from the session's first sample, at the
//! stream's `sfreq` (Hz); EEG is µV, `(n_channels, n_times)`. Wall-clock (session-clock, ms)
//! times belong to the live sources (`oddball_live`), which map them to samples.

use ndarray::Array2;
use oddball_arm::ArmSim;
use serde::{Deserialize, Serialize};

use crate::decision::{Phase, TrialRecord};
use crate::online::ChannelFaults;
use crate::SessionError;

/// A source of EEG on its own sample clock.
pub trait EegStream {
    /// Sampling rate, Hz.
    fn sfreq(&self) -> f64;
    fn ch_names(&self) -> &[String];
    /// Samples produced so far (the index of the next one).
    fn position(&self) -> u64;
    /// The next `n` samples `(n_channels, n)`, µV; an error when the source is gone.
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError>;
    /// For live streams: samples lost, reconnections (`None` for simulated sources).
    fn stream_health(&self) -> Option<String> {
        None
    }
}

/// What shows the flashes.
pub trait Presenter {
    /// Samples ahead of the stream at which flashes are announced with [`Presenter::show`]: a
    /// live panel needs its schedule before it draws (0: when the stream reaches the onset's
    /// chunk).
    fn lead(&self) -> u64 {
        0
    }
    /// A flash of stimulus `code` at sample `onset` (≥ the stream's position); `attended` when
    /// it is the stimulus the person attends.
    fn show(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), SessionError>;
    /// Flashes whose real onset has been measured since the last call (a panel stamps the frame
    /// that drew each one). The engine moves their markers there before their epochs complete;
    /// a flash reported as never drawn loses its epoch. Simulated subjects draw on schedule.
    fn drawn(&mut self) -> Vec<Drawn> {
        Vec::new()
    }
    /// A trial begins at sample `start` (its countdown); the person is cued to attend
    /// `intended` (`None`: nothing).
    fn trial_started(
        &mut self,
        _start: u64,
        _phase: Phase,
        _intended: Option<u32>,
    ) -> Result<(), SessionError> {
        Ok(())
    }
    /// Asked before every trial: `true` holds the session there (an operator paused it). While
    /// held the engine keeps taking EEG and running the arm but starts no trial and shows no
    /// flash, so a pause never cuts a trial and the recording stays continuous.
    fn hold(&mut self) -> Result<bool, SessionError> {
        Ok(false)
    }
}

/// What is told how the session goes.
pub trait Observer {
    /// A trial ended (a calibration trial's last epoch arrived, or an online decision was made
    /// and its command issued). Flashes announced for it but not yet drawn are void.
    fn trial_ended(&mut self, _trial: &TrialRecord) -> Result<(), SessionError> {
        Ok(())
    }
    /// After every chunk while the arm runs: its state at sample `position`.
    fn arm_state(&mut self, _position: u64, _arm: &ArmSim) -> Result<(), SessionError> {
        Ok(())
    }
    /// After every trial: per channel, the epochs rejected because of it so far (NaN, flat or
    /// saturated, over the threshold), in the stream's channel order.
    fn channel_faults(&mut self, _faults: &[ChannelFaults]) -> Result<(), SessionError> {
        Ok(())
    }
}

/// The person in front of the panel: an EEG stream, a presenter and an observer in one.
pub trait Subject: EegStream + Presenter + Observer {}

impl<T: EegStream + Presenter + Observer> Subject for T {}

/// A flash's measured onset: the one announced at sample `planned` with stimulus `code` was
/// drawn at sample `onset` (`None`: never drawn).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Drawn {
    pub planned: u64,
    pub code: u32,
    pub onset: Option<u64>,
}

impl EegStream for crate::subject::SimulatedSubject {
    fn sfreq(&self) -> f64 {
        crate::subject::SimulatedSubject::sfreq(self)
    }
    fn ch_names(&self) -> &[String] {
        crate::subject::SimulatedSubject::ch_names(self)
    }
    fn position(&self) -> u64 {
        crate::subject::SimulatedSubject::position(self)
    }
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        Ok(crate::subject::SimulatedSubject::render(self, n))
    }
}

/// The simulated person sees every flash on schedule.
impl Presenter for crate::subject::SimulatedSubject {
    fn show(&mut self, onset: u64, _code: u32, attended: bool) -> Result<(), SessionError> {
        self.flash(onset, attended)
    }
}

impl Observer for crate::subject::SimulatedSubject {}
