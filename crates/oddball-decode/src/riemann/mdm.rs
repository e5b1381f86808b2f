//! Minimum distance to (Riemannian) mean, as pyRiemann's `MDM`.

use nalgebra::DMatrix;
use ndarray::parallel::prelude::*;
use ndarray::{Array1, Array2, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use super::{
    mean_riemann_dm, spd_matrices, squared_distance_whitened, MeanRiemannParams, Metric, Scratch,
};
use crate::linalg::{check_labels, eigen_function, sigmoid, spd_eigen, symmetric_from, to_array2};
use crate::traits::{FeatureView, FitClassifier, Scorer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of [`Mdm`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct MdmParams {
    pub metric: Metric,
    /// Settings of the per-class Riemannian means.
    pub mean: MeanRiemannParams,
}

impl MdmParams {
    /// One Riemannian mean per class of `covs` `(n_matrices, n, n)`, labels `y` (`true` = target).
    pub fn fit(&self, covs: ArrayView3<f64>, y: &[bool]) -> Result<Mdm> {
        let Metric::Riemann = self.metric;
        check_labels(covs.dim().0, y)?;
        let mats = spd_matrices("MDM training matrices", covs)?;
        let mut means = Vec::with_capacity(2);
        for class in [false, true] {
            let members: Vec<&DMatrix<f64>> = mats
                .iter()
                .zip(y)
                .filter(|(_, &t)| t == class)
                .map(|(m, _)| m)
                .collect();
            let (mean, _, _) = mean_riemann_dm(&members, &self.mean)?;
            means.push(to_array2(&mean));
        }
        let target = means.pop().expect("two class means");
        let nontarget = means.pop().expect("two class means");
        Mdm::from_means(nontarget.view(), target.view())
    }
}

/// Minimum distance to (Riemannian) mean, binary.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "MdmRepr", into = "MdmRepr")]
pub struct Mdm {
    mean_nontarget: Array2<f64>,
    mean_target: Array2<f64>,
    /// `M^{-1/2}` of the non-target and target means.
    invsqrt: [DMatrix<f64>; 2],
}

#[derive(Serialize, Deserialize)]
struct MdmRepr {
    metric: Metric,
    mean_nontarget: Array2<f64>,
    mean_target: Array2<f64>,
}

impl TryFrom<MdmRepr> for Mdm {
    type Error = DecodeError;
    fn try_from(r: MdmRepr) -> Result<Self> {
        Self::from_means(r.mean_nontarget.view(), r.mean_target.view())
    }
}

impl From<Mdm> for MdmRepr {
    fn from(m: Mdm) -> Self {
        Self {
            metric: Metric::Riemann,
            mean_nontarget: m.mean_nontarget,
            mean_target: m.mean_target,
        }
    }
}

impl Mdm {
    /// The classifier with given class means (SPD, same size).
    pub fn from_means(
        mean_nontarget: ArrayView2<f64>,
        mean_target: ArrayView2<f64>,
    ) -> Result<Self> {
        let nt = symmetric_from("MDM non-target mean", mean_nontarget)?;
        let t = symmetric_from("MDM target mean", mean_target)?;
        if nt.nrows() != t.nrows() {
            return Err(DecodeError::ShapeMismatch {
                what: "MDM target mean".to_string(),
                expected: format!("{n}×{n}", n = nt.nrows()),
                got: format!("{n}×{n}", n = t.nrows()),
            });
        }
        let inv = |m: &DMatrix<f64>, what: &str| -> Result<DMatrix<f64>> {
            let eig = spd_eigen(what, m.clone())?;
            Ok(eigen_function(&eig, |l| 1.0 / l.sqrt()))
        };
        Ok(Self {
            invsqrt: [
                inv(&nt, "MDM non-target mean")?,
                inv(&t, "MDM target mean")?,
            ],
            mean_nontarget: to_array2(&nt),
            mean_target: to_array2(&t),
        })
    }

    /// Riemannian mean of the non-target class.
    pub fn mean_nontarget(&self) -> ArrayView2<'_, f64> {
        self.mean_nontarget.view()
    }

    /// Riemannian mean of the target class.
    pub fn mean_target(&self) -> ArrayView2<'_, f64> {
        self.mean_target.view()
    }

    /// Side `n` of the matrices.
    pub fn n_channels(&self) -> usize {
        self.mean_target.nrows()
    }

    /// Distances `(n_matrices, 2)` to the class means: column 0 non-target, column 1 target
    /// (pyRiemann's `MDM.transform` for classes `[False, True]`).
    pub fn distances(&self, covs: ArrayView3<f64>) -> Result<Array2<f64>> {
        let mut out = Array2::zeros((covs.dim().0, 2));
        let mut scratch = Scratch::default();
        for (c, mut row) in covs.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            let d2 = self.squared_distances(c, &mut scratch)?;
            row[0] = d2[0].sqrt();
            row[1] = d2[1].sqrt();
        }
        Ok(out)
    }

    /// Scores `d²(C, M_non-target) − d²(C, M_target)` (larger = more target-like).
    pub fn decision_function(&self, covs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let mut scratch = Scratch::default();
        covs.outer_iter()
            .map(|c| {
                let d2 = self.squared_distances(c, &mut scratch)?;
                Ok(d2[0] - d2[1])
            })
            .collect()
    }

    /// Score of one SPD matrix `(n, n)`.
    pub fn decision_one(&self, c: ArrayView2<f64>) -> Result<f64> {
        let d2 = self.squared_distances(c, &mut Scratch::default())?;
        Ok(d2[0] - d2[1])
    }

    /// P(target): the sigmoid of the score (pyRiemann's softmax of `−d²` over the two classes).
    pub fn predict_proba(&self, covs: ArrayView3<f64>) -> Result<Array1<f64>> {
        Ok(self.decision_function(covs)?.mapv(sigmoid))
    }

    fn squared_distances(&self, c: ArrayView2<f64>, s: &mut Scratch) -> Result<[f64; 2]> {
        let n = self.n_channels();
        if c.dim() != (n, n) {
            return Err(DecodeError::ShapeMismatch {
                what: "MDM input".to_string(),
                expected: format!("{n}×{n} matrices"),
                got: format!("{}×{}", c.nrows(), c.ncols()),
            });
        }
        s.input = symmetric_from("MDM input", c)?;
        let mut d2 = [0.0; 2];
        for (k, inv) in self.invsqrt.iter().enumerate() {
            d2[k] = squared_distance_whitened(inv, &s.input, &mut s.tmp, &mut s.white)?;
        }
        Ok(d2)
    }
}

