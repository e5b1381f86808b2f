//! Envelopes through the mirrored extrema: PyEMD's `prepare_points_simple`, scipy's not-a-knot
//! `CubicSpline` (tridiagonal solve as LAPACK's `dgtsv`) and PyEMD's three-knot spline.

use super::extrema::Extrema;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// The error of a signal whose envelopes cannot be built.
fn degenerate(reason: &str) -> DecodeError {
    DecodeError::InvalidParameter {
        name: "signal",
        value: "EMD input".into(),
        reason: reason.into(),
    }
}

#[derive(Debug, Clone, Default)]
pub(crate) struct Mirror {
    pub(crate) lmax: Vec<usize>,
    pub(crate) lmin: Vec<usize>,
    pub(crate) rmax: Vec<usize>,
    pub(crate) rmin: Vec<usize>,
}

/// Knots of one envelope: positions (sample indices, possibly beyond the ends) and values.
#[derive(Debug, Clone, Default)]
pub(crate) struct Knots {
    pub(crate) t: Vec<f64>,
    pub(crate) z: Vec<f64>,
}

/// `v[a..b]` reversed, appended to `out` (empty when `a >= b`), as numpy's `v[a:b][::-1]`.
pub(crate) fn push_rev(out: &mut Vec<usize>, v: &[usize], a: usize, b: usize) {
    if a < b {
        out.extend(v[a..b].iter().rev());
    }
}

/// PyEMD's `prepare_points_simple`: interior extrema plus `nbsym` mirrored ones at each end.
pub(crate) fn envelopes(
    s: &[f64],
    ext: &Extrema,
    nbsym: usize,
    m: &mut Mirror,
    kmax: &mut Knots,
    kmin: &mut Knots,
) -> Result<()> {
    let (imax, imin) = (&ext.maxs[..], &ext.mins[..]);
    if imax.is_empty() || imin.is_empty() {
        return Err(degenerate(
            "EMD needs at least one maximum and one minimum to build envelopes",
        ));
    }
    let n = s.len();
    let last = n - 1;
    let (end_max, end_min) = (imax.len(), imin.len());
    for v in [&mut m.lmax, &mut m.lmin, &mut m.rmax, &mut m.rmin] {
        v.clear();
    }
    // ---- left end
    let mut lsym;
    if imax[0] < imin[0] {
        if s[0] > s[imin[0]] {
            push_rev(&mut m.lmax, imax, 1, end_max.min(nbsym + 1));
            push_rev(&mut m.lmin, imin, 0, end_min.min(nbsym));
            lsym = imax[0];
        } else {
            push_rev(&mut m.lmax, imax, 0, end_max.min(nbsym));
            push_rev(&mut m.lmin, imin, 0, end_min.min(nbsym - 1));
            m.lmin.push(0);
            lsym = 0;
        }
    } else if s[0] < s[imax[0]] {
        push_rev(&mut m.lmax, imax, 0, end_max.min(nbsym));
        push_rev(&mut m.lmin, imin, 1, end_min.min(nbsym + 1));
        lsym = imin[0];
    } else {
        push_rev(&mut m.lmax, imax, 0, end_max.min(nbsym - 1));
        m.lmax.push(0);
        push_rev(&mut m.lmin, imin, 0, end_min.min(nbsym));
        lsym = 0;
    }
    // ---- right end
    let mut rsym;
    if imax[end_max - 1] < imin[end_min - 1] {
        if s[last] < s[imax[end_max - 1]] {
            push_rev(&mut m.rmax, imax, end_max.saturating_sub(nbsym), end_max);
            push_rev(
                &mut m.rmin,
                imin,
                end_min.saturating_sub(nbsym + 1),
                end_min - 1,
            );
            rsym = imin[end_min - 1];
        } else {
            m.rmax.push(last);
            push_rev(
                &mut m.rmax,
                imax,
                (end_max + 1).saturating_sub(nbsym),
                end_max,
            );
            push_rev(&mut m.rmin, imin, end_min.saturating_sub(nbsym), end_min);
            rsym = last;
        }
    } else if s[last] > s[imin[end_min - 1]] {
        push_rev(
            &mut m.rmax,
            imax,
            end_max.saturating_sub(nbsym + 1),
            end_max - 1,
        );
        push_rev(&mut m.rmin, imin, end_min.saturating_sub(nbsym), end_min);
        rsym = imax[end_max - 1];
    } else {
        push_rev(&mut m.rmax, imax, end_max.saturating_sub(nbsym), end_max);
        m.rmin.push(last);
        push_rev(
            &mut m.rmin,
            imin,
            (end_min + 1).saturating_sub(nbsym),
            end_min,
        );
        rsym = last;
    }
    // ---- an empty mirror set falls back to all extrema (PyEMD: "in case any array missing")
    if m.lmin.is_empty() {
        m.lmin.extend_from_slice(imin);
    }
    if m.rmin.is_empty() {
        m.rmin.extend_from_slice(imin);
    }
    if m.lmax.is_empty() {
        m.lmax.extend_from_slice(imax);
    }
    if m.rmax.is_empty() {
        m.rmax.extend_from_slice(imax);
    }
    let mirror = |sym: usize, i: usize| 2.0 * sym as f64 - i as f64;
    // ---- mirrored points must lie outside the signal; otherwise mirror about the end sample
    if mirror(lsym, m.lmin[0]) > 0.0 || mirror(lsym, m.lmax[0]) > 0.0 {
        if lsym == imax[0] {
            m.lmax.clear();
            push_rev(&mut m.lmax, imax, 0, end_max.min(nbsym));
        } else {
            m.lmin.clear();
            push_rev(&mut m.lmin, imin, 0, end_min.min(nbsym));
        }
        if lsym == 0 {
            return Err(degenerate("EMD mirroring failed at the left edge"));
        }
        lsym = 0;
    }
    let lt = |v: &[usize]| v[v.len() - 1];
    if mirror(rsym, lt(&m.rmin)) < last as f64 || mirror(rsym, lt(&m.rmax)) < last as f64 {
        if rsym == imax[end_max - 1] {
            m.rmax.clear();
            push_rev(&mut m.rmax, imax, end_max.saturating_sub(nbsym), end_max);
        } else {
            m.rmin.clear();
            push_rev(&mut m.rmin, imin, end_min.saturating_sub(nbsym), end_min);
        }
        if rsym == last {
            return Err(degenerate("EMD mirroring failed at the right edge"));
        }
        rsym = last;
    }
    fill_knots(kmax, s, &m.lmax, imax, &m.rmax, lsym, rsym);
    fill_knots(kmin, s, &m.lmin, imin, &m.rmin, lsym, rsym);
    Ok(())
}

