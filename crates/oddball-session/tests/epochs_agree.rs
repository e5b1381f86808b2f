//! The online epocher and the one offline preprocessing path keep and drop exactly the same
//! epochs, bit for bit, whatever the chunking: with NaN and infinite samples, channels going flat
//! and blinks over the rejection threshold.

use ndarray::{s, Array2};
use oddball_decode::pipeline::Preprocess;
use oddball_session::online::{offline_epochs, Marker, OnlineEpocher};
use oddball_signal::{Event, Events, Raw};
use proptest::prelude::*;

const SFREQ: f64 = 100.0;

/// A fault written into the clean signal.
#[derive(Debug, Clone)]
enum Fault {
    /// `len` samples of NaN on `channel` from `at`.
    Nan {
        channel: usize,
        at: usize,
        len: usize,
    },
    /// One infinite sample.
    Inf { channel: usize, at: usize },
    /// The channel holds one value from `at` on (a disconnected electrode).
    Flat { channel: usize, at: usize },
    /// A blink: `height` µV added over `len` samples.
    Blink {
        channel: usize,
        at: usize,
        len: usize,
        height: f64,
    },
}

fn fault(n_ch: usize, n: usize) -> impl Strategy<Value = Fault> {
    let (c, t) = (0..n_ch, 0..n);
    prop_oneof![
        (c.clone(), t.clone(), 1usize..40).prop_map(|(channel, at, len)| Fault::Nan {
            channel,
            at,
            len
        }),
        (c.clone(), t.clone()).prop_map(|(channel, at)| Fault::Inf { channel, at }),
        (c.clone(), 0..n / 2).prop_map(|(channel, at)| Fault::Flat { channel, at }),
        (c, t, 1usize..30, 50.0f64..2000.0).prop_map(|(channel, at, len, height)| {
            Fault::Blink {
                channel,
                at,
                len,
                height,
            }
        }),
    ]
}

fn signal(n_ch: usize, n: usize, faults: &[Fault]) -> Array2<f64> {
    let mut d = Array2::from_shape_fn((n_ch, n), |(c, t)| {
        let t = t as f64 / SFREQ;
        20.0 * (2.0 * std::f64::consts::PI * 3.0 * t + c as f64).sin()
            + 5.0 * (2.0 * std::f64::consts::PI * 11.0 * t).cos()
            + 40.0
            + c as f64
    });
    for f in faults {
        match *f {
            Fault::Nan { channel, at, len } => d
                .slice_mut(s![channel, at..(at + len).min(n)])
                .fill(f64::NAN),
            Fault::Inf { channel, at } => d[[channel, at]] = f64::INFINITY,
            Fault::Flat { channel, at } => d.slice_mut(s![channel, at..]).fill(-12.5),
            Fault::Blink {
                channel,
                at,
                len,
                height,
            } => d
                .slice_mut(s![channel, at..(at + len).min(n)])
                .mapv_inplace(|v| v + height),
        }
    }
    d
}

fn raw(data: &Array2<f64>) -> Raw {
    let names = (0..data.nrows()).map(|c| format!("E{c}")).collect();
    Raw::new(data.clone(), SFREQ, names, Events::default()).unwrap()
}