impl FitClassifier for MdmParams {
    type Fitted = Mdm;
    fn fit_classifier(&self, x: FeatureView<'_>, y: &[bool], _: usize) -> Result<Mdm> {
        self.fit(x.spd("MDM")?, y)
    }
}

/// MDM scores SPD matrices `(n_epochs, n, n)` (the output of
/// [`crate::features::FeatureParams::XdawnCovariances`]): `d²(C, M_non-target) − d²(C, M_target)`
/// (larger = closer to the target mean).
impl Scorer for Mdm {
    fn predict_proba(&self, x: FeatureView<'_>) -> Result<Array1<f64>> {
        Ok(Scorer::decision_function(self, x)?.mapv(sigmoid))
    }
    fn decision_function(&self, x: FeatureView<'_>) -> Result<Array1<f64>> {
        let covs = x.spd("MDM")?;
        let n = self.n_channels();
        if covs.dim().1 != n || covs.dim().2 != n {
            return Err(DecodeError::ShapeMismatch {
                what: "MDM input".into(),
                expected: format!("{n}×{n} matrices"),
                got: format!("{}×{}", covs.dim().1, covs.dim().2),
            });
        }
        // Matrices are independent: spread them over rayon's threads.
        let scores = covs
            .axis_iter(Axis(0))
            .into_par_iter()
            .map(|m| self.decision_one(m))
            .collect::<Result<Vec<f64>>>()?;
        Ok(Array1::from(scores))
    }
}
