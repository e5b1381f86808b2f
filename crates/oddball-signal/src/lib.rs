//! Core EEG data types and the signal processing of the oddball P300 pipeline.
//!
//! * [`Raw`], [`Events`], [`Epochs`]: continuous data `(n_channels, n_times)`, stimulus onsets, and
//!   cut epochs `(n_epochs, n_channels, n_times)`, all in µV with `sfreq` in Hz (MNE's names).
//! * [`filter`]: Butterworth design as second-order sections (designed by `sci-rs`), zero-phase
//!   [`filter::SosFilter::sosfiltfilt`] equal to scipy's with its default padding, and a causal stateful
//!   [`filter::StreamingFilter`] for online use.
//! * [`detrend`], [`decimate`], and [`epochs`]: cutting, baseline correction, amplitude-threshold
//!   and flat-channel rejection and averaging of repetitions.
//! * [`resample`]: polyphase resampling by `up / down` (scipy's `resample_poly`), and a
//!   recording moved to another rate with its events.
//! * [`non_finite`]: NaN and ±∞ held at their channel's last finite value, and where they were.
//! * [`rate`]: when two sampling rates are one, and the nominal rate behind one estimated from
//!   timestamps.
//! * [`preprocess`]: the one path from continuous EEG to epochs (held non-finite samples, detrend,
//!   band-pass, cut, rejection), MNE's `Epochs(raw, events, tmin, tmax, reject, flat)`.
//!
//! Everything is `f64`.
//!
//! # Example
//! A 1–15 Hz Butterworth band-pass (`butter(4, …)`), applied forward and backward, keeps a 10 Hz sine
//! and attenuates 50 Hz mains more than 20-fold:
//! ```
//! use ndarray::Array2;
//! use oddball_signal::filter::{Band, SosFilter};
//!
//! let sfreq = 256.0;
//! let sine = |f: f64| {
//!     Array2::from_shape_fn((1, 1024), |(_, t)| (2.0 * std::f64::consts::PI * f * t as f64 / sfreq).sin())
//! };
//! let band = Band::Bandpass { l_freq: 1.0, h_freq: 15.0 };
//! let filter = SosFilter::butter(4, band, sfreq)?;
//! let peak = |f: f64| {
//!     let y = filter.sosfiltfilt(sine(f).view()).unwrap();
//!     y.slice(ndarray::s![0, 256..768]).iter().fold(0.0f64, |m, v| m.max(v.abs()))
//! };
//! assert!((peak(10.0) - 1.0).abs() < 0.05, "10 Hz passes");
//! assert!(peak(50.0) < 0.05, "50 Hz is attenuated over 20-fold");
//! # Ok::<(), oddball_signal::SignalError>(())
//! ```

pub mod decimate;
pub mod detrend;
pub mod epochs;
mod error;
pub mod filter;
pub mod non_finite;
pub mod preprocess;
pub mod rate;
pub mod resample;
mod types;

pub use error::SignalError;
pub use types::{
    check_sfreq, check_unique_names, Epochs, Event, Events, Raw, EPOCH_CHUNK, MAX_EPOCH_OVERLAP,
    MAX_WINDOW_S, SFREQ_MAX, SFREQ_MIN,
};
