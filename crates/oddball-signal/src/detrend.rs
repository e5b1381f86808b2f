//! Removing the offset or linear trend of each channel, as scipy's `detrend(x, axis=-1, type=...)`.

use ndarray::{ArrayViewMut1, ArrayViewMut2};
use serde::{Deserialize, Serialize};

/// What to remove.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum DetrendKind {
    /// The mean (`type='constant'`).
    Constant,
    /// The least-squares straight line (`type='linear'`).
    Linear,
}

/// Detrends each row of `data` `(n_channels, n_times)` in place.
pub fn detrend(mut data: ArrayViewMut2<'_, f64>, kind: DetrendKind) {
    for row in data.rows_mut() {
        detrend_1d(row, kind);
    }
}

/// Detrends one signal in place.
pub fn detrend_1d(mut x: ArrayViewMut1<'_, f64>, kind: DetrendKind) {
    let n = x.len();
    if n == 0 {
        return;
    }
    let nf = n as f64;
    let mean = x.sum() / nf;
    match kind {
        DetrendKind::Constant => x.mapv_inplace(|v| v - mean),
        DetrendKind::Linear => {
            // Centred time keeps the normal equations well conditioned.
            let tc = (nf - 1.0) / 2.0;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for (i, &v) in x.iter().enumerate() {
                let t = i as f64 - tc;
                sxy += t * (v - mean);
                sxx += t * t;
            }
            let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
            for (i, v) in x.iter_mut().enumerate() {
                *v -= mean + slope * (i as f64 - tc);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    #[test]
    fn linear_removes_a_line_exactly_and_constant_the_mean() {
        let mut x = Array2::from_shape_fn((2, 50), |(c, t)| 3.0 + (c as f64 + 0.5) * t as f64);
        detrend(x.view_mut(), DetrendKind::Linear);
        assert!(x.iter().all(|v| v.abs() < 1e-10));
        let mut y = Array2::from_shape_fn((1, 4), |(_, t)| t as f64);
        detrend(y.view_mut(), DetrendKind::Constant);
        assert_eq!(y.row(0).to_vec(), vec![-1.5, -0.5, 0.5, 1.5]);
    }
}
