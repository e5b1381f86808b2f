//! Extrema and zero crossings of a signal, PyEMD's `_find_extrema_simple` rules.

#[derive(Debug, Clone, Default)]
pub(crate) struct Extrema {
    pub(crate) maxs: Vec<usize>,
    pub(crate) mins: Vec<usize>,
}

/// PyEMD's `_find_extrema_simple`, plateau rules included. A first pass marks the strict sign
/// changes of the first difference in 64-sample bit words (no stores, no data-dependent
/// branches); the set bits are then sorted into maxima and minima by the sign of the difference
/// before them.
pub(crate) fn find_extrema(s: &[f64], ext: &mut Extrema) {
    ext.maxs.clear();
    ext.mins.clear();
    // room for every sample: no reallocation below, nor in later calls of this length
    ext.maxs.reserve(s.len());
    ext.mins.reserve(s.len());
    let mut d1 = s[1] - s[0];
    let mut any_flat = d1 == 0.0;
    let mut b = s[1];
    // sample index of bit 0 of the current word: bit k of a word marks sample base + k, whose
    // neighbours are the previous sample and `c`
    let mut base = 1;
    for chunk in s[2..].chunks(64) {
        let mut word = 0u64;
        for (k, &c) in chunk.iter().enumerate() {
            let d2 = c - b;
            word |= u64::from(d1 * d2 < 0.0) << k;
            any_flat |= d2 == 0.0;
            d1 = d2;
            b = c;
        }
        while word != 0 {
            let i = base + word.trailing_zeros() as usize;
            word &= word - 1;
            // the same first difference as in the scan: nonzero, since the product was negative
            if s[i] - s[i - 1] > 0.0 {
                ext.maxs.push(i);
            } else {
                ext.mins.push(i);
            }
        }
        base += chunk.len();
    }
    if any_flat {
        plateaus(s, ext);
    }
}

/// Zero crossings as PyEMD counts them (`len(indzer)`): strict sign changes plus runs of exact
/// zeros.
pub(crate) fn zero_crossings(s: &[f64]) -> usize {
    let mut nz = usize::from(s[0] == 0.0);
    for (&a, &b) in s.iter().zip(&s[1..]) {
        nz += usize::from(a * b < 0.0) + usize::from(b == 0.0 && a != 0.0);
    }
    nz
}

/// The plateau part of `_find_extrema_simple` (rare: needs exactly equal neighbours).
pub(crate) fn plateaus(s: &[f64], ext: &mut Extrema) {
    let nd = s.len() - 1;
    let d = |i: usize| s[i + 1] - s[i];
    // runs [beg, fin) of zero first differences
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < nd {
        if d(i) == 0.0 {
            let beg = i;
            while i < nd && d(i) == 0.0 {
                i += 1;
            }
            runs.push((beg, i));
        } else {
            i += 1;
        }
    }
    // PyEMD drops a first run starting at difference index 1 and a last run ending at the end.
    if runs.first().is_some_and(|r| r.0 == 1) {
        runs.remove(0);
    }
    if runs.last().is_some_and(|r| r.1 == s.len() - 1) {
        runs.pop();
    }
    let mut added = false;
    for &(beg, fin) in &runs {
        // numpy's d[debs - 1] wraps to the last difference when debs == 0
        let before = if beg == 0 { d(nd - 1) } else { d(beg - 1) };
        let after = d(fin);
        let mid = ((beg + fin) as f64 / 2.0).round_ties_even() as usize;
        if before > 0.0 && after < 0.0 {
            ext.maxs.push(mid);
            added = true;
        } else if before < 0.0 && after > 0.0 {
            ext.mins.push(mid);
            added = true;
        }
    }
    if added {
        ext.maxs.sort_unstable();
        ext.mins.sort_unstable();
    }
}
