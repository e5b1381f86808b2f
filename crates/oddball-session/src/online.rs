//! Causal epoching of streamed samples: the streaming band-pass, a buffer, and the markers
//! still waiting for their epoch.
//!
//! Samples arrive in chunks of any size; markers (flash onsets on the same sample clock) may
//! arrive before or after their onset's samples, as long as the samples of their epoch are
//! still buffered. As soon as the last sample of an epoch (`tmax` after its onset) has arrived,
//! the epoch is handed out. Because [`StreamingFilter`] equals one offline causal pass over the
//! whole recording, the epochs equal those [`offline_epochs`] cuts from the saved recording, bit
//! for bit; both hold non-finite samples the same way and judge an epoch by the one rejection
//! rule, [`EpochsParams::channel_fault`] (the offline cut is
//! [`oddball_signal::preprocess::PreprocessParams::epochs`], the one preprocessing path of
//! training and evaluation).

use std::collections::VecDeque;

use ndarray::{s, Array2, ArrayView2};
use oddball_decode::pipeline::Preprocess;
use oddball_signal::epochs::{ChannelFault, DropReason, EpochsParams};
use oddball_signal::filter::{StreamInit, StreamingFilter};
use oddball_signal::preprocess::{hold_non_finite, Filtering, PreprocessParams};
use oddball_signal::{Event, Raw};

use crate::SessionError;

/// A stimulus onset on the stream's sample clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marker {
    /// Onset, samples from the first sample of the stream.
    pub onset: u64,
    pub code: u32,
    /// The caller's reference (e.g. an index into its flash list).
    pub tag: usize,
}

/// An epoch whose samples have all arrived.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadyEpoch {
    pub marker: Marker,
    /// Band-passed samples `(n_channels, n_times)`, µV.
    pub data: Array2<f64>,
    /// Passed the rejection rule: no NaN or infinity in its input, no flat channel, none over
    /// the amplitude threshold.
    pub accepted: bool,
}

/// Why epochs were rejected, counted for one channel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ChannelFaults {
    /// The channel held NaN or infinite samples in the epoch.
    pub non_finite: u64,
    /// Flat: peak-to-peak under [`oddball_decode::pipeline::FLAT_UV`] (disconnected, or stuck at
    /// a rail: saturated).
    pub flat: u64,
    /// Peak-to-peak over the rejection threshold (blinks, movement, a railing amplifier).
    pub over_threshold: u64,
}

impl ChannelFaults {
    pub fn total(&self) -> u64 {
        self.non_finite + self.flat + self.over_threshold
    }
}

/// Which channels of a sample were non-finite (up to 128 channels; more are folded).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct ChannelMask(u128);

impl std::ops::Index<usize> for ChannelMask {
    type Output = bool;
    fn index(&self, c: usize) -> &bool {
        if self.0 >> (c % 128) & 1 == 1 {
            &true
        } else {
            &false
        }
    }
}

/// Streaming filter + buffer + pending markers.
#[derive(Debug)]
pub struct OnlineEpocher {
    filter: StreamingFilter,
    /// The window and the rejection rule.
    epochs: EpochsParams,
    /// Epoch window: first sample offset from the onset, and length.
    first: i64,
    n_times: usize,
    n_channels: usize,
    /// Filtered samples, per channel, starting at absolute sample `buf_start`.
    buf: Vec<Vec<f64>>,
    /// Per buffered sample: some channel was NaN or infinite there (held at its last value).
    bad: Vec<bool>,
    /// Per buffered sample, per channel: that channel was NaN or infinite (only kept while some
    /// channel is bad; empty rows otherwise would cost memory, so a bitmask per sample).
    bad_channel: Vec<ChannelMask>,
    faults: Vec<ChannelFaults>,
    /// Last finite value per channel (what a non-finite sample is replaced with).
    hold: Vec<f64>,
    /// Non-finite samples seen, per channel.
    pub non_finite: Vec<u64>,
    /// Markers ignored because the same one was already waiting.
    pub duplicate_markers: u64,
    buf_start: u64,
    received: u64,
    /// Samples kept behind the newest one even when no marker waits (late markers).
    keep: u64,
    pending: VecDeque<Marker>,
}

