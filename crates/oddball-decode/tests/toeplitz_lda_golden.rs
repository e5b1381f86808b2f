//! Block-Toeplitz shrinkage LDA against its authors' package, `toeplitzlda` 0.4.0 (`blockmatrix`
//! 0.3.0, scikit-learn 1.9.1): reference values from `tools/golden/decode_toeplitz/make_golden.py`,
//! `ToeplitzLDA(n_channels)` with its defaults, on four small synthetic cases:
//! * `basic`: 80 epochs (20 targets) × 3 channels × 6 times, AR(1) noise mixed over channels,
//!   Ledoit–Wolf weight strictly inside (0, 1); 10 held-out rows;
//! * `clipped`: white noise, n = 150 ≫ p = 8, the Ledoit–Wolf estimate (~2.0) clipped to 1;
//! * `one_channel`: 1 channel × 8 times (a plain Toeplitz covariance);
//! * `scaled`: 4 channels × 5 times, channels 1 and 3 × 1e3 (the standardisation).
//!
//! The fixture is channel-major (feature `ch · n_times + t`), as oddball's features are; the script
//! fed `toeplitzlda` the time-major permutation and permuted its outputs back.
//!
//! Errors are relative and scale-aware, so the `scaled` case's small-scale features are checked as
//! tightly as its large-scale ones:
//! * covariance: `|Δ C_ij| / √(C_ii C_jj)` (reference diagonal), i.e. in correlation units;
//! * coef: `|Δ w_i| · √C_ii`, relative to the peak of `|w_j| · √C_jj` (weights per standard
//!   deviation of their feature);
//! * decision values: relative to the peak magnitude over the test rows;
//! * shrinkage and intercept: relative to the reference value (the clipped shrinkage must be
//!   exactly 1).
//!
//! Tolerance 1e-9 throughout (closed form on both sides: one Ledoit–Wolf weight, averages along
//! block diagonals, one linear solve; the worst condition number, `scaled`'s, is ~2e6). Run with
//! `--nocapture` to see the observed errors.

use ndarray::{Array1, Array2, ArrayView2};
use oddball_decode::classifiers::toeplitz_lda::{ToeplitzLda, ToeplitzLdaParams};
use serde::Deserialize;
use std::collections::HashMap;

#[derive(Deserialize)]
struct Golden {
    versions: HashMap<String, String>,
    cases: HashMap<String, Case>,
}

#[derive(Deserialize)]
struct Case {
    n_channels: usize,
    n_times: usize,
    x: Vec<Vec<f64>>,
    y: Vec<u8>,
    x_test: Vec<Vec<f64>>,
    coef: Vec<f64>,
    intercept: f64,
    shrinkage: f64,
    covariance: Vec<Vec<f64>>,
    decision_test: Vec<f64>,
}

const TOL: f64 = 1e-9;
/// The block-Toeplitz structure is exact up to rounding of one division per entry.
const STRUCTURE: f64 = 1e-12;
const CASES: [&str; 4] = ["basic", "clipped", "one_channel", "scaled"];

fn golden() -> Golden {
    let g: Golden = serde_json::from_str(include_str!("fixtures/toeplitz_lda_golden.json"))
        .expect("fixture parses");
    assert_eq!(g.versions["toeplitzlda"], "0.4.0");
    assert_eq!(g.versions["blockmatrix"], "0.3.0");
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

fn fit(name: &str, c: &Case) -> ToeplitzLda {
    let x = a2(&c.x);
    assert_eq!(x.ncols(), c.n_channels * c.n_times, "{name}: feature count");
    ToeplitzLdaParams::default()
        .fit(x.view(), &labels(&c.y), c.n_channels)
        .unwrap_or_else(|e| panic!("{name}: fit failed: {e}"))
}

/// The covariance the fitted model solved.
fn model_covariance<'a>(name: &str, m: &'a ToeplitzLda) -> ArrayView2<'a, f64> {
    m.covariance()
        .unwrap_or_else(|| panic!("{name}: a freshly fitted model keeps its covariance"))
}

/// Largest `|ours − reference| · scale_i / peak`, `peak` = max `|reference · scale|`; asserts it is
/// within `tol` and names the worst index.
fn check_scaled(what: &str, ours: &[f64], reference: &[f64], scale: &[f64], tol: f64) -> f64 {
    assert_eq!(ours.len(), reference.len(), "{what}: length");
    assert_eq!(scale.len(), reference.len(), "{what}: scale length");
    let peak = reference
        .iter()
        .zip(scale)
        .fold(0.0f64, |m, (v, s)| m.max((v * s).abs()))
        .max(1e-300);
    let (worst_i, worst) = ours
        .iter()
        .zip(reference)
        .zip(scale)
        .map(|((a, b), s)| (a - b).abs() * s / peak)
        .enumerate()
        .fold(
            (0, 0.0f64),
            |(wi, w), (i, e)| if e > w { (i, e) } else { (wi, w) },
        );
    eprintln!("{what:<40} max rel error {worst:.2e} (tol {tol:.0e})");
    assert!(
        worst <= tol,
        "{what}: worst relative error {worst:e} > {tol:e} at index {worst_i}: {} vs {}",
        ours[worst_i],
        reference[worst_i]
    );
    worst
}

