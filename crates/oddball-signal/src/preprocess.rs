//! Continuous EEG → epochs, in one place: non-finite samples held, detrend, band-pass, cut,
//! reject. Training, evaluation, `oddball inspect` and the offline twin of the online epocher all
//! call [`PreprocessParams::epochs`] (or [`PreprocessParams::filter`] then [`Filtered::cut`]);
//! the online epocher streams the same band-pass and asks the same rejection rule
//! ([`EpochsParams::channel_fault`]), so both keep and drop the same epochs.
//!
//! MNE's model: `raw.filter(l_freq, h_freq)` then `Epochs(raw, events, tmin, tmax, baseline,
//! reject, flat)`. The band-pass runs either zero-phase (`sosfiltfilt`, offline, after an
//! optional detrend) or causally (one forward pass from the first sample, started in the steady
//! state of that sample: what [`crate::filter::StreamingFilter`] computes chunk by chunk).
//!
//! A NaN or infinity must never enter a recursive filter (it would poison every later sample,
//! and zero-phase filtering every earlier one too). Each is replaced by its channel's last finite
//! value before filtering ([`hold_non_finite`]), and every epoch whose window covers one is
//! dropped as [`DropReason::NonFinite`](crate::epochs::DropReason::NonFinite).

use serde::{Deserialize, Serialize};

use crate::detrend::{detrend, DetrendKind};
use crate::epochs::{DropLog, EpochsParams};
use crate::filter::ButterworthParams;
pub use crate::non_finite::{hold_non_finite, NonFinite};
use crate::{Epochs, Event, Raw, SignalError};

/// How the band-pass runs over a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Filtering {
    /// Forward–backward (`sosfiltfilt`, scipy's padding), after removing each channel's trend
    /// when `detrend` is set. Offline only: it needs the whole recording.
    ZeroPhase { detrend: Option<DetrendKind> },
    /// One forward pass from the first sample, each channel started in the steady state of its
    /// first sample (scipy's `sosfilt` with `zi = sosfilt_zi(sos) · x[0]`); no detrend. Equal,
    /// bit for bit, to the streaming filter started the same way, whatever the chunking.
    Causal,
}

/// Settings of the whole path from continuous EEG to epochs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreprocessParams {
    /// Band-pass applied to the recording before epoching.
    pub band: ButterworthParams,
    pub filtering: Filtering,
    /// The window (`tmin`, `tmax`, s), baseline, rejection (`reject`, µV) and flat-channel
    /// threshold (`flat`, µV).
    pub epochs: EpochsParams,
}

/// A band-passed recording, with where its input was non-finite.
#[derive(Debug, Clone, PartialEq)]
pub struct Filtered {
    /// Band-passed µV `(n_channels, n_times)`, the events of the input.
    pub raw: Raw,
    /// Samples that were NaN or ±∞ before they were held at their channel's last finite value.
    pub non_finite: NonFinite,
}

impl PreprocessParams {
    /// Band-passes `raw` (see [`Filtering`]), its non-finite samples held first.
    pub fn filter(&self, raw: &Raw) -> Result<Filtered, SignalError> {
        self.filter_owned(raw.clone())
    }

    /// [`Self::filter`] in the recording's own memory (no copy of the samples).
    pub fn filter_owned(&self, mut raw: Raw) -> Result<Filtered, SignalError> {
        let filter = self.band.design(raw.sfreq())?;
        let mut hold = vec![0.0; raw.n_channels()];
        let non_finite = hold_non_finite(raw.data_mut(), &mut hold);
        match self.filtering {
            Filtering::Causal => {
                let filtered = filter.sosfilt(raw.data().view(), true);
                raw.data_mut().assign(&filtered);
            }
            Filtering::ZeroPhase { detrend: kind } => {
                if let Some(kind) = kind {
                    detrend(raw.data_mut(), kind);
                }
                filter.apply_raw(&mut raw)?;
            }
        }
        Ok(Filtered { raw, non_finite })
    }

    /// The epochs of every event of `raw`, and those dropped with the reason.
    pub fn epochs(&self, raw: &Raw) -> Result<(Epochs, DropLog), SignalError> {
        self.epochs_at(raw, raw.events().as_slice())
    }

    /// [`Self::epochs`] of a recording no longer needed: filtered in place and kept, the epochs
    /// windows into it ([`Epochs`]' windows: the same samples, never copied), so the memory is
    /// the recording once, however much the epochs overlap.
    pub fn epochs_owned(&self, raw: Raw) -> Result<(Epochs, DropLog), SignalError> {
        self.epochs.validate(raw.sfreq())?;
        let events = raw.events().as_slice().to_vec();
        self.filter_owned(raw)?.into_windows(&self.epochs, &events)
    }

    /// The epochs of `events` (onsets on `raw`'s sample clock; they may reach past its end),
    /// and those dropped with the reason.
    pub fn epochs_at(&self, raw: &Raw, events: &[Event]) -> Result<(Epochs, DropLog), SignalError> {
        self.epochs.validate(raw.sfreq())?;
        self.filter(raw)?.cut(&self.epochs, events)
    }
}