impl OnlineEpocher {
    /// An epocher for `n_channels` at `sfreq` Hz with the causal band-pass of `pre`.
    pub fn new(pre: &Preprocess, sfreq: f64, n_channels: usize) -> Result<Self, SessionError> {
        let (params, first, n_times) = causal(pre, sfreq)?;
        let filter = params.band.design(sfreq)?;
        Ok(Self {
            filter: StreamingFilter::new(filter, n_channels, StreamInit::Steady),
            epochs: params.epochs,
            first,
            n_times,
            n_channels,
            buf: vec![Vec::new(); n_channels],
            bad: Vec::new(),
            bad_channel: Vec::new(),
            faults: vec![ChannelFaults::default(); n_channels],
            hold: vec![0.0; n_channels],
            non_finite: vec![0; n_channels],
            duplicate_markers: 0,
            buf_start: 0,
            received: 0,
            keep: (2.0 * sfreq).ceil() as u64 + n_times as u64,
            pending: VecDeque::new(),
        })
    }

    /// Samples received so far.
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Samples per epoch.
    pub fn n_times(&self) -> usize {
        self.n_times
    }

    /// The first sample after `onset` at which its epoch is complete (exclusive end).
    pub fn epoch_end(&self, onset: u64) -> i64 {
        onset as i64 + self.first + self.n_times as i64
    }

    /// Whether the samples of an epoch at `onset` are still buffered (or still to come).
    pub fn is_kept(&self, onset: u64) -> bool {
        onset as i64 + self.first >= self.buf_start as i64
    }

    /// Registers a marker. Refused when its epoch starts before the first buffered sample or
    /// before the stream's start. A marker already waiting with the same onset and code (a
    /// marker delivered twice) is ignored: it returns `Ok(false)`.
    pub fn push_marker(&mut self, marker: Marker) -> Result<bool, SessionError> {
        if !self.is_kept(marker.onset) {
            return Err(SessionError::MarkerTooLate {
                onset: marker.onset,
                oldest_kept: self.buf_start,
            });
        }
        if self
            .pending
            .iter()
            .any(|m| m.onset == marker.onset && m.code == marker.code)
        {
            self.duplicate_markers += 1;
            return Ok(false);
        }
        // Keep pending markers ordered by onset.
        let at = self
            .pending
            .iter()
            .position(|m| m.onset > marker.onset)
            .unwrap_or(self.pending.len());
        self.pending.insert(at, marker);
        Ok(true)
    }

    /// Moves the waiting marker tagged `tag` to `onset` (a flash drawn later or earlier than
    /// planned). `Ok(false)` when no marker with that tag waits; refused like
    /// [`OnlineEpocher::push_marker`] when its epoch would start before the buffer.
    pub fn retime(&mut self, tag: usize, onset: u64) -> Result<bool, SessionError> {
        let Some(i) = self.pending.iter().position(|m| m.tag == tag) else {
            return Ok(false);
        };
        if (onset as i64 + self.first) < self.buf_start as i64 {
            return Err(SessionError::MarkerTooLate {
                onset,
                oldest_kept: self.buf_start,
            });
        }
        let mut m = self.pending.remove(i).expect("index found");
        m.onset = onset;
        let at = self
            .pending
            .iter()
            .position(|p| p.onset > onset)
            .unwrap_or(self.pending.len());
        self.pending.insert(at, m);
        Ok(true)
    }

    /// Drops the waiting marker tagged `tag` (a flash that was never drawn); `false` when none
    /// waits.
    pub fn cancel(&mut self, tag: usize) -> bool {
        match self.pending.iter().position(|m| m.tag == tag) {
            Some(i) => {
                self.pending.remove(i);
                true
            }
            None => false,
        }
    }

