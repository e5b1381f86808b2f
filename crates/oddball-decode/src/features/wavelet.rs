//! B-spline biorthogonal wavelet features: the discrete wavelet transform with PyWavelets' `bior2.2`
//! filters and `mode='symmetric'` edges, equal to `pywt.dwt` / `pywt.wavedec`.
//!
//! One level: `c[o] = Σ_j h[j] · x̃[2o + 1 − j]` for `o = 0 … ⌊(n + 5) / 2⌋ − 1`, where `h` is the
//! 6-tap decomposition filter and `x̃` the half-sample symmetric extension (`x̃[−1] = x[0]`,
//! `x̃[n] = x[n−1]`, repeating with period `2n`). [`wavedec_bior22`] applies it to the approximation
//! `level` times and returns `[cA_L, cD_L, …, cD_1]` as `pywt.wavedec`.
//!
//! [`DwtFeatures`] keeps what the peer's `paper` features keep: the level-L approximation (0 …
//! sfreq/2^(L+1), about 0–4 Hz at L = round(log2(sfreq/8))) and the level-L detail (about 4–8 Hz),
//! each channel-major, approximations first.
//!
//! Written here rather than with the `ndwt` crate (0.1.1), although ndwt's `Bior2_2` with
//! `BoundaryCondition::Symmetric` does agree with PyWavelets (checked to 2e-15 on one level): ndwt
//! requires Rust 1.95 and edition 2024 while this workspace declares `rust-version = 1.88`, and it
//! brings SIMD, proc-macro and rayon dependencies for what is a 6-tap filter on ~200 samples. The
//! transform here is checked against PyWavelets 1.9 in `tests/paper_golden.rs`.

use ndarray::{Array2, ArrayView2, ArrayView3};
use serde::{Deserialize, Serialize};

use crate::features::rows::two_block_rows;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// PyWavelets' `Wavelet('bior2.2').dec_lo` (its zero first tap kept so lengths agree with pywt).
pub const BIOR22_DEC_LO: [f64; 6] = [
    0.0,
    -0.1767766952966369,
    0.3535533905932738,
    1.0606601717798212,
    0.3535533905932738,
    -0.1767766952966369,
];

/// PyWavelets' `Wavelet('bior2.2').dec_hi`.
pub const BIOR22_DEC_HI: [f64; 6] = [
    -0.0,
    0.3535533905932738,
    -std::f64::consts::FRAC_1_SQRT_2, // -0.7071067811865476, the same double
    0.3535533905932738,
    -0.0,
    0.0,
];

/// Coefficients per band after one level on `n` samples (pywt's `dwt_coeff_len`, non-periodic modes).
pub fn dwt_len(n: usize) -> usize {
    (n + BIOR22_DEC_LO.len() - 1) / 2
}

/// Half-sample symmetric extension of `x` at any integer index.
#[inline]
fn symmetric(x: &[f64], i: isize) -> f64 {
    let n = x.len() as isize;
    let p = i.rem_euclid(2 * n);
    if p < n {
        x[p as usize]
    } else {
        x[(2 * n - 1 - p) as usize]
    }
}

/// One level of the `bior2.2` DWT with symmetric edges: `pywt.dwt(x, 'bior2.2', mode='symmetric')`.
/// `approx` and `detail` must each hold [`dwt_len`]`(x.len())` values.
pub fn dwt_bior22(x: &[f64], approx: &mut [f64], detail: &mut [f64]) -> Result<()> {
    let n = x.len();
    if n == 0 {
        return Err(DecodeError::TooFewSamples {
            what: "DWT of an empty signal".into(),
        });
    }
    let m = dwt_len(n);
    if approx.len() != m || detail.len() != m {
        return Err(DecodeError::ShapeMismatch {
            what: "DWT output lengths".into(),
            expected: format!("{m} and {m}"),
            got: format!("{} and {}", approx.len(), detail.len()),
        });
    }
    let f = BIOR22_DEC_LO.len();
    for o in 0..m {
        let i = 2 * o + 1;
        let (mut a, mut d) = (0.0, 0.0);
        if i >= f - 1 && i < n {
            // interior: no extension needed
            for j in 0..f {
                let v = x[i - j];
                a += BIOR22_DEC_LO[j] * v;
                d += BIOR22_DEC_HI[j] * v;
            }
        } else {
            for j in 0..f {
                let v = symmetric(x, i as isize - j as isize);
                a += BIOR22_DEC_LO[j] * v;
                d += BIOR22_DEC_HI[j] * v;
            }
        }
        approx[o] = a;
        detail[o] = d;
    }
    Ok(())
}

