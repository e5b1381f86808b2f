//! A pipeline fitted on epochs held as windows into their recording (read a part at a time)
//! gives what the preloaded epochs give, to the bit: a learned channel selection (fitted on the
//! target epochs' windows) in front of either kind of feature map, fitted whole and
//! cross-validated through a cache. (Evaluation and training on windows: `oddball-eval`'s
//! `tests/windows.rs`.)

use oddball_decode::pipeline::{FrontCache, PipelineParams, Preprocess};
use oddball_signal::{Epochs, Event, Events, Raw};

/// `seconds` of 8-channel EEG at 256 Hz with a flash every 0.25 s (epochs overlapping 3.2
/// times), every fifth a target.
fn recording(seconds: f64, seed: u64) -> Raw {
    let (sfreq, n_ch) = (256.0, 8);
    let n = (seconds * sfreq) as usize;
    let (data, flashes) = oddball_testkit::flash_train(n_ch, n, sfreq, 0.25, seed);
    let events = flashes
        .into_iter()
        .map(|(onset, target)| Event::new(onset, 1 + u32::from(target)).with_target(target))
        .collect();
    let names = (0..n_ch).map(|c| format!("E{c}")).collect();
    Raw::new(data, sfreq, names, Events::new(events)).unwrap()
}

fn epochs(raw: &Raw, windows: bool) -> Epochs {
    let pre = Preprocess::peer().params();
    let epochs: Epochs = if windows {
        pre.epochs_owned(raw.clone()).unwrap().0
    } else {
        pre.epochs(raw).unwrap().0
    };
    assert_eq!(epochs.is_preloaded(), !windows);
    epochs
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// A channel selection fitted on windows reads only the target epochs (the paper's map behind
/// it a part at a time; an xDAWN map behind it a copy of all the epochs): the same channels
/// and scores as on preloaded epochs, fitted whole and cross-validated through a cache.
#[test]
fn a_channel_selection_fits_on_windows_as_on_preloaded_epochs() {
    let raw = recording(60.0, 8);
    let (dense, win) = (epochs(&raw, false), epochs(&raw, true));
    let (dense, win) = (&dense, &win);
    let y: Vec<bool> = dense
        .events()
        .iter()
        .map(|e| e.target == Some(true))
        .collect();
    let n = y.len();
    let train: Vec<usize> = (0..n).filter(|i| i % 3 != 0).collect();
    let test: Vec<usize> = (0..n).filter(|i| i % 3 == 0).collect();
    let ytr: Vec<bool> = train.iter().map(|&i| y[i]).collect();
    for preset in ["paper-svm", "riemann"] {
        let p = PipelineParams::preset(preset, dense.sfreq())
            .unwrap()
            .with_channel_drop(3);
        let a = p.fit(dense.data().view(), &y).unwrap();
        let b = p.fit_source(win.into(), &y, None).unwrap();
        assert_eq!(a.selected_channels().len(), 5, "{preset}");
        assert_eq!(a.selected_channels(), b.selected_channels(), "{preset}");
        // Every fitted number, the channels' correlation scores among them.
        assert!(
            serde_json::to_string(&a).unwrap() == serde_json::to_string(&b).unwrap(),
            "{preset}: the fitted pipelines differ"
        );
        let sa = a.decision_function(dense.data().view()).unwrap();
        let sb = b.decision_function_source(win.into()).unwrap();
        assert_eq!(bits(&sa.to_vec()), bits(&sb.to_vec()), "{preset}");
        let ca = p
            .fit_score_cached(&mut FrontCache::new(dense), &train, &ytr, None, &test)
            .unwrap();
        let cb = p
            .fit_score_cached(&mut FrontCache::new(win), &train, &ytr, None, &test)
            .unwrap();
        assert_eq!(
            bits(&ca.scores.to_vec()),
            bits(&cb.scores.to_vec()),
            "{preset}"
        );
    }
}