    /// Filters a chunk `(n_channels, n)` of raw µV and returns the epochs it completes, in onset
    /// order.
    pub fn push_samples(
        &mut self,
        chunk: ArrayView2<f64>,
    ) -> Result<Vec<ReadyEpoch>, SessionError> {
        if chunk.nrows() != self.n_channels {
            return Err(SessionError::InvalidParameter {
                name: "chunk",
                value: format!("{} channels", chunk.nrows()),
                reason: format!("the stream has {} channels", self.n_channels),
            });
        }
        let mut clean = chunk.to_owned();
        let held = hold_non_finite(clean.view_mut(), &mut self.hold);
        let filtered = self.filter.process(clean.view())?;
        for (b, row) in self.buf.iter_mut().zip(filtered.rows()) {
            b.extend(row.iter());
        }
        let at = self.bad.len();
        self.bad.resize(at + chunk.ncols(), false);
        self.bad_channel
            .resize(at + chunk.ncols(), ChannelMask::default());
        for c in 0..self.n_channels {
            self.non_finite[c] += held.samples(c).len() as u64;
            for &t in held.samples(c) {
                self.bad[at + t] = true;
                self.bad_channel[at + t].0 |= 1 << (c % 128);
            }
        }
        self.received += chunk.ncols() as u64;
        let mut ready = Vec::new();
        while let Some(m) = self.pending.front() {
            if self.epoch_end(m.onset) > self.received as i64 {
                break;
            }
            let m = self.pending.pop_front().expect("front exists");
            let lo = (m.onset as i64 + self.first - self.buf_start as i64) as usize;
            let mut data = Array2::zeros((self.n_channels, self.n_times));
            for (c, b) in self.buf.iter().enumerate() {
                data.row_mut(c)
                    .assign(&ndarray::ArrayView1::from(&b[lo..lo + self.n_times]));
            }
            let accepted = self.judge(&data, lo);
            ready.push(ReadyEpoch {
                marker: m,
                data,
                accepted,
            });
        }
        self.trim();
        Ok(ready)
    }

    /// The rejection rule on a complete epoch starting at buffer index `lo`; counts, per
    /// channel, why a rejected epoch was rejected.
    fn judge(&mut self, data: &Array2<f64>, lo: usize) -> bool {
        let window = lo..lo + self.n_times;
        let held = self.bad[window.clone()].iter().any(|&b| b);
        let mut accepted = true;
        for (c, row) in data.rows().into_iter().enumerate() {
            let non_finite_at = if held {
                self.bad_channel[window.clone()].iter().position(|b| b[c])
            } else {
                None
            };
            let Some(fault) = self.epochs.channel_fault(row, non_finite_at) else {
                continue;
            };
            accepted = false;
            let f = &mut self.faults[c];
            match fault {
                ChannelFault::NonFinite { .. } => f.non_finite += 1,
                ChannelFault::Flat { .. } => f.flat += 1,
                ChannelFault::Absolute { .. } | ChannelFault::PeakToPeak { .. } => {
                    f.over_threshold += 1
                }
            }
        }
        accepted
    }

    /// Per channel: epochs rejected because of it, by reason.
    pub fn channel_faults(&self) -> &[ChannelFaults] {
        &self.faults
    }

    fn trim(&mut self) {
        let mut oldest = self.received.saturating_sub(self.keep);
        if let Some(m) = self.pending.front() {
            oldest = oldest.min((m.onset as i64 + self.first).max(0) as u64);
        }
        let drop = oldest.saturating_sub(self.buf_start) as usize;
        // Amortise: move memory only when a good share of the buffer can go.
        if drop > 4096 && drop * 2 > self.buf[0].len() {
            for b in &mut self.buf {
                b.drain(..drop);
            }
            self.bad.drain(..drop);
            self.bad_channel.drain(..drop);
            self.buf_start += drop as u64;
        }
    }
}

/// The causal path of `pre` (what the online epocher streams), its first sample offset and
/// epoch length at `sfreq`; a zero-phase one or an empty window is refused.
fn causal(pre: &Preprocess, sfreq: f64) -> Result<(PreprocessParams, i64, usize), SessionError> {
    let params = pre.params();
    if params.filtering != Filtering::Causal {
        return Err(SessionError::InvalidParameter {
            name: "preprocess.causal",
            value: "false".into(),
            reason: "online epoching filters causally; use Preprocess::online()".into(),
        });
    }
    let (first, n_times) = pre.window(sfreq);
    if n_times == 0 {
        return Err(SessionError::InvalidParameter {
            name: "preprocess.tmax",
            value: pre.tmax.to_string(),
            reason: "the epoch window is empty".into(),
        });
    }
    params.epochs.validate(sfreq)?;
    Ok((params, first, n_times))
}

/// The epochs of `events` cut from a whole recording the way [`OnlineEpocher`] cuts them from
/// the stream (as [`offline_epochs`]), held as windows into the recording's band-passed copy
/// (no epoch copied), with those dropped and why.
pub fn offline_windows(
    pre: &Preprocess,
    raw: &Raw,
    events: &[Event],
) -> Result<(oddball_signal::Epochs, oddball_signal::epochs::DropLog), SessionError> {
    let (params, _, _) = causal(pre, raw.sfreq())?;
    Ok(params.filter(raw)?.into_windows(&params.epochs, events)?)
}