/// Concatenates mirrored-left, interior and mirrored-right knots and drops the first of any two
/// consecutive knots at the same position (PyEMD's "make double sure" step).
pub(crate) fn fill_knots(
    k: &mut Knots,
    s: &[f64],
    left: &[usize],
    inner: &[usize],
    right: &[usize],
    lsym: usize,
    rsym: usize,
) {
    k.t.clear();
    k.z.clear();
    let pts = left
        .iter()
        .map(|&i| (2.0 * lsym as f64 - i as f64, s[i]))
        .chain(inner.iter().map(|&i| (i as f64, s[i])))
        .chain(right.iter().map(|&i| (2.0 * rsym as f64 - i as f64, s[i])));
    for (t, z) in pts {
        if k.t.last() == Some(&t) {
            k.t.pop();
            k.z.pop();
        }
        k.t.push(t);
        k.z.push(z);
    }
}

#[derive(Debug, Clone, Default)]
pub(crate) struct SplineWs {
    pub(crate) dx: Vec<f64>,
    pub(crate) slope: Vec<f64>,
    pub(crate) d: Vec<f64>,
    pub(crate) dl: Vec<f64>,
    pub(crate) du: Vec<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) c0: Vec<f64>,
    pub(crate) c1: Vec<f64>,
}

/// Where the values of an envelope go: the spline hands over runs of consecutive samples
/// `start..end` with the polynomial `p(t)` that covers them (`t` the sample position as f64).
pub(crate) trait Sink {
    fn segment<P: Fn(f64) -> f64>(&mut self, start: usize, end: usize, p: P);
}

/// Segments ending at or before this sample have all their positions in u32.
pub(crate) const U32_END: usize = u32::MAX as usize;

