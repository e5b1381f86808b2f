//! Cutting epochs around events, baseline correction, amplitude-threshold and flat-channel
//! rejection, and the averaging of repeated stimuli.
//!
//! The rejection rule ([`EpochsParams::channel_fault`]) is the one rule of the crate: offline cuts
//! ([`EpochsParams::cut`], [`crate::preprocess::PreprocessParams::epochs`]) and the online epocher
//! of `oddball-session` both ask it, so they keep and drop the same epochs.
//!
//! Sample convention (MNE's): an epoch covers the samples `onset + round(tmin·sfreq)` through
//! `onset + round(tmax·sfreq)`, both included, so `[0, 0.6]` s at 500 Hz is 301 samples; or, with
//! [`EpochsParams::with_end_exclusive`], up to but not including the last (numpy's
//! `x[onset : onset + round(tmax·sfreq)]` when `tmin` is 0: 0–0.8 s at 256 Hz is 205 samples).

use std::collections::BTreeMap;
use std::fmt;

use ndarray::{s, Array2, Array3, ArrayView1, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use crate::non_finite::NonFinite;
use crate::{Epochs, Event, Raw, SignalError};

/// When an epoch is dropped for its amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Reject {
    /// Any channel whose max − min exceeds this many µV (MNE's `reject=dict(eeg=...)`).
    PeakToPeak(f64),
    /// Any sample whose absolute value exceeds this many µV (the paper's amplitude threshold).
    Absolute(f64),
}

impl Reject {
    fn threshold(&self) -> f64 {
        match *self {
            Reject::PeakToPeak(v) | Reject::Absolute(v) => v,
        }
    }
}

/// Settings for cutting epochs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpochsParams {
    /// Start of the window relative to the onset, seconds.
    pub tmin: f64,
    /// End of the window relative to the onset, seconds (included unless `end_exclusive`).
    pub tmax: f64,
    /// The window stops one sample before `tmax` (a half-open window, as numpy slices).
    #[serde(default)]
    pub end_exclusive: bool,
    /// Window whose per-channel mean is subtracted, seconds; `None` for no baseline correction.
    pub baseline: Option<(f64, f64)>,
    /// Amplitude rejection, applied after baseline correction.
    pub reject: Option<Reject>,
    /// A channel whose peak-to-peak amplitude in the epoch is below this many µV is flat (a
    /// disconnected electrode, or one stuck at a rail) and drops the epoch (MNE's
    /// `flat=dict(eeg=...)`). Absent in settings saved before it existed: no flat rejection.
    #[serde(default)]
    pub flat: Option<f64>,
}

impl EpochsParams {
    /// A window with no baseline and no rejection.
    pub fn new(tmin: f64, tmax: f64) -> Self {
        Self {
            tmin,
            tmax,
            end_exclusive: false,
            baseline: None,
            reject: None,
            flat: None,
        }
    }

    /// The same window without its last sample.
    pub fn with_end_exclusive(mut self) -> Self {
        self.end_exclusive = true;
        self
    }

    /// The paper's epochs: 600 ms from the onset.
    pub fn paper() -> Self {
        Self::new(0.0, 0.6)
    }

    pub fn with_baseline(mut self, bmin: f64, bmax: f64) -> Self {
        self.baseline = Some((bmin, bmax));
        self
    }

    pub fn with_reject(mut self, reject: Reject) -> Self {
        self.reject = Some(reject);
        self
    }

    /// Drops epochs with a channel flatter than `flat_uv` peak-to-peak.
    pub fn with_flat(mut self, flat_uv: f64) -> Self {
        self.flat = Some(flat_uv);
        self
    }

    /// Checks the window for `sfreq` and the thresholds: the first and last sample offsets, as
    /// [`Self::offsets`].
    pub fn validate(&self, sfreq: f64) -> Result<(i64, i64), SignalError> {
        let offsets = self.offsets(sfreq)?;
        for t in self
            .reject
            .map(|r| r.threshold())
            .into_iter()
            .chain(self.flat)
        {
            if !(t.is_finite() && t > 0.0) {
                return Err(SignalError::InvalidThreshold { threshold: t });
            }
        }
        Ok(offsets)
    }

