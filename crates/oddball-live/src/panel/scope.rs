//! The operator's view of the signal itself, as acquisition programs show it (BCI2000's source
//! display, OpenViBE's signal display): each channel band-passed as the session's decoder sees
//! it, decimated on the server to the lowest and highest value of each bin of about
//! [`BIN_MS`] (a trace drawn from them misses no peak), with each channel's state by the
//! session's epoch rules (flat or saturated, noisy, samples lost) over the last epoch-length;
//! and after every trial the average epoch of its flashes, the attended bulb's against the
//! others'.
//!
//! Bounded: at most [`MAX_SCOPE_CHANNELS`] channels, [`BINS_PER_MESSAGE`] bins per message,
//! about 100 points per average, and a few seconds of filtered signal kept to cut epochs from.

use std::collections::{BTreeMap, VecDeque};

use ndarray::ArrayView2;
use oddball_decode::preprocess::{Preprocess, FLAT_UV};
use oddball_signal::filter::{Band, ButterworthParams, StreamInit, StreamingFilter};

use super::protocol::{SignalState, MAX_SCOPE_CHANNELS};

/// A bin of the signal display lasts about this long, ms.
pub const BIN_MS: f64 = 20.0;
/// Bins per signal message (5 bins of 20 ms: ten messages a second).
pub const BINS_PER_MESSAGE: usize = 5;
/// Points per average epoch, at most.
const ERP_POINTS: usize = 100;
/// The averages start this long before the onset, s (their baseline).
const ERP_BEFORE_S: f64 = 0.1;
/// Filtered signal kept to cut epochs from when their onset is stamped late, s.
const KEEP_S: f64 = 3.0;

/// The rules the signal display follows: the session's band-pass, flat and rejection
/// thresholds (µV peak-to-peak) and epoch window (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScopeRules {
    pub band: ButterworthParams,
    pub flat_uv: f64,
    pub noisy_uv: Option<f64>,
    pub tmin_s: f64,
    pub tmax_s: f64,
}

impl ScopeRules {
    /// The display of a session with this pre-processing.
    pub fn of(p: &Preprocess) -> Self {
        Self {
            band: p.band,
            flat_uv: FLAT_UV,
            noisy_uv: p.reject_peak_to_peak_uv,
            tmin_s: p.tmin,
            tmax_s: p.tmax,
        }
    }

    /// The band in words: `1–15 Hz`.
    pub fn band_text(&self) -> String {
        match self.band.band {
            Band::Lowpass { h_freq } => format!("below {h_freq} Hz"),
            Band::Highpass { l_freq } => format!("above {l_freq} Hz"),
            Band::Bandpass { l_freq, h_freq } => format!("{l_freq}–{h_freq} Hz"),
            Band::Bandstop { l_freq, h_freq } => format!("without {l_freq}–{h_freq} Hz"),
        }
    }
}

impl Default for ScopeRules {
    /// The online session's default pre-processing ([`Preprocess::online`]).
    fn default() -> Self {
        Self::of(&Preprocess::online())
    }
}

/// Bins of the signal display ready to send: from sample `first_sample` on, per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalBlock {
    pub first_sample: u64,
    pub lo: Vec<Vec<f32>>,
    pub hi: Vec<Vec<f32>>,
    pub state: Vec<SignalState>,
}

/// A trial's average epochs per channel (µV): of `target`'s flashes and of the others'.
#[derive(Debug, Clone, PartialEq)]
pub struct AverageBlock {
    pub target: Option<u32>,
    pub n_target: usize,
    pub n_other: usize,
    pub target_uv: Vec<Vec<f32>>,
    pub other_uv: Vec<Vec<f32>>,
}

/// One bin per channel: lowest, highest, samples lost.
#[derive(Debug, Clone)]
struct Bin {
    lo: Vec<f32>,
    hi: Vec<f32>,
    nan: Vec<bool>,
}

impl Bin {
    fn empty(n: usize) -> Self {
        Self {
            lo: vec![f32::INFINITY; n],
            hi: vec![f32::NEG_INFINITY; n],
            nan: vec![false; n],
        }
    }
}

