//! The paper's "multi-classifier": a soft-voting ensemble whose P(target) is the (weighted) mean of its
//! members' P(target), as scikit-learn's `VotingClassifier(voting='soft')`.
//!
//! [`ProbabilisticClassifier`] is the small interface a member needs; [`Svm`] and [`Knn`] implement
//! it here. Fitted ensembles are generic over the member type so any serde-able classifier can join;
//! the default member type [`Member`] is an enum of this crate's SVM and k-NN, which keeps saved
//! ensembles self-describing. [`SoftVoteParams::paper`] is the paper's ensemble: an RBF SVM with
//! 5-fold Platt calibration and a 3-NN, equally weighted. Written here: it is an average.
//!
//! Members that score by Euclidean distance to stored rows (the k-NN to its training rows, the RBF
//! SVM to its support vectors, which are training rows too when both were fitted on the same data)
//! share one distance computation: on first use the ensemble finds each member's rows among the
//! largest member's by their exact bits, then measures every query against those rows once
//! (`linalg::sq_distances`, the formula both members use alone) and hands each member its
//! columns. The scores are the members' own, bit for bit (tested); a member whose rows are not all
//! found scores alone.

use std::collections::HashMap;
use std::sync::OnceLock;

use ndarray::{Array1, Array2, ArrayView2, Axis};
use serde::{Deserialize, Serialize};

use crate::classifiers::knn::{Knn, KnnParams};
use crate::features::scaler::{check_finite, check_n_features};
use crate::classifiers::svm::{Svm, SvmParams};
use crate::traits::{FeatureView, FitClassifier};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

pub use crate::traits::ProbabilisticClassifier;

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

impl Member {
    fn inner(&self) -> &dyn ProbabilisticClassifier {
        match self {
            Member::Svm(m) => m,
            Member::Knn(m) => m,
        }
    }
}

impl ProbabilisticClassifier for Member {
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.inner().predict_proba(x)
    }
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.inner().decision_function(x)
    }
    fn distance_rows(&self) -> Option<ArrayView2<'_, f64>> {
        self.inner().distance_rows()
    }
    fn predict_proba_from_sq_distances(&self, d2: Array2<f64>) -> Result<Array1<f64>> {
        self.inner().predict_proba_from_sq_distances(d2)
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
    /// Which members share one distance computation, found on first use (not saved).
    #[serde(skip)]
    shared: OnceLock<Option<SharedDistances>>,
}

/// Members measuring queries against rows of one member's (see the module docs).
#[derive(Debug, Clone)]
struct SharedDistances {
    /// The member whose rows are measured (the one with the most).
    base: usize,
    /// Squared norms of its rows.
    rows_sq: Array1<f64>,
    /// Per member, its rows' indices among the base's; `None`: it scores alone.
    columns: Vec<Option<Vec<usize>>>,
}

impl SharedDistances {
    /// The sharing of `members`, if at least two can share.
    fn plan<M: ProbabilisticClassifier>(members: &[M]) -> Option<Self> {
        let (_, base) = members
            .iter()
            .enumerate()
            .filter_map(|(i, m)| m.distance_rows().map(|r| (r.nrows(), i)))
            .max()?;
        let rows = members[base].distance_rows()?;
        // rows indexed by their first and last values, then compared whole, bit for bit
        let key = |r: ndarray::ArrayView1<f64>| {
            [r.first(), r.last()].map(|v| v.map_or(0, |v| v.to_bits()))
        };
        let mut index: HashMap<[u64; 2], Vec<usize>> = HashMap::new();
        for (i, r) in rows.outer_iter().enumerate() {
            index.entry(key(r)).or_default().push(i);
        }
        let find = |r: ndarray::ArrayView1<f64>| {
            index.get(&key(r))?.iter().copied().find(|&i| {
                rows.row(i)
                    .iter()
                    .zip(&r)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            })
        };
        let columns: Vec<Option<Vec<usize>>> = members
            .iter()
            .map(|m| {
                let own = m.distance_rows().filter(|r| r.ncols() == rows.ncols())?;
                own.outer_iter().map(find).collect()
            })
            .collect();
        (columns.iter().flatten().count() >= 2).then(|| Self {
            base,
            rows_sq: crate::linalg::row_sq_norms(rows),
            columns,
        })
    }
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
            shared: OnceLock::new(),
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
        let shared = self
            .shared
            .get_or_init(|| SharedDistances::plan(&self.members));
        let Some(plan) = shared else {
            let mut acc = Array1::<f64>::zeros(x.nrows());
            for (m, &w) in self.members.iter().zip(&self.weights) {
                acc.scaled_add(w, &m.predict_proba(x)?);
            }
            return Ok(acc);
        };
        let rows = self.members[plan.base]
            .distance_rows()
            .expect("the plan's base member has rows");
        check_n_features("soft-vote input", rows.ncols(), x.ncols())?;
        check_finite(x, "soft-vote input")?;
        let mut out = Vec::with_capacity(x.nrows());
        for block in x.axis_chunks_iter(Axis(0), 256) {
            let d2 = crate::linalg::sq_distances(block, rows, &plan.rows_sq);
            let mut acc = Array1::<f64>::zeros(block.nrows());
            for ((m, &w), columns) in self.members.iter().zip(&self.weights).zip(&plan.columns) {
                let p = match columns {
                    // row-major, as the member's own distances (a product's rounding follows layout)
                    Some(c) => m.predict_proba_from_sq_distances(Array2::from_shape_fn(
                        (d2.nrows(), c.len()),
                        |(i, j)| d2[[i, c[j]]],
                    ))?,
                    None => m.predict_proba(block)?,
                };
                acc.scaled_add(w, &p);
            }
            out.extend(acc);
        }
        Ok(Array1::from(out))
    }

    /// The ensemble's score is its P(target) (as the peer scores its vote).
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.predict_proba(x)
    }
}