    /// The rejection rule for one channel of an epoch (after baseline correction): why it drops
    /// the epoch, if it does. In order: a non-finite sample (in `row`, or at `non_finite_at`,
    /// the first sample of the window where the channel's input was non-finite before it was
    /// replaced for filtering, see [`crate::non_finite::hold_non_finite`]); a flat channel
    /// (peak-to-peak under [`Self::flat`]); the amplitude threshold ([`Self::reject`]).
    pub fn channel_fault(
        &self,
        row: ArrayView1<f64>,
        non_finite_at: Option<usize>,
    ) -> Option<ChannelFault> {
        if let Some(sample) = non_finite_at.or_else(|| row.iter().position(|v| !v.is_finite())) {
            return Some(ChannelFault::NonFinite { sample });
        }
        let (lo, hi) = row
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let ptp = hi - lo;
        if let Some(threshold) = self.flat {
            if ptp < threshold {
                return Some(ChannelFault::Flat {
                    value: ptp,
                    threshold,
                });
            }
        }
        match self.reject {
            None => None,
            Some(Reject::Absolute(threshold)) => {
                let peak = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                (peak > threshold).then_some(ChannelFault::Absolute {
                    value: peak,
                    threshold,
                })
            }
            Some(Reject::PeakToPeak(threshold)) => {
                (ptp > threshold).then_some(ChannelFault::PeakToPeak {
                    value: ptp,
                    threshold,
                })
            }
        }
    }

    /// The rejection rule for a whole epoch `(n_channels, n_times)`: the first channel at fault
    /// and why; `non_finite_at(c)` as in [`Self::channel_fault`].
    pub fn drop_reason(
        &self,
        epoch: ArrayView2<f64>,
        ch_names: &[String],
        non_finite_at: impl Fn(usize) -> Option<usize>,
    ) -> Option<DropReason> {
        epoch.rows().into_iter().enumerate().find_map(|(c, row)| {
            self.channel_fault(row, non_finite_at(c))
                .map(|fault| fault.on_channel(&ch_names[c]))
        })
    }

    /// First and last sample offsets relative to the onset (both included).
    pub fn offsets(&self, sfreq: f64) -> Result<(i64, i64), SignalError> {
        let invalid = || SignalError::InvalidWindow {
            tmin: self.tmin,
            tmax: self.tmax,
        };
        let reach = crate::MAX_WINDOW_S;
        if !(self.tmin.is_finite() && self.tmax.is_finite() && self.tmin <= self.tmax)
            || self.tmin.abs() > reach
            || self.tmax.abs() > reach
        {
            return Err(invalid());
        }
        crate::check_sfreq(sfreq)?;
        let first = (self.tmin * sfreq).round() as i64;
        let last = (self.tmax * sfreq).round() as i64 - i64::from(self.end_exclusive);
        if last < first {
            return Err(invalid());
        }
        Ok((first, last))
    }

    /// Cuts an epoch for every event of `raw`.
    pub fn cut(&self, raw: &Raw) -> Result<(Epochs, DropLog), SignalError> {
        self.cut_events(raw, raw.events().as_slice())
    }

    /// Cuts an epoch for each of `events` (onsets on `raw`'s sample clock). Epochs reaching past
    /// either end of the recording, holding a non-finite sample, with a flat channel or over the
    /// rejection threshold are left out and listed in the [`DropLog`].
    pub fn cut_events(
        &self,
        raw: &Raw,
        events: &[Event],
    ) -> Result<(Epochs, DropLog), SignalError> {
        self.cut_marked(raw, events, None)
    }

    /// [`Self::cut_events`] on a recording whose non-finite samples were replaced before
    /// filtering: an epoch over one of `non_finite` is dropped as if it still held it.
    pub(crate) fn cut_marked(
        &self,
        raw: &Raw,
        events: &[Event],
        non_finite: Option<&NonFinite>,
    ) -> Result<(Epochs, DropLog), SignalError> {
        let (cut, log) = self.scan(raw, events, non_finite, true)?;
        let samples = cut.samples.expect("scanned with a copy");
        let data = Array3::from_shape_vec((cut.kept.len(), raw.n_channels(), cut.n_times), samples)
            .expect("buffer holds exactly the kept epochs");
        Ok((
            Epochs::new(
                data,
                raw.sfreq(),
                cut.tmin,
                raw.ch_names().to_vec(),
                cut.kept,
            )?,
            log,
        ))
    }