/// The signal display's state for one stream.
#[derive(Debug, Clone)]
pub struct Scope {
    rules: ScopeRules,
    sfreq: f64,
    names: Vec<String>,
    /// `None`: the band cannot be designed at this rate; the display shows the raw signal.
    filter: Option<StreamingFilter>,
    /// The last finite sample per channel (what a lost sample is drawn as).
    last: Vec<f64>,
    position: u64,
    bin_len: usize,
    bin: Bin,
    bin_fill: usize,
    /// Complete bins not sent yet, and the first one's sample.
    done: Vec<Bin>,
    done_from: u64,
    /// The last bins, for the channel states.
    recent: VecDeque<Bin>,
    state_bins: usize,
    /// Filtered signal per channel from sample `ring_start` on.
    ring: Vec<VecDeque<f32>>,
    ring_start: u64,
    keep: usize,
    /// Epoch window: first sample's offset from the onset, length, the baseline's length
    /// (samples before the onset), the step between points kept.
    erp_first: i64,
    erp_len: usize,
    erp_baseline: usize,
    erp_step: usize,
    /// Drawn flashes whose epochs are not complete: onset sample, bulb code.
    pending: Vec<(u64, u32)>,
    /// Per bulb code: the sum of its flashes' epochs (channel-major, points) and their count.
    sums: BTreeMap<u32, (Vec<f64>, usize)>,
}

impl Scope {
    /// The display of a stream of `ch_names` at `sfreq` Hz under `rules` (the first
    /// [`MAX_SCOPE_CHANNELS`] channels), whose next sample is number `position` (a panel
    /// attached after a calibration without it).
    pub fn new(rules: ScopeRules, sfreq: f64, ch_names: &[String], position: u64) -> Self {
        let n = ch_names.len().min(MAX_SCOPE_CHANNELS);
        let filter = rules
            .band
            .design(sfreq)
            .ok()
            .map(|f| StreamingFilter::new(f, n, StreamInit::Steady));
        let bin_len = ((BIN_MS * 1e-3 * sfreq).round() as usize).max(1);
        let window_s = (rules.tmax_s - rules.tmin_s).max(BIN_MS * 1e-3);
        let state_bins = ((window_s * sfreq / bin_len as f64).ceil() as usize).max(1);
        let erp_first = ((rules.tmin_s.min(0.0) - ERP_BEFORE_S) * sfreq).round() as i64;
        let erp_last = (rules.tmax_s * sfreq).round() as i64;
        let erp_len = (erp_last - erp_first + 1).max(1) as usize;
        let erp_baseline = (-erp_first).max(0) as usize;
        Self {
            rules,
            sfreq,
            names: ch_names[..n].to_vec(),
            filter,
            last: vec![0.0; n],
            position,
            bin_len,
            bin: Bin::empty(n),
            bin_fill: 0,
            done: Vec::new(),
            done_from: 0,
            recent: VecDeque::new(),
            state_bins,
            ring: vec![VecDeque::new(); n],
            ring_start: position,
            keep: (KEEP_S * sfreq).ceil() as usize + erp_len,
            erp_first,
            erp_len,
            erp_baseline,
            erp_step: erp_len.div_ceil(ERP_POINTS).max(1),
            pending: Vec::new(),
            sums: BTreeMap::new(),
        }
    }

