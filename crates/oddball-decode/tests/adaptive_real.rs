//! Online adaptation after a labelled calibration, on real speller replays: the `lda` preset
//! (amplitude bins + shrinkage LDA) calibrated on labelled runs, then each test character decided
//! with the model of that moment and its epochs taken in with the decision as their label
//! ([`oddball_decode::adaptive`]; the person corrects nothing, the test labels are never used by
//! the model). Compared with the same model frozen: character accuracy by repetitions (each
//! character scored by the model before it took that character in) and the AUC of those scores.

use ndarray::{s, Array2};
use oddball_decode::adaptive::{AdaptiveLdaParams, Update};
use oddball_decode::features::amplitude::AmplitudeFeatures;
use oddball_decode::metrics::{roc_auc, speller_accuracy_by_repetitions, ScoredFlash};
use oddball_decode::pipeline::Preprocess;
use oddball_io::Speller;
use oddball_signal::{Epochs, Events};

struct Run {
    x: Array2<f64>,
    y: Vec<bool>,
    codes: Vec<u32>,
    /// Epoch ranges of the characters.
    chars: Vec<std::ops::Range<usize>>,
    speller: Speller,
}

fn load(path: &std::path::Path, text: Option<&str>) -> Run {
    let mut rec = oddball_io::read(path).unwrap();
    if let Some(t) = text {
        rec.label_from_text(t).unwrap();
    }
    let speller = rec.speller.clone().unwrap();
    let (epochs, _): (Epochs, _) = Preprocess::peer().params().epochs(&rec.raw).unwrap();
    assert_eq!(epochs.n_epochs(), rec.raw.events().len());
    let x = AmplitudeFeatures::for_sfreq(epochs.sfreq())
        .unwrap()
        .transform(epochs.data().view())
        .unwrap();
    let events = Events::new(epochs.events().to_vec());
    let mut chars = Vec::new();
    let mut start = 0;
    for b in speller.character_blocks(&events) {
        chars.push(start..start + b.len());
        start += b.len();
    }
    Run {
        y: epochs.events().iter().map(|e| e.target.unwrap()).collect(),
        codes: epochs.events().iter().map(|e| e.code).collect(),
        x,
        chars,
        speller,
    }
}

fn concat(runs: &[Run]) -> (Array2<f64>, Vec<bool>) {
    let views: Vec<_> = runs.iter().map(|r| r.x.view()).collect();
    let x = ndarray::concatenate(ndarray::Axis(0), &views).unwrap();
    (x, runs.iter().flat_map(|r| r.y.clone()).collect())
}

/// (mean character accuracy over 1..=15 repetitions, accuracy at 15, AUC, updates rejected).
fn replay(train: &[Run], test: &[Run], adapt: bool) -> (f64, f64, f64, usize) {
    let (x, y) = concat(train);
    let mut m = AdaptiveLdaParams::default().fit(x.view(), &y).unwrap();
    let mut acc = [0.0; 15];
    let mut n_chars = 0;
    let (mut scores, mut truth) = (Vec::new(), Vec::new());
    let mut rejected = 0;
    for run in test {
        let rows: Vec<u32> = (0..run.speller.n_rows())
            .map(|r| run.speller.code_of_row(r))
            .collect();
        let cols: Vec<u32> = (0..run.speller.n_cols())
            .map(|c| run.speller.code_of_col(c))
            .collect();
        for range in &run.chars {
            let xs = run.x.slice(s![range.clone(), ..]);
            let sc = m.decision_function(xs).unwrap();
            let block: Vec<ScoredFlash> = range
                .clone()
                .zip(sc.iter())
                .map(|(i, &score)| ScoredFlash {
                    code: run.codes[i],
                    target: run.y[i],
                    score,
                })
                .collect();
            let (a, picks) = speller_accuracy_by_repetitions(&[block], &rows, &cols, 15).unwrap();
            for (t, v) in acc.iter_mut().zip(&a) {
                *t += v;
            }
            n_chars += 1;
            scores.extend(sc.iter().copied());
            truth.extend(run.y[range.clone()].iter().copied());
            if adapt {
                // The decision (all repetitions) labels the character's flashes.
                let (r, c) = picks[0];
                let decided: Vec<bool> = run.codes[range.clone()]
                    .iter()
                    .map(|&k| k == r || k == c)
                    .collect();
                if let Update::Rejected { .. } = m.update(xs, &decided).unwrap() {
                    rejected += 1;
                }
            }
        }
    }
    let acc: Vec<f64> = acc.iter().map(|a| a / n_chars as f64).collect();
    (
        acc.iter().sum::<f64>() / 15.0,
        acc[14],
        roc_auc(&scores, &truth).unwrap(),
        rejected,
    )
}

#[test]
fn adaptation_after_calibration_loses_nothing_on_real_replays() {
    let Some(d) = oddball_testkit::data_dir("adaptive LDA on real replays") else {
        return;
    };
    let b = d.join("bci2000-samplefiles-p300");
    let e1 = load(&b.join("eeg3_1.dat"), None);
    let e2 = load(&b.join("eeg3_2.dat"), None);
    let c = d.join("bci-competition-ii-iib");
    let iib: Vec<Run> = [
        ("AAS010R01.mat", None),
        ("AAS010R02.mat", None),
        ("AAS011R01.mat", None),
        ("AAS011R02.mat", None),
        ("AAS012R03.mat", Some("HAM")),
        ("AAS012R04.mat", Some("PIE")),
    ]
    .iter()
    .map(|(f, t)| load(&c.join(f), *t))
    .collect();
    let (iib_train, iib_test) = iib.split_at(4);
    let cases: [(&str, &[Run], &[Run]); 3] = [
        (
            "eeg3_1 -> eeg3_2",
            std::slice::from_ref(&e1),
            std::slice::from_ref(&e2),
        ),
        (
            "eeg3_2 -> eeg3_1",
            std::slice::from_ref(&e2),
            std::slice::from_ref(&e1),
        ),
        ("IIb runs 1-4 -> HAM, PIE", iib_train, iib_test),
    ];
    let mut gains = 0;
    for (name, train, test) in cases {
        let frozen = replay(train, test, false);
        let adapted = replay(train, test, true);
        println!(
            "{name}: frozen mean acc over 1-15 reps {:.3}, at 15 {:.3}, AUC {:.12}; adapted {:.3}, {:.3}, AUC {:.12} ({} updates rejected)",
            frozen.0, frozen.1, frozen.2, adapted.0, adapted.1, adapted.2, adapted.3
        );
        // The decisions (all repetitions) and the epoch AUC never get worse.
        assert!(adapted.1 >= frozen.1, "{name}: accuracy at 15 reps lost");
        assert!(adapted.2 >= frozen.2, "{name}: AUC lost");
        if adapted.2 > frozen.2 + 0.005 {
            gains += 1;
        }
    }
    assert!(gains >= 1, "adaptation gained (AUC + 0.005) on no replay");
}
