//! The data every stage reads: [`Raw`] continuous EEG, [`Events`], and cut [`Epochs`].
//!
//! Names and shapes follow MNE-Python: `Raw` holds `(n_channels, n_times)` samples, `Epochs` hold
//! `(n_epochs, n_channels, n_times)`, `sfreq` is in Hz, `tmin` in seconds relative to the event
//! onset. All amplitudes are microvolts (µV) as `f64`.

use std::collections::BTreeMap;

use std::sync::Arc;

use ndarray::{s, Array1, Array2, Array3, Axis, CowArray, Ix2, Ix3};
use serde::{Deserialize, Serialize};

use crate::SignalError;

/// One stimulus onset on the recording's sample clock.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Event {
    /// Onset in samples from the first sample of the recording (index into `Raw`'s time axis).
    pub onset: usize,
    /// Stimulus code: BCI2000 `StimulusCode` (speller rows 1–6, columns 7–12), a marker value, a bulb id.
    pub code: u32,
    /// Whether the flashed item was the one attended; `None` when the recording does not say.
    pub target: Option<bool>,
    /// Free text, e.g. an EDF+ annotation or the character being spelled.
    pub label: Option<String>,
}

impl Event {
    /// An event with no target information and no label.
    pub fn new(onset: usize, code: u32) -> Self {
        Self {
            onset,
            code,
            target: None,
            label: None,
        }
    }

    /// The same event with its target flag set.
    pub fn with_target(mut self, target: bool) -> Self {
        self.target = Some(target);
        self
    }

    /// The same event with a label.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }
}

/// Events sorted by onset (stable: events at the same sample keep their given order).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Events {
    events: Vec<Event>,
}

impl Events {
    /// Sorts the events by onset.
    pub fn new(mut events: Vec<Event>) -> Self {
        events.sort_by_key(|e| e.onset);
        Self { events }
    }

    pub fn len(&self) -> usize {
        self.events.len()
    }

    pub fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    pub fn iter(&self) -> std::slice::Iter<'_, Event> {
        self.events.iter()
    }

    pub fn as_slice(&self) -> &[Event] {
        &self.events
    }

    pub fn into_vec(self) -> Vec<Event> {
        self.events
    }

    /// Adds an event, keeping the onset order.
    pub fn push(&mut self, event: Event) {
        let at = self.events.partition_point(|e| e.onset <= event.onset);
        self.events.insert(at, event);
    }

    /// How many events carry each stimulus code.
    pub fn counts_by_code(&self) -> BTreeMap<u32, usize> {
        let mut counts = BTreeMap::new();
        for e in &self.events {
            *counts.entry(e.code).or_insert(0) += 1;
        }
        counts
    }

    /// Number of events flagged as targets.
    pub fn n_targets(&self) -> usize {
        self.events
            .iter()
            .filter(|e| e.target == Some(true))
            .count()
    }

    /// Number of events flagged as non-targets.
    pub fn n_nontargets(&self) -> usize {
        self.events
            .iter()
            .filter(|e| e.target == Some(false))
            .count()
    }
}

impl<'a> IntoIterator for &'a Events {
    type Item = &'a Event;
    type IntoIter = std::slice::Iter<'a, Event>;
    fn into_iter(self) -> Self::IntoIter {
        self.events.iter()
    }
}

impl FromIterator<Event> for Events {
    fn from_iter<I: IntoIterator<Item = Event>>(iter: I) -> Self {
        Self::new(iter.into_iter().collect())
    }
}

/// Every event onset must lie inside a recording of `n_times` samples.
fn check_events(events: &Events, n_times: usize) -> Result<(), SignalError> {
    match events.iter().find(|e| e.onset >= n_times) {
        Some(e) => Err(SignalError::EventOutOfRange {
            onset: e.onset,
            n_times,
        }),
        None => Ok(()),
    }
}

/// Channel names must be unique: channels are matched by name between recordings and between a
/// model and its input, and two channels of one name cannot both be matched.
pub fn check_unique_names(ch_names: &[String]) -> Result<(), SignalError> {
    let mut seen: std::collections::HashMap<&str, usize> =
        std::collections::HashMap::with_capacity(ch_names.len());
    for (i, n) in ch_names.iter().enumerate() {
        if let Some(&first) = seen.get(n.as_str()) {
            return Err(SignalError::DuplicateChannel {
                name: n.clone(),
                first,
                second: i,
            });
        }
        seen.insert(n, i);
    }
    Ok(())
}