fn case() -> impl Strategy<Value = (usize, Vec<usize>, Vec<u64>, Vec<Fault>)> {
    (1usize..4, proptest::collection::vec(1usize..300, 1..30)).prop_flat_map(|(n_ch, chunks)| {
        let n: usize = chunks.iter().sum();
        (
            Just(n_ch),
            Just(chunks),
            proptest::collection::vec(0u64..(n as u64 + 100), 0..16),
            proptest::collection::vec(fault(n_ch, n), 0..5),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]
    #[test]
    fn streamed_and_offline_epochs_keep_and_drop_the_same(
        (n_ch, chunks, onsets, faults) in case()
    ) {
        let n: usize = chunks.iter().sum();
        let data = signal(n_ch, n, &faults);
        let pre = Preprocess::online();
        let mut sorted = onsets.clone();
        sorted.sort_unstable();
        sorted.dedup();

        // Streamed, in the chunks given.
        let mut epocher = OnlineEpocher::new(&pre, SFREQ, n_ch).unwrap();
        for (tag, &onset) in sorted.iter().enumerate() {
            epocher.push_marker(Marker { onset, code: 1, tag }).unwrap();
        }
        let mut streamed = Vec::new();
        let mut at = 0;
        for c in &chunks {
            streamed.extend(epocher.push_samples(data.slice(s![.., at..at + c])).unwrap());
            at += c;
        }

        // The offline twin of the epocher.
        let offline: Vec<_> = offline_epochs(&pre, &raw(&data), &sorted)
            .unwrap()
            .into_iter()
            .flatten()
            .collect();
        prop_assert_eq!(streamed.len(), offline.len());
        for (g, e) in streamed.iter().zip(&offline) {
            prop_assert_eq!(g.marker.onset, e.marker.onset);
            prop_assert_eq!(&g.data, &e.data);
            prop_assert_eq!(g.accepted, e.accepted, "onset {}", g.marker.onset);
        }

        // The one preprocessing path of training and evaluation: the same epochs kept, bit for
        // bit, and every other in-bounds epoch dropped for a reason the epocher also saw.
        let events: Vec<Event> = sorted.iter().map(|&o| Event::new(o as usize, 1)).collect();
        let (epochs, log) = pre.params().epochs_at(&raw(&data), &events).unwrap();
        let kept: Vec<u64> = epochs.events().iter().map(|e| e.onset as u64).collect();
        let accepted: Vec<u64> = streamed
            .iter()
            .filter(|e| e.accepted)
            .map(|e| e.marker.onset)
            .collect();
        prop_assert_eq!(&kept, &accepted);
        for (k, e) in streamed.iter().filter(|e| e.accepted).enumerate() {
            prop_assert_eq!(epochs.epoch(k), e.data.view());
        }
        let rejected = streamed.iter().filter(|e| !e.accepted).count();
        let out_of_bounds = log.counts().get("out of bounds").copied().unwrap_or(0);
        prop_assert_eq!(log.len() - out_of_bounds, rejected, "{:?}", log.counts());
        let faults: u64 = epocher.channel_faults().iter().map(|f| f.total()).sum();
        prop_assert!(faults >= rejected as u64);
    }
}

/// The generator above does reach every reason: a channel flat from the start, NaN, a blink.
#[test]
fn every_reason_is_seen_by_both() {
    let n = 3000;
    let faults = [
        Fault::Flat {
            channel: 2,
            at: 1000,
        },
        Fault::Nan {
            channel: 0,
            at: 700,
            len: 3,
        },
        Fault::Blink {
            channel: 1,
            at: 1320,
            len: 10,
            height: 800.0,
        },
    ];
    let data = signal(3, n, &faults);
    let pre = Preprocess::online();
    let onsets = [100u64, 680, 1300, 2500, 2990];
    let mut epocher = OnlineEpocher::new(&pre, SFREQ, 3).unwrap();
    for (tag, &onset) in onsets.iter().enumerate() {
        epocher
            .push_marker(Marker {
                onset,
                code: 1,
                tag,
            })
            .unwrap();
    }
    let streamed = epocher.push_samples(data.view()).unwrap();
    let accepted: Vec<bool> = streamed.iter().map(|e| e.accepted).collect();
    assert_eq!(accepted, [true, false, false, false]);
    let f = epocher.channel_faults();
    assert_eq!(
        (f[0].non_finite, f[1].over_threshold, f[2].flat),
        (1, 1, 1),
        "{f:?}"
    );
    let events: Vec<Event> = onsets.iter().map(|&o| Event::new(o as usize, 1)).collect();
    let (_, log) = pre.params().epochs_at(&raw(&data), &events).unwrap();
    let counts = log.counts();
    assert_eq!(
        (
            counts["non-finite"],
            counts["peak-to-peak"],
            counts["flat"],
            counts["out of bounds"]
        ),
        (1, 1, 1, 1),
        "{log:?}"
    );
}
