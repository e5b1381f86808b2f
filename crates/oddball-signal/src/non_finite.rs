//! Non-finite samples (NaN, ±∞): [`hold_non_finite`] replaces each by its channel's last finite
//! value before filtering (one would poison a recursive filter) and returns where they were
//! ([`NonFinite`]), so that [`crate::epochs`] can drop every epoch whose window covers one.

use ndarray::ArrayViewMut2;

/// Where a recording held NaN or ±∞: per channel, the sample indices in ascending order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NonFinite {
    per_channel: Vec<Vec<usize>>,
}

impl NonFinite {
    /// Non-finite samples of `channel`, ascending.
    pub fn samples(&self, channel: usize) -> &[usize] {
        self.per_channel.get(channel).map_or(&[], Vec::as_slice)
    }

    /// Whether no sample was non-finite.
    pub fn is_empty(&self) -> bool {
        self.per_channel.iter().all(Vec::is_empty)
    }

    /// The first non-finite sample of `channel` in `start..start + len`, as an offset from
    /// `start`.
    pub fn first_in(&self, channel: usize, start: usize, len: usize) -> Option<usize> {
        let samples = self.samples(channel);
        let i = samples.partition_point(|&t| t < start);
        samples
            .get(i)
            .filter(|&&t| t < start + len)
            .map(|&t| t - start)
    }
}

/// Replaces each non-finite sample of `data` `(n_channels, n_times)` with its channel's last
/// finite value (`hold`, one per channel, updated: carry it from chunk to chunk of a stream;
/// start it at 0) and returns where they were.
pub fn hold_non_finite(mut data: ArrayViewMut2<'_, f64>, hold: &mut [f64]) -> NonFinite {
    let per_channel = data
        .rows_mut()
        .into_iter()
        .zip(hold.iter_mut())
        .map(|(mut row, hold)| {
            let mut bad = Vec::new();
            for (t, v) in row.iter_mut().enumerate() {
                if v.is_finite() {
                    *hold = *v;
                } else {
                    *v = *hold;
                    bad.push(t);
                }
            }
            bad
        })
        .collect();
    NonFinite { per_channel }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    #[test]
    fn held_samples_are_found_per_channel() {
        let mut d = Array2::from_shape_fn((2, 6), |(c, t)| (c * 10 + t) as f64);
        d[[0, 0]] = f64::NAN;
        d[[0, 3]] = f64::INFINITY;
        d[[1, 4]] = f64::NEG_INFINITY;
        let nf = hold_non_finite(d.view_mut(), &mut [0.0, 0.0]);
        assert_eq!(d.row(0).to_vec(), [0.0, 1.0, 2.0, 2.0, 4.0, 5.0]);
        assert_eq!(d.row(1).to_vec(), [10.0, 11.0, 12.0, 13.0, 13.0, 15.0]);
        assert_eq!(nf.samples(0), [0, 3]);
        assert_eq!(nf.first_in(0, 1, 3), Some(2));
        assert_eq!(nf.first_in(0, 1, 2), None);
        assert_eq!(nf.first_in(1, 0, 6), Some(4));
        assert!(!nf.is_empty());
    }
}