/// `pywt.wavedec(x, 'bior2.2', level=level, mode='symmetric')`: `[cA_L, cD_L, cD_{L−1}, …, cD_1]`.
/// Like pywt, a level deeper than the signal supports is computed anyway (pywt only warns).
pub fn wavedec_bior22(x: &[f64], level: usize) -> Result<Vec<Vec<f64>>> {
    if level == 0 {
        return Err(DecodeError::InvalidParameter {
            name: "level",
            value: "0".into(),
            reason: "a decomposition needs at least one level".into(),
        });
    }
    let mut a = x.to_vec();
    let mut details = Vec::with_capacity(level);
    for _ in 0..level {
        let m = dwt_len(a.len());
        let mut na = vec![0.0; m];
        let mut nd = vec![0.0; m];
        dwt_bior22(&a, &mut na, &mut nd)?;
        a = na;
        details.push(nd);
    }
    let mut out = vec![a];
    out.extend(details.into_iter().rev());
    Ok(out)
}

/// The level `level` approximation and detail of each channel. Nothing is learned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct DwtFeatures {
    /// Decomposition level L (≥ 1).
    pub level: usize,
}

impl DwtFeatures {
    /// A checked level.
    pub fn new(level: usize) -> Result<Self> {
        if level == 0 {
            return Err(DecodeError::InvalidParameter {
                name: "level",
                value: "0".into(),
                reason: "a decomposition needs at least one level".into(),
            });
        }
        Ok(Self { level })
    }

    /// The peer's level at `sfreq`: L = round(log2(sfreq / 8)), so the approximation covers about
    /// 0–4 Hz and the detail 4–8 Hz (5 at 256 Hz, 4 at 160 and 128 Hz).
    pub fn for_sfreq(sfreq: f64) -> Result<Self> {
        if !(sfreq.is_finite() && sfreq > 16.0) {
            return Err(DecodeError::InvalidParameter {
                name: "sfreq",
                value: sfreq.to_string(),
                reason: "must be finite and > 16 Hz for a level >= 1".into(),
            });
        }
        // Python's round (ties to even), as the peer
        Self::new((sfreq / 8.0).log2().round_ties_even() as usize)
    }

    /// Coefficients per band and channel after `level` levels on `n_times` samples.
    pub fn n_coefficients(&self, n_times: usize) -> usize {
        (0..self.level).fold(n_times, |n, _| dwt_len(n))
    }

    /// Output width: approximation and detail of every channel.
    pub fn n_features(&self, n_channels: usize, n_times: usize) -> usize {
        2 * n_channels * self.n_coefficients(n_times)
    }

    /// A reusable per-thread extractor for channels of `n_times` samples.
    pub fn extractor(&self, n_times: usize) -> Result<DwtExtractor> {
        if n_times == 0 {
            return Err(DecodeError::TooFewSamples {
                what: "DWT of empty epochs".into(),
            });
        }
        Ok(DwtExtractor {
            level: self.level,
            n_times,
            a: Vec::with_capacity(dwt_len(n_times)),
            na: Vec::with_capacity(dwt_len(n_times)),
            d: Vec::with_capacity(dwt_len(n_times)),
        })
    }

    /// Features of every epoch: `(n_epochs, 2 · n_channels · n_coefficients)`, approximations first.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (_, n_ch, n_t) = epochs.dim();
        let mut ex = self.extractor(n_t)?;
        let (width, split) = (self.n_features(n_ch, n_t), n_ch * self.n_coefficients(n_t));
        two_block_rows(epochs, width, split, |epoch, a, b| ex.epoch(epoch, a, b))
    }
}