/// The lowest sampling rate accepted anywhere, Hz.
pub const SFREQ_MIN: f64 = 0.1;
/// The highest sampling rate accepted anywhere, Hz (EEG amplifiers sample at most tens of kHz;
/// at 10⁹ Hz a window of a second is a gigabyte, at 10³⁰⁰ Hz the filter design breaks down).
pub const SFREQ_MAX: f64 = 1e6;
/// How many times over the epochs of one recording may hold its samples (overlapping windows:
/// a P300 speller's flashes every 175 ms with 0.8 s epochs overlap about 5 times).
pub const MAX_EPOCH_OVERLAP: usize = 20;
/// The furthest an epoch window (`tmin`, `tmax`) may reach from its onset, seconds.
pub const MAX_WINDOW_S: f64 = 100.0;

/// The one rule for a sampling rate, wherever it enters (file headers, rates estimated from
/// timestamps, saved models, command-line options): finite and within
/// [`SFREQ_MIN`]..=[`SFREQ_MAX`] Hz. Checked before any filter is designed or any buffer sized by
/// it is allocated.
pub fn check_sfreq(sfreq: f64) -> Result<(), SignalError> {
    if sfreq.is_finite() && (SFREQ_MIN..=SFREQ_MAX).contains(&sfreq) {
        Ok(())
    } else {
        Err(SignalError::InvalidSfreq { sfreq })
    }
}

/// Continuous multichannel EEG in µV, `(n_channels, n_times)`, with its events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Raw {
    data: Array2<f64>,
    sfreq: f64,
    ch_names: Vec<String>,
    events: Events,
}

impl Raw {
    /// Checks that `sfreq` is a positive finite rate, that there is one name per channel row and
    /// that every event onset lies inside the recording.
    pub fn new(
        data: Array2<f64>,
        sfreq: f64,
        ch_names: Vec<String>,
        events: Events,
    ) -> Result<Self, SignalError> {
        check_sfreq(sfreq)?;
        if ch_names.len() != data.nrows() {
            return Err(SignalError::ChannelCountMismatch {
                names: ch_names.len(),
                n_channels: data.nrows(),
            });
        }
        check_unique_names(&ch_names)?;
        check_events(&events, data.ncols())?;
        Ok(Self {
            data,
            sfreq,
            ch_names,
            events,
        })
    }

    /// Samples in µV, `(n_channels, n_times)`.
    pub fn data(&self) -> &Array2<f64> {
        &self.data
    }

    /// Mutable samples in µV, for in-place processing (the shape cannot change through this).
    pub fn data_mut(&mut self) -> ndarray::ArrayViewMut2<'_, f64> {
        self.data.view_mut()
    }

    /// Sampling rate in Hz.
    pub fn sfreq(&self) -> f64 {
        self.sfreq
    }

    pub fn ch_names(&self) -> &[String] {
        &self.ch_names
    }

    pub fn events(&self) -> &Events {
        &self.events
    }

    /// Replaces the events (checked against the recording's length).
    pub fn set_events(&mut self, events: Events) -> Result<(), SignalError> {
        check_events(&events, self.n_times())?;
        self.events = events;
        Ok(())
    }

    pub fn n_channels(&self) -> usize {
        self.data.nrows()
    }

    pub fn n_times(&self) -> usize {
        self.data.ncols()
    }

    /// Duration in seconds (`n_times / sfreq`).
    pub fn duration(&self) -> f64 {
        self.n_times() as f64 / self.sfreq
    }

    /// Sample times in seconds from the first sample.
    pub fn times(&self) -> Array1<f64> {
        Array1::from_shape_fn(self.n_times(), |i| i as f64 / self.sfreq)
    }

    /// Index of a channel by name (case-insensitive, as EEG labels are written both ways).
    pub fn channel_index(&self, name: &str) -> Result<usize, SignalError> {
        self.ch_names
            .iter()
            .position(|c| c.eq_ignore_ascii_case(name))
            .ok_or_else(|| SignalError::UnknownChannel {
                name: name.to_string(),
                available: self.ch_names.clone(),
            })
    }

    /// A copy holding only the named channels, in the order given.
    pub fn pick_channels<S: AsRef<str>>(&self, names: &[S]) -> Result<Raw, SignalError> {
        let idx = names
            .iter()
            .map(|n| self.channel_index(n.as_ref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Raw {
            data: self.data.select(Axis(0), &idx),
            sfreq: self.sfreq,
            ch_names: idx.iter().map(|&i| self.ch_names[i].clone()).collect(),
            events: self.events.clone(),
        })
    }

    /// The same recording with its channels named `ch_names`, in order (a montage naming a
    /// file's channels, or a model's spelling of matched names); as many unique names as
    /// channels.
    pub fn with_ch_names(mut self, ch_names: Vec<String>) -> Result<Raw, SignalError> {
        if ch_names.len() != self.data.nrows() {
            return Err(SignalError::ChannelCountMismatch {
                names: ch_names.len(),
                n_channels: self.data.nrows(),
            });
        }
        check_unique_names(&ch_names)?;
        self.ch_names = ch_names;
        Ok(self)
    }

    /// Splits into its parts: data `(n_channels, n_times)` µV, sfreq, channel names, events.
    pub fn into_parts(self) -> (Array2<f64>, f64, Vec<String>, Events) {
        (self.data, self.sfreq, self.ch_names, self.events)
    }
}