    /// [`Self::cut_marked`] as windows into `raw`, which the epochs keep (no samples copied):
    /// the same epochs, dropped by the same rule, with the same samples.
    pub(crate) fn cut_windows(
        &self,
        raw: Raw,
        events: &[Event],
        non_finite: Option<&NonFinite>,
    ) -> Result<(Epochs, DropLog), SignalError> {
        let (cut, log) = self.scan(&raw, events, non_finite, false)?;
        let baseline = self.baseline.map(|_| {
            Array2::from_shape_vec((cut.kept.len(), raw.n_channels()), cut.means)
                .expect("one baseline mean per kept epoch and channel")
        });
        Ok((
            Epochs::windows(raw, cut.starts, cut.n_times, baseline, cut.tmin, cut.kept)?,
            log,
        ))
    }

    /// The one pass over `events` both cuts make: which epochs are kept (and why the others
    /// are not), each kept epoch's first sample and baseline means, and with `copy` their
    /// samples.
    fn scan(
        &self,
        raw: &Raw,
        events: &[Event],
        non_finite: Option<&NonFinite>,
        copy: bool,
    ) -> Result<(Cut, DropLog), SignalError> {
        let sfreq = raw.sfreq();
        let (first, last) = self.validate(sfreq)?;
        let n_times = (last - first + 1) as usize;
        let baseline = match self.baseline {
            None => None,
            Some((bmin, bmax)) => {
                let lo = ((bmin * sfreq).round() as i64 - first).max(0);
                let hi = (bmax * sfreq).round() as i64 - first;
                if !(bmin.is_finite() && bmax.is_finite() && bmin <= bmax)
                    || hi < 0
                    || lo >= n_times as i64
                {
                    return Err(SignalError::InvalidBaseline {
                        bmin,
                        bmax,
                        tmin: self.tmin,
                        tmax: self.tmax,
                    });
                }
                Some((lo as usize, (hi as usize).min(n_times - 1)))
            }
        };
        let data = raw.data();
        let n_channels = raw.n_channels();
        let total = raw.n_times() as i64;
        // Sized by the data present: no epoch longer than the recording is ever allocated.
        let fits = n_times <= raw.n_times();
        let in_bounds = |ev: &Event| {
            let start = ev.onset as i64 + first;
            fits && start >= 0 && ev.onset as i64 + last < total
        };
        let n_fit = events.iter().filter(|e| in_bounds(e)).count();
        // Epochs overlap when events come faster than the window; past MAX_EPOCH_OVERLAP
        // times the recording (an event on every sample, say) they are refused instead of
        // allocated: memory stays linear in the data.
        let budget = (crate::MAX_EPOCH_OVERLAP * raw.n_times()).max(1 << 20);
        if n_fit.saturating_mul(n_times) > budget {
            return Err(SignalError::TooManyEpochs {
                n_events: n_fit,
                n_times,
                recording: raw.n_times(),
                max_overlap: crate::MAX_EPOCH_OVERLAP,
            });
        }
        let mut kept = Vec::with_capacity(n_fit);
        let mut samples: Option<Vec<f64>> =
            copy.then(|| Vec::with_capacity(n_fit * n_channels * n_times));
        let mut starts = Vec::with_capacity(n_fit);
        let mut means: Vec<f64> = Vec::new();
        let mut epoch_means = vec![0.0; n_channels];
        let mut log = DropLog::default();
        let mut epoch = Array2::<f64>::zeros(if fits { (n_channels, n_times) } else { (0, 0) });
        for (index, ev) in events.iter().enumerate() {
            let start = ev.onset as i64 + first;
            let end = ev.onset as i64 + last;
            if !fits || start < 0 || end >= total {
                log.dropped.push(Dropped {
                    index,
                    event: ev.clone(),
                    reason: DropReason::OutOfBounds {
                        first_sample: start,
                        last_sample: end,
                        n_times: raw.n_times(),
                    },
                });
                continue;
            }
            epoch.assign(&data.slice(s![.., start as usize..=end as usize]));
            if let Some((lo, hi)) = baseline {
                for (mut row, em) in epoch.rows_mut().into_iter().zip(&mut epoch_means) {
                    let m = row.slice(s![lo..=hi]).mean().unwrap_or(0.0);
                    row.mapv_inplace(|v| v - m);
                    *em = m;
                }
            }
            let reason = self.drop_reason(epoch.view(), raw.ch_names(), |c| {
                non_finite.and_then(|m| m.first_in(c, start as usize, n_times))
            });
            if let Some(reason) = reason {
                log.dropped.push(Dropped {
                    index,
                    event: ev.clone(),
                    reason,
                });
                continue;
            }
            if let Some(out) = &mut samples {
                out.extend(epoch.iter().copied());
            }
            starts.push(start as usize);
            if baseline.is_some() {
                means.extend_from_slice(&epoch_means);
            }
            kept.push(ev.clone());
        }
        Ok((
            Cut {
                kept,
                samples,
                starts,
                means,
                n_times,
                tmin: first as f64 / sfreq,
            },
            log,
        ))
    }
}

