//! Small dense linear-algebra helpers shared by the linear and Riemannian decoders.
//!
//! Conversions between `ndarray` (the crate's public array type) and `nalgebra` (matrix storage,
//! products, Cholesky), checks for finite / symmetric input, an accurate symmetric eigensolver
//! (Householder tridiagonalisation + implicit QL, EISPACK `tred2`/`tql2`), matrix functions
//! `V f(Λ) Vᵀ` of symmetric matrices, and the generalized
//! symmetric-definite eigenproblem `A v = λ B v` solved through the Cholesky factor of `B` (what
//! LAPACK's `sygvd`, and so `scipy.linalg.eigh(a, b)`, does).
//!
//! Written here rather than taken from a crate: no well-kept crate offers these on `ndarray` with the
//! conventions scipy and pyRiemann use (eigenvector normalisation `Vᵀ B V = I`, sorted spectra,
//! exactly symmetric matrix functions), and nalgebra's own `SymmetricEigen` is not accurate enough
//! (see [`sym_eigen`]).
//!
//! Everything is `f64`; matrices are small (at most a few hundred rows), so the helpers favour clarity
//! and exact symmetry over blocking.

use nalgebra::{Cholesky, DMatrix, DVector};
use ndarray::{Array2, ArrayView2};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Relative asymmetry `max |a_ij − a_ji| / max |a_ij|` above which a matrix is refused as not symmetric.
pub(crate) const SYMMETRY_TOL: f64 = 1e-8;

/// Errors with [`DecodeError::NonFinite`] when any value is NaN or infinite.
pub(crate) fn check_finite<'a>(
    what: &str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<()> {
    if values.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(DecodeError::NonFinite {
            what: what.to_string(),
        })
    }
}

/// Dot product with four independent partial sums (instruction-level parallelism on short vectors).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Checks `y` against `n_samples` and that both classes occur; returns `(n_targets, n_nontargets)`.
pub(crate) fn check_labels(n_samples: usize, y: &[bool]) -> Result<(usize, usize)> {
    if y.len() != n_samples {
        return Err(DecodeError::LabelCount {
            n_samples,
            n_labels: y.len(),
        });
    }
    let n_targets = y.iter().filter(|&&t| t).count();
    let n_nontargets = y.len() - n_targets;
    if n_targets == 0 || n_nontargets == 0 {
        return Err(DecodeError::NeedBothClasses {
            n_targets,
            n_nontargets,
        });
    }
    Ok((n_targets, n_nontargets))
}

/// scikit-learn's `StandardScaler` in place on the columns of `x` `(n_samples, n_features)`:
/// centred and divided by the population standard deviation, which is returned per column
/// (near-constant columns, variance ≤ n·ε·var + (n·mean·ε)², keep scale 1).
pub(crate) fn standardise_columns(x: &mut DMatrix<f64>) -> Vec<f64> {
    let nf = x.nrows() as f64;
    let mut scale = vec![1.0; x.ncols()];
    for (j, mut col) in x.column_iter_mut().enumerate() {
        let mean = col.sum() / nf;
        let var = col.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / nf;
        let bound = nf * f64::EPSILON * var + (nf * mean * f64::EPSILON).powi(2);
        if var > bound {
            scale[j] = var.sqrt();
        }
        let sj = scale[j];
        col.apply(|v| *v = (*v - mean) / sj);
    }
    scale
}

/// Numerically stable logistic function `1 / (1 + e^(−z))`.
pub(crate) fn sigmoid(z: f64) -> f64 {
    if z >= 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

/// Copies an `ndarray` matrix into a (column-major) `nalgebra` matrix of the same shape.
pub(crate) fn to_dmatrix(a: ArrayView2<f64>) -> DMatrix<f64> {
    let (r, c) = a.dim();
    DMatrix::from_fn(r, c, |i, j| a[[i, j]])
}

/// Copies an `nalgebra` matrix into an `ndarray` matrix of the same shape.
pub(crate) fn to_array2(m: &DMatrix<f64>) -> Array2<f64> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)])
}