/// Epochs cut around events: `(n_epochs, n_channels, n_times)` µV, with the event of each epoch.
///
/// Held one of two ways, as MNE's `Epochs` with `preload=True` or `False`:
/// - **preloaded**: the samples of every epoch in one array ([`Epochs::new`]);
/// - **windows** into the band-passed recording it was cut from
///   ([`crate::preprocess::PreprocessParams::epochs_owned`]): the recording once, each epoch's
///   first sample and its baseline means. Overlapping epochs (a flash every 250 ms with 0.8 s
///   windows overlaps 3.2 times) then cost the recording, not 3.2 × it. Their samples are made
///   on demand: [`Epochs::data`] for all of them, [`Epochs::gather`] for some (what cross-
///   validation and chunked feature maps read), each value `x[c, start + t] − baseline[c]`
///   exactly as the preloaded cut computes it, so both ways give the same numbers to the bit.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "EpochsRepr", into = "EpochsRepr")]
pub struct Epochs {
    store: Store,
    sfreq: f64,
    tmin: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
}

/// How an [`Epochs`] holds its samples.
#[derive(Debug, Clone)]
enum Store {
    Preloaded(Array3<f64>),
    Windows(Windows),
}

/// Epochs as windows into continuous recordings.
#[derive(Debug, Clone)]
struct Windows {
    /// Band-passed recordings `(n_channels, n_samples)`, shared by the epochs cut from them
    /// (several after [`Epochs::pool`]).
    sources: Vec<Arc<Array2<f64>>>,
    /// Each epoch's recording (index into `sources`) and first sample.
    at: Vec<(usize, usize)>,
    n_channels: usize,
    n_times: usize,
    /// The baseline mean subtracted from each epoch's channels `(n_epochs, n_channels)`;
    /// `None` without baseline correction.
    baseline: Option<Array2<f64>>,
}

impl Windows {
    /// Writes epoch `e`'s samples at every `step`-th time into `out` `(n_channels, n_out)`.
    fn fill(&self, e: usize, step: usize, mut out: ndarray::ArrayViewMut2<'_, f64>) {
        let (src, start) = self.at[e];
        let src = &self.sources[src];
        let window = src.slice(s![.., start..start + self.n_times; step]);
        match &self.baseline {
            None => out.assign(&window),
            Some(b) => {
                for ((mut o, w), &m) in out
                    .rows_mut()
                    .into_iter()
                    .zip(window.rows())
                    .zip(b.row(e).iter())
                {
                    o.zip_mut_with(&w, |o, &v| *o = v - m);
                }
            }
        }
    }
}

/// The serialised form of [`Epochs`]: always the samples themselves.
#[derive(Serialize, Deserialize)]
struct EpochsRepr {
    data: Array3<f64>,
    sfreq: f64,
    tmin: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
}

impl From<Epochs> for EpochsRepr {
    fn from(e: Epochs) -> Self {
        let (data, sfreq, tmin, ch_names, events) = e.into_parts();
        Self {
            data,
            sfreq,
            tmin,
            ch_names,
            events,
        }
    }
}

