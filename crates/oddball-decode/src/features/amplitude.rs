//! Amplitude features — the epoch's samples, bin-averaged or decimated, flattened channel-major — and
//! [`PaperFeatures`], the paper's full feature map: amplitude + Hilbert–Huang + B-spline wavelet.
//!
//! Bin averaging is the peer's `vec` features (`shared/peer/peer_eval.py`, `bin_mean`): the mean of each
//! non-overlapping bin of `bin` samples, a trailing partial bin dropped; at 256 Hz bins of
//! round(256/25) = 10 samples turn 205 samples into 20 values per channel. Decimation keeps every
//! `step`-th sample starting at the first (the signal must already be band-limited).
//!
//! [`PaperFeatures`] concatenates, per epoch and in this order (each block channel-major): amplitude
//! bins, first-IMF instantaneous-amplitude bins, first-IMF instantaneous-frequency bins
//! ([`crate::features::hilbert::HhtFeatures`]), the DWT approximation and the DWT detail
//! ([`crate::features::wavelet::DwtFeatures`]) — the peer's `paper` map, 656 features for 8 channels × 205
//! samples at 256 Hz. Checked offline on all 720 epochs of the eeg3_1 recording: every one of the
//! 656 features agrees with the peer's to ≤ 6e-13 (the golden test repeats this on synthetic epochs).
//! Batches are split over threads with rayon; each thread owns one EMD engine, one planned FFT and
//! its buffers. Written here: the maps are a few lines over [`crate::features::emd`],
//! [`crate::features::hilbert`] and [`crate::features::wavelet`].

use std::cell::RefCell;

use ndarray::{Array2, ArrayView2, ArrayView3, Axis};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::features::bins::{bin_mean_into, vec_bin};
use crate::features::hilbert::{HhtExtractor, HhtFeatures};
use crate::features::wavelet::{DwtExtractor, DwtFeatures};
use crate::traits::{FeatureData, FitTransformer, Transformer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// How an epoch's samples are reduced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Reduction {
    /// Mean of each non-overlapping bin of this many samples.
    BinMean { bin: usize },
    /// Every `step`-th sample, starting with the first.
    Decimate { step: usize },
}

/// Amplitude features. Nothing is learned, so there is no fitted counterpart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct AmplitudeFeatures {
    /// How samples are reduced.
    pub reduction: Reduction,
}

impl AmplitudeFeatures {
    /// Bin means of `bin` samples (≥ 1).
    pub fn bin_mean(bin: usize) -> Result<Self> {
        if bin == 0 {
            return Err(DecodeError::InvalidParameter {
                name: "bin",
                value: "0".into(),
                reason: "bins need at least one sample".into(),
            });
        }
        Ok(Self {
            reduction: Reduction::BinMean { bin },
        })
    }

    /// Every `step`-th sample (≥ 1).
    pub fn decimate(step: usize) -> Result<Self> {
        if step == 0 {
            return Err(DecodeError::InvalidParameter {
                name: "step",
                value: "0".into(),
                reason: "the step must be at least one sample".into(),
            });
        }
        Ok(Self {
            reduction: Reduction::Decimate { step },
        })
    }

    /// The peer's `vec` features at `sfreq`: bins of round(sfreq / 25) samples.
    pub fn for_sfreq(sfreq: f64) -> Result<Self> {
        Self::bin_mean(vec_bin(sfreq)?)
    }

    /// Values per channel for epochs of `n_times` samples.
    pub fn n_points(&self, n_times: usize) -> usize {
        match self.reduction {
            Reduction::BinMean { bin } => n_times / bin.max(1),
            Reduction::Decimate { step } => n_times.div_ceil(step.max(1)),
        }
    }

    /// Output width for epochs of `n_channels × n_times`.
    pub fn n_features(&self, n_channels: usize, n_times: usize) -> usize {
        n_channels * self.n_points(n_times)
    }

