//! Bayesian LDA against a NumPy transcription of its authors' MATLAB code (Hoffmann et al. 2008,
//! `@bayeslda/train.m`, `classify.m`): reference values from
//! `tools/golden/decode_blda/make_golden.py` (numpy 2.4.6), which also checks its transcription
//! against scikit-learn 1.9.1's `BayesianRidge` in the setting where the two must agree (centred
//! features, see the script) and records the observed agreement in each case's `sklearn_check`.
//!
//! Cases: `random` (n = 60, p = 5), `p300` (120 epochs × 4 channels × 8 times in µV, 22 targets;
//! the largest eigenvalue of XᵀX is a feature direction), `p300_tight` (the same data with
//! `tol` 1e-10), `wide` (p = 40 > n = 24), `unbalanced` (n = 150, 12 targets, small features:
//! the bias is the top eigen-direction).
//!
//! Compared, relative to the reference's magnitude (`|Δ| ≤ 1e-8 · max|ref|` over the vector, or
//! `|Δ| ≤ 1e-8 · |ref|` for a scalar): the scores of the training rows and of 20 held-out rows,
//! the weights with the bias, α, β and the log evidence (absolute 1e-8 · N); the number of
//! updates must be equal. Run with `--nocapture` to see the observed errors.

use ndarray::{Array1, Array2, Axis};
use oddball_decode::classifiers::blda::{Blda, BldaParams};
use oddball_decode::classifiers::ClassifierParams;
use oddball_decode::traits::FeatureData;
use proptest::prelude::*;
use serde::Deserialize;
use std::collections::HashMap;

#[derive(Deserialize)]
struct Golden {
    versions: HashMap<String, String>,
    cases: HashMap<String, Case>,
}

#[derive(Deserialize)]
struct Case {
    x: Vec<Vec<f64>>,
    y: Vec<u8>,
    x_test: Vec<Vec<f64>>,
    tol: f64,
    max_iter: usize,
    alpha: f64,
    beta: f64,
    weights: Vec<f64>,
    bias: f64,
    evidence: f64,
    n_iter: usize,
    scores_train: Vec<f64>,
    scores_test: Vec<f64>,
    sklearn_check: HashMap<String, f64>,
}

const TOL: f64 = 1e-8;
const CASES: [&str; 5] = ["random", "p300", "p300_tight", "wide", "unbalanced"];

fn golden() -> Golden {
    let g: Golden =
        serde_json::from_str(include_str!("fixtures/blda_golden.json")).expect("fixture parses");
    assert_eq!(g.versions["numpy"], "2.4.6");
    assert_eq!(g.versions["scikit-learn"], "1.9.1");
    for name in CASES {
        assert!(g.cases.contains_key(name), "fixture lacks case {name}");
    }
    g
}

fn a2(rows: &[Vec<f64>]) -> Array2<f64> {
    Array2::from_shape_fn((rows.len(), rows[0].len()), |(i, j)| rows[i][j])
}

fn labels(y: &[u8]) -> Vec<bool> {
    y.iter()
        .map(|&v| {
            assert!(v <= 1, "label {v} is not 0/1");
            v == 1
        })
        .collect()
}

/// `max |a − b| / max |b|`.
fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let peak = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / peak
}

fn params(case: &Case) -> BldaParams {
    BldaParams {
        tol: case.tol,
        max_iter: case.max_iter,
        ..BldaParams::default()
    }
}

#[test]
fn matches_the_authors_algorithm() {
    let g = golden();
    for name in CASES {
        let case = &g.cases[name];
        let (x, y, x_test) = (a2(&case.x), labels(&case.y), a2(&case.x_test));
        let model = params(case).fit(x.view(), &y).unwrap();
        assert_eq!(model.n_iter(), case.n_iter, "{name}: updates");

        let mut w = model.weights().to_vec();
        w.push(model.bias());
        let mut w_ref = case.weights.clone();
        w_ref.push(case.bias);
        let s_train = model.decision_function(x.view()).unwrap();
        let s_test = model.decision_function(x_test.view()).unwrap();
        let errors = [
            (
                "scores_train",
                rel_err(s_train.as_slice().unwrap(), &case.scores_train),
            ),
            (
                "scores_test",
                rel_err(s_test.as_slice().unwrap(), &case.scores_test),
            ),
            ("weights", rel_err(&w, &w_ref)),
            ("alpha", rel_err(&[model.alpha()], &[case.alpha])),
            ("beta", rel_err(&[model.beta()], &[case.beta])),
            (
                "evidence",
                (model.log_evidence() - case.evidence).abs() / case.y.len() as f64,
            ),
        ];
        println!("{name}: {errors:?}");
        for (what, e) in errors {
            assert!(e <= TOL, "{name}: {what} error {e:e}");
        }
        // The reference itself agreed with scikit-learn's BayesianRidge where they must.
        for (what, e) in &case.sklearn_check {
            if !what.ends_with("iterations") {
                assert!(*e < TOL, "{name}: sklearn check {what} {e:e}");
            }
        }
    }
}