impl TryFrom<EpochsRepr> for Epochs {
    type Error = SignalError;
    fn try_from(r: EpochsRepr) -> Result<Self, SignalError> {
        Epochs::new(r.data, r.sfreq, r.tmin, r.ch_names, r.events)
    }
}

impl PartialEq for Epochs {
    /// The same samples, rate, `tmin`, channels and events, however each is held.
    fn eq(&self, other: &Self) -> bool {
        self.sfreq == other.sfreq
            && self.tmin == other.tmin
            && self.ch_names == other.ch_names
            && self.events == other.events
            && self.dim() == other.dim()
            && self.data() == other.data()
    }
}

/// Epochs [`Epochs::chunks`] yields at a time by default: small enough that a chunk's samples
/// (64 channels × 205 samples × 8 bytes × 256 = 27 MB) stay a fixed margin, large enough for
/// the batched feature maps.
pub const EPOCH_CHUNK: usize = 256;

impl Epochs {
    /// Checks one event per epoch, one name per channel and a valid `sfreq`.
    pub fn new(
        data: Array3<f64>,
        sfreq: f64,
        tmin: f64,
        ch_names: Vec<String>,
        events: Vec<Event>,
    ) -> Result<Self, SignalError> {
        Self::checked(Store::Preloaded(data), sfreq, tmin, ch_names, events)
    }

    /// Epochs as windows into `raw`'s samples `(n_channels, n_samples)` (its events are not
    /// kept): epoch `i` is `data[:, starts[i] .. starts[i] + n_times]` minus `baseline[i, c]`
    /// on channel `c`, with the event `events[i]`.
    pub(crate) fn windows(
        raw: Raw,
        starts: Vec<usize>,
        n_times: usize,
        baseline: Option<Array2<f64>>,
        tmin: f64,
        events: Vec<Event>,
    ) -> Result<Self, SignalError> {
        let (source, sfreq, ch_names, _) = raw.into_parts();
        let n_channels = source.nrows();
        let fits = starts.iter().all(|&s| {
            s.checked_add(n_times)
                .is_some_and(|end| end <= source.ncols())
        });
        let baseline_fits = baseline
            .as_ref()
            .is_none_or(|b| b.dim() == (starts.len(), n_channels));
        if !(fits && baseline_fits) {
            return Err(SignalError::LayoutMismatch {
                what: format!(
                    "{} windows of {n_times} samples into a recording of {} samples",
                    starts.len(),
                    source.ncols()
                ),
            });
        }
        let store = Store::Windows(Windows {
            sources: vec![Arc::new(source)],
            at: starts.into_iter().map(|s| (0, s)).collect(),
            n_channels,
            n_times,
            baseline,
        });
        Self::checked(store, sfreq, tmin, ch_names, events)
    }

    fn checked(
        store: Store,
        sfreq: f64,
        tmin: f64,
        ch_names: Vec<String>,
        events: Vec<Event>,
    ) -> Result<Self, SignalError> {
        check_sfreq(sfreq)?;
        if !tmin.is_finite() {
            return Err(SignalError::InvalidWindow {
                tmin,
                tmax: f64::NAN,
            });
        }
        let epochs = Self {
            store,
            sfreq,
            tmin,
            ch_names,
            events,
        };
        let (n_epochs, n_channels, _) = epochs.dim();
        if epochs.ch_names.len() != n_channels {
            return Err(SignalError::ChannelCountMismatch {
                names: epochs.ch_names.len(),
                n_channels,
            });
        }
        if epochs.events.len() != n_epochs {
            return Err(SignalError::EventCountMismatch {
                events: epochs.events.len(),
                n_epochs,
            });
        }
        Ok(epochs)
    }

    /// `(n_epochs, n_channels, n_times)`.
    pub fn dim(&self) -> (usize, usize, usize) {
        match &self.store {
            Store::Preloaded(d) => d.dim(),
            Store::Windows(w) => (w.at.len(), w.n_channels, w.n_times),
        }
    }

    /// Whether the samples are held as one array (otherwise as windows into the recording,
    /// made on demand).
    pub fn is_preloaded(&self) -> bool {
        matches!(self.store, Store::Preloaded(_))
    }

