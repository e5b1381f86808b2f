//! Analytic signal, instantaneous amplitude and frequency, and the paper's Hilbert–Huang (HHT)
//! features.
//!
//! [`HilbertTransform`] computes scipy's `signal.hilbert` — FFT, zero the negative frequencies, double
//! the positive ones (DC and, for even lengths, Nyquist kept once), inverse FFT — with `rustfft`.
//! Because that analytic signal's real part is the input itself, only its imaginary part (the
//! Hilbert transform) is computed, as the multiplier −i·sgn k between a forward and an inverse
//! complex FFT of the signal's own length; the real part returned is the input, where scipy's is the
//! input plus FFT round-off.
//!
//! The instantaneous frequency is the peer's (`shared/peer/peer_eval.py`): `numpy.unwrap` of the
//! phase `atan2(im, re)`, its first difference times `sfreq / 2π`, and the last difference repeated so
//! the output keeps the input's length (`f[n−1] = f[n−2]`).
//!
//! [`HhtFeatures`] is the peer's HHT block: per channel, the first IMF ([`crate::features::emd`]), its
//! instantaneous amplitude and frequency, each averaged in bins of `bin` samples
//! ([`crate::features::bins::bin_mean_into`]); all amplitude bins (channel-major) come before all frequency
//! bins.
//!
//! Two shortcuts make the features cheaper than their definition, and both are checked against it
//! (tests below, and the peer's values in `tests/paper_golden.rs`):
//! * [`HilbertTransform::imag_pair`] transforms two real channels at once: the Hilbert transform is a
//!   complex-linear Fourier multiplier (−i·sgn k), so the transform of `a + i·b` is `H(a) + i·H(b)`:
//!   one complex FFT pair of length n serves two channels.
//! * [`frequency_bins`] never forms the per-sample phase: the mean of a bin of first differences is
//!   the unwrapped phase's change across the bin, so `atan2` is needed only at the bin edges. The
//!   unwrap corrections in between (numpy adds −2π·sgn(Δ) where |Δ| > π) are read off the signs of
//!   the imaginary parts and of the cross product of neighbouring samples; wherever that could
//!   disagree with numpy's rounding (a sample exactly on the real axis, or two neighbours within
//!   1e-6 rad of opposite), the correction is numpy's own, computed from both phases.
//!
//! The FFTs and their plans come from `rustfft`; the rest is written here (a few lines, and it must
//! follow scipy's and numpy's conventions exactly).

use std::sync::Arc;

use ndarray::{Array2, ArrayView3};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use serde::{Deserialize, Serialize};

use crate::features::bins::{bin_mean_into, vec_bin};
use crate::features::emd::{Emd, EmdParams};
use crate::features::rows::two_block_rows;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// A planned Hilbert transform for signals of one length, with its buffers.
#[derive(Clone)]
pub struct HilbertTransform {
    n: usize,
    /// Complex FFT plans of length n.
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
    buf: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl std::fmt::Debug for HilbertTransform {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HilbertTransform")
            .field("n", &self.n)
            .finish_non_exhaustive()
    }
}

impl HilbertTransform {
    /// Plans the transforms for signals of `n` samples (`n >= 1`).
    pub fn new(n: usize) -> Result<Self> {
        if n == 0 {
            return Err(DecodeError::TooFewSamples {
                what: "Hilbert transform of an empty signal".into(),
            });
        }
        let mut planner = FftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(n);
        let inv = planner.plan_fft_inverse(n);
        let zero = Complex::new(0.0, 0.0);
        let scratch = vec![
            zero;
            fwd.get_inplace_scratch_len()
                .max(inv.get_inplace_scratch_len())
        ];
        Ok(Self {
            n,
            fwd,
            inv,
            buf: vec![zero; n],
            scratch,
        })
    }

    /// The signal length this transform is planned for.
    pub fn n_samples(&self) -> usize {
        self.n
    }

