//! Affine-invariant Riemannian geometry of symmetric positive-definite (SPD) matrices, and the two
//! classifiers built on it: minimum distance to mean ([`Mdm`]) and tangent-space projection
//! ([`TangentSpace`]), as pyRiemann 0.12 defines them.
//!
//! * Matrix functions of SPD matrices ([`sqrtm`], [`invsqrtm`], [`logm`]) and of symmetric matrices
//!   ([`expm`]) through the symmetric eigendecomposition `C = V Λ Vᵀ → V f(Λ) Vᵀ`.
//! * [`distance_riemann`]: `d(A, B) = ‖log(B^{-1/2} A B^{-1/2})‖_F = sqrt(Σ ln² λ_i)` with `λ_i` the
//!   generalized eigenvalues of `(A, B)`; dimensionless, symmetric, and invariant under
//!   `A ↦ M A Mᵀ, B ↦ M B Mᵀ` for any invertible `M`.
//! * [`mean_riemann`]: the Karcher mean by pyRiemann's `mean_riemann` gradient descent — start at the
//!   arithmetic mean, `J = Σ w_i log(M^{-1/2} C_i M^{-1/2})`, `M ← M^{1/2} exp(ν J) M^{1/2}`, step `ν`
//!   (start 1) times 0.95 while `ν‖J‖_F` decreases and halved otherwise, stop when `‖J‖_F ≤ tol` or
//!   `ν ≤ tol` (default `tol = 1e-8`, at most 50 iterations). Not converging is reported in
//!   [`RiemannMean::converged`], not as an error (pyRiemann warns and returns the iterate).
//! * Tangent space at a reference `C_ref`: `upper(log(C_ref^{-1/2} C C_ref^{-1/2}))`, where [`upper`]
//!   lists the upper triangle row by row (`(0,0), (0,1), …, (0,n−1), (1,1), …`) with off-diagonal
//!   entries × √2, so the Euclidean norm of the vector equals the Riemannian distance to `C_ref`.
//!   [`untangent_space`] inverts it: `C_ref^{1/2} exp(unupper(t)) C_ref^{1/2}`.
//! * [`MdmParams::fit`] → [`Mdm`]: one Riemannian mean per class; the score is
//!   `d²(C, M_non-target) − d²(C, M_target)` and P(target) its sigmoid (pyRiemann's softmax of `−d²`).
//! * [`TangentSpaceParams::fit`] → [`TangentSpace`]: reference = Riemannian mean of the training
//!   matrices; vectors of length `n(n+1)/2`.
//!
//! Covariances are in µV² (any unit works: distances, scores and tangent vectors are dimensionless).
//!
//! Written here: no well-kept Rust crate provides affine-invariant Riemannian means, tangent spaces
//! or MDM on SPD matrices; checked against pyRiemann 0.12 in `tests/linear_riemann_golden.rs`.

use nalgebra::DMatrix;
use ndarray::{Array1, Array2, Array3, ArrayView1, ArrayView2, ArrayView3, ArrayViewMut1, Axis};
use serde::{Deserialize, Serialize};

use crate::linalg::{
    check_labels, congruence_into, eigen_function, eigen_function_into, eigen_function_upper,
    generalized_eigenvalues, sigmoid, spd_eigen, sym_eigen, sym_eigenvalues, symmetric_from,
    to_array2,
};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// The Riemannian metric used for means, maps and distances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Metric {
    /// The affine-invariant metric.
    #[default]
    Riemann,
}

/// Square root of an SPD matrix.
pub fn sqrtm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("sqrtm input", c, f64::sqrt)
}

/// Inverse square root of an SPD matrix.
pub fn invsqrtm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("invsqrtm input", c, |l| 1.0 / l.sqrt())
}

/// Principal logarithm of an SPD matrix (a symmetric matrix).
pub fn logm(c: ArrayView2<f64>) -> Result<Array2<f64>> {
    spd_function("logm input", c, f64::ln)
}

/// Exponential of a symmetric matrix (an SPD matrix).
pub fn expm(s: ArrayView2<f64>) -> Result<Array2<f64>> {
    let m = symmetric_from("expm input", s)?;
    let eig = sym_eigen("expm input", m)?;
    Ok(to_array2(&eigen_function(&eig, f64::exp)))
}