/// What [`EpochsParams::scan`] found: the kept epochs' events and windows, and their samples
/// when copied.
struct Cut {
    kept: Vec<Event>,
    /// The kept epochs' samples, `(n_kept, n_channels, n_times)` in order (when copied).
    samples: Option<Vec<f64>>,
    /// Each kept epoch's first sample.
    starts: Vec<usize>,
    /// Each kept epoch's baseline mean per channel, `(n_kept, n_channels)` in order (empty
    /// without baseline correction).
    means: Vec<f64>,
    n_times: usize,
    tmin: f64,
}

/// Why one channel drops an epoch (see [`EpochsParams::channel_fault`]); values in µV.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChannelFault {
    /// NaN or ±∞ at `sample` (index within the epoch).
    NonFinite { sample: usize },
    /// Peak-to-peak under the flat threshold.
    Flat { value: f64, threshold: f64 },
    /// Largest |amplitude| over the threshold.
    Absolute { value: f64, threshold: f64 },
    /// Peak-to-peak over the threshold.
    PeakToPeak { value: f64, threshold: f64 },
}

impl ChannelFault {
    /// The drop reason naming the channel.
    pub fn on_channel(self, channel: &str) -> DropReason {
        let channel = channel.to_string();
        match self {
            ChannelFault::NonFinite { sample } => DropReason::NonFinite { channel, sample },
            ChannelFault::Flat { value, threshold } => DropReason::Flat {
                channel,
                value,
                threshold,
            },
            ChannelFault::Absolute { value, threshold } => DropReason::Absolute {
                channel,
                value,
                threshold,
            },
            ChannelFault::PeakToPeak { value, threshold } => DropReason::PeakToPeak {
                channel,
                value,
                threshold,
            },
        }
    }
}

/// Why an epoch was dropped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum DropReason {
    /// The window reaches outside the recording (sample indices of the window's ends).
    OutOfBounds {
        first_sample: i64,
        last_sample: i64,
        n_times: usize,
    },
    /// A channel held NaN or ±∞ at `sample` (index within the epoch).
    NonFinite { channel: String, sample: usize },
    /// A channel's largest |amplitude| passed the threshold (µV).
    Absolute {
        channel: String,
        value: f64,
        threshold: f64,
    },
    /// A channel's peak-to-peak amplitude passed the threshold (µV).
    PeakToPeak {
        channel: String,
        value: f64,
        threshold: f64,
    },
    /// A channel's peak-to-peak amplitude was under the flat threshold (µV).
    Flat {
        channel: String,
        value: f64,
        threshold: f64,
    },
}

impl DropReason {
    /// The kind of reason, as [`DropLog::counts`] names it.
    pub fn kind(&self) -> &'static str {
        match self {
            DropReason::OutOfBounds { .. } => "out of bounds",
            DropReason::NonFinite { .. } => "non-finite",
            DropReason::Absolute { .. } => "absolute",
            DropReason::PeakToPeak { .. } => "peak-to-peak",
            DropReason::Flat { .. } => "flat",
        }
    }
}

impl fmt::Display for DropReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DropReason::OutOfBounds {
                first_sample,
                last_sample,
                n_times,
            } => write!(
                f,
                "window samples {first_sample}..={last_sample} outside the recording (0..{n_times})"
            ),
            DropReason::NonFinite { channel, sample } => {
                write!(f, "{channel}: non-finite value at epoch sample {sample}")
            }
            DropReason::Absolute {
                channel,
                value,
                threshold,
            } => write!(f, "{channel}: |amplitude| {value:.1} µV > {threshold} µV"),
            DropReason::PeakToPeak {
                channel,
                value,
                threshold,
            } => write!(f, "{channel}: peak-to-peak {value:.1} µV > {threshold} µV"),
            DropReason::Flat {
                channel,
                value,
                threshold,
            } => write!(
                f,
                "{channel}: flat, peak-to-peak {value:.2e} µV < {threshold} µV"
            ),
        }
    }
}

/// One dropped epoch: its position in the events given, the event, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dropped {
    pub index: usize,
    pub event: Event,
    pub reason: DropReason,
}

/// Every epoch left out by [`EpochsParams::cut_events`], in event order.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DropLog {
    pub dropped: Vec<Dropped>,
}

