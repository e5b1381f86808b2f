//! Polyphase resampling by a rational factor `up / down`: scipy's `signal.resample_poly` (what
//! MNE's `resample(..., method="polyphase")` calls), so recordings at another rate meet a model
//! at its own.
//!
//! The anti-aliasing filter is scipy's: a Kaiser-windowed (β = 5) sinc of `2·10·max(up, down) + 1`
//! taps with its cutoff at `1 / max(up, down)` of Nyquist, normalised to unit DC gain and
//! multiplied by `up`, then `upfirdn` (zero-stuff by `up`, filter, keep every `down`-th sample),
//! the output aligned on the filter's centre and cut to `ceil(n · up / down)` samples. The edges
//! are padded with zeros (`Pad::Constant`, scipy's default) or with each channel's mean
//! (`Pad::Mean`, `padtype="mean"`: no edge transient from an amplifier's DC offset). Checked
//! against scipy 1.17.1 (`tools/golden/resample/`).
//!
//! Written here rather than taken from a crate: `rubato` (the well-kept Rust resampler) is made
//! for audio streams — sinc interpolation with its own windows and oversampled tables, or FFT
//! resamplers over fixed chunks — and does not compute what scipy and MNE compute, which is what
//! recordings resampled here must match (a model trained on MNE-resampled epochs sees the same
//! samples). The direct polyphase form below (only the taps that meet non-zero input are
//! multiplied) is fast enough for offline recordings: 160 → 256 Hz costs 17 multiply-adds per
//! output sample.

use ndarray::{Array2, ArrayView2, Axis};

use crate::{Event, Events, Raw, SignalError};

/// The largest `up` or `down` accepted: its filter holds `20·max + 1` taps.
pub const MAX_FACTOR: u64 = 1000;

/// How the signal is extended beyond its ends while filtering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pad {
    /// Zeros (scipy's `padtype="constant"`, its default).
    Constant,
    /// Each channel's mean (scipy's `padtype="mean"`): the mean is removed, the rest resampled
    /// with zero padding, the mean added back.
    Mean,
}

/// `(up, down)` in lowest terms taking `from` Hz to `to` Hz, when both rates are whole
/// thousandths of a hertz and neither factor exceeds [`MAX_FACTOR`].
pub fn ratio(from: f64, to: f64) -> Result<(u64, u64), SignalError> {
    let bad = || SignalError::ResampleRatio { from, to };
    crate::check_sfreq(from)?;
    crate::check_sfreq(to)?;
    let milli = |f: f64| {
        let m = (f * 1000.0).round();
        ((f * 1000.0 - m).abs() < 1e-6).then_some(m as u64)
    };
    let (a, b) = (milli(to).ok_or_else(bad)?, milli(from).ok_or_else(bad)?);
    let g = gcd(a, b);
    let (up, down) = (a / g, b / g);
    if up.max(down) > MAX_FACTOR {
        return Err(bad());
    }
    Ok((up, down))
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Modified Bessel function of the first kind, order 0 (power series; terms fall below one
/// ulp of the sum long before 100 for the arguments of a Kaiser window).
fn bessel_i0(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let (mut term, mut sum) = (1.0, 1.0);
    for k in 1..200 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < sum * 1e-17 {
            break;
        }
    }
    sum
}

/// scipy's `firwin(numtaps, cutoff, window=("kaiser", beta))`: a low-pass with `cutoff` relative
/// to Nyquist, scaled to unit gain at DC.
fn firwin_kaiser(numtaps: usize, cutoff: f64, beta: f64) -> Vec<f64> {
    let alpha = 0.5 * (numtaps - 1) as f64;
    let sinc = |x: f64| {
        if x == 0.0 {
            1.0
        } else {
            let px = std::f64::consts::PI * x;
            px.sin() / px
        }
    };
    let i0_beta = bessel_i0(beta);
    let mut h: Vec<f64> = (0..numtaps)
        .map(|n| {
            let m = n as f64 - alpha;
            let r = if numtaps > 1 {
                2.0 * n as f64 / (numtaps - 1) as f64 - 1.0
            } else {
                0.0
            };
            let w = bessel_i0(beta * (1.0 - r * r).max(0.0).sqrt()) / i0_beta;
            cutoff * sinc(cutoff * m) * w
        })
        .collect();
    let s: f64 = h.iter().sum();
    for v in &mut h {
        *v /= s;
    }
    h
}

/// Output length of `upfirdn` (scipy's `_output_len`).
fn upfirdn_len(len_h: usize, n_in: usize, up: usize, down: usize) -> usize {
    ((n_in - 1) * up + len_h - 1) / down + 1
}

/// The filter, its pre-removal count and the output length for `n_in` samples (scipy's
/// `resample_poly` set-up).
struct Plan {
    h: Vec<f64>,
    up: usize,
    down: usize,
    pre_remove: usize,
    n_out: usize,
}

impl Plan {
    fn new(n_in: usize, up: u64, down: u64) -> Self {
        let (up, down) = (up as usize, down as usize);
        let n_out = (n_in * up).div_ceil(down);
        let max_rate = up.max(down);
        let half_len = 10 * max_rate;
        let mut h = firwin_kaiser(2 * half_len + 1, 1.0 / max_rate as f64, 5.0);
        for v in &mut h {
            *v *= up as f64;
        }
        let n_pre_pad = down - half_len % down;
        let pre_remove = (half_len + n_pre_pad) / down;
        let mut n_post_pad = 0;
        while upfirdn_len(h.len() + n_pre_pad + n_post_pad, n_in, up, down) < n_out + pre_remove {
            n_post_pad += 1;
        }
        let mut padded = vec![0.0; n_pre_pad];
        padded.extend(h);
        padded.extend(std::iter::repeat_n(0.0, n_post_pad));
        Self {
            h: padded,
            up,
            down,
            pre_remove,
            n_out,
        }
    }

    /// Output samples `pre_remove .. pre_remove + n_out` of `upfirdn(h, x, up, down)`: sample
    /// `k` is `Σ_j h[k·down − j·up] · x[j]` over the `j` whose tap exists.
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        let (up, down, h) = (self.up, self.down, &self.h);
        for (o, y) in out.iter_mut().enumerate() {
            let t = (o + self.pre_remove) * down;
            // j·up ≤ t and t − j·up < len(h)
            let j_max = (t / up).min(x.len() - 1);
            let j_min = (t + 1).saturating_sub(h.len()).div_ceil(up);
            let mut acc = 0.0;
            let mut j = j_max as isize;
            while j >= j_min as isize {
                let ju = j as usize;
                acc += h[t - ju * up] * x[ju];
                j -= 1;
            }
            *y = acc;
        }
    }
}