fn spd_function(what: &str, c: ArrayView2<f64>, f: impl Fn(f64) -> f64) -> Result<Array2<f64>> {
    let m = symmetric_from(what, c)?;
    let eig = spd_eigen(what, m)?;
    Ok(to_array2(&eigen_function(&eig, f)))
}

/// Affine-invariant Riemannian distance between two SPD matrices (dimensionless).
pub fn distance_riemann(a: ArrayView2<f64>, b: ArrayView2<f64>) -> Result<f64> {
    let a = symmetric_from("distance: first matrix", a)?;
    let b = symmetric_from("distance: second matrix", b)?;
    if a.nrows() != b.nrows() {
        return Err(DecodeError::ShapeMismatch {
            what: "distance: second matrix".to_string(),
            expected: format!("{n}×{n}", n = a.nrows()),
            got: format!("{n}×{n}", n = b.nrows()),
        });
    }
    // λ: generalized eigenvalues of (A, B), all positive iff A is SPD (B being SPD).
    let l = generalized_eigenvalues("distance", &a, &b)?;
    if l.iter().all(|&v| v > 0.0) {
        Ok(l.iter().map(|v| v.ln().powi(2)).sum::<f64>().sqrt())
    } else {
        Err(DecodeError::NotPositiveDefinite {
            what: "distance: first matrix".to_string(),
        })
    }
}

/// `d²(C, R)` from `R^{-1/2}`: the eigenvalues of `R^{-1/2} C R^{-1/2}`.
fn squared_distance_whitened(
    r_invsqrt: &DMatrix<f64>,
    c: &DMatrix<f64>,
    tmp: &mut DMatrix<f64>,
    w: &mut DMatrix<f64>,
) -> Result<f64> {
    congruence_into(r_invsqrt, c, tmp, w);
    let l = sym_eigenvalues("whitened matrix", w)?;
    if l.iter().all(|&v| v > 0.0) {
        Ok(l.iter().map(|v| v.ln().powi(2)).sum())
    } else {
        Err(DecodeError::NotPositiveDefinite {
            what: format!("matrix in distance (whitened eigenvalue {:e})", l.min()),
        })
    }
}

/// Settings of the Karcher-mean gradient descent (pyRiemann's defaults).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanRiemannParams {
    /// Stop when the Frobenius norm of the Riemannian gradient, or the step size, is ≤ `tol`.
    pub tol: f64,
    /// Maximum number of iterations.
    pub max_iter: usize,
}

impl Default for MeanRiemannParams {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            max_iter: 50,
        }
    }
}

/// Result of [`mean_riemann`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RiemannMean {
    /// The mean, SPD `(n, n)`.
    pub mean: Array2<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Whether a stopping criterion was met within `max_iter` iterations.
    pub converged: bool,
}

/// Riemannian (Karcher) mean of SPD matrices `covs` `(n_matrices, n, n)` with equal weights.
pub fn mean_riemann(covs: ArrayView3<f64>, params: &MeanRiemannParams) -> Result<RiemannMean> {
    let mats = spd_matrices("mean_riemann input", covs)?;
    let refs: Vec<&DMatrix<f64>> = mats.iter().collect();
    let (mean, iterations, converged) = mean_riemann_dm(&refs, params)?;
    Ok(RiemannMean {
        mean: to_array2(&mean),
        iterations,
        converged,
    })
}

/// Converts `(n_matrices, n, n)` to checked symmetric matrices; each is verified SPD.
fn spd_matrices(what: &str, covs: ArrayView3<f64>) -> Result<Vec<DMatrix<f64>>> {
    let (k, r, c) = covs.dim();
    if k == 0 || r != c || r == 0 {
        return Err(DecodeError::ShapeMismatch {
            what: what.to_string(),
            expected: "(n_matrices ≥ 1, n, n) with n ≥ 1".to_string(),
            got: format!("({k}, {r}, {c})"),
        });
    }
    covs.outer_iter()
        .enumerate()
        .map(|(i, m)| {
            let m = symmetric_from(&format!("{what} matrix {i}"), m)?;
            if nalgebra::Cholesky::new(m.clone()).is_none() {
                return Err(DecodeError::NotPositiveDefinite {
                    what: format!("{what} matrix {i}"),
                });
            }
            Ok(m)
        })
        .collect()
}

