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

/// scipy's filter for `up / down`, zero-padded in front so output samples fall on the
/// filter's centre, and the outputs of `upfirdn` dropped before the first kept one.
fn design(up: usize, down: usize) -> (Vec<f64>, usize) {
    let max_rate = up.max(down);
    let half_len = 10 * max_rate;
    let n_pre_pad = down - half_len % down;
    let mut h = vec![0.0; n_pre_pad];
    h.extend(
        firwin_kaiser(2 * half_len + 1, 1.0 / max_rate as f64, 5.0)
            .into_iter()
            .map(|v| v * up as f64),
    );
    (h, (half_len + n_pre_pad) / down)
}

/// Output sample `k` of `upfirdn(h, x, up, down)` after `pre_remove`, from the input samples
/// `x[j]` for `j` in `first..first + x.len()` (those the output needs must be there).
fn output_at(h: &[f64], up: usize, t: usize, x: &[f64], first: usize) -> f64 {
    let last = first + x.len() - 1;
    let j_max = (t / up).min(last);
    let j_min = (t + 1).saturating_sub(h.len()).div_ceil(up).max(first);
    let mut acc = 0.0;
    let mut j = j_max as isize;
    while j >= j_min as isize {
        let ju = j as usize;
        acc += h[t - ju * up] * x[ju - first];
        j -= 1;
    }
    acc
}

impl Plan {
    fn new(n_in: usize, up: u64, down: u64) -> Self {
        let (up, down) = (up as usize, down as usize);
        let n_out = (n_in * up).div_ceil(down);
        let (mut h, pre_remove) = design(up, down);
        while upfirdn_len(h.len(), n_in, up, down) < n_out + pre_remove {
            h.push(0.0);
        }
        Self {
            h,
            up,
            down,
            pre_remove,
            n_out,
        }
    }

    /// Output samples `pre_remove .. pre_remove + n_out` of `upfirdn(h, x, up, down)`: sample
    /// `k` is `Σ_j h[k·down − j·up] · x[j]` over the `j` whose tap exists.
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        for (o, y) in out.iter_mut().enumerate() {
            let t = (o + self.pre_remove) * self.down;
            *y = output_at(&self.h, self.up, t, x, 0);
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

/// [`resample_poly`] on a stream, chunk by chunk: output sample `k` is the offline one
/// (zero padding before the first sample, [`Pad::Constant`]) as soon as the input it needs has
/// arrived, about `10·max(up, down) / up` input samples after its own time (the filter's
/// half-length); only the end of a recording, which offline pads with zeros, differs. What a
/// live stream at another rate than a model's goes through.
#[derive(Debug, Clone)]
pub struct StreamResampler {
    h: Vec<f64>,
    up: usize,
    down: usize,
    pre_remove: usize,
    /// Input samples kept, per channel, from absolute input sample `first`.
    buf: Vec<Vec<f64>>,
    first: usize,
    received: usize,
    produced: usize,
}

impl StreamResampler {
    /// A resampler of `n_channels` by `up / down` (reduced; each at most [`MAX_FACTOR`]).
    pub fn new(n_channels: usize, up: u64, down: u64) -> Result<Self, SignalError> {
        if up == 0 || down == 0 || up.max(down) > MAX_FACTOR {
            return Err(SignalError::ResampleFactors { up, down });
        }
        let g = gcd(up, down);
        let (up, down) = ((up / g) as usize, (down / g) as usize);
        let (h, pre_remove) = design(up, down);
        Ok(Self {
            h,
            up,
            down,
            pre_remove,
            buf: vec![Vec::new(); n_channels],
            first: 0,
            received: 0,
            produced: 0,
        })
    }

    /// Input samples needed in all before `n` more output samples can be taken.
    pub fn input_needed(&self, n: usize) -> usize {
        if n == 0 {
            return self.received;
        }
        (self.produced + n - 1 + self.pre_remove) * self.down / self.up + 1
    }

    /// Output samples that can be taken now.
    pub fn available(&self) -> usize {
        (self.received * self.up)
            .div_ceil(self.down)
            .saturating_sub(self.pre_remove + self.produced)
    }

    /// Takes in input samples `(n_channels, n)`.
    pub fn push(&mut self, x: ArrayView2<f64>) {
        for (b, row) in self.buf.iter_mut().zip(x.axis_iter(Axis(0))) {
            b.extend(row.iter());
        }
        self.received += x.ncols();
    }

    /// The next `n` output samples `(n_channels, n)`; at most [`Self::available`].
    pub fn take(&mut self, n: usize) -> Array2<f64> {
        let n = n.min(self.available());
        let mut y = Array2::zeros((self.buf.len(), n));
        for (b, mut yr) in self.buf.iter().zip(y.axis_iter_mut(Axis(0))) {
            for (o, v) in yr.iter_mut().enumerate() {
                let t = (self.produced + o + self.pre_remove) * self.down;
                *v = output_at(&self.h, self.up, t, b, self.first);
            }
        }
        self.produced += n;
        // Inputs no later output reaches are dropped.
        let t = (self.produced + self.pre_remove) * self.down;
        let keep_from = (t + 1).saturating_sub(self.h.len()).div_ceil(self.up);
        if keep_from > self.first {
            let d = (keep_from - self.first).min(self.received - self.first);
            for b in &mut self.buf {
                b.drain(..d);
            }
            self.first += d;
        }
        y
    }
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
    fn a_stream_in_chunks_gives_the_offline_samples() {
        let n = 400;
        let x = Array2::from_shape_fn((2, n), |(c, t)| {
            let t = t as f64;
            (0.37 * t + c as f64).sin() * 20.0 + (0.05 * t).cos() * 5.0 + 3.0 * c as f64
        });
        for (up, down) in [(8u64, 5u64), (64, 125), (5, 8), (1, 2)] {
            let offline = resample_poly(x.view(), up, down, Pad::Constant).unwrap();
            let mut r = StreamResampler::new(2, up, down).unwrap();
            let mut got: Vec<Array2<f64>> = Vec::new();
            let mut at = 0;
            for (k, chunk) in [1usize, 7, 20, 3, 50, 13].iter().cycle().enumerate() {
                if at >= n {
                    break;
                }
                let c = (*chunk).min(n - at);
                r.push(x.slice(ndarray::s![.., at..at + c]));
                at += c;
                let want = if k % 2 == 0 {
                    r.available()
                } else {
                    r.available() / 2
                };
                got.push(r.take(want));
            }
            got.push(r.take(usize::MAX));
            let views: Vec<_> = got.iter().map(|a| a.view()).collect();
            let y = ndarray::concatenate(Axis(1), &views).unwrap();
            // All but the tail (which offline pads with zeros past the end) are there and equal.
            assert!(y.ncols() + 12 * (up.max(down) / up + 1) as usize >= offline.ncols());
            assert!(y.ncols() <= offline.ncols());
            let err = (&y - &offline.slice(ndarray::s![.., ..y.ncols()]))
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(err < 1e-12, "{up}/{down}: {err:e}");
            assert!(r.input_needed(1) > n);
        }
    }

    #[test]
    fn i0_matches_known_values() {
        // I0(1) and I0(5) (Abramowitz & Stegun, table 9.8).
        assert!((bessel_i0(1.0) - 1.266_065_877_752_008_4).abs() < 1e-15);
        assert!((bessel_i0(5.0) - 27.239_871_823_604_442).abs() < 1e-12);
    }
}
