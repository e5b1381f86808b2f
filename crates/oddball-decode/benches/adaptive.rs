//! One online update of the adaptive LDA (`oddball_decode::adaptive`) at 8 channels: the 20
//! epochs of one four-bulb decision (5 rounds × 4 flashes) of the `lda` preset's features
//! (8 channels × 20 bins = 160) taken into a model calibrated on 800 epochs; and, for scale, one
//! unsupervised refit (EM) of 40 decisions, and one at an uncalibrated session's cap on 64
//! channels (its last 300 four-bulb trials of 20 epochs, 64 channels × 16 bins: the refit after
//! every decision of a long 64-channel session without calibration).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use ndarray::Array2;
use oddball_decode::adaptive::AdaptiveLdaParams;
use oddball_decode::features::amplitude::AmplitudeFeatures;
use oddball_decode::unsupervised::{Constraint, UnsupervisedParams};

fn rows(n: usize, p: usize, seed: u64) -> (Array2<f64>, Vec<bool>) {
    let mut s = seed;
    let mut u = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let y: Vec<bool> = (0..n).map(|i| i % 4 == 1).collect();
    let x = Array2::from_shape_fn((n, p), |(i, j)| {
        10.0 * u() + if y[i] { (j % 20) as f64 * 0.2 } else { 0.0 }
    });
    (x, y)
}

/// `n` epochs of `p` features in four-bulb trials of 20 epochs, and the EM's settings on
/// features taken as given.
fn four_bulb(
    n: usize,
    p: usize,
    seed: u64,
) -> (
    Array2<f64>,
    Vec<u32>,
    Vec<usize>,
    Constraint,
    UnsupervisedParams,
) {
    let (x, _) = rows(n, p, seed);
    let codes: Vec<u32> = (0..n).map(|i| 1 + (i % 4) as u32).collect();
    let trials: Vec<usize> = (0..n).map(|i| i / 20).collect();
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::decimate(1).unwrap(),
        ..UnsupervisedParams::for_sfreq(500.0).unwrap()
    };
    (x, codes, trials, constraint, params)
}

fn bench(c: &mut Criterion) {
    let (cal, ycal) = rows(800, 160, 1);
    let model = AdaptiveLdaParams::default().fit(cal.view(), &ycal).unwrap();
    let (x, y) = rows(20, 160, 2);
    c.bench_function(
        "adaptive lda: one decision's update (20 epochs x 160 features)",
        |b| {
            b.iter_batched(
                || model.clone(),
                |mut m| m.update(x.view(), &y).unwrap(),
                BatchSize::SmallInput,
            )
        },
    );
    let (x, codes, trials, constraint, params) = four_bulb(800, 160, 3);
    c.bench_function(
        "unsupervised: EM refit on 40 decisions (800 epochs x 160 features)",
        |b| {
            b.iter(|| {
                params
                    .fit_features(x.view(), &codes, &trials, &constraint, None)
                    .unwrap()
            })
        },
    );
}

fn bench_cap(c: &mut Criterion) {
    let (x, codes, trials, constraint, params) = four_bulb(300 * 20, 64 * 16, 4);
    // The session's refit after a decision: warm-started from the fit before it.
    let warm = params
        .fit_features(x.view(), &codes, &trials, &constraint, None)
        .unwrap();
    let always = UnsupervisedParams {
        random_until: None,
        ..params
    };
    for (name, p) in [("default", params), ("random starts always", always)] {
        c.bench_function(
            &format!(
                "unsupervised: warm refit at the session cap, 64 channels (6000 epochs x 1024 features), {name}"
            ),
            |b| {
                b.iter(|| {
                    p.fit_features(x.view(), &codes, &trials, &constraint, Some(&warm))
                        .unwrap()
                })
            },
        );
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = bench
}
criterion_group! {
    name = cap;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(10));
    targets = bench_cap
}
criterion_main!(benches, cap);