fn mean_riemann_dm(
    mats: &[&DMatrix<f64>],
    params: &MeanRiemannParams,
) -> Result<(DMatrix<f64>, usize, bool)> {
    if !(params.tol >= 0.0 && params.tol.is_finite()) {
        return Err(DecodeError::InvalidParameter {
            name: "tol",
            value: params.tol.to_string(),
            reason: "must be finite and ≥ 0".to_string(),
        });
    }
    let n = mats[0].nrows();
    let w = 1.0 / mats.len() as f64;
    let mut m = DMatrix::zeros(n, n);
    for c in mats {
        m += *c * w;
    }
    let mut nu = 1.0;
    let mut tau = f64::MAX;
    let mut j = DMatrix::zeros(n, n);
    let (mut tmp, mut white, mut log) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
    );
    for iter in 1..=params.max_iter {
        let eig = spd_eigen("Riemannian mean iterate", m.clone())?;
        let m12 = eigen_function(&eig, f64::sqrt);
        let mm12 = eigen_function(&eig, |l| 1.0 / l.sqrt());
        j.fill(0.0);
        for c in mats {
            congruence_into(&mm12, c, &mut tmp, &mut white);
            let e = spd_eigen("whitened matrix in Riemannian mean", white.clone())?;
            eigen_function_into(&e, f64::ln, &mut log);
            j.zip_apply(&log, |a, l| *a += w * l);
        }
        let je = sym_eigen("Riemannian mean gradient", j.clone())?;
        let step = eigen_function(&je, |l| (nu * l).exp());
        congruence_into(&m12, &step, &mut tmp, &mut m);
        let crit = j.norm();
        let h = nu * crit;
        if h < tau {
            nu *= 0.95;
            tau = h;
        } else {
            nu *= 0.5;
        }
        if crit <= params.tol || nu <= params.tol {
            return Ok((m, iter, true));
        }
    }
    Ok((m, params.max_iter, false))
}

/// pyRiemann's `upper`: the upper triangle of a symmetric matrix row by row, off-diagonal × √2.
pub fn upper(s: ArrayView2<f64>) -> Result<Array1<f64>> {
    let (r, c) = s.dim();
    if r != c {
        return Err(DecodeError::ShapeMismatch {
            what: "upper input".to_string(),
            expected: "a square matrix".to_string(),
            got: format!("{r}×{c}"),
        });
    }
    let mut out = Array1::zeros(r * (r + 1) / 2);
    let mut k = 0;
    for i in 0..r {
        out[k] = s[[i, i]];
        k += 1;
        for j in (i + 1)..r {
            out[k] = std::f64::consts::SQRT_2 * s[[i, j]];
            k += 1;
        }
    }
    Ok(out)
}

/// pyRiemann's `unupper`: the symmetric matrix whose [`upper`] is `t` (length `n(n+1)/2`).
pub fn unupper(t: ArrayView1<f64>) -> Result<Array2<f64>> {
    let n = side_from_len(t.len())?;
    let mut out = Array2::zeros((n, n));
    let mut k = 0;
    for i in 0..n {
        out[[i, i]] = t[k];
        k += 1;
        for j in (i + 1)..n {
            let v = t[k] / std::f64::consts::SQRT_2;
            out[[i, j]] = v;
            out[[j, i]] = v;
            k += 1;
        }
    }
    Ok(out)
}

fn side_from_len(len: usize) -> Result<usize> {
    let n = (((8 * len + 1) as f64).sqrt() as usize).saturating_sub(1) / 2;
    if n == 0 || n * (n + 1) / 2 != len {
        return Err(DecodeError::ShapeMismatch {
            what: "tangent vector".to_string(),
            expected: "length n(n+1)/2 for some n ≥ 1".to_string(),
            got: len.to_string(),
        });
    }
    Ok(n)
}

