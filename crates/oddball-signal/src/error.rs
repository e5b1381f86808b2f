//! The one error type of `oddball-signal`: each variant carries the values at fault.

/// What went wrong in a signal-processing step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SignalError {
    #[error("sampling rate {sfreq} Hz is outside the plausible {min}–{max} Hz", min = crate::SFREQ_MIN, max = crate::SFREQ_MAX)]
    InvalidSfreq { sfreq: f64 },
    #[error("channels {first} and {second} are both named {name:?}: channel names must be unique")]
    DuplicateChannel {
        name: String,
        first: usize,
        second: usize,
    },
    #[error("{n_events} epochs of {n_times} samples would hold more than {max_overlap} times the recording's {recording} samples: events this dense (one on every sample?) are not stimulus onsets")]
    TooManyEpochs {
        n_events: usize,
        n_times: usize,
        recording: usize,
        max_overlap: usize,
    },
    #[error("{names} channel names for {n_channels} channels of data")]
    ChannelCountMismatch { names: usize, n_channels: usize },
    #[error("{events} events for {n_epochs} epochs")]
    EventCountMismatch { events: usize, n_epochs: usize },
    #[error("event onset at sample {onset} is past the end of the recording ({n_times} samples)")]
    EventOutOfRange { onset: usize, n_times: usize },
    #[error("no channel named {name:?} (channels: {available:?})")]
    UnknownChannel {
        name: String,
        available: Vec<String>,
    },
    #[error("time window [{tmin}, {tmax}] s is empty, reversed, not finite or reaches further than {max} s from the onset", max = crate::MAX_WINDOW_S)]
    InvalidWindow { tmin: f64, tmax: f64 },
    #[error("{} does not fit between 0 and the Nyquist frequency {nyquist} Hz (half the sampling rate)", band_text(.l_freq, .h_freq))]
    InvalidBand {
        l_freq: Option<f64>,
        h_freq: Option<f64>,
        nyquist: f64,
    },
    #[error("filter order {order} must be between 1 and {max}")]
    InvalidOrder { order: usize, max: usize },
    #[error("signal of {n_times} samples is too short: zero-phase filtering pads {padlen} samples at each end and needs more than that")]
    SignalTooShort { n_times: usize, padlen: usize },
    #[error("resampling from {from} Hz to {to} Hz: the rates must be whole thousandths of a hertz whose ratio reduces to factors of at most {max}", max = crate::resample::MAX_FACTOR)]
    ResampleRatio { from: f64, to: f64 },
    #[error("resampling factors up {up}, down {down}: each must be 1 to {max}", max = crate::resample::MAX_FACTOR)]
    ResampleFactors { up: u64, down: u64 },
    #[error("decimation factor {q} must be at least 1")]
    InvalidDecimation { q: usize },
    #[error("chunk has {got} channels but the filter was set up for {expected}")]
    ChunkChannels { got: usize, expected: usize },
    #[error("there are no epochs")]
    NoEpochs,
    #[error("layouts differ: {what}")]
    LayoutMismatch { what: String },
    #[error("baseline window [{bmin}, {bmax}] s lies outside the epoch [{tmin}, {tmax}] s")]
    InvalidBaseline {
        bmin: f64,
        bmax: f64,
        tmin: f64,
        tmax: f64,
    },
    #[error("second-order section {index} has a0 = 0 or a non-finite coefficient")]
    InvalidSection { index: usize },
    #[error("rejection threshold {threshold} µV must be positive and finite")]
    InvalidThreshold { threshold: f64 },
}

/// A band as a person writes it: "band 1–15 Hz", "high-pass 1 Hz", "low-pass 15 Hz".
fn band_text(l_freq: &Option<f64>, h_freq: &Option<f64>) -> String {
    match (l_freq, h_freq) {
        (Some(l), Some(h)) => format!("band {l}–{h} Hz"),
        (Some(l), None) => format!("high-pass {l} Hz"),
        (None, Some(h)) => format!("low-pass {h} Hz"),
        (None, None) => "a filter with neither edge".into(),
    }
}
