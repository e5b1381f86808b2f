//! Events of a FIF recording: trigger steps on the STIM channels (MNE's `find_events`) and the
//! samples of MNE annotations (MNE's `events_from_annotations`).

use std::collections::BTreeMap;

use oddball_signal::Event;

use crate::edf::text_codes;

use super::meas::StoredAnnotations;
use super::types::{FifAnnotation, FifChannel};

/// The STIM channels events are read from, as MNE's `find_events` picks them by default: `STI101`
/// if there is a channel of that name, else `STI 014`, else every channel of kind STIM.
pub(super) fn stim_channels(channels: &[FifChannel]) -> Vec<usize> {
    for name in ["STI101", "STI 014"] {
        if let Some(i) = channels.iter().position(|c| c.name == name) {
            return vec![i];
        }
    }
    (0..channels.len())
        .filter(|&i| channels[i].kind == FifChannel::STIM)
        .collect()
}

/// `(sample, code)` of every step up on the trigger channels: a sample whose value is above the
/// value before it (MNE's `find_events` with its default `consecutive="increasing"`: 0 → 3 and
/// 3 → 5 are events, 5 → 4 is not; a non-zero first sample is not). Values are the channel's
/// calibrated values truncated to integers, sign dropped, as MNE takes them. Steps found on
/// several channels are merged, sorted by sample then code, duplicates removed.
pub(super) fn stim_events(stim: &[Vec<u32>]) -> Vec<(usize, u32)> {
    let mut out: Vec<(usize, u32)> = stim
        .iter()
        .flat_map(|v| {
            v.windows(2)
                .enumerate()
                .filter(|(_, w)| w[1] > w[0])
                .map(|(i, w)| (i + 1, w[1]))
        })
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// When the recording is, for placing annotations.
#[derive(Debug, Clone, Copy)]
pub(super) struct Timing {
    pub sfreq: f64,
    pub first_samp: i64,
    pub n_times: usize,
    /// The measurement date, microseconds since 1970.
    pub meas_us: Option<i64>,
}

/// Seconds to whole microseconds, as Python's `timedelta(seconds=…)` rounds (half to even).
fn us(seconds: f64) -> f64 {
    (seconds * 1e6).round_ties_even()
}

/// The sample an annotation falls on, as MNE 1.13 computes it when reading a file
/// (`read_raw_fif` → `set_annotations`, which crops to the data in whole microseconds, then
/// `events_from_annotations`, which rounds half to even): an annotation ending before the first
/// sample or starting after the last sample's end is dropped; one starting before the first
/// sample and reaching it is clipped to sample 0. With an `orig_time`, onsets count from it;
/// without, from acquisition sample 0 when the file has no measurement date, else from the first
/// sample read. `None` also for a non-finite onset and for the rounding that reaches `n_times`.
pub(super) fn annotation_sample(
    t: &Timing,
    onset: f64,
    duration: f64,
    orig_us: Option<i64>,
) -> Option<usize> {
    if !onset.is_finite() {
        return None;
    }
    let duration = if duration.is_nan() { 0.0 } else { duration };
    let sfreq = t.sfreq;
    let first_time = t.first_samp as f64 / sfreq;
    let end = (t.n_times as f64 - 1.0) / sfreq + 1.0 / sfreq;
    let index = match (orig_us, t.meas_us) {
        (Some(a), Some(m)) => {
            let (a, m) = (a as f64, m as f64);
            let tmin = m + us(first_time);
            let tmax = tmin + us(end);
            let on = a + us(onset);
            if on > tmax || on + us(duration) < tmin {
                return None;
            }
            let rel = (on.max(tmin) - a) / 1e6 - (m - a) / 1e6;
            ((rel - us(first_time) / 1e6) * sfreq).round_ties_even()
        }
        (None, meas) => {
            let from_first = if meas.is_none() {
                onset - first_time
            } else {
                onset
            };
            let on = us(from_first);
            if on > us(end) || on + us(duration) < 0.0 {
                return None;
            }
            let onset = on.max(0.0) / 1e6 + first_time;
            match meas {
                None => (onset * sfreq).round_ties_even() - t.first_samp as f64,
                Some(_) => ((onset - us(first_time) / 1e6) * sfreq).round_ties_even(),
            }
        }
        // Refused when the annotations are read (MNE refuses it too).
        (Some(_), None) => return None,
    };
    (index.is_finite() && index >= 0.0 && index < t.n_times as f64).then_some(index as usize)
}

/// The annotations with their samples, their events, and the codes given to their texts
/// (EDF+'s rule, [`text_codes`], counting above `other_max`).
pub(super) fn annotation_events(
    stored: &StoredAnnotations,
    timing: &Timing,
    other_max: u32,
) -> (Vec<FifAnnotation>, Vec<Event>, BTreeMap<String, u32>) {
    let (codes, label_codes) = text_codes(stored.description.iter().map(String::as_str), other_max);
    let mut annotations = Vec::with_capacity(stored.onset.len());
    let mut events = Vec::new();
    for (i, (code, target, label)) in codes.into_iter().enumerate() {
        let (onset, duration) = (stored.onset[i], stored.duration[i]);
        let sample = annotation_sample(timing, onset, duration, stored.orig_time_us);
        if let Some(s) = sample {
            events.push(Event {
                onset: s,
                code,
                target,
                label,
            });
        }
        annotations.push(FifAnnotation {
            onset,
            duration,
            description: stored.description[i].clone(),
            sample,
        });
    }
    (annotations, events, label_codes)
}
