//! Test helpers shared by the unit tests of this crate.

use ndarray::Array3;

/// Synthetic epochs `(n_epochs, 4, 64)` at 64 Hz: uniform noise of `noise` µV peak-to-peak, a
/// 10 Hz sine, and on targets (`i % every == phase`) a Gaussian bump of `bump` × (channel + 1) µV at
/// 300 ms. Deterministic in `seed` (an LCG).
pub(crate) fn synthetic_p300(
    n_epochs: usize,
    seed: u64,
    every: usize,
    phase: usize,
    bump: f64,
    noise: f64,
) -> (Array3<f64>, Vec<bool>) {
    let (n_ch, n_t, sfreq) = (4, 64, 64.0);
    let mut state = seed;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let y: Vec<bool> = (0..n_epochs).map(|i| i % every == phase).collect();
    let x = Array3::from_shape_fn((n_epochs, n_ch, n_t), |(e, c, t)| {
        let tt = t as f64 / sfreq;
        let b = if y[e] {
            bump * (c as f64 + 1.0) * (-((tt - 0.3) / 0.05).powi(2)).exp()
        } else {
            0.0
        };
        b + noise * uniform() + (2.0 * std::f64::consts::PI * 10.0 * tt + c as f64).sin()
    });
    (x, y)
}
