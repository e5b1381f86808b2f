//! k-nearest-neighbour classification with scikit-learn's `KNeighborsClassifier(n_neighbors=k)`
//! semantics (uniform weights, Euclidean distance): `predict_proba` is the fraction of target epochs
//! among the `k` training epochs nearest to the query, so with k = 3 it takes the values 0, ⅓, ⅔, 1.
//!
//! The search is brute force — squared distances to every training epoch as `‖q‖² + ‖x‖² − 2 q·x`
//! through one matrix product per block of queries (scikit-learn's brute-force formula), keeping the
//! `k` smallest; a tie in distance goes to the training epoch that comes first. At the paper's sizes
//! (hundreds of epochs, a few hundred PCA scores) that is a few milliseconds for a whole test set,
//! and a tree or `linfa-nn` would not pay for itself. Written here for that reason.

use ndarray::{Array1, Array2, ArrayView1, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use crate::features::scaler::{check_finite, check_n_features};
use crate::linalg::check_labels;
use crate::traits::{FeatureView, FitClassifier, ProbabilisticClassifier};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Unfitted k-NN settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct KnnParams {
    /// Neighbours consulted (the paper: 3).
    pub k: usize,
}

impl Default for KnnParams {
    fn default() -> Self {
        Self { k: 3 }
    }
}

/// A fitted k-NN classifier: the training set itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Knn {
    k: usize,
    x: Array2<f64>,
    y: Vec<bool>,
    /// `‖xᵢ‖²` per training sample, computed on first use (not saved).
    #[serde(skip)]
    x_sq: std::sync::OnceLock<Array1<f64>>,
}

impl KnnParams {
    /// Stores the training set `x` `(n_samples, n_features)` and labels (both classes needed).
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<Knn> {
        check_labels(x.nrows(), y)?;
        check_finite(x, "k-NN training features")?;
        if self.k == 0 || self.k > x.nrows() {
            return Err(DecodeError::InvalidParameter {
                name: "k",
                value: self.k.to_string(),
                reason: format!("must be between 1 and the {} training samples", x.nrows()),
            });
        }
        Ok(Knn {
            k: self.k,
            x: x.to_owned(),
            y: y.to_vec(),
            x_sq: Default::default(),
        })
    }
}

impl Knn {
    /// Neighbours consulted.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Features expected.
    pub fn n_features(&self) -> usize {
        self.x.ncols()
    }

    /// Indices of the `k` training samples nearest to `q`, nearest first (ties: lower index first).
    pub fn neighbours(&self, q: ArrayView1<f64>) -> Result<Vec<usize>> {
        check_n_features("k-NN query", self.n_features(), q.len())?;
        let q2 = q.insert_axis(Axis(0));
        let d = self.sq_distances(q2);
        let mut best = Vec::with_capacity(self.k + 1);
        self.k_smallest(d.row(0), &mut best);
        Ok(best.into_iter().map(|(_, i)| i).collect())
    }

    /// Squared distances `(n_queries, n_train)` as `‖q‖² + ‖x‖² − 2 q·x` (one matrix product, the
    /// formula scikit-learn's brute-force search uses), clipped at 0.
    fn sq_distances(&self, q: ArrayView2<f64>) -> Array2<f64> {
        let x_sq = self
            .x_sq
            .get_or_init(|| crate::linalg::row_sq_norms(self.x.view()));
        crate::linalg::sq_distances(q, self.x.view(), x_sq)
    }