impl DropLog {
    pub fn len(&self) -> usize {
        self.dropped.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dropped.is_empty()
    }

    /// Counts per kind of reason: `out of bounds`, `non-finite`, `absolute`, `peak-to-peak`,
    /// `flat`.
    pub fn counts(&self) -> BTreeMap<&'static str, usize> {
        let mut m = BTreeMap::new();
        for d in &self.dropped {
            *m.entry(d.reason.kind()).or_insert(0) += 1;
        }
        m
    }

    /// Why epochs were dropped, for people: each kind's count and its first case, e.g.
    /// `240 non-finite (first: event 0 at sample 300: channel "Cz" is NaN or infinite …)`.
    pub fn summary(&self) -> String {
        let counts = self.counts();
        counts
            .iter()
            .map(|(kind, n)| {
                let first = self
                    .dropped
                    .iter()
                    .find(|d| d.reason.kind() == *kind)
                    .map(|d| {
                        format!(
                            " (first: event {} at sample {}: {})",
                            d.index, d.event.onset, d.reason
                        )
                    })
                    .unwrap_or_default();
                format!("{n} {kind}{first}")
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The average of the epochs of one stimulus code.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evoked {
    pub code: u32,
    /// `Some` when every averaged epoch agreed on the target flag.
    pub target: Option<bool>,
    /// How many epochs were averaged.
    pub nave: usize,
    /// Mean in µV, `(n_channels, n_times)`.
    pub data: Array2<f64>,
}

fn common_target(events: &[&Event]) -> Option<bool> {
    let first = events.first()?.target;
    events.iter().all(|e| e.target == first).then_some(first)?
}

/// Epoch indices of each stimulus code, in epoch order.
fn indices_by_code(epochs: &Epochs) -> BTreeMap<u32, Vec<usize>> {
    let mut by_code: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (i, e) in epochs.events().iter().enumerate() {
        by_code.entry(e.code).or_default().push(i);
    }
    by_code
}

/// The mean of all epochs of each stimulus code, in code order.
pub fn average_by_code(epochs: &Epochs) -> Vec<Evoked> {
    indices_by_code(epochs)
        .into_iter()
        .map(|(code, idx)| {
            let evs: Vec<&Event> = idx.iter().map(|&i| &epochs.events()[i]).collect();
            Evoked {
                code,
                target: common_target(&evs),
                nave: idx.len(),
                data: epochs
                    .gather(&idx, 1)
                    .mean_axis(Axis(0))
                    .expect("at least one epoch per code"),
            }
        })
        .collect()
}

/// Averages the repetitions of each stimulus code in consecutive groups of `n_reps`, as the paper
/// averages the 5 flashes of each bulb in a decision. Within each code, epochs are taken in their
/// order; a final group with fewer than `n_reps` epochs is left out. The averaged epoch carries
/// the event of its group's first epoch, with the target flag kept only if the group agrees.
pub fn average_repetitions(epochs: &Epochs, n_reps: usize) -> Result<Epochs, SignalError> {
    if n_reps == 0 {
        return Err(SignalError::NoEpochs);
    }
    // Groups ordered by the position of their first epoch, so the output keeps time order.
    let mut groups: Vec<Vec<usize>> = indices_by_code(epochs)
        .into_values()
        .flat_map(|idx| {
            idx.chunks_exact(n_reps)
                .map(|c| c.to_vec())
                .collect::<Vec<_>>()
        })
        .collect();
    groups.sort_by_key(|g| g[0]);
    let (_, n_channels, n_times) = epochs.dim();
    let mut data = Array3::zeros((groups.len(), n_channels, n_times));
    let mut events = Vec::with_capacity(groups.len());
    for (g, idx) in groups.iter().enumerate() {
        let mean = epochs
            .gather(idx, 1)
            .mean_axis(Axis(0))
            .expect("non-empty group");
        data.index_axis_mut(Axis(0), g).assign(&mean);
        let evs: Vec<&Event> = idx.iter().map(|&i| &epochs.events()[i]).collect();
        let mut ev = evs[0].clone();
        ev.target = common_target(&evs);
        events.push(ev);
    }
    Epochs::new(
        data,
        epochs.sfreq(),
        epochs.tmin(),
        epochs.ch_names().to_vec(),
        events,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Events;

    fn ramp_raw() -> Raw {
        let data = Array2::from_shape_fn((2, 1000), |(c, t)| (c * 1000 + t) as f64);
        let events = Events::new(vec![
            Event::new(5, 1).with_target(true),
            Event::new(100, 2).with_target(false),
            Event::new(995, 1).with_target(true),
        ]);
        Raw::new(data, 100.0, vec!["Cz".into(), "Pz".into()], events).unwrap()
    }

    #[test]
    fn windows_are_inclusive_and_out_of_bounds_epochs_are_logged() {
        let raw = ramp_raw();
        let (ep, log) = EpochsParams::new(-0.05, 0.1).cut(&raw).unwrap();
        assert_eq!(ep.n_epochs(), 2);
        assert_eq!(ep.n_times(), 16);
        assert!((ep.tmin() + 0.05).abs() < 1e-12);
        assert_eq!(ep.data()[[0, 0, 0]], 0.0);
        assert_eq!(ep.data()[[1, 1, 15]], (1000 + 110) as f64);
        assert_eq!(log.len(), 1);
        assert_eq!(log.dropped[0].index, 2);
        assert!(matches!(
            log.dropped[0].reason,
            DropReason::OutOfBounds { .. }
        ));
    }

    #[test]
    fn an_end_exclusive_window_drops_its_last_sample() {
        let raw = ramp_raw();
        let half_open = EpochsParams::new(-0.05, 0.1).with_end_exclusive();
        let (ep, _) = half_open.cut(&raw).unwrap();
        assert_eq!(ep.n_times(), 15);
        assert_eq!(ep.data()[[1, 1, 14]], (1000 + 109) as f64);
        // a window of one sample has nothing left without its end
        assert!(EpochsParams::new(0.1, 0.1).offsets(100.0).is_ok());
        assert!(matches!(
            EpochsParams::new(0.1, 0.1)
                .with_end_exclusive()
                .offsets(100.0),
            Err(SignalError::InvalidWindow { .. })
        ));
    }

    #[test]
    fn baseline_and_threshold() {
        let raw = ramp_raw();
        let (ep, _) = EpochsParams::new(0.0, 0.1)
            .with_baseline(0.0, 0.0)
            .cut(&raw)
            .unwrap();
        assert_eq!(ep.data()[[1, 0, 10]], 10.0);
        let (ep, log) = EpochsParams::new(0.0, 0.1)
            .with_reject(Reject::Absolute(500.0))
            .cut(&raw)
            .unwrap();
        // Every epoch has channel Pz above 1000 µV.
        assert_eq!(ep.n_epochs(), 0);
        assert!(log
            .dropped
            .iter()
            .any(|d| matches!(&d.reason, DropReason::Absolute { channel, .. } if channel == "Pz")));
        let (ep, _) = EpochsParams::new(0.0, 0.1)
            .with_reject(Reject::PeakToPeak(10.5))
            .cut(&raw)
            .unwrap();
        assert_eq!(
            ep.n_epochs(),
            2,
            "a 10 µV ramp passes a 10.5 µV peak-to-peak limit"
        );
        let (ep, _) = EpochsParams::new(0.0, 0.1)
            .with_reject(Reject::PeakToPeak(9.5))
            .cut(&raw)
            .unwrap();
        assert_eq!(ep.n_epochs(), 0);
    }

    #[test]
    fn repetitions_average_per_code_in_groups() {
        let n = 7;
        let data = Array3::from_shape_fn((n, 1, 3), |(e, _, t)| (e * 10 + t) as f64);
        let events = (0..n)
            .map(|i| Event::new(i * 10, (i % 2) as u32 + 1).with_target(i % 2 == 0))
            .collect();
        let ep = Epochs::new(data, 100.0, 0.0, vec!["Pz".into()], events).unwrap();
        // code 1: epochs 0,2,4,6 -> groups [0,2],[4,6]; code 2: epochs 1,3,5 -> [1,3]
        let avg = average_repetitions(&ep, 2).unwrap();
        assert_eq!(avg.n_epochs(), 3);
        let codes: Vec<u32> = avg.events().iter().map(|e| e.code).collect();
        assert_eq!(codes, vec![1, 2, 1]);
        assert_eq!(avg.data()[[0, 0, 0]], 10.0);
        assert_eq!(avg.data()[[1, 0, 1]], 21.0);
        assert_eq!(avg.events()[2].target, Some(true));
        let by_code = average_by_code(&ep);
        assert_eq!(by_code.len(), 2);
        assert_eq!(by_code[0].nave, 4);
        assert_eq!(by_code[1].data[[0, 0]], 30.0);
    }
}