    /// The imaginary part of the analytic signal of `x` (its Hilbert transform) into `out`.
    pub fn imag(&mut self, x: &[f64], out: &mut [f64]) -> Result<()> {
        self.check_len("Hilbert input", x.len())?;
        self.check_len("Hilbert output", out.len())?;
        for (z, &re) in self.buf.iter_mut().zip(x) {
            *z = Complex::new(re, 0.0);
        }
        self.transform_buf();
        let scale = 1.0 / self.n as f64;
        for (o, z) in out.iter_mut().zip(&self.buf) {
            *o = z.re * scale;
        }
        Ok(())
    }

    /// The Hilbert transforms of two signals at once (see the module docs): `out_a = H(a)`,
    /// `out_b = H(b)`, as [`Self::imag`] of each to FFT round-off.
    pub fn imag_pair(
        &mut self,
        a: &[f64],
        b: &[f64],
        out_a: &mut [f64],
        out_b: &mut [f64],
    ) -> Result<()> {
        self.check_len("Hilbert input", a.len())?;
        self.check_len("Hilbert input", b.len())?;
        self.check_len("Hilbert output", out_a.len())?;
        self.check_len("Hilbert output", out_b.len())?;
        for ((z, &re), &im) in self.buf.iter_mut().zip(a).zip(b) {
            *z = Complex::new(re, im);
        }
        self.transform_buf();
        let scale = 1.0 / self.n as f64;
        for ((oa, ob), z) in out_a.iter_mut().zip(out_b.iter_mut()).zip(&self.buf) {
            *oa = z.re * scale;
            *ob = z.im * scale;
        }
        Ok(())
    }

    /// `buf` ← n·H(`buf`): forward FFT, −i·sgn(k), inverse FFT (unscaled). Positive frequencies
    /// 1 ≤ k < (n+1)/2 are multiplied by −i, negative ones by +i; DC and (n even) Nyquist dropped —
    /// scipy's doubled positive half, seen from the imaginary part.
    fn transform_buf(&mut self) {
        self.fwd
            .process_with_scratch(&mut self.buf, &mut self.scratch);
        let n = self.n;
        let first_negative = n / 2 + 1;
        for (k, z) in self.buf.iter_mut().enumerate() {
            *z = if k == 0 || (n % 2 == 0 && k == n / 2) {
                Complex::new(0.0, 0.0)
            } else if k < first_negative {
                Complex::new(z.im, -z.re)
            } else {
                Complex::new(-z.im, z.re)
            };
        }
        self.inv
            .process_with_scratch(&mut self.buf, &mut self.scratch);
    }

    /// Instantaneous amplitude `|z|` and frequency (Hz, the peer's convention, see the module docs)
    /// of `x` sampled at `sfreq`. Needs at least 2 samples.
    pub fn amplitude_frequency(
        &mut self,
        x: &[f64],
        sfreq: f64,
        amp: &mut [f64],
        freq: &mut [f64],
    ) -> Result<()> {
        self.check_len("instantaneous amplitude output", amp.len())?;
        self.imag(x, freq)?;
        magnitude_into(x, freq, amp);
        // the imaginary part sits in `freq`; turn it into phase in place, then into frequency
        for (f, &re) in freq.iter_mut().zip(x) {
            *f = f.atan2(re);
        }
        phase_to_frequency(freq, sfreq)
    }

    fn check_len(&self, what: &str, got: usize) -> Result<()> {
        if got != self.n {
            return Err(DecodeError::ShapeMismatch {
                what: what.into(),
                expected: self.n.to_string(),
                got: got.to_string(),
            });
        }
        Ok(())
    }
}

/// The analytic signal of `x` as (real, imaginary) parts: scipy's `signal.hilbert(x)`.
pub fn analytic_signal(x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut h = HilbertTransform::new(x.len())?;
    let mut im = vec![0.0; x.len()];
    h.imag(x, &mut im)?;
    Ok((x.to_vec(), im))
}

