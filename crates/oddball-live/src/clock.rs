//! The session clock, and pacing a source by it.
//!
//! Times are milliseconds since the clock was made (monotonic): the panel stamps flashes on it,
//! the sources map sample indices to it ([`crate::live::EegSource::time_of`]), markers and the
//! recording are written on it. [`Pacer`] is the one place a source waits for the wall clock to
//! reach a sample (the simulated subject, a played-back recording); a real stream paces itself.

use std::time::{Duration, Instant};

/// The session clock: milliseconds since it was made, monotonic.
#[derive(Debug, Clone, Copy)]
pub struct Clock {
    zero: Instant,
}

impl Clock {
    pub fn new() -> Self {
        Self {
            zero: Instant::now(),
        }
    }
    pub fn now_ms(&self) -> f64 {
        self.zero.elapsed().as_secs_f64() * 1e3
    }
    /// The instant of clock time `ms`.
    pub fn instant(&self, ms: f64) -> Instant {
        self.zero + Duration::from_secs_f64(ms.max(0.0) / 1e3)
    }
}

impl Default for Clock {
    fn default() -> Self {
        Self::new()
    }
}

/// A source's sample clock on the session clock: sample `i` (at `sfreq` Hz) is due at
/// `start_ms + i / sfreq` (ms), and, when paced, is not handed out before then (plus a
/// latency).
#[derive(Debug, Clone, Copy)]
pub struct Pacer {
    clock: Clock,
    sfreq: f64,
    start_ms: f64,
    /// Wait for the wall clock (`false`: as fast as the consumer takes samples).
    pub paced: bool,
}

impl Pacer {
    /// Sample 0 due now.
    pub fn new(clock: Clock, sfreq: f64, paced: bool) -> Self {
        Self {
            start_ms: clock.now_ms(),
            clock,
            sfreq,
            paced,
        }
    }

    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// Session-clock time (ms) of sample `sample`.
    pub fn time_of(&self, sample: u64) -> f64 {
        self.start_ms + sample as f64 * 1e3 / self.sfreq
    }

    /// Sample `position` is due now (after a pause, or an unpaced calibration).
    pub fn restart_at(&mut self, position: u64) {
        self.start_ms = self.clock.now_ms() - position as f64 * 1e3 / self.sfreq;
    }

    /// When paced, sleeps until sample `sample` is due plus `latency_ms`.
    pub fn wait_for(&self, sample: u64, latency_ms: f64) {
        if !self.paced {
            return;
        }
        let at = self.clock.instant(self.time_of(sample) + latency_ms);
        let now = Instant::now();
        if at > now {
            std::thread::sleep(at - now);
        }
    }
}
