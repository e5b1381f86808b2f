//! Bins of samples: how many samples make one bin at a rate, and the bin means the amplitude
//! and Hilbert–Huang features share.

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// The peer's bin for `vec` features at `sfreq`: max(1, round(sfreq / 25)) samples (25 Hz rate).
pub fn vec_bin(sfreq: f64) -> Result<usize> {
    if !(sfreq.is_finite() && sfreq > 0.0) {
        return Err(DecodeError::InvalidParameter {
            name: "sfreq",
            value: sfreq.to_string(),
            reason: "must be finite and > 0".into(),
        });
    }
    Ok(samples_per(sfreq, 25.0))
}

/// max(1, round(sfreq / rate_hz)) samples, rounded as Python's `round` (ties to even), the way
/// the peer derives its bins and steps from the sampling rate (64 Hz at 160 Hz: 2, not 3).
pub(crate) fn samples_per(sfreq: f64, rate_hz: f64) -> usize {
    ((sfreq / rate_hz).round_ties_even() as usize).max(1)
}

/// Means of the non-overlapping bins of `bin` samples of `x` into `out` (`x.len() / bin` values; a
/// trailing partial bin is dropped).
pub fn bin_mean_into(x: &[f64], bin: usize, out: &mut [f64]) -> Result<()> {
    if bin == 0 {
        return Err(DecodeError::InvalidParameter {
            name: "bin",
            value: "0".into(),
            reason: "bins need at least one sample".into(),
        });
    }
    let nb = x.len() / bin;
    if out.len() != nb {
        return Err(DecodeError::ShapeMismatch {
            what: "bin means".into(),
            expected: nb.to_string(),
            got: out.len().to_string(),
        });
    }
    let k = bin as f64;
    for (o, chunk) in out.iter_mut().zip(x.chunks_exact(bin)) {
        *o = chunk.iter().sum::<f64>() / k;
    }
    Ok(())
}