/// Instantaneous frequency (Hz) from an analytic signal's parts: `np.diff(np.unwrap(np.angle(z)))
/// · sfreq / 2π`, last value repeated to keep the length.
pub fn instantaneous_frequency(re: &[f64], im: &[f64], sfreq: f64, out: &mut [f64]) -> Result<()> {
    if re.len() != im.len() || out.len() != re.len() {
        return Err(DecodeError::ShapeMismatch {
            what: "instantaneous frequency buffers".into(),
            expected: format!("{0} / {0} / {0}", re.len()),
            got: format!("{} / {} / {}", re.len(), im.len(), out.len()),
        });
    }
    for ((o, &r), &i) in out.iter_mut().zip(re).zip(im) {
        *o = i.atan2(r);
    }
    phase_to_frequency(out, sfreq)
}

/// An instantaneous frequency needs 2 samples and a finite, positive `sfreq`.
fn check_frequency_args(n: usize, sfreq: f64) -> Result<()> {
    if n < 2 {
        return Err(DecodeError::TooFewSamples {
            what: format!("instantaneous frequency needs 2 samples, got {n}"),
        });
    }
    if !(sfreq.is_finite() && sfreq > 0.0) {
        return Err(DecodeError::InvalidParameter {
            name: "sfreq",
            value: sfreq.to_string(),
            reason: "must be finite and > 0".into(),
        });
    }
    Ok(())
}

/// Wrapped phase (in place) → instantaneous frequency, as `numpy.unwrap` then `numpy.diff`.
fn phase_to_frequency(p: &mut [f64], sfreq: f64) -> Result<()> {
    let n = p.len();
    check_frequency_args(n, sfreq)?;
    let pi = std::f64::consts::PI;
    let to_hz = |d: f64| d * sfreq / (2.0 * pi);
    // numpy.unwrap: up[i] = p[i] + cumsum(correction)[i-1]
    let mut cum = 0.0;
    let mut prev_up = p[0];
    let mut prev_p = p[0];
    for i in 1..n {
        let pi_now = p[i];
        cum += unwrap_correction(pi_now - prev_p);
        let up = pi_now + cum;
        p[i - 1] = to_hz(up - prev_up);
        prev_up = up;
        prev_p = pi_now;
    }
    p[n - 1] = p[n - 2];
    Ok(())
}

/// `|re + i·im|` per sample into `out`, as √(re² + im²): within an ulp of numpy's `hypot`, several
/// times faster, and µV-scale values can't overflow.
fn magnitude_into(re: &[f64], im: &[f64], out: &mut [f64]) {
    for ((a, &r), &i) in out.iter_mut().zip(re).zip(im) {
        *a = (r * r + i * i).sqrt();
    }
}

/// numpy's `unwrap` correction of one phase step `dd` (`ph_correct`): 0 unless |dd| reaches π
/// (numpy computes it everywhere, then masks), else the multiple of 2π (to round-off) that brings
/// the step into [−π, π], a step of exactly ±π kept as it is.
fn unwrap_correction(dd: f64) -> f64 {
    let pi = std::f64::consts::PI;
    if dd.abs() < pi {
        return 0.0;
    }
    let mut ddmod = np_mod(dd + pi, 2.0 * pi) - pi;
    if ddmod == -pi && dd > 0.0 {
        ddmod = pi;
    }
    ddmod - dd
}

/// numpy's unwrap correction of the phase step from sample `(ar, ai)` to `(br, bi)` of an analytic
/// signal, without the phases where the geometry decides it (see the module docs): in one open
/// half-plane the step is below π; across the real axis it wraps exactly when the short rotation
/// crosses the negative half-axis, told by the sign of the cross product. Samples on the real axis
/// and near-opposite neighbours take numpy's rule on the two `atan2` phases.
#[inline]
fn step_correction(ar: f64, ai: f64, br: f64, bi: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let halves = ai * bi;
    if halves > 0.0 && halves.is_finite() {
        return 0.0; // one open half-plane: |Δ| < π
    }
    if halves < 0.0 {
        // across the real axis
        let cross = ar * bi - ai * br;
        let dot = ar * br + ai * bi;
        // near-opposite (the rotation within 1e-6 rad of π, where rounding could decide), or a
        // cross product that underflowed or overflowed
        let near_opposite = dot < 0.0 && cross.abs() <= 1e-6 * (ar.hypot(ai) * br.hypot(bi));
        if !near_opposite && cross.abs() > 0.0 && cross.is_finite() {
            return match (ai < 0.0, cross < 0.0) {
                (true, true) => -two_pi,  // lower → upper, clockwise through −π/π: Δ > π
                (false, false) => two_pi, // upper → lower, anticlockwise through π/−π: Δ < −π
                _ => 0.0,
            };
        }
    }
    // on the real axis (signed zeros matter to atan2), underflow, near-opposite or not finite
    unwrap_correction(bi.atan2(br) - ai.atan2(ar))
}