/// The epochs of `onsets` cut from a whole recording the way [`OnlineEpocher`] cuts them from
/// the stream: the one offline path ([`PreprocessParams::filter`] then
/// [`oddball_signal::preprocess::Filtered::cut`]) with `pre`'s causal band-pass. Epochs that do
/// not fit in the recording are `None`; rejected ones keep their data, `accepted` false.
pub fn offline_epochs(
    pre: &Preprocess,
    raw: &Raw,
    onsets: &[u64],
) -> Result<Vec<Option<ReadyEpoch>>, SessionError> {
    let (params, first, n_times) = causal(pre, raw.sfreq())?;
    let filtered = params.filter(raw)?;
    let events: Vec<Event> = onsets.iter().map(|&o| Event::new(o as usize, 0)).collect();
    let (epochs, log) = filtered.cut(&params.epochs, &events)?;
    let mut out: Vec<Option<ReadyEpoch>> = Vec::with_capacity(onsets.len());
    let mut dropped = log.dropped.iter().peekable();
    let mut kept = 0;
    for (tag, &onset) in onsets.iter().enumerate() {
        let marker = Marker {
            onset,
            code: 0,
            tag,
        };
        match dropped.next_if(|d| d.index == tag) {
            Some(d) if matches!(d.reason, DropReason::OutOfBounds { .. }) => out.push(None),
            Some(_) => {
                let lo = (onset as i64 + first) as usize;
                out.push(Some(ReadyEpoch {
                    marker,
                    data: filtered
                        .raw
                        .data()
                        .slice(s![.., lo..lo + n_times])
                        .to_owned(),
                    accepted: false,
                }));
            }
            None => {
                out.push(Some(ReadyEpoch {
                    marker,
                    data: epochs.epoch(kept).to_owned(),
                    accepted: true,
                }));
                kept += 1;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn raw(data: &Array2<f64>) -> Raw {
        let names = (0..data.nrows()).map(|c| format!("E{c}")).collect();
        Raw::new(
            data.clone(),
            100.0,
            names,
            oddball_signal::Events::default(),
        )
        .unwrap()
    }

    fn signal(n_ch: usize, n: usize) -> Array2<f64> {
        Array2::from_shape_fn((n_ch, n), |(c, t)| {
            let t = t as f64 / 100.0;
            20.0 * (2.0 * std::f64::consts::PI * 3.0 * t + c as f64).sin()
                + 5.0 * (2.0 * std::f64::consts::PI * 11.0 * t).cos()
                + 40.0
                + c as f64
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Any chunking and any marker timing give the epochs the offline cut gives, bit for bit.
        #[test]
        fn streamed_epochs_equal_offline_epochs(
            chunks in proptest::collection::vec(1usize..180, 1..40),
            onsets in proptest::collection::vec(0u64..2500, 0..12),
        ) {
            let n: usize = chunks.iter().sum();
            let data = signal(3, n);
            let pre = Preprocess::online();
            let mut ep = OnlineEpocher::new(&pre, 100.0, 3).unwrap();
            let mut sorted = onsets.clone();
            sorted.sort_unstable();
            // The same onset twice is one flash delivered twice: the epocher scores it once
            // (tested on its own below), the offline cut would cut it twice.
            sorted.dedup();
            for (tag, &onset) in sorted.iter().enumerate() {
                ep.push_marker(Marker { onset, code: 1, tag }).unwrap();
            }
            let mut got = Vec::new();
            let mut at = 0;
            for c in chunks {
                got.extend(ep.push_samples(data.slice(s![.., at..at + c])).unwrap());
                at += c;
            }
            let offline = offline_epochs(&pre, &raw(&data), &sorted).unwrap();
            let expected: Vec<_> = offline.into_iter().flatten().collect();
            prop_assert_eq!(got.len(), expected.len());
            for (g, e) in got.iter().zip(&expected) {
                prop_assert_eq!(g.marker.onset, e.marker.onset);
                prop_assert_eq!(&g.data, &e.data);
                prop_assert_eq!(g.accepted, e.accepted);
            }
        }
    }

    #[test]
    fn late_markers_within_the_buffer_still_get_their_epoch() {
        let pre = Preprocess::online();
        let data = signal(2, 20_000);
        let mut ep = OnlineEpocher::new(&pre, 100.0, 2).unwrap();
        let mut got = ep.push_samples(data.slice(s![.., ..10_000])).unwrap();
        assert!(got.is_empty());
        // 1 s late: still buffered.
        ep.push_marker(Marker {
            onset: 9_900,
            code: 2,
            tag: 0,
        })
        .unwrap();
        got.extend(ep.push_samples(data.slice(s![.., 10_000..10_001])).unwrap());
        assert_eq!(got.len(), 1);
        let offline = offline_epochs(&pre, &raw(&data), &[9_900]).unwrap();
        assert_eq!(got[0].data, offline[0].as_ref().unwrap().data);
        // Long gone: a clear error.
        ep.push_samples(data.slice(s![.., 10_001..])).unwrap();
        let err = ep
            .push_marker(Marker {
                onset: 100,
                code: 1,
                tag: 1,
            })
            .unwrap_err();
        assert!(
            matches!(err, SessionError::MarkerTooLate { onset: 100, .. }),
            "{err}"
        );
    }

    #[test]
    fn nan_samples_reject_their_epochs_but_never_poison_the_filter() {
        let pre = Preprocess::online();
        let mut data = signal(2, 3000);
        for t in 1000..1010 {
            data[[0, t]] = f64::NAN;
        }
        data[[1, 1500]] = f64::INFINITY;
        let mut ep = OnlineEpocher::new(&pre, 100.0, 2).unwrap();
        let onsets = [500u64, 960, 1005, 1480, 2500];
        for (tag, &onset) in onsets.iter().enumerate() {
            ep.push_marker(Marker {
                onset,
                code: 1,
                tag,
            })
            .unwrap();
        }
        let got = ep.push_samples(data.view()).unwrap();
        let accepted: Vec<bool> = got.iter().map(|e| e.accepted).collect();
        assert_eq!(accepted, [true, false, false, false, true]);
        assert!(got.iter().all(|e| e.data.iter().all(|v| v.is_finite())));
        assert_eq!(ep.non_finite, [10, 1]);
        // The offline cut agrees, NaNs and all.
        let off = offline_epochs(&pre, &raw(&data), &onsets).unwrap();
        for (g, o) in got.iter().zip(off.iter().flatten()) {
            assert_eq!((&g.data, g.accepted), (&o.data, o.accepted));
        }
    }

    #[test]
    fn a_marker_delivered_twice_gives_one_epoch() {
        let pre = Preprocess::online();
        let data = signal(2, 1000);
        let mut ep = OnlineEpocher::new(&pre, 100.0, 2).unwrap();
        let m = Marker {
            onset: 300,
            code: 2,
            tag: 0,
        };
        assert!(ep.push_marker(m).unwrap());
        assert!(!ep.push_marker(Marker { tag: 1, ..m }).unwrap());
        let got = ep.push_samples(data.view()).unwrap();
        assert_eq!(got.len(), 1);
        assert_eq!(ep.duplicate_markers, 1);
    }

    #[test]
    fn a_flat_channel_rejects_the_epoch() {
        let pre = Preprocess::online();
        let mut data = signal(2, 2000);
        data.row_mut(1).fill(3.0);
        let mut ep = OnlineEpocher::new(&pre, 100.0, 2).unwrap();
        ep.push_marker(Marker {
            onset: 1200,
            code: 1,
            tag: 0,
        })
        .unwrap();
        let got = ep.push_samples(data.view()).unwrap();
        assert!(!got[0].accepted);
    }

    #[test]
    fn nan_and_blinks_reject_the_epoch() {
        let pre = Preprocess::online();
        let mut data = signal(2, 1000);
        data[[1, 300]] = 5000.0;
        let mut ep = OnlineEpocher::new(&pre, 100.0, 2).unwrap();
        for (tag, onset) in [100u64, 280, 600].into_iter().enumerate() {
            ep.push_marker(Marker {
                onset,
                code: 1,
                tag,
            })
            .unwrap();
        }
        let got = ep.push_samples(data.view()).unwrap();
        let accepted: Vec<bool> = got.iter().map(|e| e.accepted).collect();
        assert_eq!(accepted, [true, false, true]);
        assert!(OnlineEpocher::new(&Preprocess::peer(), 100.0, 2).is_err());
    }
}