    /// The reduced samples of one channel into `out` (`n_points` values).
    pub fn channel(&self, x: ndarray::ArrayView1<f64>, out: &mut [f64]) -> Result<()> {
        let np = self.n_points(x.len());
        if out.len() != np {
            return Err(DecodeError::ShapeMismatch {
                what: "amplitude feature slots".into(),
                expected: np.to_string(),
                got: out.len().to_string(),
            });
        }
        match self.reduction {
            Reduction::BinMean { bin } => match x.as_slice() {
                Some(s) => bin_mean_into(s, bin, out)?,
                None => bin_mean_into(&x.to_vec(), bin, out)?,
            },
            Reduction::Decimate { step } => {
                for (o, v) in out.iter_mut().zip(x.iter().step_by(step)) {
                    *o = *v;
                }
            }
        }
        Ok(())
    }

    /// Features of one epoch `(n_channels, n_times)` into `out`.
    pub fn epoch(&self, epoch: ArrayView2<f64>, out: &mut [f64]) -> Result<()> {
        let np = self.n_points(epoch.ncols());
        if out.len() != epoch.nrows() * np {
            return Err(DecodeError::ShapeMismatch {
                what: "amplitude feature row".into(),
                expected: (epoch.nrows() * np).to_string(),
                got: out.len().to_string(),
            });
        }
        for (lane, o) in epoch.outer_iter().zip(out.chunks_exact_mut(np.max(1))) {
            self.channel(lane, o)?;
        }
        Ok(())
    }

    /// Features of every epoch: `(n_epochs, n_channels · n_points)`.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (n_ep, n_ch, n_t) = epochs.dim();
        let mut out = Array2::zeros((n_ep, self.n_features(n_ch, n_t)));
        for (epoch, mut row) in epochs.outer_iter().zip(out.rows_mut()) {
            let row = row
                .as_slice_mut()
                .expect("rows of a standard-layout array are contiguous");
            self.epoch(epoch, row)?;
        }
        Ok(out)
    }
}

/// The paper's feature map (the peer's `paper` features): amplitude + HHT + DWT. Nothing is learned.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PaperFeatures {
    /// Amplitude block.
    pub amplitude: AmplitudeFeatures,
    /// Hilbert–Huang block (instantaneous amplitude, then frequency).
    pub hht: HhtFeatures,
    /// Wavelet block (approximation, then detail).
    pub dwt: DwtFeatures,
}

/// Widths of the blocks of one [`PaperFeatures`] row, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PaperLayout {
    pub amplitude: usize,
    pub inst_amplitude: usize,
    pub inst_frequency: usize,
    pub dwt_approx: usize,
    pub dwt_detail: usize,
}

impl PaperLayout {
    /// Total width.
    pub fn total(&self) -> usize {
        self.amplitude
            + self.inst_amplitude
            + self.inst_frequency
            + self.dwt_approx
            + self.dwt_detail
    }
}

impl PaperFeatures {
    /// The peer's settings at `sfreq`: bins of round(sfreq/25), PyEMD defaults, DWT level
    /// round(log2(sfreq/8)).
    pub fn for_sfreq(sfreq: f64) -> Result<Self> {
        Ok(Self {
            amplitude: AmplitudeFeatures::for_sfreq(sfreq)?,
            hht: HhtFeatures::for_sfreq(sfreq)?,
            dwt: DwtFeatures::for_sfreq(sfreq)?,
        })
    }

    /// Block widths for epochs of `n_channels × n_times`.
    pub fn layout(&self, n_channels: usize, n_times: usize) -> PaperLayout {
        let hb = n_channels * self.hht.n_bins(n_times);
        let dc = n_channels * self.dwt.n_coefficients(n_times);
        PaperLayout {
            amplitude: self.amplitude.n_features(n_channels, n_times),
            inst_amplitude: hb,
            inst_frequency: hb,
            dwt_approx: dc,
            dwt_detail: dc,
        }
    }

    /// Output width for epochs of `n_channels × n_times`.
    pub fn n_features(&self, n_channels: usize, n_times: usize) -> usize {
        self.layout(n_channels, n_times).total()
    }

    /// A reusable single-thread extractor for epochs of `n_times` samples.
    pub fn extractor(&self, n_times: usize) -> Result<PaperExtractor> {
        Ok(PaperExtractor {
            params: *self,
            hht: self.hht.extractor(n_times)?,
            dwt: self.dwt.extractor(n_times)?,
            n_times,
        })
    }

