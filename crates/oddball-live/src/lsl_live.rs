//! An LSL EEG stream as a live session's source, and an LSL marker outlet as its marker sink.
//!
//! Sample `i` of the session is the `i`-th sample the stream delivered, with samples the stream
//! lost (a forward jump of its timestamps) filled in as NaN, so the sample clock keeps pace
//! with the amplifier's and the epochs that span a gap are rejected rather than misaligned.
//! A backward jump is counted and the samples kept in arrival order. Session-clock times map to
//! LSL times by the offset measured when the source starts (both are the machine's monotonic
//! clock).

use std::collections::VecDeque;

use ndarray::Array2;

use crate::clock::Clock;
use crate::live::{EegSource, MarkerSink};
use crate::lsl::{local_clock, EegInlet, MarkerOutlet, StreamQuery};
use crate::LiveError;

/// A forward jump of the timestamps longer than this is an error, not a gap to fill, s.
pub const MAX_GAP_S: f64 = 10.0;

/// An LSL EEG inlet as an [`EegSource`].
#[derive(Debug)]
pub struct LslSource {
    inlet: EegInlet,
    /// LSL clock − session clock, seconds.
    offset_s: f64,
    /// Samples received and not yet taken: values per sample.
    buf: VecDeque<Vec<f64>>,
    /// Index of the next sample to take.
    taken: u64,
    /// The most recent sample received: its index and LSL timestamp.
    last: (u64, f64),
    pub filled: u64,
    pub backwards: u64,
}

impl LslSource {
    /// Resolves the stream and waits for its first sample (sample 0).
    pub fn resolve(query: &StreamQuery, timeout_s: f64, clock: Clock) -> Result<Self, LiveError> {
        let mut inlet = EegInlet::resolve(query, timeout_s)?;
        let offset_s = local_clock() - clock.now_ms() / 1e3;
        // The first sample may take as long as finding the stream: a program (a stimulus
        // program playing EEG, an amplifier's app) may wait for its listeners before it sends.
        // From then on a quiet stream is a stalled one.
        inlet.set_stall_timeout(timeout_s.max(crate::lsl::DEFAULT_STALL_TIMEOUT_S));
        let (d, ts) = inlet.read(1)?;
        inlet.set_stall_timeout(crate::lsl::DEFAULT_STALL_TIMEOUT_S);
        let mut buf = VecDeque::new();
        buf.push_back(d.column(0).to_vec());
        Ok(Self {
            inlet,
            offset_s,
            buf,
            taken: 0,
            last: (0, ts[0]),
            filled: 0,
            backwards: 0,
        })
    }

    pub fn inlet_mut(&mut self) -> &mut EegInlet {
        &mut self.inlet
    }

    /// Session-clock ms of LSL time `t`.
    pub fn session_ms(&self, t: f64) -> f64 {
        (t - self.offset_s) * 1e3
    }
}

impl EegSource for LslSource {
    fn sfreq(&self) -> f64 {
        self.inlet.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.inlet.ch_names()
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        let sfreq = self.inlet.sfreq();
        while self.buf.len() < n {
            let (d, ts) = self.inlet.read(n - self.buf.len())?;
            for (col, &t) in d.columns().into_iter().zip(&ts) {
                let (i, prev) = self.last;
                let periods = (t - prev) * sfreq;
                if periods < 0.0 {
                    self.backwards += 1;
                } else if periods > 1.5 {
                    if periods / sfreq > MAX_GAP_S {
                        return Err(LiveError::InvalidParameter {
                            name: "stream timestamps",
                            value: format!("{t:.3} s after {prev:.3} s"),
                            reason: format!(
                                "jumped forward by more than {MAX_GAP_S} s: the stream restarted"
                            ),
                        });
                    }
                    let missing = periods.round() as u64 - 1;
                    for _ in 0..missing {
                        self.buf.push_back(vec![f64::NAN; col.len()]);
                    }
                    self.filled += missing;
                    self.last.0 = i + missing;
                }
                self.buf.push_back(col.to_vec());
                self.last = (self.last.0 + 1, t);
            }
        }
        Ok(())
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        let nc = self.inlet.ch_names().len();
        let mut out = Array2::zeros((nc, n));
        for t in 0..n {
            let s = self.buf.pop_front().ok_or(LiveError::InvalidParameter {
                name: "take",
                value: n.to_string(),
                reason: "more samples than waited for".into(),
            })?;
            for (c, v) in s.into_iter().enumerate() {
                out[[c, t]] = v;
            }
        }
        self.taken += n as u64;
        Ok(out)
    }
    fn time_of(&self, sample: u64) -> f64 {
        let (i, t) = self.last;
        self.session_ms(t + (sample as f64 - i as f64) / self.inlet.sfreq())
    }
    fn health(&self) -> Option<String> {
        Some(format!(
            "LSL {}: {} samples lost (filled with NaN), {} timestamps backwards",
            self.inlet.name(),
            self.filled,
            self.backwards
        ))
    }
}

/// An LSL marker outlet as the session's [`MarkerSink`], on the LSL clock.
#[derive(Debug)]
pub struct LslMarkers {
    outlet: MarkerOutlet,
    offset_s: f64,
}

impl LslMarkers {
    pub fn new(name: &str, clock: Clock) -> Result<Self, LiveError> {
        Ok(Self {
            outlet: MarkerOutlet::new(name, "oddball-panel")?,
            offset_s: local_clock() - clock.now_ms() / 1e3,
        })
    }
}

impl LslMarkers {
    /// Waits up to `timeout_s` for a consumer (a recorder, a simulated subject): markers pushed
    /// before anyone listens are lost. `false` when nobody came.
    pub fn wait_for_consumers(&self, timeout_s: f64) -> bool {
        self.outlet.wait_for_consumers(timeout_s)
    }
}

impl MarkerSink for LslMarkers {
    fn marker(&mut self, text: &str, ms: f64) {
        self.outlet.push(text, ms / 1e3 + self.offset_s);
    }
}