/// Resamples each row of `x` (`(n_channels, n_times)`) by `up / down` along time, as
/// `scipy.signal.resample_poly(x, up, down, axis=1, padtype=…)`: `ceil(n_times · up / down)`
/// samples out.
pub fn resample_poly(
    x: ArrayView2<f64>,
    up: u64,
    down: u64,
    pad: Pad,
) -> Result<Array2<f64>, SignalError> {
    if up == 0 || down == 0 || up.max(down) > MAX_FACTOR {
        return Err(SignalError::ResampleFactors { up, down });
    }
    let g = gcd(up, down);
    let (up, down) = (up / g, down / g);
    let n_in = x.ncols();
    if (up, down) == (1, 1) || n_in == 0 {
        return Ok(x.to_owned());
    }
    let plan = Plan::new(n_in, up, down);
    let mut y = Array2::zeros((x.nrows(), plan.n_out));
    let mut row = vec![0.0; n_in];
    for (xr, mut yr) in x.axis_iter(Axis(0)).zip(y.axis_iter_mut(Axis(0))) {
        let mean = match pad {
            Pad::Constant => 0.0,
            Pad::Mean => xr.sum() / n_in as f64,
        };
        for (r, v) in row.iter_mut().zip(xr.iter()) {
            *r = v - mean;
        }
        let out = yr.as_slice_mut().expect("a standard-layout row");
        plan.apply(&row, out);
        if mean != 0.0 {
            for v in out.iter_mut() {
                *v += mean;
            }
        }
    }
    Ok(y)
}

/// A recording at `sfreq` Hz: every channel resampled ([`resample_poly`], each channel's mean as
/// padding), each event moved to `round(onset · up / down)` (MNE's rule for events), kept
/// when inside the resampled recording.
pub fn resample_raw(raw: &Raw, sfreq: f64) -> Result<Raw, SignalError> {
    let (up, down) = ratio(raw.sfreq(), sfreq)?;
    let data = resample_poly(raw.data().view(), up, down, Pad::Mean)?;
    let n = data.ncols();
    let events = raw
        .events()
        .iter()
        .map(|e| Event {
            onset: (e.onset as f64 * up as f64 / down as f64).round() as usize,
            ..e.clone()
        })
        .filter(|e| e.onset < n)
        .collect();
    Raw::new(data, sfreq, raw.ch_names().to_vec(), Events::new(events))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_in_lowest_terms() {
        assert_eq!(ratio(160.0, 256.0).unwrap(), (8, 5));
        assert_eq!(ratio(256.0, 128.0).unwrap(), (1, 2));
        assert_eq!(ratio(500.0, 500.0).unwrap(), (1, 1));
        assert!(ratio(256.0, 1.0 / 3.0).is_err());
        assert!(ratio(1000.0, 999.999).is_err(), "factors over the limit");
    }

    #[test]
    fn a_constant_stays_constant_with_mean_padding_and_length_is_the_ceiling() {
        let x = Array2::from_elem((2, 101), 40.0);
        let y = resample_poly(x.view(), 8, 5, Pad::Mean).unwrap();
        assert_eq!(y.ncols(), (101usize * 8).div_ceil(5));
        assert!(y.iter().all(|v| (v - 40.0).abs() < 1e-9));
    }

    #[test]
    fn i0_matches_known_values() {
        // I0(1) and I0(5) (Abramowitz & Stegun, table 9.8).
        assert!((bessel_i0(1.0) - 1.266_065_877_752_008_4).abs() < 1e-15);
        assert!((bessel_i0(5.0) - 27.239_871_823_604_442).abs() < 1e-12);
    }
}
