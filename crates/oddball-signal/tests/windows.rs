//! Epochs held as windows into their recording (`PreprocessParams::epochs_owned`) are the
//! epochs the preloaded cut (`PreprocessParams::epochs`) gives, to the bit: the same kept and
//! dropped epochs, the same samples through every accessor (all, a gather with a step, chunks,
//! one epoch, a selection, a crop, a pool of recordings, the averages, the saved form).

use ndarray::{s, Array2, Array3, Axis};
use oddball_signal::epochs::{average_by_code, average_repetitions, EpochsParams, Reject};
use oddball_signal::filter::{Band, ButterworthParams};
use oddball_signal::preprocess::{Filtering, PreprocessParams};
use oddball_signal::{Epochs, Event, Events, Raw};
use proptest::prelude::*;

fn bits(a: &Array3<f64>) -> Vec<u64> {
    a.iter().map(|v| v.to_bits()).collect()
}

fn same_bits(a: &Epochs, b: &Epochs) {
    assert_eq!(a.dim(), b.dim());
    assert_eq!(a.events(), b.events());
    assert_eq!(a.ch_names(), b.ch_names());
    assert_eq!(a.tmin(), b.tmin());
    assert_eq!(bits(&a.data().into_owned()), bits(&b.data().into_owned()));
}

fn recording(n_ch: usize, n: usize, seed: u64, onsets: &[usize], nan_at: Option<usize>) -> Raw {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut data = Array2::from_shape_fn((n_ch, n), |(c, t)| {
        let t = t as f64 / 100.0;
        20.0 * (2.0 * std::f64::consts::PI * 4.0 * t + c as f64).sin() + 30.0 + 10.0 * noise()
    });
    if let Some(t) = nan_at {
        data[[n_ch - 1, t % n]] = f64::NAN;
    }
    let names = (0..n_ch).map(|c| format!("E{c}")).collect();
    let events = Events::new(
        onsets
            .iter()
            .enumerate()
            .map(|(i, &t)| Event::new(t.min(n - 1), 1 + (i % 3) as u32).with_target(i % 3 == 0))
            .collect(),
    );
    Raw::new(data, 100.0, names, events).unwrap()
}