/// Bin means of the instantaneous frequency (Hz) of the analytic signal `re + i·im` sampled at
/// `sfreq`: `bin_mean(np.diff(np.unwrap(np.angle(z))) · sfreq / 2π, bin)` with the last difference
/// repeated (the peer's), `re.len() / bin` values into `out`, to round-off. Computed from the
/// phase at the bin edges and the unwrap corrections between them (see the module docs).
pub fn frequency_bins(
    re: &[f64],
    im: &[f64],
    sfreq: f64,
    bin: usize,
    out: &mut [f64],
) -> Result<()> {
    let n = re.len();
    if im.len() != n || bin == 0 || out.len() != n / bin {
        return Err(DecodeError::ShapeMismatch {
            what: "instantaneous frequency bins".into(),
            expected: format!("{n} imaginary parts and {} bins of {bin}", n / bin.max(1)),
            got: format!("{} imaginary parts and {} bins", im.len(), out.len()),
        });
    }
    check_frequency_args(n, sfreq)?;
    let to_hz = sfreq / (2.0 * std::f64::consts::PI);
    let phase = |j: usize| im[j].atan2(re[j]);
    let correction = |k: usize| step_correction(re[k], im[k], re[k + 1], im[k + 1]);
    let mut p_start = phase(0);
    for (b, o) in out.iter_mut().enumerate() {
        // the bin averages f[s..e]; f[i] = up[i+1] − up[i] for i < n−1 and f[n−1] = f[n−2]
        let s = b * bin;
        let e = s + bin;
        let last = e.min(n - 1);
        let mut wraps = 0.0;
        for (r, i) in re[s..=last].windows(2).zip(im[s..=last].windows(2)) {
            wraps += step_correction(r[0], i[0], r[1], i[1]);
        }
        let p_last = phase(last);
        let mut dphase = (p_last - p_start) + wraps;
        if e == n {
            dphase += (p_last - phase(n - 2)) + correction(n - 2);
        }
        *o = dphase * to_hz / bin as f64;
        p_start = p_last;
    }
    Ok(())
}

/// numpy's float `mod` (result has the sign of the divisor).
fn np_mod(a: f64, b: f64) -> f64 {
    let m = a % b;
    if m != 0.0 && (m < 0.0) != (b < 0.0) {
        m + b
    } else if m == 0.0 {
        0.0f64.copysign(b)
    } else {
        m
    }
}

/// The paper's HHT features: bin-averaged instantaneous amplitude and frequency of each channel's
/// first IMF. Nothing is learned, so there is no fitted counterpart.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HhtFeatures {
    /// Sampling rate (Hz), for the frequency in Hz.
    pub sfreq: f64,
    /// Samples per averaging bin (the peer: round(sfreq / 25)); a trailing partial bin is dropped.
    pub bin: usize,
    /// EMD settings (PyEMD's defaults).
    pub emd: EmdParams,
}

impl HhtFeatures {
    /// Checked settings.
    pub fn new(sfreq: f64, bin: usize, emd: EmdParams) -> Result<Self> {
        if !(sfreq.is_finite() && sfreq > 0.0) {
            return Err(DecodeError::InvalidParameter {
                name: "sfreq",
                value: sfreq.to_string(),
                reason: "must be finite and > 0".into(),
            });
        }
        if bin == 0 {
            return Err(DecodeError::InvalidParameter {
                name: "bin",
                value: "0".into(),
                reason: "bins need at least one sample".into(),
            });
        }
        emd.validate()?;
        Ok(Self { sfreq, bin, emd })
    }

