//! First IMF ([`Emd::first_imf`]) of 205-sample channels, as the `paper` pipeline computes it for
//! every channel of every epoch.
//!
//! Two fixed signal sets: `synthetic` (256 sums of 2–20 Hz sinusoids plus white noise at 256 Hz,
//! from a fixed seed) and, when the speller recording is found (`../shared/data` or
//! `ODDBALL_DATA`), `eeg3_1` (the 8 channels of its first 40 epochs, band-passed 0.5–20 Hz as the
//! peer does: 320 channels).
//!
//! `EMD_BENCH_ONCE=all` (or a set's name) skips criterion and runs each set (that set) once, for
//! instruction counts:
//!
//! ```text
//! EMD_BENCH_ONCE=eeg3_1 valgrind --tool=callgrind --toggle-collect='*Emd*first_imf*' <bench binary>
//! ```

use criterion::{criterion_group, Criterion, Throughput};
use oddball_decode::features::emd::{Emd, EmdParams};
use oddball_decode::pipeline::Preprocess;

mod speller;
use speller::speller_epochs;

const N: usize = 205;
const FS: f64 = 256.0;

/// splitmix64: a fixed, dependency-free stream of pseudo-random numbers.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn synthetic() -> Vec<Vec<f64>> {
    let mut rng = Rng(0x00DD_BA11);
    (0..256)
        .map(|_| {
            let n_comp = 2 + (rng.next_u64() % 5) as usize;
            let comps: Vec<(f64, f64, f64)> = (0..n_comp)
                .map(|_| {
                    let f = 2.0 + 18.0 * rng.uniform();
                    let a = 1.0 + 9.0 * rng.uniform();
                    let ph = std::f64::consts::TAU * rng.uniform();
                    (f, a, ph)
                })
                .collect();
            let noise = 0.5 + 2.0 * rng.uniform();
            (0..N)
                .map(|j| {
                    let t = j as f64 / FS;
                    let s: f64 = comps
                        .iter()
                        .map(|&(f, a, ph)| a * (std::f64::consts::TAU * f * t + ph).sin())
                        .sum();
                    s + noise * (rng.uniform() - 0.5)
                })
                .collect()
        })
        .collect()
}

fn eeg() -> Option<Vec<Vec<f64>>> {
    let epochs = speller_epochs("eeg3_1.dat", &Preprocess::peer())?;
    let data = epochs.data();
    let mut out = Vec::new();
    for e in 0..40.min(data.shape()[0]) {
        for c in 0..data.shape()[1] {
            out.push(data.slice(ndarray::s![e, c, ..]).to_vec());
        }
    }
    Some(out)
}

fn sets() -> Vec<(&'static str, Vec<Vec<f64>>)> {
    let mut v = vec![("synthetic", synthetic())];
    if let Some(e) = eeg() {
        v.push(("eeg3_1", e));
    }
    v
}

fn run(emd: &mut Emd, signals: &[Vec<f64>], out: &mut [f64]) -> usize {
    let mut siftings = 0;
    for s in signals {
        siftings += emd.first_imf(s, out).unwrap().n_siftings;
    }
    siftings
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("emd_first_imf");
    for (name, signals) in sets() {
        let mut emd = Emd::new(EmdParams::default()).unwrap();
        let mut out = vec![0.0; N];
        group.throughput(Throughput::Elements(signals.len() as u64));
        group.bench_function(name, |b| {
            b.iter(|| run(&mut emd, std::hint::black_box(&signals), &mut out))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);

fn main() {
    if let Some(which) = std::env::var_os("EMD_BENCH_ONCE") {
        for (name, signals) in sets() {
            if which != "all" && which != name {
                continue;
            }
            let mut emd = Emd::new(EmdParams::default()).unwrap();
            let mut out = vec![0.0; N];
            let siftings = run(&mut emd, &signals, &mut out);
            let check: f64 = out.iter().sum();
            println!(
                "{name}: {} signals, {siftings} siftings ({:.2} per signal), last-IMF sum {check:e}",
                signals.len(),
                siftings as f64 / signals.len() as f64
            );
        }
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