/// Copies `x` `(n_rows, n_cols)` into `out` as its transpose `(n_cols, n_rows)`, resizing `out` when
/// needed. For a row-major `x` this is a straight copy of its memory (nalgebra is column-major).
pub(crate) fn copy_transposed_into(x: ArrayView2<f64>, out: &mut DMatrix<f64>) {
    let (r, c) = x.dim();
    if out.nrows() != c || out.ncols() != r {
        *out = DMatrix::zeros(c, r);
    }
    match x.as_slice() {
        Some(s) => out.as_mut_slice().copy_from_slice(s),
        None => {
            for i in 0..r {
                for j in 0..c {
                    out[(j, i)] = x[[i, j]];
                }
            }
        }
    }
}

/// Checks that `m` is square, finite and symmetric (to [`SYMMETRY_TOL`] relative), and returns its
/// symmetric part `(m + mᵀ)/2`.
pub(crate) fn symmetric_from(what: &str, m: ArrayView2<f64>) -> Result<DMatrix<f64>> {
    let (r, c) = m.dim();
    if r != c || r == 0 {
        return Err(DecodeError::ShapeMismatch {
            what: what.to_string(),
            expected: "a non-empty square matrix".to_string(),
            got: format!("{r}×{c}"),
        });
    }
    check_finite(what, m.iter())?;
    let mut out = to_dmatrix(m);
    symmetrize_checked(what, &mut out)?;
    Ok(out)
}

/// Replaces `m` by its symmetric part after checking that it is symmetric to [`SYMMETRY_TOL`].
pub(crate) fn symmetrize_checked(what: &str, m: &mut DMatrix<f64>) -> Result<()> {
    let n = m.nrows();
    let peak = m.amax();
    let mut worst = 0.0f64;
    for j in 0..n {
        for i in (j + 1)..n {
            worst = worst.max((m[(i, j)] - m[(j, i)]).abs());
        }
    }
    if worst > SYMMETRY_TOL * peak {
        return Err(DecodeError::NotPositiveDefinite {
            what: format!("{what} (not symmetric: asymmetry {worst:e} for peak {peak:e})"),
        });
    }
    symmetrize(m);
    Ok(())
}