impl FitClassifier for SoftVoteParams {
    type Fitted = SoftVote;
    fn fit_classifier(&self, x: FeatureView<'_>, y: &[bool], _: usize) -> Result<SoftVote> {
        self.fit(x.rows("soft vote")?, y)
    }
    fn with_scale_gamma(&self, gamma: f64) -> Self {
        SoftVoteParams {
            members: self
                .members
                .iter()
                .map(|m| match m {
                    MemberParams::Svm(p) => MemberParams::Svm(p.with_scale_gamma(gamma)),
                    m => *m,
                })
                .collect(),
            weights: self.weights.clone(),
        }
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

    /// Two overlapping classes in 12 dimensions, deterministic.
    fn overlapping(n: usize, seed: usize) -> (Array2<f64>, Vec<bool>) {
        let y: Vec<bool> = (0..n).map(|i| i % 4 == 0).collect();
        let x = Array2::from_shape_fn((n, 12), |(i, j)| {
            let c = if y[i] { 0.6 } else { -0.2 };
            c + (((i + seed) * 31 + j * 17) as f64 * 0.7).sin() * (1.0 + j as f64 * 0.1)
        });
        (x, y)
    }

    #[test]
    fn shared_distances_give_the_members_own_scores_bit_for_bit() {
        let (x, y) = overlapping(200, 0);
        let v = SoftVoteParams::paper().fit(x.view(), &y).unwrap();
        let plan = SharedDistances::plan(v.members()).expect("SVM and k-NN share the rows");
        assert_eq!(plan.base, 1, "the k-NN holds every training row");
        let n_sv = match &v.members()[0] {
            Member::Svm(s) => s.n_support(),
            Member::Knn(_) => unreachable!(),
        };
        assert!(n_sv > 10 && n_sv < 200, "{n_sv} support vectors");
        assert_eq!(plan.columns[0].as_ref().map(Vec::len), Some(n_sv));
        // one query, a few (one dot product per entry), and more than a block of 256
        let (q, _) = overlapping(300, 1000);
        for n in [1usize, 5, 16, 300] {
            let q = q.slice(ndarray::s![..n, ..]);
            let got = v.predict_proba(q).unwrap();
            let mut want = Array1::<f64>::zeros(n);
            for (m, &w) in v.members().iter().zip(v.weights()) {
                want.scaled_add(w, &m.predict_proba(q).unwrap());
            }
            assert_eq!(got, want, "{n} queries");
        }
        assert!(v.predict_proba(Array2::zeros((1, 3)).view()).is_err());
        assert!(v
            .predict_proba(Array2::from_elem((1, 12), f64::NAN).view())
            .is_err());
    }

    #[test]
    fn members_fitted_on_other_rows_score_alone() {
        let (x, y) = overlapping(120, 0);
        let (x2, y2) = overlapping(120, 7);
        let svm = MemberParams::Svm(SvmParams::default())
            .fit(x.view(), &y)
            .unwrap();
        let knn = MemberParams::Knn(KnnParams::default())
            .fit(x2.view(), &y2)
            .unwrap();
        let linear = MemberParams::Svm(SvmParams {
            kernel: crate::classifiers::svm::Kernel::Linear,
            ..SvmParams::default()
        })
        .fit(x.view(), &y)
        .unwrap();
        assert!(SharedDistances::plan(&[svm.clone(), knn.clone()]).is_none());
        assert!(SharedDistances::plan(&[linear, knn.clone()]).is_none());
        let v = SoftVote::from_fitted(vec![svm.clone(), knn.clone()], None).unwrap();
        let (q, _) = overlapping(3, 500);
        let want =
            (svm.predict_proba(q.view()).unwrap() + knn.predict_proba(q.view()).unwrap()) / 2.0;
        let got = v.predict_proba(q.view()).unwrap();
        assert!(got.iter().zip(&want).all(|(a, b)| (a - b).abs() < 1e-15));
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
