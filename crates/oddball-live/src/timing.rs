//! How the flashes were drawn, measured: on-times, onset errors, the page's report delays and
//! the flashes lost ([`FlashTiming`]), the rule a page's stamp must pass ([`plausible_stamp`]),
//! and the summary statistics the reports print ([`Summary`]).

use crate::panel::protocol::UNDRAWN_AFTER_MS;

/// Flash timing as measured: on-times and onset errors (ms), and the flashes lost.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FlashTiming {
    pub on_ms: Vec<f64>,
    /// Drawn onset − planned onset.
    pub onset_error_ms: Vec<f64>,
    /// Stamp arrival − drawn onset (page → server delay of the on report).
    pub report_delay_ms: Vec<f64>,
    pub undrawn: usize,
    /// Stamps that came after their flash had been declared undrawn.
    pub late_stamps: usize,
    /// Stamps refused as implausible ([`plausible_stamp`]): their flash counts as undrawn.
    pub refused_stamps: usize,
}

/// Whether a page's stamp `on_ms` for a flash scheduled at `at_ms` (both session-clock ms) is
/// plausible: within [`UNDRAWN_AFTER_MS`] either side of the schedule. A page draws a flash at
/// the frame nearest its time; a stamp far off it (a clock gone wrong, a hostile client: `0`,
/// `1e15`) would move the flash's epoch before the buffered EEG or into a future that never
/// comes. One home for the rule: every stamp passes here before it reaches the engine.
pub fn plausible_stamp(at_ms: f64, on_ms: f64) -> bool {
    (on_ms - at_ms).abs() <= UNDRAWN_AFTER_MS
}

/// Summary statistics of a list of numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    pub sd: f64,
    pub min: f64,
    pub max: f64,
}

impl Summary {
    pub fn of(x: &[f64]) -> Option<Self> {
        if x.is_empty() {
            return None;
        }
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        Some(Self {
            n: x.len(),
            mean,
            sd,
            min: x.iter().copied().fold(f64::INFINITY, f64::min),
            max: x.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.2} ± {:.2} ms [{:.2}, {:.2}], n = {}",
            self.mean, self.sd, self.min, self.max, self.n
        )
    }
}

impl FlashTiming {
    pub fn report(&self) -> String {
        let s = |x: &[f64]| Summary::of(x).map_or("–".to_string(), |s| s.to_string());
        format!(
            "flash on-time {}\nonset − schedule {}\nstamp delay {}\nundrawn {}, late stamps {}, refused stamps {}",
            s(&self.on_ms),
            s(&self.onset_error_ms),
            s(&self.report_delay_ms),
            self.undrawn,
            self.late_stamps,
            self.refused_stamps
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue #19, defects 1 and 2: the stamps `on_ms: 0` and `1e15` are refused; a frame
    /// or two off the schedule is not.
    #[test]
    fn implausible_stamps_are_refused() {
        let at = 12_345.0;
        for on in [at, at - 16.7, at + 33.4, at + UNDRAWN_AFTER_MS] {
            assert!(plausible_stamp(at, on), "{on}");
        }
        for on in [0.0, 1e15, -1e15, at + UNDRAWN_AFTER_MS + 1.0, f64::NAN] {
            assert!(!plausible_stamp(at, on), "{on}");
        }
    }
}
