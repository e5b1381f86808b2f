//! Core EEG data types and the signal processing of the oddball P300 pipeline.
//!
//! * [`Raw`], [`Events`], [`Epochs`]: continuous data `(n_channels, n_times)`, stimulus onsets, and
//!   cut epochs `(n_epochs, n_channels, n_times)`, all in µV with `sfreq` in Hz (MNE's names).
//! * [`filter`]: Butterworth design as second-order sections (designed by `sci-rs`), zero-phase
//!   [`filter::sosfiltfilt`] equal to scipy's with its default padding, and a causal stateful
//!   [`filter::StreamingFilter`] for online use.
//! * [`detrend`], [`decimate`], and [`epochs`]: cutting, baseline correction, amplitude-threshold
//!   and flat-channel rejection and averaging of repetitions.
//! * [`preprocess`]: the one path from continuous EEG to epochs (held non-finite samples, detrend,
//!   band-pass, cut, rejection), MNE's `Epochs(raw, events, tmin, tmax, reject, flat)`.
//!
//! Everything is `f64`.

pub mod decimate;
pub mod detrend;
pub mod epochs;
mod error;
pub mod filter;
pub mod preprocess;
mod types;

pub use error::SignalError;
pub use types::{Epochs, Event, Events, Raw};