    /// The peer's settings at `sfreq`: bins of round(sfreq / 25) samples, PyEMD's defaults.
    pub fn for_sfreq(sfreq: f64) -> Result<Self> {
        Self::new(sfreq, vec_bin(sfreq)?, EmdParams::default())
    }

    /// Bins per channel and quantity for epochs of `n_times` samples.
    pub fn n_bins(&self, n_times: usize) -> usize {
        n_times / self.bin
    }

    /// Output width: amplitude and frequency bins of every channel.
    pub fn n_features(&self, n_channels: usize, n_times: usize) -> usize {
        2 * n_channels * self.n_bins(n_times)
    }

    /// A reusable per-thread extractor for channels of `n_times` samples.
    pub fn extractor(&self, n_times: usize) -> Result<HhtExtractor> {
        if n_times < 3 {
            return Err(DecodeError::TooFewSamples {
                what: format!("HHT features need at least 3 samples per epoch, got {n_times}"),
            });
        }
        if self.n_bins(n_times) == 0 {
            return Err(DecodeError::TooFewSamples {
                what: format!("epochs of {n_times} samples hold no bin of {}", self.bin),
            });
        }
        Ok(HhtExtractor {
            params: *self,
            emd: Emd::new(self.emd)?,
            hilbert: HilbertTransform::new(n_times)?,
            signal: vec![0.0; n_times],
            imf: vec![0.0; n_times],
            imf_b: vec![0.0; n_times],
            imag: vec![0.0; n_times],
            imag_b: vec![0.0; n_times],
            amp: vec![0.0; n_times],
        })
    }

    /// Features of every epoch: `(n_epochs, 2 · n_channels · n_bins)`, amplitude block first.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (_, n_ch, n_t) = epochs.dim();
        let mut ex = self.extractor(n_t)?;
        let (width, split) = (self.n_features(n_ch, n_t), n_ch * self.n_bins(n_t));
        two_block_rows(epochs, width, split, |epoch, a, b| ex.epoch(epoch, a, b))
    }
}

/// Per-thread state of [`HhtFeatures`]: an EMD engine, a planned Hilbert transform and buffers.
#[derive(Debug, Clone)]
pub struct HhtExtractor {
    params: HhtFeatures,
    emd: Emd,
    hilbert: HilbertTransform,
    signal: Vec<f64>,
    imf: Vec<f64>,
    imf_b: Vec<f64>,
    imag: Vec<f64>,
    imag_b: Vec<f64>,
    amp: Vec<f64>,
}

impl HhtExtractor {
    /// Bin-averaged instantaneous amplitude and frequency of the first IMF of one channel.
    pub fn channel(
        &mut self,
        x: &[f64],
        amp_bins: &mut [f64],
        freq_bins: &mut [f64],
    ) -> Result<()> {
        self.emd.first_imf(x, &mut self.imf)?;
        self.hilbert.imag(&self.imf, &mut self.imag)?;
        self.bins(false, amp_bins, freq_bins)
    }