    /// Runs `f` with this thread's cached extractor for these settings and `n_times`, (re)building
    /// it when the settings or length changed: planning the FFT and allocating the buffers costs
    /// about as much as the HHT of one channel, which matters when epochs arrive one at a time.
    fn with_extractor<R>(
        &self,
        n_times: usize,
        f: impl FnOnce(&mut PaperExtractor) -> Result<R>,
    ) -> Result<R> {
        EXTRACTOR.with(|cell| {
            let mut slot = cell.borrow_mut();
            let fresh = match slot.as_ref() {
                Some(ex) => ex.params != *self || ex.n_times != n_times,
                None => true,
            };
            if fresh {
                *slot = Some(self.extractor(n_times)?);
            }
            f(slot.as_mut().expect("just filled"))
        })
    }

    /// Features of every epoch: `(n_epochs, n_features)`. Batches are spread over rayon's threads;
    /// a single epoch is computed on the calling thread with its cached extractor.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let (n_ep, n_ch, n_t) = epochs.dim();
        let width = self.n_features(n_ch, n_t);
        let mut out = Array2::zeros((n_ep, width));
        if n_ep == 0 {
            return Ok(out);
        }
        if n_ep == 1 {
            let row = out.as_slice_mut().expect("a new array is contiguous");
            self.with_extractor(n_t, |ex| ex.epoch(epochs.index_axis(Axis(0), 0), row))?;
            return Ok(out);
        }
        let template = self.with_extractor(n_t, |ex| Ok(ex.clone()))?;
        out.as_slice_mut()
            .expect("a new array is contiguous")
            .par_chunks_mut(width.max(1))
            .enumerate()
            .try_for_each_init(
                || template.clone(),
                |ex, (i, row)| ex.epoch(epochs.index_axis(Axis(0), i), row),
            )?;
        Ok(out)
    }
}

thread_local! {
    /// The last extractor [`PaperFeatures::transform`] used on this thread.
    static EXTRACTOR: RefCell<Option<PaperExtractor>> = const { RefCell::new(None) };
}

/// Per-thread state of [`PaperFeatures`].
#[derive(Debug, Clone)]
pub struct PaperExtractor {
    params: PaperFeatures,
    hht: HhtExtractor,
    dwt: DwtExtractor,
    n_times: usize,
}

impl PaperExtractor {
    /// Features of one epoch `(n_channels, n_times)` into `out` (`n_features` values).
    pub fn epoch(&mut self, epoch: ArrayView2<f64>, out: &mut [f64]) -> Result<()> {
        let (n_ch, n_t) = epoch.dim();
        if n_t != self.n_times {
            return Err(DecodeError::ShapeMismatch {
                what: "epoch length".into(),
                expected: self.n_times.to_string(),
                got: n_t.to_string(),
            });
        }
        let lay = self.params.layout(n_ch, n_t);
        if out.len() != lay.total() {
            return Err(DecodeError::ShapeMismatch {
                what: "paper feature row".into(),
                expected: lay.total().to_string(),
                got: out.len().to_string(),
            });
        }
        let (amp, rest) = out.split_at_mut(lay.amplitude);
        let (ia, rest) = rest.split_at_mut(lay.inst_amplitude);
        let (ifr, rest) = rest.split_at_mut(lay.inst_frequency);
        let (da, dd) = rest.split_at_mut(lay.dwt_approx);
        self.params.amplitude.epoch(epoch, amp)?;
        self.hht.epoch(epoch, ia, ifr)?;
        self.dwt.epoch(epoch, da, dd)
    }
}

/// Nothing to learn: the settings are the fitted map.
impl FitTransformer for AmplitudeFeatures {
    type Fitted = AmplitudeFeatures;
    fn fit_transformer(&self, _: ArrayView3<f64>, _: &[bool]) -> Result<AmplitudeFeatures> {
        Ok(*self)
    }
    fn is_stateless(&self) -> bool {
        true
    }
}

impl Transformer for AmplitudeFeatures {
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        Ok(FeatureData::Rows(self.transform(epochs)?))
    }
}

