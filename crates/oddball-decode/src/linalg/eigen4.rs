//! Four symmetric eigendecompositions at once, lane by lane the same arithmetic as
//! [`tridiagonal_ql`](super::tridiagonal_ql).
//!
//! Why: the Riemannian mean and the tangent space decompose thousands of small (16×16) whitened
//! matrices, and there the implicit QL iteration is bound by the latency of one dependency chain
//! per rotation (`hypot` → `sqrt` → division → the next rotation's `p`), not by arithmetic
//! throughput. Four independent matrices stored lane by lane (one AVX2 register per element)
//! advance four chains in the time of one. No crate does this for us, and the results must be
//! those of the one-matrix solver bit for bit (the project's scores are pinned). Without AVX2
//! (detected at run time) the one-matrix solver simply runs four times.
//!
//! Every lane performs exactly the operations, in the same order, of the one-matrix solver on its
//! own matrix; where the lanes' control flow differs (the QL split point `m`, the number of QL
//! sweeps, signs) a lane that has nothing to do keeps its values (selects, no arithmetic shortcut).
//! Where the one-matrix solver would take a rare branch (a zero Householder scale, more than
//! the allowed QL sweeps, non-finite eigenvalues) the batch gives up and the caller runs the
//! one-matrix solver on each matrix, which then also produces its errors.

use nalgebra::DMatrix;

use super::eigen::{spd_eigen, SymEigen};
use super::{check_finite, Result};
use crate::DecodeError;

const W: usize = 4;

/// Four decompositions, or the four matrices given back.
pub(crate) type Eigen4 = std::result::Result<[SymEigen; W], [DMatrix<f64>; W]>;

/// [`spd_eigen`] of four matrices of the same side, in order: the same results (bit for bit)
/// and the same first error. The matrices' storage is reused for the eigenvectors.
pub(crate) fn spd_eigen4(what: &str, mats: [DMatrix<f64>; W]) -> Result<[SymEigen; W]> {
    let n = mats[0].nrows();
    let same_shape = mats.iter().all(|m| m.nrows() == n && m.ncols() == n);
    // (no early exit: a branch-free pass over the values)
    let finite = same_shape
        && mats
            .iter()
            .all(|m| m.iter().fold(true, |ok, v| ok & v.is_finite()));
    let mats = if n > 0 && finite {
        match sym_eigen4(mats) {
            Ok(eigs) => {
                for e in &eigs {
                    if e.eigenvalues[0] <= 0.0 || e.eigenvalues[0].is_nan() {
                        return Err(DecodeError::NotPositiveDefinite {
                            what: format!("{what} (smallest eigenvalue {:e})", e.eigenvalues[0]),
                        });
                    }
                }
                return Ok(eigs);
            }
            Err(mats) => mats,
        }
    } else {
        mats
    };
    let [a, b, c, d] = mats;
    Ok([
        spd_eigen(what, a)?,
        spd_eigen(what, b)?,
        spd_eigen(what, c)?,
        spd_eigen(what, d)?,
    ])
}