/// Stores the envelope.
pub(crate) struct Store<'a>(pub(crate) &'a mut [f64]);

impl Sink for Store<'_> {
    #[inline(always)]
    fn segment<P: Fn(f64) -> f64>(&mut self, start: usize, end: usize, p: P) {
        let out = &mut self.0[start..end];
        if end <= U32_END {
            // u32 → f64 is exact like usize → f64, and the compiler converts two at a time
            for (j, o) in (start as u32..end as u32).zip(out) {
                *o = p(f64::from(j));
            }
        } else {
            for (j, o) in (start..end).zip(out) {
                *o = p(j as f64);
            }
        }
    }
}

/// The sifting step with this envelope as the lower one: `new = old − (upper + lower) / 2`.
pub(crate) struct SubtractMean<'a> {
    pub(crate) upper: &'a [f64],
    pub(crate) old: &'a [f64],
    pub(crate) new: &'a mut [f64],
}

impl Sink for SubtractMean<'_> {
    #[inline(always)]
    fn segment<P: Fn(f64) -> f64>(&mut self, start: usize, end: usize, p: P) {
        let new = &mut self.new[start..end];
        let old = &self.old[start..end];
        let upper = &self.upper[start..end];
        let values = new.iter_mut().zip(old).zip(upper);
        if end <= U32_END {
            for (j, ((v, &o), &a)) in (start as u32..end as u32).zip(values) {
                *v = o - 0.5 * (a + p(f64::from(j)));
            }
        } else {
            for (j, ((v, &o), &a)) in (start..end).zip(values) {
                *v = o - 0.5 * (a + p(j as f64));
            }
        }
    }
}

/// Evaluates the envelope spline through `k` at the sample positions 0..n into `sink` (scipy's
/// `CubicSpline` through more than three knots, PyEMD's `cubic_spline_3pts` through three).
pub(crate) fn spline_envelope<S: Sink>(
    k: &Knots,
    n: usize,
    sink: &mut S,
    ws: &mut SplineWs,
) -> Result<()> {
    let m = k.t.len();
    if m < 3 {
        return Err(degenerate("EMD envelope has fewer than three knots"));
    }
    if k.t[0] > 0.0 || k.t[m - 1] < (n - 1) as f64 {
        return Err(degenerate("EMD envelope knots do not span the signal"));
    }
    if k.t.windows(2).any(|w| w[1] <= w[0]) {
        return Err(degenerate("EMD envelope knots are not strictly increasing"));
    }
    if m == 3 {
        spline_3pts(&k.t, &k.z, n, sink);
        return Ok(());
    }
    not_a_knot(&k.t, &k.z, ws)?;
    // PPoly evaluation: sample j uses the interval x[i] <= j < x[i+1] (the last one closed on the
    // right); walk the intervals and hand over the samples each covers.
    let (x, y) = (&k.t[..m], &k.z[..m]);
    let (c2, c1, c0) = (&ws.b[..m], &ws.c1[..m - 1], &ws.c0[..m - 1]);
    let mut j = 0usize;
    for i in 0..m - 1 {
        let end = if i + 2 == m {
            n
        } else {
            // first sample at or beyond the next knot (knots are integers, possibly negative)
            (x[i + 1].max(0.0) as usize).min(n)
        };
        if j < end {
            let (yi, c2, c1, c0, xi) = (y[i], c2[i], c1[i], c0[i], x[i]);
            sink.segment(j, end, |t| {
                let s = t - xi;
                let s2 = s * s;
                let s3 = s2 * s;
                yi + c2 * s + c1 * s2 + c0 * s3
            });
            j = end;
        }
    }
    Ok(())
}