#[test]
fn reached_through_the_registry() {
    let g = golden();
    let case = &g.cases["random"];
    let (x, y) = (a2(&case.x), labels(&case.y));
    let features = FeatureData::Rows(x.clone());
    let fitted = ClassifierParams::Blda(BldaParams::default())
        .fit(features.view(), &y, 1)
        .unwrap();
    let s = fitted.scorer().decision_function(features.view()).unwrap();
    assert!(rel_err(s.as_slice().unwrap(), &case.scores_train) <= TOL);
    let p = fitted.scorer().predict_proba(features.view()).unwrap();
    assert!(p.iter().all(|&v| (0.0..=1.0).contains(&v)));
    // P(target) is increasing in the score.
    let mut order: Vec<usize> = (0..s.len()).collect();
    order.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    assert!(order.windows(2).all(|w| p[w[0]] <= p[w[1]]));
    // A saved model round-trips.
    let json = serde_json::to_string(&fitted).unwrap();
    let back: oddball_decode::classifiers::Classifier = serde_json::from_str(&json).unwrap();
    let s2 = back.scorer().decision_function(features.view()).unwrap();
    assert_eq!(s, s2);
}

fn fit_scores(x: &Array2<f64>, y: &[bool], test: &Array2<f64>) -> (Blda, Array1<f64>) {
    let m = BldaParams::default().fit(x.view(), y).unwrap();
    let s = m.decision_function(test.view()).unwrap();
    (m, s)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Two invariants of the algorithm on a random permutation of the `p300` case's rows:
    /// * the model does not depend on the order of the training rows (scores equal to 1e-9 of
    ///   their peak, the same number of updates);
    /// * swapping which class is the target negates the regression targets exactly
    ///   (N/N₁ ↔ −N/N₂), so the posterior mean is negated and α, β are unchanged: the scores are
    ///   the negated scores (to 1e-9 of their peak) and α, β agree to 1e-9.
    #[test]
    fn row_order_and_class_swap(seed in any::<u64>()) {
        let g = golden();
        let case = &g.cases["p300"];
        let (x, y, x_test) = (a2(&case.x), labels(&case.y), a2(&case.x_test));
        let n = y.len();
        // A Fisher–Yates permutation from a small LCG on the seed.
        let mut state = seed | 1;
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let j = (state >> 33) as usize % (i + 1);
            perm.swap(i, j);
        }
        let xp = x.select(Axis(0), &perm);
        let yp: Vec<bool> = perm.iter().map(|&i| y[i]).collect();

        let (m0, s0) = fit_scores(&x, &y, &x_test);
        let (m1, s1) = fit_scores(&xp, &yp, &x_test);
        prop_assert_eq!(m0.n_iter(), m1.n_iter());
        let e = rel_err(s1.as_slice().unwrap(), s0.as_slice().unwrap());
        prop_assert!(e <= 1e-9, "permuted rows: {e:e}");

        let swapped: Vec<bool> = yp.iter().map(|&t| !t).collect();
        let (m2, s2) = fit_scores(&xp, &swapped, &x_test);
        let neg: Vec<f64> = s2.iter().map(|v| -v).collect();
        let e = rel_err(&neg, s0.as_slice().unwrap());
        prop_assert!(e <= 1e-9, "swapped classes: {e:e}");
        prop_assert!(rel_err(&[m2.alpha()], &[m0.alpha()]) <= 1e-9);
        prop_assert!(rel_err(&[m2.beta()], &[m0.beta()]) <= 1e-9);
    }
}