    /// The samples when they are held as one array (preloaded); `None` for windows.
    pub fn preloaded(&self) -> Option<ndarray::ArrayView3<'_, f64>> {
        match &self.store {
            Store::Preloaded(d) => Some(d.view()),
            Store::Windows(_) => None,
        }
    }

    /// Samples in µV, `(n_epochs, n_channels, n_times)`: borrowed when preloaded, otherwise
    /// made (all of them: to read a few, [`Self::gather`]; to read all a part at a time,
    /// [`Self::chunks`]).
    pub fn data(&self) -> CowArray<'_, f64, Ix3> {
        match &self.store {
            Store::Preloaded(d) => CowArray::from(d.view()),
            Store::Windows(_) => {
                let all: Vec<usize> = (0..self.n_epochs()).collect();
                CowArray::from(self.gather(&all, 1))
            }
        }
    }

    /// A copy of the epochs at `indices`, in that order, keeping every `step`-th sample
    /// (`(indices.len(), n_channels, ⌈n_times / step⌉)`; `step` 1 keeps all).
    ///
    /// # Panics
    /// When an index is out of range or `step` is 0.
    pub fn gather(&self, indices: &[usize], step: usize) -> Array3<f64> {
        assert!(step > 0, "a step of 0 samples");
        match &self.store {
            Store::Preloaded(d) => d.slice(s![.., .., ..;step]).select(Axis(0), indices),
            Store::Windows(w) => {
                let n_out = w.n_times.div_ceil(step);
                let mut out = Array3::zeros((indices.len(), w.n_channels, n_out));
                for (mut o, &e) in out.outer_iter_mut().zip(indices) {
                    w.fill(e, step, o.view_mut());
                }
                out
            }
        }
    }

    /// The epochs `range` as an array: a view when preloaded, otherwise a copy.
    fn slab(&self, range: std::ops::Range<usize>) -> CowArray<'_, f64, Ix3> {
        match &self.store {
            Store::Preloaded(d) => CowArray::from(d.slice(s![range, .., ..])),
            Store::Windows(_) => {
                let idx: Vec<usize> = range.collect();
                CowArray::from(self.gather(&idx, 1))
            }
        }
    }

    /// The epochs in consecutive parts of at most `size` (at least 1) epochs, each with its
    /// range: views when preloaded, otherwise copies of one part at a time.
    pub fn chunks(
        &self,
        size: usize,
    ) -> impl Iterator<Item = (std::ops::Range<usize>, CowArray<'_, f64, Ix3>)> + '_ {
        let size = size.max(1);
        let n = self.n_epochs();
        (0..n.div_ceil(size)).map(move |k| {
            let r = k * size..((k + 1) * size).min(n);
            (r.clone(), self.slab(r))
        })
    }

    pub fn sfreq(&self) -> f64 {
        self.sfreq
    }

    /// Time of the first sample relative to the event onset, seconds.
    pub fn tmin(&self) -> f64 {
        self.tmin
    }

    /// Time of the last sample relative to the event onset, seconds.
    pub fn tmax(&self) -> f64 {
        self.tmin + (self.n_times().saturating_sub(1)) as f64 / self.sfreq
    }

    pub fn ch_names(&self) -> &[String] {
        &self.ch_names
    }

    /// The event of each epoch, in epoch order.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    pub fn n_epochs(&self) -> usize {
        self.dim().0
    }

    pub fn n_channels(&self) -> usize {
        self.dim().1
    }

    pub fn n_times(&self) -> usize {
        self.dim().2
    }

    pub fn is_empty(&self) -> bool {
        self.n_epochs() == 0
    }

    /// Sample times in seconds relative to the onset.
    pub fn times(&self) -> Array1<f64> {
        Array1::from_shape_fn(self.n_times(), |i| self.tmin + i as f64 / self.sfreq)
    }

    /// One epoch, `(n_channels, n_times)`: borrowed when preloaded, otherwise made.
    pub fn epoch(&self, i: usize) -> CowArray<'_, f64, Ix2> {
        match &self.store {
            Store::Preloaded(d) => CowArray::from(d.index_axis(Axis(0), i)),
            Store::Windows(w) => {
                let mut out = Array2::zeros((w.n_channels, w.n_times));
                w.fill(i, 1, out.view_mut());
                CowArray::from(out)
            }
        }
    }

    /// The target flag of each epoch.
    pub fn targets(&self) -> Vec<Option<bool>> {
        self.events.iter().map(|e| e.target).collect()
    }

    /// The epochs at `indices`, in that order: a copy of their samples when preloaded, other
    /// windows into the same recording otherwise (no samples copied).
    pub fn select(&self, indices: &[usize]) -> Epochs {
        let store = match &self.store {
            Store::Preloaded(d) => Store::Preloaded(d.select(Axis(0), indices)),
            Store::Windows(w) => Store::Windows(Windows {
                sources: w.sources.clone(),
                at: indices.iter().map(|&i| w.at[i]).collect(),
                n_channels: w.n_channels,
                n_times: w.n_times,
                baseline: w.baseline.as_ref().map(|b| b.select(Axis(0), indices)),
            }),
        };
        Epochs {
            store,
            sfreq: self.sfreq,
            tmin: self.tmin,
            ch_names: self.ch_names.clone(),
            events: indices.iter().map(|&i| self.events[i].clone()).collect(),
        }
    }

    /// A copy holding only the channels at `indices`, in that order (preloaded).
    pub fn select_channels(&self, indices: &[usize]) -> Epochs {
        Epochs {
            store: Store::Preloaded(self.data().select(Axis(1), indices)),
            sfreq: self.sfreq,
            tmin: self.tmin,
            ch_names: indices.iter().map(|&i| self.ch_names[i].clone()).collect(),
            events: self.events.clone(),
        }
    }

    /// The samples whose time lies in `[tmin, tmax]` (seconds): a copy when preloaded,
    /// shorter windows otherwise.
    pub fn crop(&self, tmin: f64, tmax: f64) -> Result<Epochs, SignalError> {
        if !(tmin.is_finite() && tmax.is_finite() && tmin <= tmax) {
            return Err(SignalError::InvalidWindow { tmin, tmax });
        }
        let first = ((tmin - self.tmin) * self.sfreq - 1e-9).ceil().max(0.0) as usize;
        let last = ((tmax - self.tmin) * self.sfreq + 1e-9).floor();
        if last < 0.0 || first >= self.n_times() {
            return Err(SignalError::InvalidWindow { tmin, tmax });
        }
        let last = (last as usize).min(self.n_times() - 1);
        let store = match &self.store {
            Store::Preloaded(d) => Store::Preloaded(d.slice(s![.., .., first..=last]).to_owned()),
            Store::Windows(w) => Store::Windows(Windows {
                at: w.at.iter().map(|&(src, s)| (src, s + first)).collect(),
                n_times: last - first + 1,
                ..w.clone()
            }),
        };
        Ok(Epochs {
            store,
            sfreq: self.sfreq,
            tmin: self.tmin + first as f64 / self.sfreq,
            ch_names: self.ch_names.clone(),
            events: self.events.clone(),
        })
    }

    /// The mean over all epochs, `(n_channels, n_times)`; `None` when there are no epochs.
    pub fn average(&self) -> Option<Array2<f64>> {
        match &self.store {
            Store::Preloaded(d) => d.mean_axis(Axis(0)),
            Store::Windows(w) => {
                if w.at.is_empty() {
                    return None;
                }
                let mut sum = Array2::zeros((w.n_channels, w.n_times));
                let mut one = Array2::zeros((w.n_channels, w.n_times));
                for e in 0..w.at.len() {
                    w.fill(e, 1, one.view_mut());
                    sum += &one;
                }
                Some(sum / w.at.len() as f64)
            }
        }
    }

    /// Concatenates epochs of the same layout (channels, sfreq, tmin, n_times): owned epochs
    /// or references (`&[&Epochs]`, no copy of the parts first). Windows stay windows into
    /// the parts' recordings (shared, not copied); otherwise the samples are copied into one
    /// array.
    pub fn concatenate<E: std::borrow::Borrow<Epochs>>(parts: &[E]) -> Result<Epochs, SignalError> {
        let first = parts.first().ok_or(SignalError::NoEpochs)?.borrow();
        for p in parts[1..].iter().map(E::borrow) {
            first.check_same_layout(p)?;
        }
        if parts.iter().all(|p| !p.borrow().is_preloaded()) {
            return Self::pool(parts.iter().map(|p| p.borrow().clone()).collect());
        }
        let datas: Vec<_> = parts.iter().map(|p| p.borrow().data()).collect();
        let views: Vec<_> = datas.iter().map(|d| d.view()).collect();
        let data =
            ndarray::concatenate(Axis(0), &views).map_err(|e| SignalError::LayoutMismatch {
                what: e.to_string(),
            })?;
        Ok(Epochs {
            store: Store::Preloaded(data),
            sfreq: first.sfreq,
            tmin: first.tmin,
            ch_names: first.ch_names.clone(),
            events: parts
                .iter()
                .flat_map(|p| p.borrow().events.iter().cloned())
                .collect(),
        })
    }

    /// Epochs of the same layout as one set, moving the parts' samples in. Windows into
    /// recordings stay windows (the recordings are moved, not copied). Preloaded parts are
    /// copied into one array, each part freed as soon as it is copied and the set's pages
    /// written only as they are filled, so the parts and the set together stay about one
    /// set's size in resident memory (where [`Self::concatenate`] holds both).
    pub fn pool(parts: Vec<Epochs>) -> Result<Epochs, SignalError> {
        let first = parts.first().ok_or(SignalError::NoEpochs)?;
        for p in &parts[1..] {
            first.check_same_layout(p)?;
        }
        let (sfreq, tmin, ch_names) = (first.sfreq, first.tmin, first.ch_names.clone());
        let (n_channels, n_times) = (first.n_channels(), first.n_times());
        let n_epochs: usize = parts.iter().map(Epochs::n_epochs).sum();
        let mut events = Vec::with_capacity(n_epochs);
        let store = if parts.iter().all(|p| !p.is_preloaded()) {
            let with_baseline = parts.iter().any(|p| match &p.store {
                Store::Windows(w) => w.baseline.is_some(),
                Store::Preloaded(_) => false,
            });
            let mut sources = Vec::new();
            let mut at = Vec::with_capacity(n_epochs);
            let mut baseline = Vec::new();
            for part in parts {
                let Store::Windows(w) = part.store else {
                    unreachable!("every part is windows")
                };
                let offset = sources.len();
                at.extend(w.at.iter().map(|&(s, t)| (s + offset, t)));
                sources.extend(w.sources);
                if with_baseline {
                    match w.baseline {
                        Some(b) => baseline.extend(b.iter().copied()),
                        None => baseline.extend(std::iter::repeat_n(0.0, w.at.len() * n_channels)),
                    }
                }
                events.extend(part.events);
            }
            Store::Windows(Windows {
                sources,
                at,
                n_channels,
                n_times,
                baseline: with_baseline.then(|| {
                    Array2::from_shape_vec((n_epochs, n_channels), baseline)
                        .expect("one baseline mean per epoch and channel")
                }),
            })
        } else {
            let mut samples = Vec::with_capacity(n_epochs * n_channels * n_times);
            for part in parts {
                // Copied in epoch, channel, time order whatever the part's memory layout.
                match &part.store {
                    Store::Preloaded(d) => samples.extend(d.iter().copied()),
                    Store::Windows(_) => {
                        for (_, chunk) in part.chunks(EPOCH_CHUNK) {
                            samples.extend(chunk.iter().copied());
                        }
                    }
                }
                events.extend(part.events);
            }
            Store::Preloaded(
                Array3::from_shape_vec((n_epochs, n_channels, n_times), samples)
                    .expect("the pooled samples fill the pooled shape"),
            )
        };
        Ok(Epochs {
            store,
            sfreq,
            tmin,
            ch_names,
            events,
        })
    }

    /// Errors unless `other` has the same channels, rate, `tmin` and window length.
    fn check_same_layout(&self, other: &Epochs) -> Result<(), SignalError> {
        if other.ch_names != self.ch_names
            || other.sfreq != self.sfreq
            || other.tmin != self.tmin
            || other.n_times() != self.n_times()
        {
            return Err(SignalError::LayoutMismatch {
                what: format!(
                    "epochs of {} channels at {} Hz, tmin {} s, {} samples vs {} channels at {} Hz, tmin {} s, {} samples",
                    self.n_channels(), self.sfreq, self.tmin, self.n_times(),
                    other.n_channels(), other.sfreq, other.tmin, other.n_times()
                ),
            });
        }
        Ok(())
    }

    /// Splits into its parts: data, sfreq, tmin, channel names, events.
    pub fn into_parts(self) -> (Array3<f64>, f64, f64, Vec<String>, Vec<Event>) {
        let data = match self.store {
            Store::Preloaded(d) => d,
            Store::Windows(_) => self.data().into_owned(),
        };
        (data, self.sfreq, self.tmin, self.ch_names, self.events)
    }
}
