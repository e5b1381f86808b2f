//! Down-sampling with an anti-aliasing filter, as scipy's `decimate(x, q)` with its defaults:
//! an order-8 Chebyshev type I low-pass (0.05 dB ripple, cutoff 0.8 × the new Nyquist frequency)
//! applied zero-phase with `sosfiltfilt`, then every `q`-th sample from the first.

use ndarray::{s, Array2, ArrayView2};

use crate::filter::SosFilter;
use crate::{Raw, SignalError};

/// The anti-aliasing filter `decimate` uses for factor `q` (> 1).
pub fn antialias_filter(q: usize) -> Result<SosFilter, SignalError> {
    if q < 2 {
        return Err(SignalError::InvalidDecimation { q });
    }
    SosFilter::cheby1_lowpass(8, 0.05, 0.8 / q as f64)
}

/// Decimates each row of `data` `(n_channels, n_times)` by `q`; `q = 1` returns a copy.
pub fn decimate(data: ArrayView2<'_, f64>, q: usize) -> Result<Array2<f64>, SignalError> {
    match q {
        0 => Err(SignalError::InvalidDecimation { q }),
        1 => Ok(data.to_owned()),
        _ => {
            let filtered = antialias_filter(q)?.sosfiltfilt(data)?;
            Ok(filtered.slice(s![.., ..;q]).to_owned())
        }
    }
}

/// Decimates a recording: data as [`decimate`], `sfreq / q`, event onsets mapped to the nearest
/// kept sample (`round(onset / q)`, clamped to the new length).
pub fn decimate_raw(raw: &Raw, q: usize) -> Result<Raw, SignalError> {
    let data = decimate(raw.data().view(), q)?;
    let n_times = data.ncols();
    let events = raw
        .events()
        .iter()
        .map(|e| {
            let mut e = e.clone();
            e.onset = ((e.onset as f64 / q as f64).round() as usize).min(n_times.saturating_sub(1));
            e
        })
        .collect();
    Raw::new(
        data,
        raw.sfreq() / q as f64,
        raw.ch_names().to_vec(),
        events,
    )
}
