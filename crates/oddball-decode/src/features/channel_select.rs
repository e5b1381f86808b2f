//! The paper's channel selection by correlation of the target responses.
//!
//! Fitting (training epochs only): the average target ERP of every channel (mean over target epochs,
//! `n_times` samples); the Pearson correlation of every pair of channel ERPs over time; each channel's
//! score is its mean correlation with the *other* channels. Channels whose target response agrees
//! least with the rest are taken to carry least of the P300 and are dropped first. A channel whose
//! average target ERP is constant has no defined correlation: it scores −1 (the minimum) and counts
//! as uncorrelated (0) in the others' means. Ties in score drop the later channel first. `transform`
//! keeps the selected channels in their original order.
//!
//! Written here: a correlation matrix and a sort.

use ndarray::{Array1, Array2, Array3, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// How many channels to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ChannelCount {
    /// Drop this many least-correlated channels (fewer than the channel count).
    Drop(usize),
    /// Keep this many best-correlated channels (at least 1).
    Keep(usize),
}

/// Unfitted channel-selection settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChannelSelectionParams {
    pub count: ChannelCount,
}

/// A fitted selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelSelection {
    /// Score of every input channel (mean correlation with the others).
    pub scores: Array1<f64>,
    /// Kept channel indices, ascending.
    pub selected: Vec<usize>,
    /// Channels seen in fitting.
    pub n_channels: usize,
}

impl ChannelSelectionParams {
    /// Scores the channels on training `epochs` `(n_epochs, n_channels, n_times)` with labels `y`.
    pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<ChannelSelection> {
        let (n_ep, n_ch, n_t) = epochs.dim();
        if y.len() != n_ep {
            return Err(DecodeError::LabelCount {
                n_samples: n_ep,
                n_labels: y.len(),
            });
        }
        let n_targets = y.iter().filter(|&&t| t).count();
        if n_targets == 0 {
            return Err(DecodeError::NeedBothClasses {
                n_targets,
                n_nontargets: n_ep,
            });
        }
        if n_ch < 2 || n_t < 2 {
            return Err(DecodeError::TooFewSamples {
                what: format!(
                    "channel correlation needs at least 2 channels and 2 samples, got {n_ch} x {n_t}"
                ),
            });
        }
        let n_keep = match self.count {
            ChannelCount::Keep(k) if (1..=n_ch).contains(&k) => k,
            ChannelCount::Drop(d) if d < n_ch => n_ch - d,
            other => {
                return Err(DecodeError::InvalidParameter {
                    name: "count",
                    value: format!("{other:?}"),
                    reason: format!("must leave between 1 and {n_ch} channels"),
                })
            }
        };
        if epochs.iter().any(|v| !v.is_finite()) {
            return Err(DecodeError::NonFinite {
                what: "channel-selection epochs".into(),
            });
        }
        // average target ERP (n_ch, n_t), then centred and normalised rows
        let mut erp = Array2::<f64>::zeros((n_ch, n_t));
        for (epoch, _) in epochs.outer_iter().zip(y).filter(|(_, &t)| t) {
            erp += &epoch;
        }
        erp /= n_targets as f64;
        let mut flat = vec![false; n_ch];
        for (c, mut row) in erp.axis_iter_mut(Axis(0)).enumerate() {
            let m = row.mean().expect("n_t >= 2");
            row.mapv_inplace(|v| v - m);
            let norm = row.dot(&row).sqrt();
            if norm > 0.0 && norm.is_finite() {
                row.mapv_inplace(|v| v / norm);
            } else {
                flat[c] = true;
                row.fill(0.0);
            }
        }
        let corr = erp.dot(&erp.t());
        let scores = Array1::from_shape_fn(n_ch, |c| {
            if flat[c] {
                -1.0
            } else {
                (0..n_ch)
                    .filter(|&d| d != c)
                    .map(|d| corr[[c, d]])
                    .sum::<f64>()
                    / (n_ch - 1) as f64
            }
        });
        // best first; among equal scores the earlier channel ranks higher
        let mut order: Vec<usize> = (0..n_ch).collect();
        order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
        let mut selected = order[..n_keep].to_vec();
        selected.sort_unstable();
        Ok(ChannelSelection {
            scores,
            selected,
            n_channels: n_ch,
        })
    }
}

impl ChannelSelection {
    /// The kept channels of `epochs`, in their original order.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array3<f64>> {
        if epochs.dim().1 != self.n_channels {
            return Err(DecodeError::ShapeMismatch {
                what: "channel-selection input".into(),
                expected: format!("{} channels", self.n_channels),
                got: format!("{} channels", epochs.dim().1),
            });
        }
        Ok(epochs.select(Axis(1), &self.selected))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 4 channels: 0–2 carry the same target bump (different gains), 3 carries an unrelated wave.
    fn epochs() -> (Array3<f64>, Vec<bool>) {
        let (n_ep, n_t) = (12, 50);
        let y: Vec<bool> = (0..n_ep).map(|i| i % 3 == 0).collect();
        let x = Array3::from_shape_fn((n_ep, 4, n_t), |(e, c, t)| {
            let tt = t as f64 / n_t as f64;
            let bump = (-((tt - 0.4) / 0.1).powi(2)).exp();
            let noise = 0.05 * ((e * 31 + c * 17 + t * 7) as f64).sin();
            match c {
                3 => (12.0 * tt).sin() + noise,
                _ if y[e] => (1.0 + c as f64) * bump + noise,
                _ => noise,
            }
        });
        (x, y)
    }

    #[test]
    fn drops_the_uncorrelated_channel() {
        let (x, y) = epochs();
        let sel = ChannelSelectionParams {
            count: ChannelCount::Drop(1),
        }
        .fit(x.view(), &y)
        .unwrap();
        assert_eq!(sel.selected, vec![0, 1, 2]);
        assert!(sel.scores[3] < sel.scores[0]);
        let kept = sel.transform(x.view()).unwrap();
        assert_eq!(kept.dim(), (12, 3, 50));
        assert_eq!(kept.index_axis(Axis(1), 2), x.index_axis(Axis(1), 2));
        let keep2 = ChannelSelectionParams {
            count: ChannelCount::Keep(2),
        }
        .fit(x.view(), &y)
        .unwrap();
        assert_eq!(keep2.selected.len(), 2);
        assert!(!keep2.selected.contains(&3));
    }

    #[test]
    fn flat_channel_goes_first_and_errors() {
        let (mut x, y) = epochs();
        x.index_axis_mut(Axis(1), 1).fill(2.0);
        let sel = ChannelSelectionParams {
            count: ChannelCount::Drop(1),
        }
        .fit(x.view(), &y)
        .unwrap();
        assert_eq!(sel.scores[1], -1.0);
        assert_eq!(sel.selected, vec![0, 2, 3]);
        let p = ChannelSelectionParams {
            count: ChannelCount::Drop(4),
        };
        assert!(p.fit(x.view(), &y).is_err());
        let keep = ChannelSelectionParams {
            count: ChannelCount::Keep(2),
        };
        assert!(keep.fit(x.view(), &[false; 12]).is_err());
        assert!(keep.fit(x.view(), &y[..5]).is_err());
        let sel = keep.fit(x.view(), &y).unwrap();
        assert!(sel.transform(x.slice(ndarray::s![.., ..3, ..])).is_err());
    }
}
