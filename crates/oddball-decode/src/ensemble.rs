//! The paper's "multi-classifier": a soft-voting ensemble whose P(target) is the (weighted) mean of its
//! members' P(target), as scikit-learn's `VotingClassifier(voting='soft')`.
//!
//! [`ProbabilisticClassifier`] is the small interface a member needs; [`Svm`] and [`Knn`] implement
//! it here. Fitted ensembles are generic over the member type so any serde-able classifier can join;
//! the default member type [`Member`] is an enum of this crate's SVM and k-NN, which keeps saved
//! ensembles self-describing. [`SoftVoteParams::paper`] is the paper's ensemble: an RBF SVM with
//! 5-fold Platt calibration and a 3-NN, equally weighted. Written here: it is an average.

use ndarray::{Array1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::knn::{Knn, KnnParams};
use crate::svm::{Svm, SvmParams};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// A fitted binary classifier that scores and gives P(target).
pub trait ProbabilisticClassifier {
    /// P(target) per row of `x` `(n_samples, n_features)`.
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>>;
    /// Continuous score per row, larger = more target-like.
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>>;
}

impl ProbabilisticClassifier for Svm {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Svm::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Svm::decision_function(self, x)
    }
}

impl ProbabilisticClassifier for Knn {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Knn::predict_proba(self, x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        Knn::decision_function(self, x)
    }
}

/// Unfitted member settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum MemberParams {
    Svm(SvmParams),
    Knn(KnnParams),
}

/// A fitted member.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub enum Member {
    Svm(Svm),
    Knn(Knn),
}

impl MemberParams {
    /// Fits this member on `x`, `y`.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<Member> {
        Ok(match self {
            MemberParams::Svm(p) => Member::Svm(p.fit(x, y)?),
            MemberParams::Knn(p) => Member::Knn(p.fit(x, y)?),
        })
    }
}

impl ProbabilisticClassifier for Member {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        match self {
            Member::Svm(m) => m.predict_proba(x),
            Member::Knn(m) => m.predict_proba(x),
        }
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        match self {
            Member::Svm(m) => m.decision_function(x),
            Member::Knn(m) => m.decision_function(x),
        }
    }
}

/// Unfitted soft-vote settings: members and optional weights (equal when `None`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SoftVoteParams {
    pub members: Vec<MemberParams>,
    pub weights: Option<Vec<f64>>,
}

impl SoftVoteParams {
    /// The paper's multi-classifier: RBF SVM (C = 1, γ = 'scale', 5-fold Platt) + 3-NN, equal weights.
    pub fn paper() -> Self {
        Self {
            members: vec![
                MemberParams::Svm(SvmParams::default()),
                MemberParams::Knn(KnnParams::default()),
            ],
            weights: None,
        }
    }

    /// Fits every member on the same data.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<SoftVote> {
        let members = self
            .members
            .iter()
            .map(|m| m.fit(x, y))
            .collect::<Result<Vec<_>>>()?;
        SoftVote::from_fitted(members, self.weights.clone())
    }
}

/// A fitted soft-vote ensemble over members of type `M`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SoftVote<M = Member> {
    members: Vec<M>,
    /// Normalised weights (sum 1).
    weights: Vec<f64>,
}

impl<M: ProbabilisticClassifier> SoftVote<M> {
    /// An ensemble of already fitted members; `weights` (non-negative, positive sum) default to equal.
    pub fn from_fitted(members: Vec<M>, weights: Option<Vec<f64>>) -> Result<Self> {
        if members.is_empty() {
            return Err(DecodeError::InvalidParameter {
                name: "members",
                value: "[]".into(),
                reason: "an ensemble needs at least one member".into(),
            });
        }
        let w = weights.unwrap_or_else(|| vec![1.0; members.len()]);
        let total: f64 = w.iter().sum();
        if w.len() != members.len()
            || w.iter().any(|v| !(v.is_finite() && *v >= 0.0))
            || total.is_nan()
            || total <= 0.0
        {
            return Err(DecodeError::InvalidParameter {
                name: "weights",
                value: format!("{w:?}"),
                reason: format!(
                    "need {} finite non-negative weights with a positive sum",
                    members.len()
                ),
            });
        }
        Ok(Self {
            members,
            weights: w.iter().map(|v| v / total).collect(),
        })
    }

    /// The members.
    pub fn members(&self) -> &[M] {
        &self.members
    }

    /// The normalised weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
}

impl<M: ProbabilisticClassifier> ProbabilisticClassifier for SoftVote<M> {
    /// Weighted mean of the members' P(target).
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        let mut acc = Array1::<f64>::zeros(x.nrows());
        for (m, &w) in self.members.iter().zip(&self.weights) {
            acc.scaled_add(w, &m.predict_proba(x)?);
        }
        Ok(acc)
    }

    /// The ensemble's score is its P(target) (as the peer scores its vote).
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.predict_proba(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{array, Array2};

    struct Fixed(f64);
    impl ProbabilisticClassifier for Fixed {
        fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
            Ok(Array1::from_elem(x.nrows(), self.0))
        }
        fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
            self.predict_proba(x)
        }
    }

    #[test]
    fn weighted_mean_of_members() {
        let x = Array2::<f64>::zeros((2, 1));
        let v = SoftVote::from_fitted(vec![Fixed(0.2), Fixed(0.8)], None).unwrap();
        assert!(v
            .predict_proba(x.view())
            .unwrap()
            .iter()
            .all(|p| (p - 0.5).abs() < 1e-15));
        let w = SoftVote::from_fitted(vec![Fixed(0.2), Fixed(0.8)], Some(vec![3.0, 1.0])).unwrap();
        assert!((w.decision_function(x.view()).unwrap()[0] - 0.35).abs() < 1e-15);
        assert!(SoftVote::from_fitted(Vec::<Fixed>::new(), None).is_err());
        assert!(SoftVote::from_fitted(vec![Fixed(0.1)], Some(vec![0.0])).is_err());
        assert!(SoftVote::from_fitted(vec![Fixed(0.1)], Some(vec![1.0, 1.0])).is_err());
    }

    #[test]
    fn paper_ensemble_fits_and_round_trips() {
        let x = Array2::from_shape_fn((30, 2), |(i, j)| {
            let c = if i % 3 == 0 { 1.0 } else { -1.0 };
            c + 0.4 * ((i * 7 + j * 3) as f64).sin()
        });
        let y: Vec<bool> = (0..30).map(|i| i % 3 == 0).collect();
        let v = SoftVoteParams::paper().fit(x.view(), &y).unwrap();
        let p = v
            .predict_proba(array![[1.0, 1.0], [-1.0, -1.0]].view())
            .unwrap();
        assert!(p[0] > 0.7 && p[1] < 0.3, "{p}");
        let json = serde_json::to_string(&v).unwrap();
        let back: SoftVote = serde_json::from_str(&json).unwrap();
        // serde_json's default float parsing may be off by one ulp
        let (a, b) = (
            back.predict_proba(x.view()).unwrap(),
            v.predict_proba(x.view()).unwrap(),
        );
        assert!(a.iter().zip(&b).all(|(p, q)| (p - q).abs() < 1e-12));
    }
}
