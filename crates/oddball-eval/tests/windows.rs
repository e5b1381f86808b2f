//! Evaluating and training on epochs held as windows into their recording (what
//! `dataset::epoch` cuts, read a part at a time) gives what the preloaded epochs give, to the
//! bit: every fold's AUC, every held-out score, the saved model and its decision model — for a
//! front that learns nothing (`lda`: cached features, read in chunks), an xDAWN front reading
//! every 4th sample (`riemann`: fitted on a decimated copy), the paper's map with a scaler and
//! PCA (`paper-svm`) and a stack (`stack`: its members and inner folds on the folds' windows).
//! (A learned channel selection on windows: `oddball-decode`'s `tests/windows.rs`.)

use oddball_decode::model::Model;
use oddball_decode::pipeline::Preprocess;
use oddball_decode::preset::Preset;
use oddball_eval::evaluate::{self, EpochedRecording, EvaluateParams, TrainingSet};
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

fn recs(raws: &[Raw], windows: bool) -> Vec<EpochedRecording> {
    let pre = Preprocess::peer().params();
    raws.iter()
        .enumerate()
        .map(|(i, raw)| {
            let epochs: Epochs = if windows {
                pre.epochs_owned(raw.clone()).unwrap().0
            } else {
                pre.epochs(raw).unwrap().0
            };
            assert_eq!(epochs.is_preloaded(), !windows);
            EpochedRecording {
                name: format!("r{i}"),
                n_events: raw.events().len(),
                speller: None,
                epochs,
            }
        })
        .collect()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn windows_score_and_train_as_preloaded_epochs() {
    let train = [recording(100.0, 3), recording(80.0, 4)];
    let test = [recording(90.0, 5)];
    let presets = [
        Preset::Lda,
        Preset::Riemann,
        Preset::PaperSvm,
        Preset::Stack,
    ];
    let cv = EvaluateParams {
        presets: presets.to_vec(),
        folds: 3,
        tune: false,
    };
    let mut outcomes = Vec::new();
    for windows in [false, true] {
        let set = TrainingSet::pool(recs(&train, windows)).unwrap();
        assert_eq!(set.epochs().is_preloaded(), !windows);
        let folds = evaluate::evaluate(&cv, &set, &[], &mut |_| {}).unwrap();
        let held = evaluate::evaluate(&cv, &set, &recs(&test, windows), &mut |_| {}).unwrap();
        let mut models = Vec::new();
        for p in presets {
            let t = evaluate::train(p, &set, None, &mut |_| {}).unwrap();
            let mut model = Model::new(
                Preprocess::peer(),
                t.sfreq,
                set.epochs().ch_names().to_vec(),
                t.pipeline,
            );
            model.decision = Some(t.decision);
            models.push((model.to_json(), t.cv_auc.to_bits()));
        }
        outcomes.push((folds, held, models));
    }
    // Windows of several recordings borrowed as one set share the recordings.
    let held = recs(&train, true);
    let of = TrainingSet::of(&held).unwrap();
    assert!(!of.epochs().is_preloaded());
    assert!(of.epochs() == TrainingSet::pool(recs(&train, false)).unwrap().epochs());

    let (dense, win) = (&outcomes[0], &outcomes[1]);
    for (a, b) in dense.0.iter().zip(&win.0).chain(dense.1.iter().zip(&win.1)) {
        assert_eq!(a.pipeline, b.pipeline);
        assert_eq!(bits(&a.auc_folds), bits(&b.auc_folds), "{}", a.pipeline);
        assert!(a.auc > 0.6, "{} finds the step: AUC {}", a.pipeline, a.auc);
    }
    assert_eq!(dense.0.len(), presets.len());
    assert_eq!(dense.1.len(), presets.len());
    for (a, b) in dense.2.iter().zip(&win.2) {
        assert_eq!(a.1, b.1, "out-of-fold AUC");
        assert!(a.0 == b.0, "the saved models differ");
    }
}

/// The hyper-parameter search reads windows as the fits do (an xDAWN front on every 4th
/// sample, the channel selection on the targets): the same choices and scores.
#[test]
fn windows_tune_as_preloaded_epochs() {
    let train = [recording(60.0, 6)];
    let test = [recording(40.0, 7)];
    let params = EvaluateParams {
        presets: vec![Preset::Riemann, Preset::PaperSvm],
        folds: 2,
        tune: true,
    };
    let mut outcomes = Vec::new();
    for windows in [false, true] {
        let set = TrainingSet::pool(recs(&train, windows)).unwrap();
        let held = evaluate::evaluate(&params, &set, &recs(&test, windows), &mut |_| {}).unwrap();
        let t = evaluate::train(Preset::Riemann, &set, Some(2), &mut |_| {}).unwrap();
        let chosen = serde_json::to_string(&t.tuning).unwrap();
        let model = Model::new(Preprocess::peer(), t.sfreq, vec![], t.pipeline).to_json();
        outcomes.push((held, chosen, model));
    }
    let (dense, win) = (&outcomes[0], &outcomes[1]);
    for (a, b) in dense.0.iter().zip(&win.0) {
        assert_eq!(bits(&a.auc_folds), bits(&b.auc_folds), "{}", a.pipeline);
        assert_eq!(
            serde_json::to_string(&a.tuning).unwrap(),
            serde_json::to_string(&b.tuning).unwrap()
        );
    }
    assert_eq!(dense.1, win.1, "the search's report");
    assert!(dense.2 == win.2, "the tuned models differ");
}
