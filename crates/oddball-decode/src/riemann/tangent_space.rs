//! pyRiemann's tangent space: `upper(log(C_ref^{-1/2} C C_ref^{-1/2}))` and back.

use nalgebra::DMatrix;
use ndarray::{
    s, Array1, Array2, Array3, ArrayView1, ArrayView2, ArrayView3, ArrayViewMut1, ArrayViewMut2,
    Axis,
};
use serde::{Deserialize, Serialize};

use super::{mean_riemann, MeanRiemannParams, Metric};
use crate::linalg::{
    congruence_into, eigen_function, eigen_function_upper, spd_eigen, spd_eigen4, sym_eigen,
    symmetric_from, to_array2, SymEigen,
};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

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

pub(crate) fn side_from_len(len: usize) -> Result<usize> {
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
    pub(crate) input: DMatrix<f64>,
    pub(crate) tmp: DMatrix<f64>,
    pub(crate) white: DMatrix<f64>,
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
        let mut pool: [DMatrix<f64>; 4] = Default::default();
        let k = covs.dim().0;
        let mut start = 0;
        // Four matrices decomposed at once (the same numbers as one by one); a group with an
        // input that is not symmetric goes one by one, for the errors in order.
        while start + 4 <= k {
            let group = covs.slice(s![start..start + 4, .., ..]);
            let inputs: Result<Vec<DMatrix<f64>>> = group
                .outer_iter()
                .map(|c| symmetric_from("tangent-space input", c))
                .collect();
            let mut rows = out.slice_mut(s![start..start + 4, ..]);
            match inputs {
                Ok(inputs) => self.vectorize4_into(&inputs, &mut pool, &mut scratch, rows)?,
                Err(_) => {
                    for (c, row) in group.outer_iter().zip(rows.axis_iter_mut(Axis(0))) {
                        self.vectorize_into(c, &mut scratch, row)?;
                    }
                }
            }
            start += 4;
        }
        for (c, row) in covs
            .slice(s![start.., .., ..])
            .outer_iter()
            .zip(out.slice_mut(s![start.., ..]).axis_iter_mut(Axis(0)))
        {
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
        out: ArrayViewMut1<f64>,
    ) -> Result<()> {
        congruence_into(&self.invsqrt_ref, c, &mut s.tmp, &mut s.white);
        let eig = spd_eigen("tangent-space input", std::mem::take(&mut s.white))?;
        log_upper_into(&eig, out);
        // The eigenvectors' storage serves the next whitened matrix.
        s.white = eig.eigenvectors;
        Ok(())
    }

    /// Tangent vectors of four exactly symmetric matrices into the four rows of `out`, their
    /// whitened matrices decomposed at once (`pool`: storage for them, reused).
    pub(crate) fn vectorize4_into(
        &self,
        inputs: &[DMatrix<f64>],
        pool: &mut [DMatrix<f64>; 4],
        s: &mut Scratch,
        mut out: ArrayViewMut2<f64>,
    ) -> Result<()> {
        let whites: [DMatrix<f64>; 4] = std::array::from_fn(|k| {
            let mut w = std::mem::take(&mut pool[k]);
            congruence_into(&self.invsqrt_ref, &inputs[k], &mut s.tmp, &mut w);
            w
        });
        let eigs = spd_eigen4("tangent-space input", whites)?;
        for ((eig, row), slot) in eigs
            .into_iter()
            .zip(out.axis_iter_mut(Axis(0)))
            .zip(pool.iter_mut())
        {
            log_upper_into(&eig, row);
            *slot = eig.eigenvectors;
        }
        Ok(())
    }
}

/// pyRiemann's `upper(log(W))` of `W` given by its eigendecomposition, into `out`.
fn log_upper_into(eig: &SymEigen, mut out: ArrayViewMut1<f64>) {
    let mut k = 0;
    eigen_function_upper(eig, f64::ln, |i, j, v| {
        out[k] = if i == j {
            v
        } else {
            std::f64::consts::SQRT_2 * v
        };
        k += 1;
    });
}