    /// The channels shown.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    pub fn rules(&self) -> &ScopeRules {
        &self.rules
    }

    /// A bin's length, ms.
    pub fn bin_ms(&self) -> f64 {
        self.bin_len as f64 / self.sfreq * 1e3
    }

    /// The band the display shows (`raw` when it cannot be designed at this rate).
    pub fn band_text(&self) -> String {
        match self.filter {
            Some(_) => self.rules.band_text(),
            None => "raw".into(),
        }
    }

    /// The averages' first point after the onset and the spacing of their points, ms.
    pub fn erp_axis_ms(&self) -> (f64, f64) {
        (
            self.erp_first as f64 / self.sfreq * 1e3,
            self.erp_step as f64 / self.sfreq * 1e3,
        )
    }

    /// Takes the stream's next samples `(n_channels, n)`, µV; returns the bins ready to send.
    pub fn push(&mut self, data: ArrayView2<f64>) -> Option<SignalBlock> {
        let n = self.names.len();
        let mut x = data.slice(ndarray::s![..n, ..]).to_owned();
        let mut lost = ndarray::Array2::from_elem(x.dim(), false);
        for ((c, t), v) in x.indexed_iter_mut() {
            if v.is_finite() {
                self.last[c] = *v;
            } else {
                *v = self.last[c];
                lost[(c, t)] = true;
            }
        }
        if let Some(f) = &mut self.filter {
            // The chunk has the filter's channel count: it cannot fail.
            let _ = f.process_inplace(x.view_mut());
        }
        for t in 0..x.ncols() {
            for c in 0..n {
                let v = x[(c, t)] as f32;
                self.bin.lo[c] = self.bin.lo[c].min(v);
                self.bin.hi[c] = self.bin.hi[c].max(v);
                self.bin.nan[c] |= lost[(c, t)];
                self.ring[c].push_back(v);
            }
            self.bin_fill += 1;
            self.position += 1;
            if self.bin_fill == self.bin_len {
                let bin = std::mem::replace(&mut self.bin, Bin::empty(n));
                if self.done.is_empty() {
                    self.done_from = self.position - self.bin_len as u64;
                }
                self.recent.push_back(bin.clone());
                if self.recent.len() > self.state_bins {
                    self.recent.pop_front();
                }
                self.done.push(bin);
                self.bin_fill = 0;
            }
        }
        let excess = self
            .ring
            .first()
            .map_or(0, VecDeque::len)
            .saturating_sub(self.keep);
        if excess > 0 {
            for r in &mut self.ring {
                r.drain(..excess);
            }
            self.ring_start += excess as u64;
        }
        self.cut_epochs();
        (self.done.len() >= BINS_PER_MESSAGE).then(|| self.take_block())
    }

    fn take_block(&mut self) -> SignalBlock {
        let n = self.names.len();
        let round = |v: f32| (v * 10.0).round() / 10.0;
        let done = std::mem::take(&mut self.done);
        SignalBlock {
            first_sample: self.done_from,
            lo: (0..n)
                .map(|c| done.iter().map(|b| round(b.lo[c])).collect())
                .collect(),
            hi: (0..n)
                .map(|c| done.iter().map(|b| round(b.hi[c])).collect())
                .collect(),
            state: self.states(),
        }
    }

    /// Each channel's state over the last epoch-length, by the session's epoch rules.
    pub fn states(&self) -> Vec<SignalState> {
        (0..self.names.len())
            .map(|c| {
                if self.recent.is_empty() {
                    return SignalState::Ok;
                }
                if self.recent.iter().any(|b| b.nan[c]) {
                    return SignalState::Nan;
                }
                let lo = self
                    .recent
                    .iter()
                    .map(|b| b.lo[c])
                    .fold(f32::INFINITY, f32::min);
                let hi = self
                    .recent
                    .iter()
                    .map(|b| b.hi[c])
                    .fold(f32::NEG_INFINITY, f32::max);
                let ptp = f64::from(hi - lo);
                if ptp < self.rules.flat_uv {
                    SignalState::Flat
                } else if self.rules.noisy_uv.is_some_and(|t| ptp > t) {
                    SignalState::Noisy
                } else {
                    SignalState::Ok
                }
            })
            .collect()
    }

    /// A flash of bulb `code` was drawn at sample `onset`: its epoch goes into the trial's
    /// averages once its samples are in.
    pub fn flash(&mut self, onset: u64, code: u32) {
        self.pending.push((onset, code));
        self.cut_epochs();
    }

    fn cut_epochs(&mut self) {
        let points = self.erp_len.div_ceil(self.erp_step);
        let n = self.names.len();
        let (first, len, position, ring_start) = (
            self.erp_first,
            self.erp_len as i64,
            self.position as i64,
            self.ring_start as i64,
        );
        let mut k = 0;
        while k < self.pending.len() {
            let (onset, code) = self.pending[k];
            let start = onset as i64 + first;
            if start + len > position {
                k += 1;
                continue;
            }
            self.pending.swap_remove(k);
            if start < ring_start {
                // Its samples are gone already (an onset stamped far too late).
                continue;
            }
            let at = (start - ring_start) as usize;
            let (sum, count) = self
                .sums
                .entry(code)
                .or_insert_with(|| (vec![0.0; n * points], 0));
            for c in 0..n {
                let r = &self.ring[c];
                let base = if self.erp_baseline > 0 {
                    (at..at + self.erp_baseline)
                        .map(|i| f64::from(r[i]))
                        .sum::<f64>()
                        / self.erp_baseline as f64
                } else {
                    0.0
                };
                for p in 0..points {
                    sum[c * points + p] += f64::from(r[at + p * self.erp_step]) - base;
                }
            }
            *count += 1;
        }
    }

    /// The trial is over: its averages (the flashes of `target`, the cued or decided bulb,
    /// against the others'; with no target, all flashes as the others'), `None` when none of
    /// its epochs was complete. Epochs still incomplete are dropped.
    pub fn trial_done(&mut self, target: Option<u32>) -> Option<AverageBlock> {
        self.pending.clear();
        let sums = std::mem::take(&mut self.sums);
        if sums.is_empty() {
            return None;
        }
        let n = self.names.len();
        let points = self.erp_len.div_ceil(self.erp_step);
        let mut t_sum = vec![0.0; n * points];
        let mut o_sum = vec![0.0; n * points];
        let (mut n_target, mut n_other) = (0, 0);
        for (code, (sum, count)) in sums {
            let (acc, k) = if Some(code) == target {
                (&mut t_sum, &mut n_target)
            } else {
                (&mut o_sum, &mut n_other)
            };
            acc.iter_mut().zip(&sum).for_each(|(a, s)| *a += s);
            *k += count;
        }
        let mean = |sum: &[f64], k: usize| -> Vec<Vec<f32>> {
            if k == 0 {
                return Vec::new();
            }
            sum.chunks(points)
                .map(|ch| {
                    ch.iter()
                        .map(|s| ((s / k as f64) * 10.0).round() as f32 / 10.0)
                        .collect()
                })
                .collect()
        };
        Some(AverageBlock {
            target,
            n_target,
            n_other,
            target_uv: mean(&t_sum, n_target),
            other_uv: mean(&o_sum, n_other),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    fn names(n: usize) -> Vec<String> {
        (0..n).map(|c| format!("ch{c}")).collect()
    }

    /// 4 channels at 250 Hz: a 10 Hz sine of 40 µV, a dead one, one of ±500 µV, one with a
    /// lost sample.
    fn block(t0: usize, n: usize) -> Array2<f64> {
        Array2::from_shape_fn((4, n), |(c, t)| {
            let s = (2.0 * std::f64::consts::PI * 10.0 * (t0 + t) as f64 / 250.0).sin();
            match c {
                0 => 20.0 * s,
                1 => 4000.0,
                2 => 250.0 * s,
                _ if t == 3 => f64::NAN,
                _ => 20.0 * s,
            }
        })
    }

    #[test]
    fn bins_carry_the_peaks_and_channels_their_state() {
        let mut s = Scope::new(ScopeRules::default(), 250.0, &names(4), 0);
        assert_eq!(s.bin_ms(), 20.0);
        let mut blocks = Vec::new();
        for k in 0..50 {
            if let Some(b) = s.push(block(k * 25, 25).view()) {
                blocks.push(b);
            }
        }
        // 1250 samples: 250 bins of 5 samples, 5 per message, in order.
        assert_eq!(blocks.len(), 50);
        assert!(blocks
            .windows(2)
            .all(|w| w[1].first_sample == w[0].first_sample + 25));
        let last = blocks.last().unwrap();
        assert_eq!(last.lo.len(), 4);
        assert_eq!(last.hi[0].len(), BINS_PER_MESSAGE);
        // The sine passes the 1–15 Hz band: its bins span most of ±20 µV.
        let hi = last.hi[0].iter().copied().fold(f32::MIN, f32::max);
        let lo = last.lo[0].iter().copied().fold(f32::MAX, f32::min);
        assert!(hi > 12.0 && lo < -12.0, "{lo} {hi}");
        assert_eq!(
            last.state,
            [
                SignalState::Ok,
                SignalState::Flat,
                SignalState::Noisy,
                SignalState::Nan
            ]
        );
    }

    #[test]
    fn the_average_separates_the_attended_flashes() {
        let sfreq = 250.0;
        // The stream began long before the display (a panel attached after calibration).
        let start = 90_000;
        let mut s = Scope::new(ScopeRules::default(), sfreq, &names(1), start as u64);
        // Flashes every 250 ms, code 1 followed by a 300 ms-late bump of 10 µV, the others not.
        let n = 5000;
        let mut x = Array2::zeros((1, n));
        let mut flashes = Vec::new();
        for (i, onset) in (250..4000).step_by(62).enumerate() {
            let code = (i % 4) as u32 + 1;
            flashes.push(((start + onset) as u64, code));
            if code == 1 {
                for t in 0..50 {
                    let w = (std::f64::consts::PI * t as f64 / 50.0).sin();
                    x[(0, onset + 50 + t)] += 10.0 * w;
                }
            }
        }
        let mut next = 0;
        for k in 0..n / 25 {
            while next < flashes.len() && flashes[next].0 < (start + k * 25 + 25) as u64 {
                s.flash(flashes[next].0, flashes[next].1);
                next += 1;
            }
            s.push(x.slice(ndarray::s![.., k * 25..k * 25 + 25]));
        }
        let a = s.trial_done(Some(1)).unwrap();
        assert_eq!(a.n_target + a.n_other, flashes.len());
        assert_eq!(a.n_target, flashes.iter().filter(|f| f.1 == 1).count());
        let (t0, dt) = s.erp_axis_ms();
        assert_eq!(t0, -100.0);
        // Peak-to-peak from 200 to 500 ms (the band-pass rings after the bump, as the
        // decoder's epochs do).
        let ptp = |v: &[f32]| {
            let w = &v[((200.0 - t0) / dt) as usize..((500.0 - t0) / dt) as usize];
            w.iter().copied().fold(f32::MIN, f32::max) - w.iter().copied().fold(f32::MAX, f32::min)
        };
        // The others' average holds only the neighbouring bumps' edges and the filter's ringing.
        let (target, other) = (ptp(&a.target_uv[0]), ptp(&a.other_uv[0]));
        assert!(target > 8.0, "{:?}", a.target_uv[0]);
        assert!(other < target / 2.0, "{:?}", a.other_uv[0]);
        // A new trial starts empty.
        assert_eq!(s.trial_done(Some(1)), None);
    }
}