/// Per-thread buffers of [`DwtFeatures`].
#[derive(Debug, Clone)]
pub struct DwtExtractor {
    level: usize,
    n_times: usize,
    a: Vec<f64>,
    na: Vec<f64>,
    d: Vec<f64>,
}

impl DwtExtractor {
    /// Level-L approximations of every channel of one epoch `(n_channels, n_times)` into
    /// `approx`, details into `detail` (channel-major, `n_channels · n_coefficients` each).
    pub fn epoch(
        &mut self,
        epoch: ArrayView2<f64>,
        approx: &mut [f64],
        detail: &mut [f64],
    ) -> Result<()> {
        let nc = approx.len() / epoch.nrows().max(1);
        for (c, lane) in epoch.outer_iter().enumerate() {
            self.channel(
                lane.iter().copied(),
                &mut approx[c * nc..(c + 1) * nc],
                &mut detail[c * nc..(c + 1) * nc],
            )?;
        }
        Ok(())
    }

    /// Level-L approximation and detail of one channel (`n_times` samples).
    pub fn channel(
        &mut self,
        x: impl ExactSizeIterator<Item = f64>,
        approx: &mut [f64],
        detail: &mut [f64],
    ) -> Result<()> {
        if x.len() != self.n_times {
            return Err(DecodeError::ShapeMismatch {
                what: "DWT channel length".into(),
                expected: self.n_times.to_string(),
                got: x.len().to_string(),
            });
        }
        self.a.clear();
        self.a.extend(x);
        for lvl in 0..self.level {
            let m = dwt_len(self.a.len());
            self.na.clear();
            self.na.resize(m, 0.0);
            self.d.clear();
            self.d.resize(m, 0.0);
            dwt_bior22(&self.a, &mut self.na, &mut self.d)?;
            std::mem::swap(&mut self.a, &mut self.na);
            if lvl + 1 == self.level {
                if approx.len() != m || detail.len() != m {
                    return Err(DecodeError::ShapeMismatch {
                        what: "DWT feature slots".into(),
                        expected: m.to_string(),
                        got: format!("{} and {}", approx.len(), detail.len()),
                    });
                }
                approx.copy_from_slice(&self.a);
                detail.copy_from_slice(&self.d);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_follow_pywt() {
        assert_eq!(dwt_len(205), 105);
        let f = DwtFeatures::for_sfreq(256.0).unwrap();
        assert_eq!(f.level, 5);
        assert_eq!(f.n_coefficients(205), 11);
        assert_eq!(DwtFeatures::for_sfreq(160.0).unwrap().level, 4);
        assert_eq!(DwtFeatures::for_sfreq(128.0).unwrap().level, 4);
    }

    #[test]
    fn constant_signal_gives_scaled_approximation_and_zero_detail() {
        // symmetric extension of a constant is constant: Σ dec_lo = √2, Σ dec_hi = 0
        let x = vec![3.0; 37];
        let m = dwt_len(37);
        let (mut a, mut d) = (vec![0.0; m], vec![0.0; m]);
        dwt_bior22(&x, &mut a, &mut d).unwrap();
        assert!(a
            .iter()
            .all(|v| (v - 3.0 * std::f64::consts::SQRT_2).abs() < 1e-12));
        assert!(d.iter().all(|v| v.abs() < 1e-12));
    }

    #[test]
    fn linear_ramp_has_zero_interior_detail() {
        // bior2.2's analysis high-pass has two vanishing moments: no detail inside a ramp
        let x: Vec<f64> = (0..64).map(|i| 0.5 * i as f64 - 3.0).collect();
        let c = wavedec_bior22(&x, 1).unwrap();
        for v in &c[1][2..c[1].len() - 3] {
            assert!(v.abs() < 1e-12, "{v}");
        }
    }

    #[test]
    fn rejects_level_zero_and_wrong_buffers() {
        assert!(DwtFeatures::new(0).is_err());
        assert!(wavedec_bior22(&[1.0, 2.0], 0).is_err());
        let mut a = vec![0.0; 2];
        let mut d = vec![0.0; 3];
        assert!(dwt_bior22(&[1.0, 2.0, 3.0], &mut a, &mut d).is_err());
    }
}
