//! Analytic signal, instantaneous amplitude and frequency, and the paper's Hilbert–Huang (HHT)
//! features.
//!
//! [`HilbertTransform`] computes scipy's `signal.hilbert` — FFT, zero the negative frequencies, double
//! the positive ones (DC and, for even lengths, Nyquist kept once), inverse FFT — with the `realfft`
//! crate. Because that analytic signal's real part is the input itself, only its imaginary part (the
//! Hilbert transform) is computed, as one real-to-complex and one complex-to-real FFT of the signal's
//! own length; the real part returned is the input, where scipy's is the input plus FFT round-off.
//!
//! The instantaneous frequency is the peer's (`shared/peer/peer_eval.py`): `numpy.unwrap` of the
//! phase `atan2(im, re)`, its first difference times `sfreq / 2π`, and the last difference repeated so
//! the output keeps the input's length (`f[n−1] = f[n−2]`).
//!
//! [`HhtFeatures`] is the peer's HHT block: per channel, the first IMF ([`crate::emd`]), its
//! instantaneous amplitude and frequency, each averaged in bins of `bin` samples
//! ([`crate::amplitude::bin_mean_into`]); all amplitude bins (channel-major) come before all frequency
//! bins.
//!
//! The FFT and its plans come from `realfft`; the rest is written here (a few lines, and it must
//! follow scipy's and numpy's conventions exactly).

use std::sync::Arc;

use ndarray::{Array2, ArrayView3};
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use serde::{Deserialize, Serialize};

use crate::amplitude::{bin_mean_into, vec_bin};
use crate::emd::{Emd, EmdParams};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// A planned Hilbert transform for signals of one length, with its buffers.
#[derive(Clone)]
pub struct HilbertTransform {
    n: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    input: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
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
        let mut planner = RealFftPlanner::<f64>::new();
        let r2c = planner.plan_fft_forward(n);
        let c2r = planner.plan_fft_inverse(n);
        let scratch =
            vec![Complex::new(0.0, 0.0); r2c.get_scratch_len().max(c2r.get_scratch_len())];
        Ok(Self {
            n,
            input: vec![0.0; n],
            spectrum: r2c.make_output_vec(),
            r2c,
            c2r,
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
        self.input.copy_from_slice(x);
        self.r2c
            .process_with_scratch(&mut self.input, &mut self.spectrum, &mut self.scratch)
            .map_err(fft_error)?;
        // -i·X_k for 0 < k < n/2 (doubled positive frequencies, the negative ones dropped); DC and
        // Nyquist carry no imaginary part.
        let half = self.spectrum.len();
        let nyquist = if self.n % 2 == 0 { half - 1 } else { half };
        for (k, c) in self.spectrum.iter_mut().enumerate() {
            *c = if k == 0 || k >= nyquist {
                Complex::new(0.0, 0.0)
            } else {
                Complex::new(c.im, -c.re)
            };
        }
        self.c2r
            .process_with_scratch(&mut self.spectrum, out, &mut self.scratch)
            .map_err(fft_error)?;
        let scale = 1.0 / self.n as f64;
        out.iter_mut().for_each(|v| *v *= scale);
        Ok(())
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
        // |z| as √(re² + im²): within an ulp of numpy's `hypot`, several times faster, and µV-scale
        // values can't overflow
        for ((a, &re), &im) in amp.iter_mut().zip(x).zip(freq.iter()) {
            *a = (re * re + im * im).sqrt();
        }
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

fn fft_error(e: realfft::FftError) -> DecodeError {
    DecodeError::ShapeMismatch {
        what: "FFT buffers".into(),
        expected: "planned lengths".into(),
        got: e.to_string(),
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

/// Wrapped phase (in place) → instantaneous frequency, as `numpy.unwrap` then `numpy.diff`.
fn phase_to_frequency(p: &mut [f64], sfreq: f64) -> Result<()> {
    let n = p.len();
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
    let pi = std::f64::consts::PI;
    let period = 2.0 * pi;
    let to_hz = |d: f64| d * sfreq / (2.0 * pi);
    // numpy.unwrap: up[i] = p[i] + cumsum(correction)[i-1]
    let mut cum = 0.0;
    let mut prev_up = p[0];
    let mut prev_p = p[0];
    for i in 1..n {
        let pi_now = p[i];
        let dd = pi_now - prev_p;
        // the correction is 0 unless the step reaches π (numpy computes it everywhere, then masks)
        let correction = if dd.abs() < pi {
            0.0
        } else {
            let mut ddmod = np_mod(dd + pi, period) - pi;
            if ddmod == -pi && dd > 0.0 {
                ddmod = pi;
            }
            ddmod - dd
        };
        cum += correction;
        let up = pi_now + cum;
        p[i - 1] = to_hz(up - prev_up);
        prev_up = up;
        prev_p = pi_now;
    }
    p[n - 1] = p[n - 2];
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
            amp: vec![0.0; n_times],
            freq: vec![0.0; n_times],
        })
    }

    /// Features of every epoch: `(n_epochs, 2 · n_channels · n_bins)`, amplitude block first.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (n_ep, n_ch, n_t) = epochs.dim();
        let nb = self.n_bins(n_t);
        let mut ex = self.extractor(n_t)?;
        let mut out = Array2::zeros((n_ep, self.n_features(n_ch, n_t)));
        for (epoch, mut row) in epochs.outer_iter().zip(out.rows_mut()) {
            let row = row
                .as_slice_mut()
                .expect("rows of a standard-layout array are contiguous");
            let (amp_block, freq_block) = row.split_at_mut(n_ch * nb);
            for (c, lane) in epoch.outer_iter().enumerate() {
                ex.channel_lane(
                    lane,
                    &mut amp_block[c * nb..(c + 1) * nb],
                    &mut freq_block[c * nb..(c + 1) * nb],
                )?;
            }
        }
        Ok(out)
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
    amp: Vec<f64>,
    freq: Vec<f64>,
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
        self.hilbert.amplitude_frequency(
            &self.imf,
            self.params.sfreq,
            &mut self.amp,
            &mut self.freq,
        )?;
        bin_mean_into(&self.amp, self.params.bin, amp_bins)?;
        bin_mean_into(&self.freq, self.params.bin, freq_bins)
    }

    /// As [`Self::channel`] for a possibly strided lane of an epoch array.
    pub fn channel_lane(
        &mut self,
        lane: ndarray::ArrayView1<f64>,
        amp_bins: &mut [f64],
        freq_bins: &mut [f64],
    ) -> Result<()> {
        if lane.len() != self.signal.len() {
            return Err(DecodeError::ShapeMismatch {
                what: "HHT channel length".into(),
                expected: self.signal.len().to_string(),
                got: lane.len().to_string(),
            });
        }
        let mut signal = std::mem::take(&mut self.signal);
        for (s, &v) in signal.iter_mut().zip(lane.iter()) {
            *s = v;
        }
        let r = self.channel(&signal, amp_bins, freq_bins);
        self.signal = signal;
        r
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