/// Tangent vectors `(n_matrices, n(n+1)/2)` of `covs` `(n_matrices, n, n)` at `reference`.
pub fn tangent_space(covs: ArrayView3<f64>, reference: ArrayView2<f64>) -> Result<Array2<f64>> {
    TangentSpace::from_reference(reference)?.transform(covs)
}

/// SPD matrices `(n_vectors, n, n)` whose tangent vectors at `reference` are the rows of `vectors`.
pub fn untangent_space(
    vectors: ArrayView2<f64>,
    reference: ArrayView2<f64>,
) -> Result<Array3<f64>> {
    TangentSpace::from_reference(reference)?.inverse_transform(vectors)
}

/// Settings of [`TangentSpace`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TangentSpaceParams {
    pub metric: Metric,
    /// Settings of the Riemannian mean that gives the reference point.
    pub mean: MeanRiemannParams,
}

impl TangentSpaceParams {
    /// Reference point = Riemannian mean of the training matrices `covs` `(n_matrices, n, n)`.
    pub fn fit(&self, covs: ArrayView3<f64>) -> Result<TangentSpace> {
        let Metric::Riemann = self.metric;
        let mean = mean_riemann(covs, &self.mean)?;
        TangentSpace::from_reference(mean.mean.view())
    }
}

/// A fitted tangent-space projection at a reference SPD matrix.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "TangentSpaceRepr", into = "TangentSpaceRepr")]
pub struct TangentSpace {
    reference: Array2<f64>,
    sqrt_ref: DMatrix<f64>,
    invsqrt_ref: DMatrix<f64>,
}

#[derive(Serialize, Deserialize)]
struct TangentSpaceRepr {
    metric: Metric,
    reference: Array2<f64>,
}

impl TryFrom<TangentSpaceRepr> for TangentSpace {
    type Error = DecodeError;
    fn try_from(r: TangentSpaceRepr) -> Result<Self> {
        Self::from_reference(r.reference.view())
    }
}

impl From<TangentSpace> for TangentSpaceRepr {
    fn from(t: TangentSpace) -> Self {
        Self {
            metric: Metric::Riemann,
            reference: t.reference,
        }
    }
}

/// Scratch buffers of one projection, reused across matrices (one per thread in batches).
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    input: DMatrix<f64>,
    tmp: DMatrix<f64>,
    white: DMatrix<f64>,
}

impl TangentSpace {
    /// The projection at a given SPD reference `(n, n)`.
    pub fn from_reference(reference: ArrayView2<f64>) -> Result<Self> {
        let r = symmetric_from("tangent-space reference", reference)?;
        let eig = spd_eigen("tangent-space reference", r.clone())?;
        Ok(Self {
            reference: to_array2(&r),
            sqrt_ref: eigen_function(&eig, f64::sqrt),
            invsqrt_ref: eigen_function(&eig, |l| 1.0 / l.sqrt()),
        })
    }