/// Replaces `m` by `(m + mᵀ)/2` (no check).
pub(crate) fn symmetrize(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for j in 0..n {
        for i in (j + 1)..n {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

/// Eigendecomposition `A = V diag(λ) Vᵀ` of a symmetric matrix: eigenvalues ascending, eigenvectors
/// orthonormal columns (empty when only eigenvalues were asked for).
#[derive(Debug, Clone)]
pub(crate) struct SymEigen {
    pub(crate) eigenvalues: DVector<f64>,
    pub(crate) eigenvectors: DMatrix<f64>,
}

/// Symmetric eigendecomposition of a finite symmetric matrix (only its lower triangle is read).
///
/// Householder tridiagonalisation followed by the implicit QL algorithm with Wilkinson-type shifts
/// (EISPACK's `tred2`/`tql2`, in the formulation of the public-domain JAMA library). nalgebra's
/// `SymmetricEigen` is not used: it loses accuracy on close eigenvalues (residuals ~1e-9 on a 3×3
/// with a 3e-3 gap; see also dimforge/nalgebra#1109), far from what the scipy/pyRiemann references need.
pub(crate) fn sym_eigen(what: &str, m: DMatrix<f64>) -> Result<SymEigen> {
    tridiagonal_ql(what, m, true)
}

/// Eigenvalues only (ascending) of a finite symmetric matrix (lower triangle read).
pub(crate) fn sym_eigenvalues(what: &str, m: &DMatrix<f64>) -> Result<DVector<f64>> {
    check_finite(what, m.iter())?;
    Ok(tridiagonal_ql(what, m.clone(), false)?.eigenvalues)
}

fn tridiagonal_ql(what: &str, mut v: DMatrix<f64>, want_vectors: bool) -> Result<SymEigen> {
    let n = v.nrows();
    if n == 0 {
        return Ok(SymEigen {
            eigenvalues: DVector::zeros(0),
            eigenvectors: DMatrix::zeros(0, 0),
        });
    }
    // Column-major storage: element (i, j) at i + j·n, so the inner loops below (over rows of one
    // column, or over two columns) run over contiguous memory.
    let a = v.as_mut_slice();
    // Use the lower triangle: mirror it into the upper one.
    for j in 0..n {
        for i in (j + 1)..n {
            a[j + i * n] = a[i + j * n];
        }
    }
    let mut d = vec![0.0; n];
    let mut e = vec![0.0; n];

    // --- tred2: Householder reduction to tridiagonal form (V accumulates the transformations).
    for j in 0..n {
        d[j] = a[(n - 1) + j * n];
    }
    for i in (1..n).rev() {
        let mut h = 0.0;
        let scale: f64 = d[..i].iter().map(|x| x.abs()).sum();
        if scale == 0.0 {
            e[i] = d[i - 1];
            for j in 0..i {
                d[j] = a[(i - 1) + j * n];
                a[i + j * n] = 0.0;
                a[j + i * n] = 0.0;
            }
        } else {
            for dk in &mut d[..i] {
                *dk /= scale;
                h += *dk * *dk;
            }
            let mut f = d[i - 1];
            let mut g = h.sqrt();
            if f > 0.0 {
                g = -g;
            }
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            e[..i].fill(0.0);
            for j in 0..i {
                f = d[j];
                a[j + i * n] = f;
                let col = &a[j * n..j * n + i];
                g = e[j] + col[j] * f;
                for ((c, dk), ek) in col[(j + 1)..i]
                    .iter()
                    .zip(&d[(j + 1)..i])
                    .zip(&mut e[(j + 1)..i])
                {
                    g += c * dk;
                    *ek += c * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for j in 0..i {
                e[j] /= h;
                f += e[j] * d[j];
            }
            let hh = f / (h + h);
            for j in 0..i {
                e[j] -= hh * d[j];
            }
            for j in 0..i {
                f = d[j];
                g = e[j];
                let col = &mut a[j * n + j..j * n + i];
                for ((c, ek), dk) in col.iter_mut().zip(&e[j..i]).zip(&d[j..i]) {
                    *c -= f * ek + g * dk;
                }
                d[j] = a[(i - 1) + j * n];
                a[i + j * n] = 0.0;
            }
        }
        d[i] = h;
    }
    if want_vectors {
        for i in 0..(n - 1) {
            a[(n - 1) + i * n] = a[i + i * n];
            a[i + i * n] = 1.0;
            let h = d[i + 1];
            if h != 0.0 {
                let next = (i + 1) * n;
                for k in 0..=i {
                    d[k] = a[next + k] / h;
                }
                let (left, right) = a.split_at_mut(next);
                let col_next = &right[..=i];
                for j in 0..=i {
                    let col = &mut left[j * n..j * n + i + 1];
                    let g: f64 = col_next.iter().zip(col.iter()).map(|(x, y)| x * y).sum();
                    for (c, dk) in col.iter_mut().zip(&d[..=i]) {
                        *c -= g * dk;
                    }
                }
            }
            a[(i + 1) * n..(i + 1) * n + i + 1].fill(0.0);
        }
        for j in 0..n {
            d[j] = a[(n - 1) + j * n];
            a[(n - 1) + j * n] = 0.0;
        }
        a[(n - 1) + (n - 1) * n] = 1.0;
    } else {
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = a[j + j * n];
        }
    }

    // --- tql2: implicit QL iterations on the tridiagonal matrix.
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let mut f = 0.0;
    let mut tst1 = 0.0f64;
    let eps = f64::EPSILON;
    const MAX_SWEEPS: usize = 60;
    for l in 0..n {
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        let mut m = l;
        while m < n - 1 && e[m].abs() > eps * tst1 {
            m += 1;
        }
        if m > l {
            let mut iter = 0;
            loop {
                iter += 1;
                if iter > MAX_SWEEPS {
                    return Err(DecodeError::NoConvergence {
                        what: format!("symmetric eigendecomposition of {what}"),
                        iterations: MAX_SWEEPS,
                    });
                }
                let g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = hypot(p, 1.0);
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let mut h = g - d[l];
                for di in &mut d[(l + 2)..n] {
                    *di -= h;
                }
                f += h;
                p = d[m];
                let mut c = 1.0;
                let mut c2 = c;
                let mut c3 = c;
                let el1 = e[l + 1];
                let mut s = 0.0;
                let mut s2 = 0.0;
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    h = c * p;
                    r = hypot(p, e[i]);
                    e[i + 1] = s * r;
                    let inv_r = 1.0 / r;
                    s = e[i] * inv_r;
                    c = p * inv_r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    if want_vectors {
                        let (left, right) = a.split_at_mut((i + 1) * n);
                        let col_i = &mut left[i * n..];
                        let col_next = &mut right[..n];
                        for (x, y) in col_i.iter_mut().zip(col_next.iter_mut()) {
                            let h = *y;
                            *y = s * *x + c * h;
                            *x = c * *x - s * h;
                        }
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if e[l].abs() <= eps * tst1 {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    if d.iter().any(|x| !x.is_finite()) {
        return Err(DecodeError::NonFinite {
            what: format!("eigenvalues of {what}"),
        });
    }

    // Ascending order.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| d[x].total_cmp(&d[y]));
    let eigenvalues = DVector::from_iterator(n, order.iter().map(|&k| d[k]));
    let eigenvectors = if want_vectors {
        if order.iter().enumerate().all(|(k, &o)| k == o) {
            v
        } else {
            DMatrix::from_fn(n, n, |r, c| v[(r, order[c])])
        }
    } else {
        DMatrix::zeros(0, 0)
    };
    Ok(SymEigen {
        eigenvalues,
        eigenvectors,
    })
}

/// `sqrt(a² + b²)` without overflow or harmful underflow; much cheaper than libm's `hypot`, which
/// otherwise dominates the QL iteration's cost.
#[inline]
fn hypot(a: f64, b: f64) -> f64 {
    let (a, b) = (a.abs(), b.abs());
    let m = a.max(b);
    if m > 1e-150 && m < 1e150 {
        (a * a + b * b).sqrt()
    } else if m == 0.0 {
        0.0
    } else {
        let (x, y) = (a / m, b / m);
        m * (x * x + y * y).sqrt()
    }
}

/// Eigendecomposition of a symmetric positive-definite matrix; errors unless every eigenvalue is
/// positive and finite.
pub(crate) fn spd_eigen(what: &str, m: DMatrix<f64>) -> Result<SymEigen> {
    check_finite(what, m.iter())?;
    let eig = sym_eigen(what, m)?;
    if eig.eigenvalues[0] > 0.0 {
        Ok(eig)
    } else {
        Err(DecodeError::NotPositiveDefinite {
            what: format!("{what} (smallest eigenvalue {:e})", eig.eigenvalues[0]),
        })
    }
}

/// `V diag(f(λ)) Vᵀ`, exactly symmetric, written into `out` (resized when needed).
pub(crate) fn eigen_function_into(eig: &SymEigen, f: impl Fn(f64) -> f64, out: &mut DMatrix<f64>) {
    let n = eig.eigenvectors.nrows();
    if out.nrows() != n || out.ncols() != n {
        *out = DMatrix::zeros(n, n);
    }
    eigen_function_upper(eig, f, |i, j, v| {
        out[(i, j)] = v;
        out[(j, i)] = v;
    });
}

/// Calls `emit(i, j, [V diag(f(λ)) Vᵀ]_ij)` for the upper triangle `j ≥ i`, row by row.
pub(crate) fn eigen_function_upper(
    eig: &SymEigen,
    f: impl Fn(f64) -> f64,
    mut emit: impl FnMut(usize, usize, f64),
) {
    let n = eig.eigenvectors.nrows();
    // Rows of V as contiguous slices: Vᵀ in column-major storage.
    let vt = eig.eigenvectors.transpose();
    let vt = vt.as_slice();
    let fl: Vec<f64> = eig.eigenvalues.iter().map(|&l| f(l)).collect();
    let mut weighted = vec![0.0; n];
    for i in 0..n {
        let row_i = &vt[i * n..(i + 1) * n];
        for ((w, &x), &fk) in weighted.iter_mut().zip(row_i).zip(&fl) {
            *w = x * fk;
        }
        for j in i..n {
            emit(i, j, dot(&weighted, &vt[j * n..(j + 1) * n]));
        }
    }
}

/// `V diag(f(λ)) Vᵀ` as a new matrix.
pub(crate) fn eigen_function(eig: &SymEigen, f: impl Fn(f64) -> f64) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(0, 0);
    eigen_function_into(eig, f, &mut out);
    out
}

/// `a · m · a` for symmetric `a` and `m`, exactly symmetric, written into `out` using `tmp` as scratch.
pub(crate) fn congruence_into(
    a: &DMatrix<f64>,
    m: &DMatrix<f64>,
    tmp: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    let n = a.nrows();
    if tmp.nrows() != n || tmp.ncols() != n {
        *tmp = DMatrix::zeros(n, n);
    }
    if out.nrows() != n || out.ncols() != n {
        *out = DMatrix::zeros(n, n);
    }
    tmp.gemm(1.0, a, m, 0.0);
    out.gemm(1.0, tmp, a, 0.0);
    symmetrize(out);
}

/// `C = L⁻¹ A L⁻ᵀ` with `B = L Lᵀ` (Cholesky): the standard symmetric problem equivalent to
/// `A v = λ B v`. Also returns `L`.
fn reduce_generalized(
    what: &str,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let not_spd = || DecodeError::NotPositiveDefinite {
        what: format!("{what}: right-hand matrix"),
    };
    check_finite(what, a.iter().chain(b.iter()))?;
    let l = Cholesky::new(b.clone()).ok_or_else(not_spd)?.unpack();
    // C = L⁻¹ A L⁻ᵀ: Y = L⁻¹ A, then C = L⁻¹ Yᵀ (A symmetric).
    let y = l.solve_lower_triangular(a).ok_or_else(not_spd)?;
    let mut c = l
        .solve_lower_triangular(&y.transpose())
        .ok_or_else(not_spd)?;
    symmetrize(&mut c);
    Ok((c, l))
}

/// Eigenvalues (ascending) of the generalized symmetric-definite problem `A v = λ B v`.
pub(crate) fn generalized_eigenvalues(
    what: &str,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
) -> Result<DVector<f64>> {
    let (c, _) = reduce_generalized(what, a, b)?;
    sym_eigenvalues(what, &c)
}

/// Solution of the generalized symmetric-definite eigenproblem `A v = λ B v` (`A` symmetric, `B`
/// SPD), eigenvalues in ascending order and eigenvectors as columns normalised as scipy's
/// `eigh(a, b)`: `Vᵀ B V = I`. Signs of the eigenvectors are arbitrary.
pub(crate) fn generalized_eigh(
    what: &str,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
) -> Result<(Vec<f64>, DMatrix<f64>)> {
    let (c, l) = reduce_generalized(what, a, b)?;
    let eig = sym_eigen(what, c)?;
    let values: Vec<f64> = eig.eigenvalues.iter().copied().collect();
    // V = L⁻ᵀ W.
    let v = l
        .tr_solve_lower_triangular(&eig.eigenvectors)
        .ok_or_else(|| DecodeError::NotPositiveDefinite {
            what: format!("{what}: right-hand matrix"),
        })?;
    Ok((values, v))
}

/// `a · b` over equal-length slices of a few dozen values or more (short ones: [`dot`]), in 16 independent lanes summed pairwise at the end. On an
/// x86-64 CPU with AVX2 and FMA (checked at run time, once per call: a cached flag) the lanes
/// become four 256-bit fused multiply-add accumulators, about twice the throughput of the
/// baseline SSE2 build; elsewhere the same lane order runs without fusion. The scoring of one
/// epoch is a few of these matrix–vector products (PCA, SVM kernel, k-NN distances), so this is
/// what single-epoch latency mostly waits on.
pub(crate) fn dot_wide(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            #[allow(unsafe_code)]
            // SAFETY: `dot_avx2_fma` only needs AVX2 and FMA, which the CPU was just seen to have.
            return unsafe { dot_avx2_fma(a, b) };
        }
    }
    dot_lanes::<false>(a, b)
}

/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx2,fma")]
unsafe fn dot_avx2_fma(a: &[f64], b: &[f64]) -> f64 {
    dot_lanes::<true>(a, b)
}

/// The lane-wise dot product behind [`dot_wide`]; `FUSED` uses `mul_add` (one rounding per term), which
/// is only fast where the FMA instruction is enabled.
#[inline(always)]
fn dot_lanes<const FUSED: bool>(a: &[f64], b: &[f64]) -> f64 {
    const LANES: usize = 16;
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ta, tb) = (ca.remainder(), cb.remainder());
    let mut acc = [0.0f64; LANES];
    for (x, y) in ca.zip(cb) {
        let (x, y): (&[f64; LANES], &[f64; LANES]) = (
            x.try_into().expect("a whole chunk"),
            y.try_into().expect("a whole chunk"),
        );
        for i in 0..LANES {
            acc[i] = if FUSED {
                x[i].mul_add(y[i], acc[i])
            } else {
                acc[i] + x[i] * y[i]
            };
        }
    }
    for (i, (x, y)) in ta.iter().zip(tb).enumerate() {
        acc[i] = if FUSED {
            x.mul_add(*y, acc[i])
        } else {
            acc[i] + x * y
        };
    }
    let mut width = LANES;
    while width > 1 {
        width /= 2;
        for i in 0..width {
            acc[i] += acc[i + width];
        }
    }
    acc[0]
}

/// `out[i] = m.row(i) · x` for every row of `m` `(n_rows, n)`. Rows that are not contiguous
/// in memory are copied first.
pub(crate) fn mat_vec_into(m: ndarray::ArrayView2<f64>, x: &[f64], out: &mut [f64]) {
    debug_assert_eq!(m.ncols(), x.len());
    debug_assert_eq!(m.nrows(), out.len());
    let mut copy = Vec::new();
    for (o, row) in out.iter_mut().zip(m.outer_iter()) {
        *o = dot_wide(contiguous(row, &mut copy), x);
    }
}

/// `v` as a slice: itself when contiguous, else copied into `copy`.
pub(crate) fn contiguous<'s, 'v: 's>(
    v: ndarray::ArrayView1<'v, f64>,
    copy: &'s mut Vec<f64>,
) -> &'s [f64] {
    match v.to_slice() {
        Some(s) => s,
        None => {
            copy.clear();
            copy.extend(v.iter().copied());
            copy
        }
    }
}

/// Squared Euclidean distances `(n_queries, n_rows)` from the rows of `q` to the rows of `rows`, as
/// `‖q‖² + ‖r‖² − 2 q·r` through one matrix product (the formula of scikit-learn's brute-force
/// neighbours and of libsvm's RBF kernel), clipped at 0. `rows_sq` is [`row_sq_norms`] of `rows`.
/// The k-NN and the RBF SVM both measure through this, so a soft vote can share it between them.
pub(crate) fn sq_distances(
    q: ndarray::ArrayView2<f64>,
    rows: ndarray::ArrayView2<f64>,
    rows_sq: &ndarray::Array1<f64>,
) -> ndarray::Array2<f64> {
    let mut d = crate::scaler::dot_transposed(q, rows);
    for (mut row, qr) in d.outer_iter_mut().zip(q.outer_iter()) {
        let q_sq = qr.dot(&qr);
        for (v, s) in row.iter_mut().zip(rows_sq) {
            *v = (q_sq + s - 2.0 * *v).max(0.0);
        }
    }
    d
}

/// Squared norm of each row of `m`.
pub(crate) fn row_sq_norms(m: ndarray::ArrayView2<f64>) -> ndarray::Array1<f64> {
    m.outer_iter()
        .map(|r| match r.as_slice() {
            Some(s) => dot_wide(s, s),
            None => r.dot(&r),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generalized_eigh_matches_definition() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let b = DMatrix::from_row_slice(3, 3, &[2.0, 0.3, 0.1, 0.3, 1.5, 0.2, 0.1, 0.2, 1.0]);
        let (vals, v) = generalized_eigh("test", &a, &b).unwrap();
        assert!(vals.windows(2).all(|w| w[0] <= w[1]));
        let vtbv = v.transpose() * &b * &v;
        assert!((vtbv - DMatrix::identity(3, 3)).amax() < 1e-12);
        for (k, &l) in vals.iter().enumerate() {
            let col = v.column(k);
            let resid = &a * col - l * (&b * col);
            assert!(resid.amax() < 1e-12, "residual {}", resid.amax());
        }
    }

    #[test]
    fn rejects_asymmetric_and_nonfinite() {
        let m = ndarray::array![[1.0, 0.5], [0.0, 1.0]];
        assert!(matches!(
            symmetric_from("m", m.view()),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
        let m = ndarray::array![[1.0, f64::NAN], [f64::NAN, 1.0]];
        assert!(matches!(
            symmetric_from("m", m.view()),
            Err(DecodeError::NonFinite { .. })
        ));
        let m = ndarray::array![[1.0, 2.0], [2.0, 1.0]];
        assert!(matches!(
            spd_eigen("m", to_dmatrix(m.view())),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
    }

    fn check_decomposition(a: &DMatrix<f64>) {
        let n = a.nrows();
        let eig = sym_eigen("test", a.clone()).unwrap();
        let v = &eig.eigenvectors;
        let scale = a.amax().max(1e-300);
        assert!((v.transpose() * v - DMatrix::identity(n, n)).amax() < 1e-13 * n as f64);
        let recon = v * DMatrix::from_diagonal(&eig.eigenvalues) * v.transpose();
        assert!((recon - a).amax() < 1e-13 * scale * n as f64);
        for k in 0..n {
            let col = v.column(k);
            let r: DVector<f64> = a * col - col * eig.eigenvalues[k];
            assert!(
                r.amax() < 1e-13 * scale * n as f64,
                "residual {:e}",
                r.amax()
            );
        }
        assert!(eig.eigenvalues.as_slice().windows(2).all(|w| w[0] <= w[1]));
        let only = sym_eigenvalues("test", a).unwrap();
        assert!((only - &eig.eigenvalues).amax() < 1e-13 * scale * n as f64);
    }

    #[test]
    fn eigensolver_is_accurate() {
        // Close eigenvalues (where nalgebra's SymmetricEigen leaves residuals ~1e-9).
        let b = DMatrix::from_row_slice(3, 3, &[2.0, 0.3, 0.1, 0.3, 1.5, 0.2, 0.1, 0.2, 1.0]);
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let l = Cholesky::new(b).unwrap().l();
        let y = l.solve_lower_triangular(&a).unwrap();
        let mut c = l.solve_lower_triangular(&y.transpose()).unwrap();
        symmetrize(&mut c);
        check_decomposition(&c);
        // dimforge/nalgebra#1109 (wide dynamic range).
        #[rustfmt::skip]
        let m = DMatrix::from_row_slice(4, 4, &[
            -19884.07, -10.07188, 11.277279, -188560.63,
            -10.07188, 12.518197, 1.3770627, -102.97504,
            11.277279, 1.3770627, 14.587362, 113.26099,
            -188560.63, -102.97504, 113.26099, -1788112.3,
        ]);
        check_decomposition(&m);
        // Repeated eigenvalues, diagonal, 1×1, zero, and a pseudo-random 16×16.
        check_decomposition(&DMatrix::from_row_slice(
            3,
            3,
            &[2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0],
        ));
        check_decomposition(&DMatrix::from_diagonal(&DVector::from_vec(vec![
            3.0, -1.0, 2.0, 0.0,
        ])));
        check_decomposition(&DMatrix::from_element(1, 1, 5.0));
        check_decomposition(&DMatrix::zeros(3, 3));
        let mut s = 7u64;
        let r = DMatrix::from_fn(16, 16, |_, _| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        });
        check_decomposition(&(&r + r.transpose()));
        check_decomposition(&(&r * r.transpose()));
    }

    #[test]
    fn wide_dot_and_mat_vec_match_the_naive_sums() {
        // fixed pseudo-random values, lengths around the 16-lane chunks and their tails
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for n in [0, 1, 3, 15, 16, 17, 31, 33, 207, 656] {
            let a: Vec<f64> = (0..n).map(|_| next()).collect();
            let b: Vec<f64> = (0..n).map(|_| next()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
            assert!(
                (dot_wide(&a, &b) - naive).abs() <= 1e-14 * scale.max(1.0),
                "n = {n}"
            );
        }
        // a matrix whose rows are not contiguous (a transposed view) gives the same products
        let m = Array2::from_shape_fn((5, 40), |(i, j)| ((i * 40 + j) as f64).sin());
        let x: Vec<f64> = (0..40).map(|j| (j as f64 * 0.3).cos()).collect();
        let mt = m.t().to_owned();
        let mut fast = vec![0.0; 5];
        let mut strided = vec![0.0; 5];
        mat_vec_into(m.view(), &x, &mut fast);
        mat_vec_into(mt.t(), &x, &mut strided);
        for i in 0..5 {
            let naive: f64 = m.row(i).iter().zip(&x).map(|(a, b)| a * b).sum();
            assert!((fast[i] - naive).abs() < 1e-12);
            assert_eq!(fast[i], strided[i]);
        }
        let norms = row_sq_norms(m.view());
        assert!((norms[2] - m.row(2).dot(&m.row(2))).abs() < 1e-12);
    }
}