    /// The HHT block of one epoch `(n_channels, n_times)`: amplitude bins of every channel
    /// (channel-major) into `amp_block`, frequency bins into `freq_block`. Channels go through the
    /// Hilbert transform two at a time ([`HilbertTransform::imag_pair`]).
    pub fn epoch(
        &mut self,
        epoch: ndarray::ArrayView2<f64>,
        amp_block: &mut [f64],
        freq_block: &mut [f64],
    ) -> Result<()> {
        let (n_ch, n_t) = epoch.dim();
        let nb = self.params.n_bins(n_t);
        if n_t != self.signal.len() || amp_block.len() != n_ch * nb || freq_block.len() != n_ch * nb
        {
            return Err(DecodeError::ShapeMismatch {
                what: "HHT epoch (n_channels × n_times, bins)".into(),
                expected: format!("{n_ch} × {}, {} bins", self.signal.len(), n_ch * nb),
                got: format!(
                    "{n_ch} × {n_t}, {} / {} bins",
                    amp_block.len(),
                    freq_block.len()
                ),
            });
        }
        let (mut amp_rows, mut freq_rows) = (amp_block.chunks_mut(nb), freq_block.chunks_mut(nb));
        let mut bins = |ex: &mut Self, second| -> Result<()> {
            let (a, f) = (amp_rows.next(), freq_rows.next());
            ex.bins(
                second,
                a.expect("a row per channel"),
                f.expect("a row per channel"),
            )
        };
        for c in (0..n_ch).step_by(2) {
            self.first_imf_of(epoch.row(c), false)?;
            if c + 1 < n_ch {
                self.first_imf_of(epoch.row(c + 1), true)?;
                self.hilbert
                    .imag_pair(&self.imf, &self.imf_b, &mut self.imag, &mut self.imag_b)?;
                bins(self, false)?;
                bins(self, true)?;
            } else {
                self.hilbert.imag(&self.imf, &mut self.imag)?;
                bins(self, false)?;
            }
        }
        Ok(())
    }

    /// The first IMF of a possibly strided lane into `imf` (or `imf_b`).
    fn first_imf_of(&mut self, lane: ndarray::ArrayView1<f64>, second: bool) -> Result<()> {
        let signal: &[f64] = match lane.as_slice() {
            Some(s) => s,
            None => {
                for (s, &v) in self.signal.iter_mut().zip(lane.iter()) {
                    *s = v;
                }
                &self.signal
            }
        };
        let out = if second {
            &mut self.imf_b
        } else {
            &mut self.imf
        };
        self.emd.first_imf(signal, out)?;
        Ok(())
    }

