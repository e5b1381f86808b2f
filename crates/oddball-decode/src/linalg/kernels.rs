//! Inner loops of scoring: wide dot products (AVX2 + FMA when the CPU has them), matrix–vector
//! products and squared Euclidean distances between rows.

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
pub(crate) fn dot_lanes<const FUSED: bool>(a: &[f64], b: &[f64]) -> f64 {
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
    let mut d = dot_transposed(q, rows);
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

/// `x · mᵀ` for `x` `(n, p)` and `m` `(k, p)`. A matrix product packs `m` on every call, which
/// dominates for a few rows (one epoch scored online), so up to 16 rows go through one
/// matrix–vector product per row instead.
pub(crate) fn dot_transposed(
    x: ndarray::ArrayView2<f64>,
    m: ndarray::ArrayView2<f64>,
) -> ndarray::Array2<f64> {
    if x.nrows() > 16 {
        return x.dot(&m.t());
    }
    let mut out = ndarray::Array2::zeros((x.nrows(), m.nrows()));
    let mut copy = Vec::new();
    for (mut o, row) in out.outer_iter_mut().zip(x.outer_iter()) {
        let o = o.as_slice_mut().expect("a new array's rows are contiguous");
        mat_vec_into(m, contiguous(row, &mut copy), o);
    }
    out
}