fn check_scalar(what: &str, ours: f64, reference: f64, tol: f64) {
    let err = (ours - reference).abs() / reference.abs().max(1e-300);
    eprintln!("{what:<40} rel error     {err:.2e} (tol {tol:.0e})");
    assert!(err <= tol, "{what}: {ours} vs {reference} (rel {err:e})");
}

#[test]
fn toeplitz_lda_matches_toeplitzlda() {
    let g = golden();
    for name in CASES {
        let c = &g.cases[name];
        let p = c.n_channels * c.n_times;
        let m = fit(name, c);

        if c.shrinkage == 1.0 {
            assert_eq!(
                m.shrinkage(),
                1.0,
                "{name}: shrinkage must be clipped to exactly 1"
            );
            eprintln!(
                "{:<40} clipped to 1 (as toeplitzlda)",
                format!("{name} shrinkage")
            );
        } else {
            check_scalar(
                &format!("{name} shrinkage"),
                m.shrinkage(),
                c.shrinkage,
                TOL,
            );
        }

        let reference_cov = a2(&c.covariance);
        assert_eq!(
            reference_cov.dim(),
            (p, p),
            "{name}: fixture covariance shape"
        );
        let cov = model_covariance(name, &m);
        assert_eq!(cov.dim(), (p, p), "{name}: covariance shape");
        let sd: Vec<f64> = reference_cov.diag().iter().map(|v| v.sqrt()).collect();
        let corr_scale: Vec<f64> = (0..p * p).map(|k| 1.0 / (sd[k / p] * sd[k % p])).collect();
        check_scaled(
            &format!("{name} covariance (index i*p+j)"),
            &cov.iter().copied().collect::<Vec<_>>(),
            &reference_cov.iter().copied().collect::<Vec<_>>(),
            &corr_scale,
            TOL,
        );

        assert_eq!(m.coef().len(), p, "{name}: coef length");
        check_scaled(
            &format!("{name} coef"),
            &m.coef().to_vec(),
            &c.coef,
            &sd,
            TOL,
        );
        check_scalar(
            &format!("{name} intercept"),
            m.intercept(),
            c.intercept,
            TOL,
        );

        let dec: Array1<f64> = m
            .decision_function(a2(&c.x_test).view())
            .unwrap_or_else(|e| panic!("{name}: decision_function failed: {e}"));
        check_scaled(
            &format!("{name} decision_test"),
            &dec.to_vec(),
            &c.decision_test,
            &vec![1.0; c.decision_test.len()],
            TOL,
        );
    }
}

/// Before the linear taper the covariance is block-Toeplitz over time: the entry for channels
/// `(a, b)` at times `(t, t + d)` depends on `(a, b, d)` only. In the channel-major layout that is
/// `C[a·nt + t, b·nt + t + d] / ((nt − |d|) / nt)` equal for every valid `t`. Checked on the Rust
/// model's covariance and on the fixture's (which also confirms the fixture was permuted back to
/// channel-major correctly).
#[test]
fn covariance_is_tapered_block_toeplitz_in_channel_major_layout() {
    let g = golden();
    let c = &g.cases["basic"];
    let m = fit("basic", c);
    let reference = a2(&c.covariance);
    let (nc, nt) = (c.n_channels, c.n_times);
    assert!(
        nc > 1 && nt > 2,
        "basic case must have several channels and lags"
    );
    for (what, cov) in [
        ("rust", model_covariance("basic", &m)),
        ("fixture", reference.view()),
    ] {
        let peak = cov.iter().fold(0.0f64, |mx, v| mx.max(v.abs()));
        let mut worst = 0.0f64;
        for a in 0..nc {
            for b in 0..nc {
                for d in -(nt as isize - 1)..nt as isize {
                    let taper = (nt - d.unsigned_abs()) as f64 / nt as f64;
                    let ts: Vec<usize> = (0..nt)
                        .filter(|&t| (0..nt as isize).contains(&(t as isize + d)))
                        .collect();
                    let untapered =
                        |t: usize| cov[[a * nt + t, b * nt + (t as isize + d) as usize]] / taper;
                    let first = untapered(ts[0]);
                    for &t in &ts[1..] {
                        let err = (untapered(t) - first).abs() / peak;
                        worst = worst.max(err);
                        assert!(
                            err <= STRUCTURE,
                            "basic ({what}): channels ({a}, {b}), lag {d}, time {t}: {} vs {} at \
                             time {} (rel {err:e})",
                            untapered(t),
                            first,
                            ts[0]
                        );
                    }
                }
            }
        }
        eprintln!(
            "{:<40} max rel spread {worst:.2e} (tol {STRUCTURE:.0e})",
            format!("basic ({what}) block-Toeplitz")
        );
    }
}