    /// Amplitude and frequency bins of the analytic signal `imf + i·imag` (or of the `_b` pair).
    fn bins(&mut self, second: bool, amp_bins: &mut [f64], freq_bins: &mut [f64]) -> Result<()> {
        let (re, im) = if second {
            (&self.imf_b, &self.imag_b)
        } else {
            (&self.imf, &self.imag)
        };
        magnitude_into(re, im, &mut self.amp);
        bin_mean_into(&self.amp, self.params.bin, amp_bins)?;
        frequency_bins(re, im, self.params.sfreq, self.params.bin, freq_bins)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hilbert_of_a_cosine_is_a_sine() {
        for n in [64usize, 65] {
            // whole number of cycles, so the FFT sees a pure tone
            let k = 5.0;
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * std::f64::consts::PI * k * i as f64 / n as f64).cos())
                .collect();
            let (_, im) = analytic_signal(&x).unwrap();
            for (i, v) in im.iter().enumerate() {
                let want = (2.0 * std::f64::consts::PI * k * i as f64 / n as f64).sin();
                assert!((v - want).abs() < 1e-12, "n={n} i={i}: {v} vs {want}");
            }
        }
    }

    #[test]
    fn tone_has_constant_amplitude_and_frequency() {
        let n = 256;
        let fs = 256.0;
        let f0 = 16.0;
        let x: Vec<f64> = (0..n)
            .map(|i| 3.0 * (2.0 * std::f64::consts::PI * f0 * i as f64 / fs + 0.3).sin())
            .collect();
        let mut h = HilbertTransform::new(n).unwrap();
        let mut amp = vec![0.0; n];
        let mut freq = vec![0.0; n];
        h.amplitude_frequency(&x, fs, &mut amp, &mut freq).unwrap();
        assert!(amp.iter().all(|a| (a - 3.0).abs() < 1e-9));
        assert!(freq.iter().all(|f| (f - f0).abs() < 1e-9), "{freq:?}");
    }

    #[test]
    fn unwrap_handles_phase_jumps() {
        // a phase ramp of 1.5 rad per sample wraps every few samples; frequency stays constant
        let n = 20;
        let re: Vec<f64> = (0..n).map(|i| (1.5 * i as f64).cos()).collect();
        let im: Vec<f64> = (0..n).map(|i| (1.5 * i as f64).sin()).collect();
        let mut f = vec![0.0; n];
        instantaneous_frequency(&re, &im, 2.0 * std::f64::consts::PI, &mut f).unwrap();
        assert!(f.iter().all(|v| (v - 1.5).abs() < 1e-12), "{f:?}");
    }

    /// Uniform values in [−0.5, 0.5) from a fixed-seed LCG.
    fn lcg(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
    }

    fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_pair_transform_equals_two_single_ones() {
        let mut u = lcg(7);
        for n in [2usize, 3, 8, 9, 64, 128, 205, 256] {
            let a: Vec<f64> = (0..n).map(|_| 50.0 * u()).collect();
            let b: Vec<f64> = (0..n)
                .map(|i| 20.0 * u() + (0.3 * i as f64).sin())
                .collect();
            let mut h = HilbertTransform::new(n).unwrap();
            let (mut sa, mut sb) = (vec![0.0; n], vec![0.0; n]);
            h.imag(&a, &mut sa).unwrap();
            h.imag(&b, &mut sb).unwrap();
            let (mut pa, mut pb) = (vec![0.0; n], vec![0.0; n]);
            h.imag_pair(&a, &b, &mut pa, &mut pb).unwrap();
            let (ea, eb) = (max_abs_diff(&pa, &sa), max_abs_diff(&pb, &sb));
            assert!(
                ea <= 1e-12 * 50.0 && eb <= 1e-12 * 50.0,
                "n={n}: {ea:e} {eb:e}"
            );
        }
        let mut h = HilbertTransform::new(8).unwrap();
        let mut out = vec![0.0; 8];
        assert!(h
            .imag_pair(&[0.0; 8], &[0.0; 7], &mut out.clone(), &mut out)
            .is_err());
    }

    /// The definition: per-sample phase, numpy's unwrap, first differences, bin means.
    fn naive_frequency_bins(re: &[f64], im: &[f64], sfreq: f64, bin: usize) -> Vec<f64> {
        let mut f = vec![0.0; re.len()];
        instantaneous_frequency(re, im, sfreq, &mut f).unwrap();
        let mut out = vec![0.0; re.len() / bin];
        bin_mean_into(&f, bin, &mut out).unwrap();
        out
    }

    fn check_bins(re: &[f64], im: &[f64], sfreq: f64, what: &str) {
        for bin in [1usize, 2, 3, 10] {
            if re.len() / bin == 0 {
                continue;
            }
            let want = naive_frequency_bins(re, im, sfreq, bin);
            let mut got = vec![0.0; re.len() / bin];
            frequency_bins(re, im, sfreq, bin, &mut got).unwrap();
            let e = max_abs_diff(&got, &want);
            assert!(
                e <= 1e-10 * sfreq,
                "{what}, bin {bin}: {e:e}\n{got:?}\n{want:?}"
            );
        }
    }

    #[test]
    fn frequency_bins_equal_the_per_sample_definition() {
        let fs = 256.0;
        let mut u = lcg(11);
        // analytic signals of noise and of tones up to Nyquist (many wraps per bin), lengths with
        // and without a last bin that reaches the final sample
        for case in 0..400 {
            let n = 2 + case % 211;
            let f0 = fs * (case % 13) as f64 / 24.0;
            let x: Vec<f64> = (0..n)
                .map(|i| {
                    let t = i as f64 / fs;
                    (2.0 * std::f64::consts::PI * f0 * t).cos() + 0.7 * u()
                })
                .collect();
            let mut h = HilbertTransform::new(n).unwrap();
            let mut im = vec![0.0; n];
            h.imag(&x, &mut im).unwrap();
            check_bins(&x, &im, fs, &format!("case {case} (n {n}, {f0} Hz)"));
        }
        // the edges: samples on the real axis (signed zeros), neighbours exactly and nearly opposite,
        // values quantised so that such coincidences are common
        for case in 0..400 {
            let n = 2 + case % 37;
            let q = |v: f64| (v * 4.0).round() / 4.0;
            let re: Vec<f64> = (0..n).map(|_| q(u())).collect();
            let im: Vec<f64> = (0..n)
                .map(|i| match (case + i) % 5 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 1e-300 * u(),
                    _ => q(u()),
                })
                .collect();
            check_bins(&re, &im, fs, &format!("edge case {case}"));
        }
        // a Nyquist tone: every step rotates by π, give or take round-off in either direction
        for eps in [0.0, 1e-17, -1e-17, 1e-12, -1e-12, 1e-7, -1e-7] {
            let n = 40;
            let re: Vec<f64> = (0..n)
                .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
                .collect();
            let im: Vec<f64> = (0..n).map(|i| eps * (i as f64 - 7.5)).collect();
            check_bins(&re, &im, fs, &format!("Nyquist tone, eps {eps:e}"));
        }
    }

    #[test]
    fn frequency_bins_refuse_bad_shapes() {
        let mut out = vec![0.0; 2];
        assert!(frequency_bins(&[1.0; 8], &[1.0; 7], 256.0, 4, &mut out).is_err());
        assert!(frequency_bins(&[1.0; 8], &[1.0; 8], 256.0, 0, &mut out).is_err());
        assert!(frequency_bins(&[1.0; 8], &[1.0; 8], 256.0, 5, &mut out).is_err());
        assert!(frequency_bins(&[1.0; 8], &[1.0; 8], f64::NAN, 4, &mut out).is_err());
        assert!(frequency_bins(&[1.0], &[1.0], 256.0, 1, &mut out[..1]).is_err());
    }

    #[test]
    fn epoch_features_equal_the_channel_by_channel_ones() {
        let mut u = lcg(3);
        for n_ch in [1usize, 2, 5, 8] {
            let n_t = 205;
            let epoch = ndarray::Array2::from_shape_fn((n_ch, n_t), |(c, t)| {
                let tt = t as f64 / 256.0;
                10.0 * (2.0 * std::f64::consts::PI * (3.0 + 2.0 * c as f64) * tt).sin() + 5.0 * u()
            });
            let h = HhtFeatures::for_sfreq(256.0).unwrap();
            let nb = h.n_bins(n_t);
            let mut ex = h.extractor(n_t).unwrap();
            let (mut amp, mut freq) = (vec![0.0; n_ch * nb], vec![0.0; n_ch * nb]);
            ex.epoch(epoch.view(), &mut amp, &mut freq).unwrap();
            // a channel-last (strided) view gives the same
            let strided = epoch.t().to_owned();
            let (mut amp_s, mut freq_s) = (vec![0.0; n_ch * nb], vec![0.0; n_ch * nb]);
            ex.epoch(strided.t(), &mut amp_s, &mut freq_s).unwrap();
            assert_eq!((&amp, &freq), (&amp_s, &freq_s));
            for c in 0..n_ch {
                let (mut a, mut f) = (vec![0.0; nb], vec![0.0; nb]);
                let x = epoch.row(c).to_vec();
                ex.channel(&x, &mut a, &mut f).unwrap();
                let bins = c * nb..(c + 1) * nb;
                assert!(
                    max_abs_diff(&a, &amp[bins.clone()]) <= 1e-11,
                    "n_ch {n_ch}, c {c}"
                );
                assert!(max_abs_diff(&f, &freq[bins]) <= 1e-9, "n_ch {n_ch}, c {c}");
            }
        }
    }

    #[test]
    fn hht_feature_shape_and_errors() {
        let h = HhtFeatures::for_sfreq(256.0).unwrap();
        assert_eq!(h.bin, 10);
        assert_eq!(h.n_features(8, 205), 2 * 8 * 20);
        assert!(HhtFeatures::new(0.0, 10, EmdParams::default()).is_err());
        assert!(HhtFeatures::new(256.0, 0, EmdParams::default()).is_err());
        let mut t = HilbertTransform::new(8).unwrap();
        let mut out = vec![0.0; 7];
        assert!(t.imag(&[0.0; 8], &mut out).is_err());
    }
}