/// scipy's `CubicSpline(x, y)` (not-a-knot both ends, n > 3): the slopes from `dgtsv`, then the
/// `CubicHermiteSpline` coefficients. Leaves c3 = y, c2 = slopes (in `b`), c1, c0.
pub(crate) fn not_a_knot(x: &[f64], y: &[f64], ws: &mut SplineWs) -> Result<()> {
    let m = x.len();
    // grow-only buffers, used through slices of the exact lengths (every element is written
    // below, so nothing is zero-filled, and the loops below need no bounds checks)
    for v in [
        &mut ws.dx,
        &mut ws.slope,
        &mut ws.d,
        &mut ws.dl,
        &mut ws.du,
        &mut ws.b,
        &mut ws.c0,
        &mut ws.c1,
    ] {
        if v.len() < m {
            v.resize(m, 0.0);
        }
    }
    let dx = &mut ws.dx[..m - 1];
    let slope = &mut ws.slope[..m - 1];
    let d = &mut ws.d[..m];
    let dl = &mut ws.dl[..m - 1];
    let du = &mut ws.du[..m - 1];
    let b = &mut ws.b[..m];
    let c0 = &mut ws.c0[..m - 1];
    let c1 = &mut ws.c1[..m - 1];
    for (((h, sl), x), y) in dx
        .iter_mut()
        .zip(slope.iter_mut())
        .zip(x.windows(2))
        .zip(y.windows(2))
    {
        *h = x[1] - x[0];
        *sl = (y[1] - y[0]) / *h;
    }
    // interior rows
    for (((dr, br), h), sl) in d[1..m - 1]
        .iter_mut()
        .zip(b[1..m - 1].iter_mut())
        .zip(dx.windows(2))
        .zip(slope.windows(2))
    {
        *dr = 2.0 * (h[0] + h[1]);
        *br = 3.0 * (h[1] * sl[0] + h[0] * sl[1]);
    }
    // sub-diagonal dx[i+1] (rows 1..m-2), super-diagonal dx[i-1] (rows 1..m-2)
    dl[..m - 2].copy_from_slice(&dx[1..m - 1]);
    du[1..m - 1].copy_from_slice(&dx[..m - 2]);
    // not-a-knot start
    let w = x[2] - x[0];
    d[0] = dx[1];
    du[0] = w;
    b[0] = ((dx[0] + 2.0 * w) * dx[1] * slope[0] + dx[0] * dx[0] * slope[1]) / w;
    // not-a-knot end
    let w = x[m - 1] - x[m - 3];
    d[m - 1] = dx[m - 3];
    dl[m - 2] = w;
    b[m - 1] = (dx[m - 2] * dx[m - 2] * slope[m - 3]
        + (2.0 * w + dx[m - 2]) * dx[m - 3] * slope[m - 2])
        / w;
    dgtsv(dl, d, du, b)?;
    // CubicHermiteSpline: t = (s_i + s_{i+1} - 2 slope_i) / dx_i; c0 = t / dx; c1 = (slope - s_i) / dx - t
    for ((((c0, c1), bw), &sl), &h) in c0
        .iter_mut()
        .zip(c1.iter_mut())
        .zip(b.windows(2))
        .zip(slope.iter())
        .zip(dx.iter())
    {
        let t = (bw[0] + bw[1] - 2.0 * sl) / h;
        *c0 = t / h;
        *c1 = (sl - bw[0]) / h - t;
    }
    Ok(())
}

/// LAPACK `dgtsv` for one right-hand side: tridiagonal solve by Gaussian elimination with partial
/// pivoting. `dl` (sub-diagonal) is reused for the second super-diagonal; the solution replaces `b`.
pub(crate) fn dgtsv(dl: &mut [f64], d: &mut [f64], du: &mut [f64], b: &mut [f64]) -> Result<()> {
    let n = d.len();
    let singular = || degenerate("EMD envelope spline system is singular");
    // views of the exact lengths, so that the compiler can drop the bounds checks below
    let nm1 = n.saturating_sub(1);
    let (dl, du, b) = (&mut dl[..nm1], &mut du[..nm1], &mut b[..n]);
    for i in 0..n.saturating_sub(2) {
        if !eliminate(i, true, dl, d, du, b) {
            return Err(singular());
        }
    }
    // The last row has no second super-diagonal to fill.
    if n > 1 && !eliminate(n - 2, false, dl, d, du, b) {
        return Err(singular());
    }
    if d[n - 1] == 0.0 {
        return Err(singular());
    }
    b[n - 1] /= d[n - 1];
    if n > 1 {
        b[n - 2] = (b[n - 2] - du[n - 2] * b[n - 1]) / d[n - 2];
    }
    for i in (0..n.saturating_sub(2)).rev() {
        b[i] = (b[i] - du[i] * b[i + 1] - dl[i] * b[i + 2]) / d[i];
    }
    Ok(())
}

