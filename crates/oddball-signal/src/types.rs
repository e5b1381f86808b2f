//! The data every stage reads: [`Raw`] continuous EEG, [`Events`], and cut [`Epochs`].
//!
//! Names and shapes follow MNE-Python: `Raw` holds `(n_channels, n_times)` samples, `Epochs` hold
//! `(n_epochs, n_channels, n_times)`, `sfreq` is in Hz, `tmin` in seconds relative to the event
//! onset. All amplitudes are microvolts (µV) as `f64`.

use std::collections::BTreeMap;

use ndarray::{s, Array1, Array2, Array3, ArrayView2, Axis};
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Epochs {
    data: Array3<f64>,
    sfreq: f64,
    tmin: f64,
    ch_names: Vec<String>,
    events: Vec<Event>,
}

impl Epochs {
    /// Checks one event per epoch, one name per channel and a valid `sfreq`.
    pub fn new(
        data: Array3<f64>,
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
        let (n_epochs, n_channels, _) = data.dim();
        if ch_names.len() != n_channels {
            return Err(SignalError::ChannelCountMismatch {
                names: ch_names.len(),
                n_channels,
            });
        }
        if events.len() != n_epochs {
            return Err(SignalError::EventCountMismatch {
                events: events.len(),
                n_epochs,
            });
        }
        Ok(Self {
            data,
            sfreq,
            tmin,
            ch_names,
            events,
        })
    }

    /// Samples in µV, `(n_epochs, n_channels, n_times)`.
    pub fn data(&self) -> &Array3<f64> {
        &self.data
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
        self.data.dim().0
    }

    pub fn n_channels(&self) -> usize {
        self.data.dim().1
    }

    pub fn n_times(&self) -> usize {
        self.data.dim().2
    }

    pub fn is_empty(&self) -> bool {
        self.n_epochs() == 0
    }

    /// Sample times in seconds relative to the onset.
    pub fn times(&self) -> Array1<f64> {
        Array1::from_shape_fn(self.n_times(), |i| self.tmin + i as f64 / self.sfreq)
    }

    /// One epoch, `(n_channels, n_times)`.
    pub fn epoch(&self, i: usize) -> ArrayView2<'_, f64> {
        self.data.index_axis(Axis(0), i)
    }

    /// The target flag of each epoch.
    pub fn targets(&self) -> Vec<Option<bool>> {
        self.events.iter().map(|e| e.target).collect()
    }

    /// A copy holding the epochs at `indices`, in that order.
    pub fn select(&self, indices: &[usize]) -> Epochs {
        Epochs {
            data: self.data.select(Axis(0), indices),
            sfreq: self.sfreq,
            tmin: self.tmin,
            ch_names: self.ch_names.clone(),
            events: indices.iter().map(|&i| self.events[i].clone()).collect(),
        }
    }

    /// A copy holding only the channels at `indices`, in that order.
    pub fn select_channels(&self, indices: &[usize]) -> Epochs {
        Epochs {
            data: self.data.select(Axis(1), indices),
            sfreq: self.sfreq,
            tmin: self.tmin,
            ch_names: indices.iter().map(|&i| self.ch_names[i].clone()).collect(),
            events: self.events.clone(),
        }
    }

    /// A copy keeping the samples whose time lies in `[tmin, tmax]` (seconds).
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
        Ok(Epochs {
            data: self.data.slice(s![.., .., first..=last]).to_owned(),
            sfreq: self.sfreq,
            tmin: self.tmin + first as f64 / self.sfreq,
            ch_names: self.ch_names.clone(),
            events: self.events.clone(),
        })
    }

    /// The mean over all epochs, `(n_channels, n_times)`; `None` when there are no epochs.
    pub fn average(&self) -> Option<Array2<f64>> {
        self.data.mean_axis(Axis(0))
    }

    /// Concatenates epochs of the same layout (channels, sfreq, tmin, n_times): owned epochs
    /// or references (`&[&Epochs]`, no copy of the parts first).
    pub fn concatenate<E: std::borrow::Borrow<Epochs>>(parts: &[E]) -> Result<Epochs, SignalError> {
        let first = parts.first().ok_or(SignalError::NoEpochs)?.borrow();
        for p in parts[1..].iter().map(E::borrow) {
            first.check_same_layout(p)?;
        }
        let views: Vec<_> = parts.iter().map(|p| p.borrow().data.view()).collect();
        let data =
            ndarray::concatenate(Axis(0), &views).map_err(|e| SignalError::LayoutMismatch {
                what: e.to_string(),
            })?;
        Ok(Epochs {
            data,
            sfreq: first.sfreq,
            tmin: first.tmin,
            ch_names: first.ch_names.clone(),
            events: parts
                .iter()
                .flat_map(|p| p.borrow().events.iter().cloned())
                .collect(),
        })
    }

    /// Epochs of the same layout as one set, moving the parts' samples in: each part is freed
    /// as soon as it is copied, and the set's pages are written only as they are filled, so
    /// the parts and the set together stay about one set's size in resident memory (where
    /// [`Self::concatenate`] holds both).
    pub fn pool(parts: Vec<Epochs>) -> Result<Epochs, SignalError> {
        let first = parts.first().ok_or(SignalError::NoEpochs)?;
        for p in &parts[1..] {
            first.check_same_layout(p)?;
        }
        let (sfreq, tmin, ch_names) = (first.sfreq, first.tmin, first.ch_names.clone());
        let (n_channels, n_times) = (first.n_channels(), first.n_times());
        let n_epochs: usize = parts.iter().map(Epochs::n_epochs).sum();
        let mut samples = Vec::with_capacity(n_epochs * n_channels * n_times);
        let mut events = Vec::with_capacity(n_epochs);
        for part in parts {
            // Copied in epoch, channel, time order whatever the part's memory layout.
            samples.extend(part.data.iter().copied());
            events.extend(part.events);
        }
        let data = Array3::from_shape_vec((n_epochs, n_channels, n_times), samples)
            .expect("the pooled samples fill the pooled shape");
        Ok(Epochs {
            data,
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
        (self.data, self.sfreq, self.tmin, self.ch_names, self.events)
    }
}