    /// The reference point `(n, n)`.
    pub fn reference(&self) -> ArrayView2<'_, f64> {
        self.reference.view()
    }

    /// Side `n` of the matrices.
    pub fn n_channels(&self) -> usize {
        self.reference.nrows()
    }

    /// Length `n(n+1)/2` of the tangent vectors.
    pub fn n_features(&self) -> usize {
        let n = self.n_channels();
        n * (n + 1) / 2
    }

    /// Tangent vectors `(n_matrices, n(n+1)/2)` of `covs` `(n_matrices, n, n)`.
    pub fn transform(&self, covs: ArrayView3<f64>) -> Result<Array2<f64>> {
        self.check_shape(covs.dim().1, covs.dim().2)?;
        let mut out = Array2::zeros((covs.dim().0, self.n_features()));
        let mut scratch = Scratch::default();
        for (c, row) in covs.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            self.vectorize_into(c, &mut scratch, row)?;
        }
        Ok(out)
    }

    /// Tangent vector `(n(n+1)/2,)` of one SPD matrix `(n, n)`.
    pub fn transform_one(&self, c: ArrayView2<f64>) -> Result<Array1<f64>> {
        self.check_shape(c.nrows(), c.ncols())?;
        let mut out = Array1::zeros(self.n_features());
        self.vectorize_into(c, &mut Scratch::default(), out.view_mut())?;
        Ok(out)
    }

    /// SPD matrices `(n_vectors, n, n)` from tangent vectors `(n_vectors, n(n+1)/2)`.
    pub fn inverse_transform(&self, vectors: ArrayView2<f64>) -> Result<Array3<f64>> {
        if vectors.ncols() != self.n_features() {
            return Err(DecodeError::ShapeMismatch {
                what: "tangent vectors".to_string(),
                expected: format!("{} columns", self.n_features()),
                got: vectors.ncols().to_string(),
            });
        }
        let n = self.n_channels();
        let mut out = Array3::zeros((vectors.nrows(), n, n));
        let (mut tmp, mut c) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
        for (t, mut dst) in vectors.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            let s = symmetric_from("tangent vector", unupper(t)?.view())?;
            let eig = sym_eigen("tangent vector", s)?;
            let e = eigen_function(&eig, f64::exp);
            congruence_into(&self.sqrt_ref, &e, &mut tmp, &mut c);
            dst.indexed_iter_mut()
                .for_each(|((i, j), v)| *v = c[(i, j)]);
        }
        Ok(out)
    }

    fn check_shape(&self, r: usize, c: usize) -> Result<()> {
        let n = self.n_channels();
        if r != n || c != n {
            return Err(DecodeError::ShapeMismatch {
                what: "tangent-space input".to_string(),
                expected: format!("{n}×{n} matrices"),
                got: format!("{r}×{c}"),
            });
        }
        Ok(())
    }

    fn vectorize_into(
        &self,
        c: ArrayView2<f64>,
        s: &mut Scratch,
        out: ArrayViewMut1<f64>,
    ) -> Result<()> {
        let input = symmetric_from("tangent-space input", c)?;
        self.vectorize_symmetric_into(&input, s, out)?;
        s.input = input;
        Ok(())
    }

    /// Tangent vector of `c`, an exactly symmetric matrix of the right side (checked for
    /// finiteness and positive definiteness, not for symmetry), into `out`.
    pub(crate) fn vectorize_symmetric_into(
        &self,
        c: &DMatrix<f64>,
        s: &mut Scratch,
        mut out: ArrayViewMut1<f64>,
    ) -> Result<()> {
        congruence_into(&self.invsqrt_ref, c, &mut s.tmp, &mut s.white);
        let eig = spd_eigen("tangent-space input", std::mem::take(&mut s.white))?;
        let mut k = 0;
        eigen_function_upper(&eig, f64::ln, |i, j, v| {
            out[k] = if i == j {
                v
            } else {
                std::f64::consts::SQRT_2 * v
            };
            k += 1;
        });
        // The eigenvectors' storage serves the next whitened matrix.
        s.white = eig.eigenvectors;
        Ok(())
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::{array, Array3};
    use proptest::prelude::*;

    fn dm(a: ArrayView2<f64>) -> DMatrix<f64> {
        crate::linalg::to_dmatrix(a)
    }

    /// SPD `B Bᵀ + 0.1 I` from `n²` entries of `B`.
    fn spd_from(n: usize, entries: &[f64]) -> Array2<f64> {
        let b = DMatrix::from_row_slice(n, n, &entries[..n * n]);
        let mut c = &b * b.transpose();
        for i in 0..n {
            c[(i, i)] += 0.1;
        }
        to_array2(&c)
    }

    fn rel_err(a: ArrayView2<f64>, b: ArrayView2<f64>) -> f64 {
        let peak = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .zip(b.iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / peak
    }

    fn is_spd(a: ArrayView2<f64>) -> bool {
        let m = dm(a);
        (&m - m.transpose()).amax() <= 1e-12 * m.amax()
            && crate::linalg::sym_eigenvalues("t", &m).unwrap().min() > 0.0
    }

    /// Strategy: a side n in 2..=5 and k SPD matrices of that side.
    fn spd_set(k: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Vec<Array2<f64>>> {
        (2usize..=5, k).prop_flat_map(|(n, k)| {
            prop::collection::vec(prop::collection::vec(-2.0f64..2.0, n * n), k)
                .prop_map(move |bs| bs.iter().map(|b| spd_from(n, b)).collect())
        })
    }

    fn stack(ms: &[Array2<f64>]) -> Array3<f64> {
        let n = ms[0].nrows();
        Array3::from_shape_fn((ms.len(), n, n), |(k, i, j)| ms[k][[i, j]])
    }

    proptest! {
        // No regression files: failures print the minimal input instead.
        #![proptest_config(ProptestConfig {
            cases: 64,
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn mean_is_spd_and_stationary(ms in spd_set(1..=6)) {
            let covs = stack(&ms);
            let r = mean_riemann(covs.view(), &MeanRiemannParams::default()).unwrap();
            prop_assert!(is_spd(r.mean.view()));
            if r.converged {
                // First-order condition: Σ log(M^{-1/2} C_i M^{-1/2}) ≈ 0 (to the stopping tolerance).
                let ts = TangentSpace::from_reference(r.mean.view()).unwrap();
                let v = ts.transform(covs.view()).unwrap();
                let g = v.sum_axis(Axis(0)) / ms.len() as f64;
                prop_assert!(g.iter().all(|x| x.abs() < 1e-7), "gradient {g}");
            }
        }

        #[test]
        fn expm_of_logm_round_trips(ms in spd_set(1..=1)) {
            let c = &ms[0];
            let l = logm(c.view()).unwrap();
            let back = expm(l.view()).unwrap();
            prop_assert!(is_spd(back.view()));
            let cond = {
                let e = sym_eigenvalues("t", &dm(c.view())).unwrap();
                e.max() / e.min()
            };
            prop_assert!(rel_err(back.view(), c.view()) < 1e-13 * cond.max(1.0) + 1e-12);
            let s = sqrtm(c.view()).unwrap();
            let is = invsqrtm(c.view()).unwrap();
            prop_assert!(rel_err(s.dot(&s).view(), c.view()) < 1e-12 * cond.max(1.0));
            let eye = Array2::eye(c.nrows());
            prop_assert!(rel_err(s.dot(&is).view(), eye.view()) < 1e-12 * cond.max(1.0));
        }

        #[test]
        fn distance_is_symmetric_and_affine_invariant(
            ms in spd_set(2..=2),
            m_entries in prop::collection::vec(-1.0f64..1.0, 25),
        ) {
            let (a, b) = (&ms[0], &ms[1]);
            let n = a.nrows();
            let dab = distance_riemann(a.view(), b.view()).unwrap();
            let dba = distance_riemann(b.view(), a.view()).unwrap();
            prop_assert!((dab - dba).abs() <= 1e-10 * (1.0 + dab));
            prop_assert!(distance_riemann(a.view(), a.view()).unwrap() < 1e-7);
            // M = R + 2.5 I is invertible and modestly conditioned for |R_ij| < 1, n ≤ 5.
            let mut m = DMatrix::from_row_slice(n, n, &m_entries[..n * n]);
            for i in 0..n {
                m[(i, i)] += 2.5;
            }
            prop_assume!(m.clone().svd(false, false).singular_values.min() > 0.2);
            let cong = |x: &Array2<f64>| to_array2(&(&m * dm(x.view()) * m.transpose()));
            let d2 = distance_riemann(cong(a).view(), cong(b).view()).unwrap();
            prop_assert!((d2 - dab).abs() <= 1e-8 * (1.0 + dab), "{d2} vs {dab}");
        }

        #[test]
        fn tangent_space_round_trips(ms in spd_set(3..=3)) {
            let reference = &ms[0];
            let covs = stack(&ms[1..]);
            let v = tangent_space(covs.view(), reference.view()).unwrap();
            let back = untangent_space(v.view(), reference.view()).unwrap();
            for k in 0..2 {
                prop_assert!(is_spd(back.index_axis(Axis(0), k)));
                prop_assert!(rel_err(back.index_axis(Axis(0), k), covs.index_axis(Axis(0), k)) < 1e-9);
                // The vector's norm is the Riemannian distance to the reference.
                let d = distance_riemann(covs.index_axis(Axis(0), k), reference.view()).unwrap();
                let norm = v.row(k).dot(&v.row(k)).sqrt();
                prop_assert!((norm - d).abs() <= 1e-9 * (1.0 + d));
            }
        }
    }

    #[test]
    fn upper_order_and_weights() {
        let s = array![[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]];
        let u = upper(s.view()).unwrap();
        let r2 = std::f64::consts::SQRT_2;
        assert_eq!(
            u.to_vec(),
            vec![1.0, 2.0 * r2, 3.0 * r2, 4.0, 5.0 * r2, 6.0]
        );
        let back = unupper(u.view()).unwrap();
        assert!(rel_err(back.view(), s.view()) < 1e-15);
        assert!(unupper(Array1::zeros(5).view()).is_err());
    }

    #[test]
    fn mean_of_identical_matrices_and_of_two_commuting() {
        let a = array![[2.0, 0.0], [0.0, 8.0]];
        let b = array![[8.0, 0.0], [0.0, 2.0]];
        let r = mean_riemann(stack(&[a.clone(), a.clone()]).view(), &Default::default()).unwrap();
        assert!(rel_err(r.mean.view(), a.view()) < 1e-14 && r.converged);
        // Commuting matrices: the mean is the elementwise geometric mean, here 4·I.
        let r = mean_riemann(stack(&[a, b]).view(), &Default::default()).unwrap();
        assert!(rel_err(r.mean.view(), (4.0 * Array2::<f64>::eye(2)).view()) < 1e-9);
    }

    #[test]
    fn mdm_classifies_by_nearest_mean_and_serializes() {
        let a = array![[2.0, 0.3], [0.3, 1.0]];
        let b = array![[1.0, -0.2], [-0.2, 3.0]];
        let covs = stack(&[a.clone(), a.clone() * 1.1, b.clone(), b.clone() * 0.9]);
        let mdm = MdmParams::default()
            .fit(covs.view(), &[false, false, true, true])
            .unwrap();
        let s = mdm.decision_function(covs.view()).unwrap();
        assert!(s[0] < 0.0 && s[1] < 0.0 && s[2] > 0.0 && s[3] > 0.0);
        let d = mdm.distances(covs.view()).unwrap();
        assert!((d[[2, 0]].powi(2) - d[[2, 1]].powi(2) - s[2]).abs() < 1e-12);
        let json = serde_json::to_string(&mdm).unwrap();
        let back: Mdm = serde_json::from_str(&json).unwrap();
        // serde_json's float parsing may be off by an ulp.
        let again = back.decision_function(covs.view()).unwrap();
        assert!(again
            .iter()
            .zip(s.iter())
            .all(|(a, b)| (a - b).abs() < 1e-12));
        let ts = TangentSpaceParams::default().fit(covs.view()).unwrap();
        let back: TangentSpace =
            serde_json::from_str(&serde_json::to_string(&ts).unwrap()).unwrap();
        let (a, b) = (
            back.transform(covs.view()).unwrap(),
            ts.transform(covs.view()).unwrap(),
        );
        assert!(a.iter().zip(b.iter()).all(|(a, b)| (a - b).abs() < 1e-12));
    }

    #[test]
    fn errors() {
        let not_spd = array![[1.0, 2.0], [2.0, 1.0]];
        assert!(matches!(
            logm(not_spd.view()),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            distance_riemann(not_spd.view(), Array2::eye(2).view()),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
        let covs = stack(&[Array2::eye(2), Array2::eye(2)]);
        assert!(matches!(
            MdmParams::default().fit(covs.view(), &[true, true]),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        let ts = TangentSpace::from_reference(Array2::eye(2).view()).unwrap();
        assert!(matches!(
            ts.transform(Array3::zeros((1, 3, 3)).view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        let bad: std::result::Result<Mdm, _> = serde_json::from_str(
            r#"{"metric":"Riemann","mean_nontarget":{"v":1,"dim":[2,2],"data":[1,2,2,1]},"mean_target":{"v":1,"dim":[2,2],"data":[1,0,0,1]}}"#,
        );
        assert!(bad.is_err());
    }
}