/// Nothing to learn: the settings are the fitted map.
impl FitTransformer for PaperFeatures {
    type Fitted = PaperFeatures;
    fn fit_transformer(&self, _: ArrayView3<f64>, _: &[bool]) -> Result<PaperFeatures> {
        Ok(*self)
    }
    fn is_stateless(&self) -> bool {
        true
    }
}

impl Transformer for PaperFeatures {
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        Ok(FeatureData::Rows(self.transform(epochs)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array3;

    #[test]
    fn bin_means_drop_the_partial_bin() {
        let mut out = vec![0.0; 2];
        bin_mean_into(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0], 3, &mut out).unwrap();
        assert_eq!(out, vec![2.0, 5.0]);
        assert!(bin_mean_into(&[1.0], 0, &mut out).is_err());
    }

    #[test]
    fn amplitude_features_are_channel_major() {
        let x = Array3::from_shape_fn((2, 2, 6), |(e, c, t)| (100 * e + 10 * c + t) as f64);
        let f = AmplitudeFeatures::bin_mean(2)
            .unwrap()
            .transform(x.view())
            .unwrap();
        assert_eq!(
            f.row(1).to_vec(),
            vec![100.5, 102.5, 104.5, 110.5, 112.5, 114.5]
        );
        let d = AmplitudeFeatures::decimate(4)
            .unwrap()
            .transform(x.view())
            .unwrap();
        assert_eq!(d.row(0).to_vec(), vec![0.0, 4.0, 10.0, 14.0]);
        // strided input (time not the last memory axis) gives the same values
        let xt = Array3::from_shape_fn((2, 6, 2), |(e, t, c)| (100 * e + 10 * c + t) as f64)
            .permuted_axes([0, 2, 1]);
        assert!(xt.index_axis(Axis(0), 0).row(0).as_slice().is_none());
        let f2 = AmplitudeFeatures::bin_mean(2)
            .unwrap()
            .transform(xt.view())
            .unwrap();
        assert_eq!(f, f2);
        assert_eq!(
            AmplitudeFeatures::for_sfreq(256.0).unwrap().n_points(205),
            20
        );
        assert_eq!(
            AmplitudeFeatures::for_sfreq(160.0).unwrap().n_points(128),
            21
        );
    }

    #[test]
    fn paper_layout_matches_the_peer_width() {
        let p = PaperFeatures::for_sfreq(256.0).unwrap();
        // 8 ch x (20 amp + 20 inst amp + 20 inst freq + 11 approx + 11 detail) = 656, as the peer
        assert_eq!(p.n_features(8, 205), 656);
        // epochs too short for a single amplitude bin are refused
        let e = Array3::<f64>::zeros((1, 1, 4));
        assert!(p.transform(e.view()).is_err());
    }

    #[test]
    fn paper_features_batch_equals_single_epochs() {
        let x = Array3::from_shape_fn((5, 3, 205), |(e, c, t)| {
            let t = t as f64 / 256.0;
            10.0 * (2.0 * std::f64::consts::PI * (3.0 + e as f64) * t + c as f64).sin()
                + 4.0 * (2.0 * std::f64::consts::PI * 11.0 * t).cos()
        });
        let p = PaperFeatures::for_sfreq(256.0).unwrap();
        let batch = p.transform(x.view()).unwrap();
        let mut ex = p.extractor(205).unwrap();
        for (i, epoch) in x.outer_iter().enumerate() {
            let mut row = vec![0.0; p.n_features(3, 205)];
            ex.epoch(epoch, &mut row).unwrap();
            assert_eq!(row, batch.row(i).to_vec());
            // one epoch at a time goes through the thread's cached extractor
            let one = p.transform(x.slice(ndarray::s![i..i + 1, .., ..])).unwrap();
            assert_eq!(one.row(0), batch.row(i));
        }
        // other settings or lengths rebuild the cached extractor
        let q = PaperFeatures::for_sfreq(160.0).unwrap();
        let short = x.slice(ndarray::s![..1, .., ..128]);
        let mut row = vec![0.0; q.n_features(3, 128)];
        q.extractor(128)
            .unwrap()
            .epoch(short.index_axis(Axis(0), 0), &mut row)
            .unwrap();
        assert_eq!(q.transform(short).unwrap().row(0).to_vec(), row);
    }
}