    /// The training rows, which [`crate::classifiers::ensemble::SoftVote`] may measure queries against once for
    /// several members.
    pub fn training_rows(&self) -> ArrayView2<'_, f64> {
        self.x.view()
    }

    /// [`Self::predict_proba`] from squared distances `(n_queries, n_train)` to the training rows.
    pub fn predict_proba_from_sq_distances(&self, d2: ArrayView2<f64>) -> Result<Array1<f64>> {
        check_n_features("k-NN distances", self.x.nrows(), d2.ncols())?;
        let mut best = Vec::with_capacity(self.k + 1);
        let k = self.k as f64;
        Ok(d2
            .outer_iter()
            .map(|row| {
                self.k_smallest(row, &mut best);
                best.iter().filter(|&&(_, i)| self.y[i]).count() as f64 / k
            })
            .collect())
    }

    /// The `k` smallest entries of a distance row as (distance, index), ascending; equal distances
    /// keep the lower index first.
    fn k_smallest(&self, d: ArrayView1<f64>, best: &mut Vec<(f64, usize)>) {
        best.clear();
        for (i, &v) in d.iter().enumerate() {
            if best.len() == self.k && v >= best[self.k - 1].0 {
                continue;
            }
            let pos = best.partition_point(|&(bd, _)| bd <= v);
            best.insert(pos, (v, i));
            best.truncate(self.k);
        }
    }

    /// P(target) per row of `x`: the target fraction of its `k` nearest training samples.
    pub fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        check_n_features("k-NN input", self.n_features(), x.ncols())?;
        check_finite(x, "k-NN input")?;
        let mut out = Vec::with_capacity(x.nrows());
        for block in x.axis_chunks_iter(Axis(0), 256) {
            out.extend(self.predict_proba_from_sq_distances(self.sq_distances(block).view())?);
        }
        Ok(Array1::from(out))
    }

    /// The continuous score: P(target) itself (as the peer scores its k-NN).
    pub fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.predict_proba(x)
    }

    /// Majority vote: P(target) > ½ (scikit-learn's argmax, ties to the non-target class).
    pub fn predict(&self, x: ArrayView2<f64>) -> Result<Vec<bool>> {
        Ok(self.predict_proba(x)?.iter().map(|&p| p > 0.5).collect())
    }
}

impl ProbabilisticClassifier for Knn {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Knn::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Knn::decision_function(self, x)
    }
    fn distance_rows(&self) -> Option<ArrayView2<'_, f64>> {
        Some(self.training_rows())
    }
    fn predict_proba_from_sq_distances(&self, d2: Array2<f64>) -> Result<Array1<f64>> {
        Knn::predict_proba_from_sq_distances(self, d2.view())
    }
}

impl FitClassifier for KnnParams {
    type Fitted = Knn;
    fn fit_classifier(&self, x: FeatureView<'_>, y: &[bool], _: usize) -> Result<Knn> {
        self.fit(x.rows("k-NN")?, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn fractions_of_target_neighbours() {
        let x = array![[0.0], [1.0], [2.0], [10.0], [11.0], [12.0]];
        let y = [true, true, false, false, false, true];
        let m = KnnParams::default().fit(x.view(), &y).unwrap();
        let p = m
            .predict_proba(array![[0.4], [11.2], [6.0]].view())
            .unwrap();
        assert_eq!(p, array![2.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0]);
        assert_eq!(m.predict(array![[0.4]].view()).unwrap(), vec![true]);
    }

    #[test]
    fn ties_go_to_the_earlier_training_sample() {
        // query at 0: training points at -1 (target, index 0) and +1 (non-target, index 1)
        let x = array![[-1.0], [1.0], [5.0]];
        let y = [true, false, false];
        let m = KnnParams { k: 1 }.fit(x.view(), &y).unwrap();
        assert_eq!(m.neighbours(array![0.0].view()).unwrap(), vec![0]);
        let x2 = array![[1.0], [-1.0], [5.0]];
        let m2 = KnnParams { k: 1 }
            .fit(x2.view(), &[false, true, true])
            .unwrap();
        assert_eq!(m2.predict_proba(array![[0.0]].view()).unwrap()[0], 0.0);
    }

    #[test]
    fn rejects_bad_input() {
        let x = array![[0.0], [1.0]];
        assert!(KnnParams { k: 3 }.fit(x.view(), &[true, false]).is_err());
        assert!(KnnParams { k: 0 }.fit(x.view(), &[true, false]).is_err());
        assert!(KnnParams { k: 1 }.fit(x.view(), &[true, true]).is_err());
        let m = KnnParams { k: 1 }.fit(x.view(), &[true, false]).unwrap();
        assert!(m.predict_proba(array![[0.0, 1.0]].view()).is_err());
    }
}