fn params(tmin: f64, baseline: bool, reject: Option<f64>) -> PreprocessParams {
    let mut epochs = EpochsParams::new(tmin, 0.5).with_flat(1e-6);
    if baseline {
        epochs = epochs.with_baseline(tmin, 0.0);
    }
    if let Some(r) = reject {
        epochs = epochs.with_reject(Reject::PeakToPeak(r));
    }
    PreprocessParams {
        band: ButterworthParams {
            order: 4,
            band: Band::Bandpass {
                l_freq: 1.0,
                h_freq: 15.0,
            },
        },
        filtering: Filtering::ZeroPhase { detrend: None },
        epochs,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn windows_are_the_preloaded_epochs(
        n_ch in 1usize..4,
        n in 120usize..400,
        seed in 0u64..1000,
        onsets in proptest::collection::vec(0usize..420, 0..30),
        baseline in any::<bool>(),
        early in any::<bool>(),
        reject in proptest::option::of(20.0f64..80.0),
        nan_at in proptest::option::of(0usize..400),
        step in 1usize..5,
    ) {
        let raw = recording(n_ch, n, seed, &onsets, nan_at);
        let p = params(if early { -0.1 } else { 0.0 }, baseline, reject);
        let (dense, dense_log) = p.epochs(&raw).unwrap();
        let (win, win_log) = p.epochs_owned(raw).unwrap();
        prop_assert!(dense.is_preloaded());
        prop_assert!(!win.is_preloaded());
        prop_assert_eq!(&dense_log, &win_log);
        same_bits(&dense, &win);
        prop_assert!(dense == win);

        let n_ep = dense.n_epochs();
        // A gather with a step, in any order, with repeats.
        let idx: Vec<usize> = (0..n_ep).rev().chain((0..n_ep).step_by(2)).collect();
        let want = dense.data().slice(s![.., .., ..;step]).select(Axis(0), &idx);
        prop_assert_eq!(bits(&win.gather(&idx, step)), bits(&want));
        prop_assert_eq!(bits(&dense.gather(&idx, step)), bits(&want));
        // Chunks, one epoch at a time.
        let mut parts = Vec::new();
        for (r, c) in win.chunks(3) {
            prop_assert_eq!(r.len(), c.dim().0);
            parts.push(c.into_owned());
        }
        if n_ep > 0 {
            let views: Vec<_> = parts.iter().map(|p| p.view()).collect();
            let joined = ndarray::concatenate(Axis(0), &views).unwrap();
            prop_assert_eq!(bits(&joined), bits(&dense.data().into_owned()));
            let i = n_ep / 2;
            prop_assert_eq!(win.epoch(i).into_owned(), dense.epoch(i).into_owned());
        }
        // A selection stays windows; a crop too.
        let sel = win.select(&idx);
        prop_assert!(!sel.is_preloaded());
        same_bits(&sel, &dense.select(&idx));
        let (c0, c1) = (dense.tmin() + 0.05, dense.tmax() - 0.1);
        same_bits(&win.crop(c0, c1).unwrap(), &dense.crop(c0, c1).unwrap());
        same_bits(&win.select_channels(&[0]), &dense.select_channels(&[0]));
        // Averages (summed in another order: equal to rounding).
        match (win.average(), dense.average()) {
            (Some(a), Some(b)) => prop_assert!((a - b).iter().all(|d| d.abs() < 1e-9)),
            (None, None) => {}
            other => prop_assert!(false, "{other:?}"),
        }
        let (a, b) = (average_by_code(&win), average_by_code(&dense));
        prop_assert_eq!(a, b);
        if n_ep > 0 {
            same_bits(
                &average_repetitions(&win, 2).unwrap(),
                &average_repetitions(&dense, 2).unwrap(),
            );
        }
        // The saved form is the samples.
        let json = serde_json::to_string(&win).unwrap();
        let back: Epochs = serde_json::from_str(&json).unwrap();
        prop_assert!(back.is_preloaded());
        prop_assert!(back == dense);
    }
}

/// Windows of several recordings pool into windows (their recordings moved, not copied): the
/// concatenation of the preloaded epochs, baseline or none.
#[test]
fn pooled_windows_are_the_concatenation() {
    for baseline in [false, true] {
        let p = params(-0.1, baseline, None);
        let raws = [
            recording(3, 300, 1, &[20, 50, 90, 200], None),
            recording(3, 250, 2, &[30, 31, 100], None),
        ];
        let dense: Vec<Epochs> = raws.iter().map(|r| p.epochs(r).unwrap().0).collect();
        let win: Vec<Epochs> = raws
            .into_iter()
            .map(|r| p.epochs_owned(r).unwrap().0)
            .collect();
        let joined = Epochs::concatenate(&win).unwrap();
        assert!(!joined.is_preloaded());
        let pooled = Epochs::pool(win).unwrap();
        assert!(!pooled.is_preloaded());
        let want = Epochs::concatenate(&dense).unwrap();
        assert!(want.is_preloaded());
        same_bits(&pooled, &want);
        same_bits(&joined, &want);
    }
    // Windows without baseline and with it, in one set.
    let a = params(-0.1, false, None)
        .epochs_owned(recording(2, 300, 3, &[40, 80], None))
        .unwrap()
        .0;
    let b = params(-0.1, true, None)
        .epochs_owned(recording(2, 300, 4, &[60], None))
        .unwrap()
        .0;
    let want = Epochs::concatenate(&[&a, &b]).unwrap();
    let pooled = Epochs::pool(vec![a.clone(), b]).unwrap();
    assert!(!pooled.is_preloaded());
    same_bits(&pooled, &want);
    // Windows and preloaded epochs pool into one array.
    let dense = params(-0.1, false, None)
        .epochs(&recording(2, 300, 5, &[70], None))
        .unwrap()
        .0;
    let want = Epochs::concatenate(&[&a, &dense]).unwrap();
    let pooled = Epochs::pool(vec![a, dense]).unwrap();
    assert!(pooled.is_preloaded());
    same_bits(&pooled, &want);
}