impl Filtered {
    /// Cuts epochs of `events` with `params`; an epoch over a sample that was non-finite is
    /// dropped.
    pub fn cut(
        &self,
        params: &EpochsParams,
        events: &[Event],
    ) -> Result<(Epochs, DropLog), SignalError> {
        params.cut_marked(&self.raw, events, Some(&self.non_finite))
    }

    /// [`Self::cut`] as windows into the filtered recording, which the epochs keep.
    pub fn into_windows(
        self,
        params: &EpochsParams,
        events: &[Event],
    ) -> Result<(Epochs, DropLog), SignalError> {
        params.cut_windows(self.raw, events, Some(&self.non_finite))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::epochs::{DropReason, Reject};
    use crate::filter::Band;
    use crate::Events;
    use ndarray::Array2;

    fn raw(data: Array2<f64>, onsets: &[usize]) -> Raw {
        let names = (0..data.nrows()).map(|c| format!("E{c}")).collect();
        let events = Events::new(onsets.iter().map(|&t| Event::new(t, 1)).collect());
        Raw::new(data, 100.0, names, events).unwrap()
    }

    fn wave(n_ch: usize, n: usize) -> Array2<f64> {
        Array2::from_shape_fn((n_ch, n), |(c, t)| {
            let t = t as f64 / 100.0;
            20.0 * (2.0 * std::f64::consts::PI * 4.0 * t + c as f64).sin() + 30.0
        })
    }

    fn params(filtering: Filtering) -> PreprocessParams {
        PreprocessParams {
            band: ButterworthParams {
                order: 4,
                band: Band::Bandpass {
                    l_freq: 1.0,
                    h_freq: 15.0,
                },
            },
            filtering,
            epochs: EpochsParams::new(0.0, 0.6)
                .with_reject(Reject::PeakToPeak(150.0))
                .with_flat(1e-3),
        }
    }

    /// A NaN drops only the epochs over it, offline zero-phase as causal, instead of poisoning
    /// every epoch of its channel; a flat channel drops every epoch; a blink the epochs over it.
    #[test]
    fn nan_flat_and_blinks_drop_exactly_their_epochs() {
        for filtering in [
            Filtering::Causal,
            Filtering::ZeroPhase {
                detrend: Some(DetrendKind::Constant),
            },
        ] {
            let mut d = wave(2, 3000);
            d[[1, 1000]] = f64::NAN;
            let (ep, log) = params(filtering)
                .epochs(&raw(d, &[300, 960, 1500, 2990]))
                .unwrap();
            let onsets: Vec<usize> = ep.events().iter().map(|e| e.onset).collect();
            assert_eq!(onsets, [300, 1500], "{filtering:?}");
            assert!(matches!(
                &log.dropped[0].reason,
                DropReason::NonFinite { channel, sample: 40 } if channel == "E1"
            ));
            assert!(matches!(
                log.dropped[1].reason,
                DropReason::OutOfBounds { .. }
            ));
            assert!(ep.data().iter().all(|v| v.is_finite()));

            let mut d = wave(2, 3000);
            d.row_mut(0).fill(7.0);
            let (ep, log) = params(filtering).epochs(&raw(d, &[300, 1500])).unwrap();
            assert_eq!(ep.n_epochs(), 0);
            assert_eq!(log.counts()["flat"], 2, "{log:?}");

            let mut d = wave(2, 3000);
            d[[0, 1520]] += 5000.0;
            let (ep, log) = params(filtering).epochs(&raw(d, &[300, 1500])).unwrap();
            assert_eq!(ep.n_epochs(), 1);
            assert_eq!(log.counts()["peak-to-peak"], 1);
        }
    }

    #[test]
    fn causal_filtering_is_one_forward_pass_and_zero_phase_detrends_first() {
        let d = wave(3, 1200);
        let r = raw(d.clone(), &[]);
        let f = params(Filtering::Causal).filter(&r).unwrap();
        let sos = params(Filtering::Causal).band.design(100.0).unwrap();
        assert_eq!(f.raw.data(), &sos.sosfilt(d.view(), true));
        let z = params(Filtering::ZeroPhase {
            detrend: Some(DetrendKind::Linear),
        })
        .filter(&r)
        .unwrap();
        let mut expected = d.clone();
        detrend(expected.view_mut(), DetrendKind::Linear);
        assert_eq!(z.raw.data(), &sos.sosfiltfilt(expected.view()).unwrap());
        assert!(f.non_finite.is_empty());
    }

    #[test]
    fn invalid_thresholds_are_refused() {
        let mut p = params(Filtering::Causal);
        p.epochs.flat = Some(f64::NAN);
        assert!(matches!(
            p.epochs(&raw(wave(1, 500), &[10])),
            Err(SignalError::InvalidThreshold { .. })
        ));
    }
}