/// Symmetric eigendecompositions of four finite symmetric `n×n` matrices (lower triangles read),
/// or the matrices back, untouched, where the one-matrix solver must decide (see the module docs)
/// or the CPU lacks AVX2.
// The declined matrices come back by value (the rare path), not boxed.
#[allow(clippy::result_large_err)]
pub(crate) fn sym_eigen4(mats: [DMatrix<f64>; W]) -> Eigen4 {
    debug_assert!(mats.iter().all(|m| check_finite("", m.iter()).is_ok()));
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            #[allow(unsafe_code)]
            // SAFETY: `avx2::sym_eigen4` only needs AVX2, which the CPU was just seen to have.
            return unsafe { avx2::sym_eigen4(mats) };
        }
    }
    Err(mats)
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use nalgebra::{DMatrix, DVector};

    use super::super::eigen::{hypot, SymEigen, MAX_SWEEPS};
    use super::{Eigen4, W};

    /// One element of the four matrices, lane `k` from matrix `k`.
    type V = __m256d;

    #[inline(always)]
    fn arr(v: V) -> [f64; W] {
        #[allow(unsafe_code)]
        // SAFETY: same size, and every bit pattern is valid for both types.
        unsafe {
            std::mem::transmute::<V, [f64; W]>(v)
        }
    }

    #[inline(always)]
    fn from(a: [f64; W]) -> V {
        #[allow(unsafe_code)]
        // SAFETY: same size, and every bit pattern is valid for both types.
        unsafe {
            std::mem::transmute::<[f64; W], V>(a)
        }
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn splat(x: f64) -> V {
        _mm256_set1_pd(x)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn add(a: V, b: V) -> V {
        _mm256_add_pd(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn sub(a: V, b: V) -> V {
        _mm256_sub_pd(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn mul(a: V, b: V) -> V {
        _mm256_mul_pd(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn div(a: V, b: V) -> V {
        _mm256_div_pd(a, b)
    }
    /// `-a` (the sign bit flipped, as scalar negation).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn neg(a: V) -> V {
        _mm256_xor_pd(a, _mm256_set1_pd(-0.0))
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn abs(a: V) -> V {
        _mm256_andnot_pd(_mm256_set1_pd(-0.0), a)
    }
    /// `new` in the lanes where `on` is all ones, `old` elsewhere.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn select(on: V, new: V, old: V) -> V {
        _mm256_blendv_pd(old, new, on)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    fn mask(on: [bool; W]) -> V {
        let m = |b: bool| if b { -1i64 } else { 0 };
        _mm256_castsi256_pd(_mm256_setr_epi64x(m(on[0]), m(on[1]), m(on[2]), m(on[3])))
    }

    /// [`hypot`] lane by lane (all lanes in the safe range: as one vector).
    #[inline]
    #[target_feature(enable = "avx2")]
    fn hypot4(a: V, b: V) -> V {
        let (aa, ba) = (arr(abs(a)), arr(abs(b)));
        if (0..W).all(|k| {
            let m = aa[k].max(ba[k]);
            m > 1e-150 && m < 1e150
        }) {
            _mm256_sqrt_pd(add(mul(a, a), mul(b, b)))
        } else {
            from(std::array::from_fn(|k| hypot(aa[k], ba[k])))
        }
    }

    /// [`super::sym_eigen4`] (to be called only where the CPU has AVX2).
    #[target_feature(enable = "avx2")]
    #[allow(clippy::result_large_err)]
    pub(super) fn sym_eigen4(mut mats: [DMatrix<f64>; W]) -> Eigen4 {
        let n = mats[0].nrows();
        // Element (i, j) at a[i + j·n], column-major as in the one-matrix solver.
        let mut a: Vec<V> = {
            let [m0, m1, m2, m3] = std::array::from_fn(|k| &mats[k].as_slice()[..n * n]);
            (0..n * n)
                .map(|x| _mm256_setr_pd(m0[x], m1[x], m2[x], m3[x]))
                .collect()
        };
        let mut d: Vec<V> = vec![splat(0.0); n];
        let mut e: Vec<V> = vec![splat(0.0); n];
        if !decompose(&mut a, &mut d, &mut e, n) {
            return Err(mats);
        }
        let mut order: Vec<usize> = Vec::with_capacity(n);
        Ok(std::array::from_fn(|k| {
            let dk = |x: usize| arr(d[x])[k];
            order.clear();
            order.extend(0..n);
            order.sort_by(|&x, &y| dk(x).total_cmp(&dk(y)));
            let eigenvalues = DVector::from_iterator(n, order.iter().map(|&o| dk(o)));
            let vs = mats[k].as_mut_slice();
            for (c, &o) in order.iter().enumerate() {
                for (v, &x) in vs[c * n..(c + 1) * n]
                    .iter_mut()
                    .zip(&a[o * n..(o + 1) * n])
                {
                    *v = arr(x)[k];
                }
            }
            SymEigen {
                eigenvalues,
                eigenvectors: std::mem::replace(&mut mats[k], DMatrix::zeros(0, 0)),
            }
        }))
    }

    /// `tred2` + `tql2` lane by lane; eigenvalues (unsorted) in `d`, eigenvectors in `a`.
    /// `false` where the one-matrix solver must decide.
    #[target_feature(enable = "avx2")]
    fn decompose(a: &mut [V], d: &mut [V], e: &mut [V], n: usize) -> bool {
        let zero = splat(0.0);
        let mut gs = vec![zero; n];
        for j in 0..n {
            for i in (j + 1)..n {
                a[j + i * n] = a[i + j * n];
            }
        }

        // --- tred2
        for j in 0..n {
            d[j] = a[(n - 1) + j * n];
        }
        for i in (1..n).rev() {
            let mut scale = splat(-0.0);
            for &dk in &d[..i] {
                scale = add(scale, abs(dk));
            }
            if arr(scale).contains(&0.0) {
                return false;
            }
            let mut h = zero;
            for dk in &mut d[..i] {
                *dk = div(*dk, scale);
                h = add(h, mul(*dk, *dk));
            }
            let mut f = d[i - 1];
            let g0 = _mm256_sqrt_pd(h);
            let mut g = select(_mm256_cmp_pd::<_CMP_GT_OQ>(f, zero), neg(g0), g0);
            e[i] = mul(scale, g);
            h = sub(h, mul(f, g));
            d[i - 1] = sub(f, g);
            // e = A d over the leading i×i block (lower triangle stored): each e[j] summed from
            // +0 over k ascending, as the one-matrix solver does, but with the k loop outside so
            // that the i sums advance side by side instead of one long chain after another.
            e[..i].fill(zero);
            for j in 0..i {
                a[j + i * n] = d[j];
            }
            for k in 0..i {
                let dk = d[k];
                for j in 0..k {
                    e[j] = add(e[j], mul(a[j * n + k], dk));
                }
                for j in k..i {
                    e[j] = add(e[j], mul(a[k * n + j], dk));
                }
            }
            f = zero;
            for j in 0..i {
                e[j] = div(e[j], h);
                f = add(f, mul(e[j], d[j]));
            }
            let hh = div(f, add(h, h));
            for j in 0..i {
                e[j] = sub(e[j], mul(hh, d[j]));
            }
            for j in 0..i {
                f = d[j];
                g = e[j];
                for r in j..i {
                    let c = &mut a[j * n + r];
                    *c = sub(*c, add(mul(f, e[r]), mul(g, d[r])));
                }
                d[j] = a[(i - 1) + j * n];
                a[i + j * n] = zero;
            }
            d[i] = h;
        }
        for i in 0..(n - 1) {
            a[(n - 1) + i * n] = a[i + i * n];
            a[i + i * n] = splat(1.0);
            let h = d[i + 1];
            if arr(h).contains(&0.0) {
                return false;
            }
            let next = (i + 1) * n;
            for r in 0..=i {
                d[r] = div(a[next + r], h);
            }
            // gs[j] = column next · column j, each summed from -0 over r ascending (as the
            // one-matrix solver's `sum`), the i + 1 sums side by side.
            gs[..=i].fill(splat(-0.0));
            for r in 0..=i {
                let x = a[next + r];
                for (j, gj) in gs[..=i].iter_mut().enumerate() {
                    *gj = add(*gj, mul(x, a[j * n + r]));
                }
            }
            for (j, &gj) in gs[..=i].iter().enumerate() {
                for r in 0..=i {
                    let c = &mut a[j * n + r];
                    *c = sub(*c, mul(gj, d[r]));
                }
            }
            a[next..next + i + 1].fill(zero);
        }
        for j in 0..n {
            d[j] = a[(n - 1) + j * n];
            a[(n - 1) + j * n] = zero;
        }
        a[(n - 1) + (n - 1) * n] = splat(1.0);

        // --- tql2
        for i in 1..n {
            e[i - 1] = e[i];
        }
        e[n - 1] = zero;
        let mut f = zero;
        let mut tst1 = [0.0f64; W];
        let eps = f64::EPSILON;
        for l in 0..n {
            let mut m = [l; W];
            let mut active = [false; W];
            let (dl, el) = (arr(d[l]), arr(e[l]));
            for k in 0..W {
                tst1[k] = tst1[k].max(dl[k].abs() + el[k].abs());
                while m[k] < n - 1 && arr(e[m[k]])[k].abs() > eps * tst1[k] {
                    m[k] += 1;
                }
                active[k] = m[k] > l;
            }
            let mut iter = 0;
            while active.iter().any(|&x| x) {
                iter += 1;
                if iter > MAX_SWEEPS {
                    return false;
                }
                let on_l = mask(active);
                let g = d[l];
                let el = e[l];
                let p = div(sub(d[l + 1], g), mul(splat(2.0), el));
                let r1 = hypot4(p, splat(1.0));
                let r = select(_mm256_cmp_pd::<_CMP_LT_OQ>(p, zero), neg(r1), r1);
                let pr = add(p, r);
                d[l] = select(on_l, div(el, pr), d[l]);
                d[l + 1] = select(on_l, mul(el, pr), d[l + 1]);
                let dl1 = d[l + 1];
                let h = sub(g, d[l]);
                for di in &mut d[(l + 2)..n] {
                    *di = select(on_l, sub(*di, h), *di);
                }
                f = select(on_l, add(f, h), f);
                let dm: [[f64; W]; W] = std::array::from_fn(|k| arr(d[m[k]]));
                let mut p = from(std::array::from_fn(|k| dm[k][k]));
                let mut c = splat(1.0);
                let mut c2 = c;
                let mut c3 = c;
                let el1 = e[l + 1];
                let mut s = zero;
                let mut s2 = zero;
                let top = (0..W)
                    .filter(|&k| active[k])
                    .map(|k| m[k])
                    .max()
                    .unwrap_or(l);
                for i in (l..top).rev() {
                    let all = (0..W).all(|k| active[k] && i < m[k]);
                    let on = mask(std::array::from_fn(|k| active[k] && i < m[k]));
                    let ei = e[i];
                    let di = d[i];
                    let g = mul(c, ei);
                    let hc = mul(c, p);
                    let r = hypot4(p, ei);
                    let e_next = mul(s, r);
                    let inv_r = div(splat(1.0), r);
                    let s_new = mul(ei, inv_r);
                    let c_new = mul(p, inv_r);
                    let p_new = sub(mul(c_new, di), mul(s_new, g));
                    let d_next = add(hc, mul(s_new, add(mul(c_new, g), mul(s_new, di))));
                    c3 = select(on, c2, c3);
                    c2 = select(on, c, c2);
                    s2 = select(on, s, s2);
                    e[i + 1] = select(on, e_next, e[i + 1]);
                    d[i + 1] = select(on, d_next, d[i + 1]);
                    s = select(on, s_new, s);
                    c = select(on, c_new, c);
                    p = select(on, p_new, p);
                    let (left, right) = a.split_at_mut((i + 1) * n);
                    let pairs = left[i * n..].iter_mut().zip(right[..n].iter_mut());
                    if all {
                        for (x, y) in pairs {
                            let (xo, yo) = (*x, *y);
                            *y = add(mul(s, xo), mul(c, yo));
                            *x = sub(mul(c, xo), mul(s, yo));
                        }
                    } else {
                        for (x, y) in pairs {
                            let (xo, yo) = (*x, *y);
                            *y = select(on, add(mul(s, xo), mul(c, yo)), yo);
                            *x = select(on, sub(mul(c, xo), mul(s, yo)), xo);
                        }
                    }
                }
                let el = e[l];
                let p = div(mul(mul(mul(mul(neg(s), s2), c3), el1), el), dl1);
                e[l] = select(on_l, mul(s, p), e[l]);
                d[l] = select(on_l, mul(c, p), d[l]);
                let el = arr(e[l]);
                for k in 0..W {
                    if active[k] && el[k].abs() <= eps * tst1[k] {
                        active[k] = false;
                    }
                }
            }
            d[l] = add(d[l], f);
            e[l] = zero;
        }
        d.iter().all(|&x| arr(x).iter().all(|v| v.is_finite()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::tridiagonal_ql;

    fn bits(x: &[f64]) -> Vec<u64> {
        x.iter().map(|v| v.to_bits()).collect()
    }

    fn random(n: usize, s: &mut u64) -> DMatrix<f64> {
        DMatrix::from_fn(n, n, |_, _| {
            *s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (*s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
    }

    /// Each lane gives bit for bit what the one-matrix solver gives, for SPD and indefinite
    /// matrices, clustered spectra and the identity (no QL sweep at all in some lanes).
    #[test]
    fn batch_matches_one_matrix_solver_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        if !std::arch::is_x86_feature_detected!("avx2") {
            return; // no batch: spd_eigen4 is the one-matrix solver
        }
        #[cfg(not(target_arch = "x86_64"))]
        return;
        let mut s = 5u64;
        for n in [1usize, 2, 3, 4, 7, 16, 17] {
            for trial in 0..40 {
                let mats: [DMatrix<f64>; W] = std::array::from_fn(|k| {
                    let r = random(n, &mut s);
                    match (trial + k) % 5 {
                        0 => &r * r.transpose() + DMatrix::identity(n, n) * 1e-3,
                        1 => &r + r.transpose(),
                        // tridiagonal form reached at once: no QL sweep in this lane
                        2 => {
                            DMatrix::from_fn(n, n, |i, j| if i == j { i as f64 + 1.0 } else { 0.0 })
                                + (&r + r.transpose()) * 1e-20
                        }
                        // nearly a multiple of the identity: close eigenvalues
                        3 => DMatrix::identity(n, n) * 2.0 + (&r + r.transpose()) * 1e-7,
                        _ => {
                            let x = DMatrix::from_fn(n, 3 * n, |_, _| {
                                s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
                                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
                            });
                            &x * x.transpose()
                        }
                    }
                });
                let batch = sym_eigen4(mats.clone()).unwrap_or_else(|_| panic!("batch declined"));
                for (m, b) in mats.iter().zip(&batch) {
                    let one = tridiagonal_ql("test", m.clone(), true).unwrap();
                    assert_eq!(
                        bits(one.eigenvalues.as_slice()),
                        bits(b.eigenvalues.as_slice()),
                        "eigenvalues, n = {n}"
                    );
                    assert_eq!(
                        bits(one.eigenvectors.as_slice()),
                        bits(b.eigenvectors.as_slice()),
                        "eigenvectors, n = {n}"
                    );
                }
            }
        }
    }

    /// Against nalgebra's independent `SymmetricEigen`: the same spectrum, and `V Λ Vᵀ = A` with
    /// orthonormal `V`.
    #[test]
    fn batch_agrees_with_nalgebra() {
        let mut s = 17u64;
        for _ in 0..50 {
            let mats: [DMatrix<f64>; W] = std::array::from_fn(|_| {
                let r = random(16, &mut s);
                &r * r.transpose() + DMatrix::identity(16, 16) * 0.1
            });
            let batch = spd_eigen4("test", mats.clone()).unwrap();
            for (m, b) in mats.iter().zip(&batch) {
                let mut reference: Vec<f64> = m
                    .clone()
                    .symmetric_eigen()
                    .eigenvalues
                    .iter()
                    .copied()
                    .collect();
                reference.sort_by(f64::total_cmp);
                for (x, y) in reference.iter().zip(b.eigenvalues.iter()) {
                    assert!((x - y).abs() < 1e-12 * m.amax(), "{x} vs {y}");
                }
                let v = &b.eigenvectors;
                let recon = v * DMatrix::from_diagonal(&b.eigenvalues) * v.transpose();
                assert!((recon - m).amax() < 1e-12 * m.amax());
                assert!((v.transpose() * v - DMatrix::identity(16, 16)).amax() < 1e-13);
            }
        }
    }

    /// Errors are those of the one-matrix solver on the first failing matrix, in order.
    #[test]
    fn batch_errors_as_one_matrix_solver() {
        let spd = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let nan = DMatrix::from_row_slice(2, 2, &[1.0, f64::NAN, f64::NAN, 1.0]);
        let r = spd_eigen4(
            "m",
            [spd.clone(), indefinite.clone(), nan.clone(), spd.clone()],
        );
        assert!(matches!(r, Err(DecodeError::NotPositiveDefinite { .. })));
        let r = spd_eigen4("m", [spd.clone(), nan, indefinite, spd.clone()]);
        assert!(matches!(r, Err(DecodeError::NonFinite { .. })));
        assert!(spd_eigen4("m", [spd.clone(), spd.clone(), spd.clone(), spd]).is_ok());
        // a zero Householder scale (the identity): declined, and the one-matrix solver's result
        let id = DMatrix::<f64>::identity(3, 3);
        assert!(sym_eigen4([id.clone(), id.clone(), id.clone(), id.clone()]).is_err());
        let r = spd_eigen4("m", [id.clone(), id.clone(), id.clone(), id.clone()]).unwrap();
        let one = tridiagonal_ql("m", id, true).unwrap();
        assert_eq!(r[3].eigenvectors, one.eigenvectors);
        assert_eq!(r[3].eigenvalues, one.eigenvalues);
    }
}
