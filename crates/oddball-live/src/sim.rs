//! The simulated subject as a live source ([`SimSource`]), paced by the wall clock or as fast
//! as it is processed: `--source sim`.

use ndarray::Array2;
use oddball_session::SimulatedSubject;

use crate::clock::{Clock, Pacer};
use crate::live::EegSource;
use crate::LiveError;

/// The simulated subject as a live source, paced by the wall clock: sample `i` is acquired at
/// `start_ms + i / sfreq` and delivered `latency_ms` later (an amplifier's buffering), which is
/// what lets a flash stamped by the page reach the simulated brain before its samples render.
#[derive(Debug)]
pub struct SimSource {
    sim: SimulatedSubject,
    pacer: Pacer,
    latency_ms: f64,
    /// Samples that arrived too late to carry their flash's response.
    pub late_flashes: u64,
}

impl SimSource {
    pub fn new(sim: SimulatedSubject, clock: Clock, latency_ms: f64) -> Self {
        Self {
            pacer: Pacer::new(clock, sim.sfreq(), true),
            sim,
            latency_ms,
            late_flashes: 0,
        }
    }

    /// From now on paced by the wall clock, the next sample acquired now (after an unpaced
    /// calibration, say).
    pub fn pace_from_now(&mut self, latency_ms: f64) {
        self.pacer.paced = true;
        self.latency_ms = latency_ms;
        self.pacer.restart_at(self.sim.position());
    }

    /// As fast as it can (tests, and replaying a session's timing without waiting).
    pub fn unpaced(sim: SimulatedSubject, clock: Clock) -> Self {
        let mut s = Self::new(sim, clock, 0.0);
        s.pacer.paced = false;
        s
    }
}

impl EegSource for SimSource {
    fn sfreq(&self) -> f64 {
        self.sim.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.sim.ch_names()
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        self.pacer
            .wait_for(self.sim.position() + n as u64, self.latency_ms);
        Ok(())
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        Ok(self.sim.render(n))
    }
    fn time_of(&self, sample: u64) -> f64 {
        self.pacer.time_of(sample)
    }
    fn start_now(&mut self) {
        if self.pacer.paced {
            self.pace_from_now(self.latency_ms);
        }
    }
    fn saw(&mut self, onset: u64, _code: u32, attended: bool) -> Result<(), LiveError> {
        if onset < self.sim.position() || self.sim.flash(onset, attended).is_err() {
            self.late_flashes += 1;
        }
        Ok(())
    }
}
