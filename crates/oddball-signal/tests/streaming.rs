//! Property: the streaming filter's output on any chunking equals one offline causal pass.

use ndarray::{s, Array2};
use oddball_signal::filter::{Band, SosFilter, StreamInit, StreamingFilter};
use proptest::prelude::*;

fn signal(n_channels: usize, n_times: usize, seed: u64) -> Array2<f64> {
    // A small deterministic generator: sines plus an LCG's noise, offsets per channel.
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
    Array2::from_shape_fn((n_channels, n_times), |(c, t)| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let noise = ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
        50.0 * c as f64 + 20.0 * (t as f64 * 0.07 * (c + 1) as f64).sin() + 10.0 * noise
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn chunked_streaming_equals_offline(
        n_channels in 1usize..20,
        seed in any::<u64>(),
        cuts in proptest::collection::vec(0usize..700, 0..12),
        steady in any::<bool>(),
    ) {
        let n_times = 700;
        let x = signal(n_channels, n_times, seed);
        let f = SosFilter::butter(4, Band::Bandpass { l_freq: 1.0, h_freq: 15.0 }, 500.0).unwrap();
        let offline = f.sosfilt(x.view(), steady);
        let init = if steady { StreamInit::Steady } else { StreamInit::Rest };
        let mut stream = StreamingFilter::new(f, n_channels, init);
        let mut bounds = cuts.clone();
        bounds.push(0);
        bounds.push(n_times);
        bounds.sort_unstable();
        let mut online = Array2::zeros((n_channels, n_times));
        for w in bounds.windows(2) {
            let (a, b) = (w[0], w[1]);
            let y = stream.process(x.slice(s![.., a..b])).unwrap();
            online.slice_mut(s![.., a..b]).assign(&y);
        }
        // Same operations in the same order: bit-identical.
        prop_assert_eq!(online, offline);
    }
}
