//! Fit time, batch throughput and single-epoch latency of each pipeline preset on the eeg3 speller
//! files (train eeg3_1, score eeg3_2: 720 epochs of 8 channels × 205 samples, band-passed 0.5–20 Hz, as the peer).
//! The real recordings are read from `../shared/data` (or `ODDBALL_DATA`); without them the
//! benchmark says so and measures nothing.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use ndarray::Axis;
use oddball_decode::pipeline::{PipelineParams, Preprocess};
use oddball_signal::detrend::{detrend, DetrendKind};
use oddball_signal::Epochs;

fn speller_epochs(name: &str, pre: &Preprocess) -> Option<Epochs> {
    let dir = std::env::var_os("ODDBALL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        });
    let path = dir.join("bci2000-samplefiles-p300").join(name);
    if !path.is_file() {
        eprintln!(
            "skipping the preset benchmarks: {} not found",
            path.display()
        );
        return None;
    }
    let rec = oddball_io::read(&path).expect("the speller file reads");
    let mut raw = rec.raw;
    detrend(raw.data_mut(), DetrendKind::Constant);
    pre.band
        .design(raw.sfreq())
        .unwrap()
        .apply_raw(&mut raw)
        .unwrap();
    Some(pre.epochs_params().cut(&raw).unwrap().0)
}

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
    for name in ["lda", "riemann", "lda+riemann", "paper-svm", "paper"] {
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
