//! Fit time, batch throughput and single-epoch latency of each pipeline preset on the eeg3 speller
//! files (train eeg3_1, score eeg3_2: 720 epochs of 8 channels × 205 samples, band-passed 0.5–20 Hz, as the peer).
//! The real recordings are read from `../shared/data` (or `ODDBALL_DATA`); without them the
//! benchmark says so and measures nothing.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use ndarray::Axis;
use oddball_decode::pipeline::{PipelineParams, Preprocess};

mod speller;
use speller::speller_epochs;

fn presets(c: &mut Criterion) {
    let pre = Preprocess::peer();
    let (Some(train), Some(test)) = (
        speller_epochs("eeg3_1.dat", &pre),
        speller_epochs("eeg3_2.dat", &pre),
    ) else {
        return;
    };
    let y: Vec<bool> = train
        .events()
        .iter()
        .map(|e| e.target == Some(true))
        .collect();
    for name in [
        "lda",
        "toeplitz-lda",
        "riemann",
        "lda+riemann",
        "stack",
        "paper-svm",
        "paper",
    ] {
        let params = PipelineParams::preset(name, train.sfreq()).unwrap();
        let mut group = c.benchmark_group(format!("preset_{name}"));
        group.sample_size(10);
        group.bench_function("fit_720_epochs", |b| {
            b.iter(|| params.fit(train.data().view(), &y).unwrap())
        });
        let model = params.fit(train.data().view(), &y).unwrap();
        group.throughput(Throughput::Elements(test.n_epochs() as u64));
        group.bench_function("batch_720_epochs", |b| {
            b.iter(|| model.decision_function(test.data().view()).unwrap())
        });
        group.throughput(Throughput::Elements(1));
        let mut i = 0;
        group.bench_function("single_epoch", |b| {
            b.iter_batched(
                || {
                    i = (i + 1) % test.n_epochs();
                    test.data().index_axis(Axis(0), i).to_owned()
                },
                |epoch| model.score_epoch(epoch.view()).unwrap(),
                BatchSize::SmallInput,
            )
        });
        group.finish();
    }
}

criterion_group!(benches, presets);
criterion_main!(benches);
