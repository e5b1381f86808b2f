//! The replay subject on the real BCI2000 speller files (skipped when ../shared/data is absent).

use oddball_decode::preset::Preset;
use std::path::PathBuf;

use oddball_arm::Command;
use oddball_decode::decision::DecisionRule;
use oddball_session::decision::Decision;
use oddball_session::replay::{
    calibrate, calibrate_for_bit_rate, replay, stream_epochs, ReplayOrigin, ReplayParams,
};

fn data_file(name: &str) -> Option<PathBuf> {
    oddball_testkit::data_file(
        "the replay test",
        &format!("bci2000-samplefiles-p300/{name}"),
    )
}

#[test]
fn replayed_speller_decisions_are_well_above_chance_and_dynamic_stopping_saves_rounds() {
    let (Some(cal), Some(test)) = (data_file("eeg3_1.dat"), data_file("eeg3_2.dat")) else {
        return;
    };
    let cal = oddball_io::read(cal).unwrap();
    let test = oddball_io::read(test).unwrap();
    for pipeline in [Preset::Lda, Preset::Riemann] {
        let params = ReplayParams::paper(pipeline);
        let (model, report) = calibrate(std::slice::from_ref(&cal), &params).unwrap();
        let fixed = replay(
            std::slice::from_ref(&test),
            &model,
            &Command::LETTER_G,
            &params,
        )
        .unwrap();
        let mut dyn_params = params.clone();
        dyn_params.decoder.rule = DecisionRule::dynamic(5);
        let dynamic = replay(
            std::slice::from_ref(&test),
            &model,
            &Command::LETTER_G,
            &dyn_params,
        )
        .unwrap();
        let acc = |d: &[(Decision, ReplayOrigin)]| {
            d.iter().filter(|(d, _)| d.correct()).count() as f64 / d.len() as f64
        };
        let mean_rounds =
            dynamic.iter().map(|(d, _)| d.rounds as f64).sum::<f64>() / dynamic.len() as f64;
        let abstained = dynamic.iter().filter(|(d, _)| d.abstained).count();
        eprintln!(
            "{pipeline}: cv AUC {:.3}, d' {:.2}; {} decisions; fixed 5 rounds accuracy {:.3}; dynamic accuracy {:.3}, mean rounds {:.2}, abstained {}",
            report.cv_auc,
            report.d_prime,
            fixed.len(),
            acc(&fixed),
            acc(&dynamic),
            mean_rounds,
            abstained
        );
        assert_eq!(fixed.len(), 24, "4 characters × (rows, columns) × 3");
        assert!(fixed.iter().all(|(d, _)| d.rounds == 5));
        assert!(
            acc(&fixed) >= 0.75,
            "{pipeline}: far above the 0.25 of chance"
        );
        assert!(mean_rounds < 5.0);
    }
}

fn iib(name: &str) -> Option<oddball_io::Recording> {
    let p = oddball_testkit::data_file(
        "the replay test",
        &format!("bci-competition-ii-iib/{name}.mat"),
    )?;
    Some(oddball_io::read(p).unwrap())
}

/// Several recordings: the four IIb training runs calibrate together (characters numbered
/// across them, so cross-validation folds keep each whole), and a test run recorded without
/// labels is refused until its spelled text labels it.
#[test]
fn several_speller_runs_calibrate_together_and_an_unlabelled_run_is_refused() {
    let names = ["AAS010R01", "AAS010R02", "AAS011R01", "AAS011R02"];
    let Some(cal) = names.iter().map(|n| iib(n)).collect::<Option<Vec<_>>>() else {
        return;
    };
    let Some(mut test) = iib("AAS012R03") else {
        return;
    };
    let params = ReplayParams::paper(Preset::Lda);
    let (model, report) = calibrate(&cal, &params).unwrap();
    assert_eq!(report.n_trials, 12, "3 characters in each of 4 runs");
    assert_eq!(report.n_epochs, 4 * 540);
    assert_eq!(report.n_targets, 4 * 90);
    let err = replay(
        std::slice::from_ref(&test),
        &model,
        &Command::LETTER_G,
        &params,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("none of its 540 flashes is labelled target"),
        "{err}"
    );
    test.label_from_text("HAM").unwrap();
    let d = replay(
        std::slice::from_ref(&test),
        &model,
        &Command::LETTER_G,
        &params,
    )
    .unwrap();
    assert_eq!(
        d.len(),
        3 * 2 * 3,
        "3 characters × (rows, columns) × 3 slots"
    );
    let right = d.iter().filter(|(d, _)| d.correct()).count();
    eprintln!(
        "HAM replayed: {right}/18 right (cv AUC {:.3})",
        report.cv_auc
    );
    // Measured 17/18 (5 fixed rounds of the paper's timing).
    assert!(right >= 16, "{right}/18");
    // The characters of a second run follow the first's.
    let (Some(a), Some(b)) = (iib("AAS010R01"), iib("AAS010R02")) else {
        return;
    };
    let both = replay(&[a, b], &model, &Command::LETTER_G, &params).unwrap();
    assert_eq!(both.len(), 36);
    assert_eq!(both.last().unwrap().1.character, 5);
}

/// A calibration's epochs (what it is fitted on, and what the report's ERP shows) are held as
/// windows into each run's causally band-passed copy, not kept as the stream hands them over:
/// they are the epochs the online epocher streams, bit for bit and in order (two runs, streamed
/// in chunks of 7 samples).
#[test]
fn calibration_windows_are_the_streamed_epochs() {
    let (Some(a), Some(b)) = (iib("AAS010R01"), iib("AAS010R02")) else {
        return;
    };
    let recs = [a, b];
    let params = ReplayParams::paper(Preset::Lda);
    let pre = params.decoder.preprocess;
    let windows = calibrate_for_bit_rate(&recs, &params).unwrap().epochs;
    assert!(!windows.is_preloaded());
    let mut streamed = Vec::new();
    for rec in &recs {
        let events = rec.raw.events().as_slice();
        for e in stream_epochs(rec, &pre, 7).unwrap().into_iter().flatten() {
            if e.accepted {
                streamed.push((events[e.marker.tag].clone(), e.data));
            }
        }
    }
    assert_eq!(windows.n_epochs(), streamed.len());
    assert_eq!(streamed.len(), 2 * 540, "every flash of the two runs");
    for (k, (event, data)) in streamed.iter().enumerate() {
        assert_eq!(&windows.events()[k], event);
        let w = windows.epoch(k);
        assert!(
            w.iter().zip(data).all(|(x, y)| x.to_bits() == y.to_bits()),
            "epoch {k} differs"
        );
    }
}
