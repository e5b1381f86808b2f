//! The Riemannian steps of the `riemann` preset and of the Python `XdawnCovariances →
//! TangentSpace` pipeline on eeg3_1 (720 epochs, 16×16 xDAWN covariances: 4 filters × 2 classes,
//! prototypes stacked on the filtered epochs): the Karcher mean of the first 576 matrices (one
//! training fold of 5, what `TangentSpace.fit` does), the tangent vectors of all 720, and the
//! xDAWN covariances themselves. Without `../shared/data` (or `ODDBALL_DATA`) it says so and
//! measures nothing.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ndarray::s;
use oddball_decode::pipeline::Preprocess;
use oddball_decode::riemann::xdawn::XdawnCovariancesParams;
use oddball_decode::riemann::{mean_riemann, MeanRiemannParams, TangentSpaceParams};

mod speller;
use speller::speller_epochs;

fn riemann(c: &mut Criterion) {
    let Some(train) = speller_epochs("eeg3_1.dat", &Preprocess::peer()) else {
        return;
    };
    let y: Vec<bool> = train
        .events()
        .iter()
        .map(|e| e.target == Some(true))
        .collect();
    let data = train.data();
    let x = data.view();
    let xc_params = XdawnCovariancesParams::default();
    let xc = xc_params.fit(x, &y).unwrap();
    let covs = xc.transform(x).unwrap();
    let fold = covs.slice(s![..576, .., ..]);
    let params = MeanRiemannParams::default();
    let mean = mean_riemann(fold, &params).unwrap();
    eprintln!(
        "covariances {:?}; mean of 576: {} iterations",
        covs.dim(),
        mean.iterations
    );

    let mut group = c.benchmark_group("riemann");
    group.sample_size(20);
    group.throughput(Throughput::Elements(576));
    group.bench_function("mean_riemann_576", |b| {
        b.iter(|| mean_riemann(fold, &params).unwrap())
    });
    let ts = TangentSpaceParams::default().fit(fold).unwrap();
    group.throughput(Throughput::Elements(covs.dim().0 as u64));
    group.bench_function("tangent_space_transform_720", |b| {
        b.iter(|| ts.transform(covs.view()).unwrap())
    });
    group.bench_function("xdawn_covariances_fit_720", |b| {
        b.iter(|| xc_params.fit(x, &y).unwrap())
    });
    group.bench_function("xdawn_covariances_transform_720", |b| {
        b.iter(|| xc.transform(x).unwrap())
    });
    group.finish();
}

criterion_group!(benches, riemann);
criterion_main!(benches);