/// [`dgtsv`]'s elimination of row `i + 1` by row `i` (LAPACK's loop body), pivoting on the larger
/// of `d[i]` and `dl[i]`; `fill` (every row but the last) also fills the second super-diagonal
/// (kept in `dl[i]`). False when the pivot is zero (the system is singular).
#[inline(always)]
fn eliminate(
    i: usize,
    fill: bool,
    dl: &mut [f64],
    d: &mut [f64],
    du: &mut [f64],
    b: &mut [f64],
) -> bool {
    if d[i].abs() >= dl[i].abs() {
        if d[i] == 0.0 {
            return false;
        }
        let fact = dl[i] / d[i];
        d[i + 1] -= fact * du[i];
        b[i + 1] -= fact * b[i];
        if fill {
            dl[i] = 0.0;
        }
    } else {
        let fact = d[i] / dl[i];
        d[i] = dl[i];
        let temp = d[i + 1];
        d[i + 1] = du[i] - fact * temp;
        if fill {
            dl[i] = du[i + 1];
            du[i + 1] = -fact * dl[i];
        }
        du[i] = temp;
        let temp = b[i];
        b[i] = b[i + 1];
        b[i + 1] = temp - fact * b[i + 1];
    }
    true
}

/// PyEMD's `cubic_spline_3pts` (a natural cubic spline through three knots), evaluated at 0..n.
pub(crate) fn spline_3pts<S: Sink>(x: &[f64], y: &[f64], n: usize, sink: &mut S) {
    let (x0, x1, x2) = (x[0], x[1], x[2]);
    let (y0, y1, y2) = (y[0], y[1], y[2]);
    let (x1x0, x2x1) = (x1 - x0, x2 - x1);
    let (y1y0, y2y1) = (y1 - y0, y2 - y1);
    let (ix1x0, ix2x1) = (1.0 / x1x0, 1.0 / x2x1);
    let mut a = [
        [2.0 * ix1x0, ix1x0, 0.0],
        [ix1x0, 2.0 * (ix1x0 + ix2x1), ix2x1],
        [0.0, ix2x1, 2.0 * ix2x1],
    ];
    let v1 = 3.0 * y1y0 * ix1x0 * ix1x0;
    let v3 = 3.0 * y2y1 * ix2x1 * ix2x1;
    let mut v = [v1, v1 + v3, v3];
    solve3(&mut a, &mut v);
    let k = v;
    let a1 = k[0] * x1x0 - y1y0;
    let b1 = -k[1] * x1x0 + y1y0;
    let a2 = k[1] * x2x1 - y2y1;
    let b2 = -k[2] * x2x1 + y2y1;
    // the samples with t < x1 (a prefix), then the rest
    let split = (x1.ceil().max(0.0) as usize).min(n);
    sink.segment(0, split, |t| {
        let t1 = (t - x0) / x1x0;
        let t11 = 1.0 - t1;
        t11 * y0 + t1 * y1 + t1 * t11 * (a1 * t11 + b1 * t1)
    });
    sink.segment(split, n, |t| {
        let t2 = (t - x1) / x2x1;
        let t22 = 1.0 - t2;
        t22 * y1 + t2 * y2 + t2 * t22 * (a2 * t22 + b2 * t2)
    });
}

/// 3×3 solve by Gaussian elimination with partial pivoting (as `numpy.linalg.solve` / LAPACK `gesv`).
pub(crate) fn solve3(a: &mut [[f64; 3]; 3], v: &mut [f64; 3]) {
    for col in 0..3 {
        let p = (col..3)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()).then(j.cmp(&i)))
            .unwrap_or(col);
        a.swap(col, p);
        v.swap(col, p);
        let pivot = a[col];
        for r in col + 1..3 {
            let f = a[r][col] / pivot[col];
            for (x, p) in a[r][col..].iter_mut().zip(&pivot[col..]) {
                *x -= f * p;
            }
            v[r] -= f * v[col];
        }
    }
    for col in (0..3).rev() {
        let mut acc = v[col];
        for c in col + 1..3 {
            acc -= a[col][c] * v[c];
        }
        v[col] = acc / a[col][col];
    }
}
