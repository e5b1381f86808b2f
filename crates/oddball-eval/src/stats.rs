//! Paired comparison of two decoders across subjects: the Wilcoxon signed-rank test, as MOABB
//! reports it (`scipy.stats.wilcoxon` with its defaults).
//!
//! `d = x − y`; zeros are dropped (`zero_method="wilcox"`); `|d|` is ranked with ties given their
//! average rank; `W+` is the sum of the ranks of the positive differences. The p-value is
//! computed as scipy's `method="auto"` does:
//! * no ties and no zeros and n ≤ 50: the exact null distribution of `W+` (subset sums of 1..n);
//! * ties or zeros and n ≤ 13 (n counting zeros): the exact sign-flip permutation test (all 2ⁿ
//!   flips, as `scipy.stats.permutation_test` enumerates when 2ⁿ < 9999);
//! * otherwise: the normal approximation with the tie correction and no continuity correction.
//!
//! The statistic is `min(W+, W−)` for the two-sided test and `W+` for one-sided tests. Checked
//! against scipy 1.17.1 (`tools/golden/stats`, fixture `tests/fixtures/wilcoxon_golden.json`).
//! Written here because no maintained Rust crate reproduces scipy's choice of method.

use thiserror::Error;

/// The alternative hypothesis about the median of `x − y`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Alternative {
    TwoSided,
    /// `x` tends to be larger than `y`.
    Greater,
    /// `x` tends to be smaller than `y`.
    Less,
}

/// How the p-value was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WilcoxonMethod {
    Exact,
    Permutation,
    Normal,
}

/// The result of [`wilcoxon`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wilcoxon {
    pub statistic: f64,
    pub pvalue: f64,
    pub method: WilcoxonMethod,
    /// Pairs that entered the ranks (non-zero differences).
    pub n: usize,
}

/// Inputs the test cannot take.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StatsError {
    #[error("paired samples differ in length ({x} and {y})")]
    Length { x: usize, y: usize },
    #[error("no pairs to compare")]
    Empty,
    #[error("pair {index} is not finite ({x}, {y})")]
    NotFinite { index: usize, x: f64, y: f64 },
    #[error("every difference is zero: the test has nothing to rank")]
    AllZero,
}

/// Average ranks (1-based) of `v`, and the tie correction `Σ (t³ − t)` over tie groups.
fn average_ranks(v: &[f64]) -> (Vec<f64>, f64) {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut ranks = vec![0.0; v.len()];
    let mut ties = 0.0;
    let mut i = 0;
    while i < order.len() {
        let mut j = i + 1;
        while j < order.len() && v[order[j]] == v[order[i]] {
            j += 1;
        }
        let rank = (i + 1 + j) as f64 / 2.0;
        for &k in &order[i..j] {
            ranks[k] = rank;
        }
        let t = (j - i) as f64;
        ties += t * t * t - t;
        i = j;
    }
    (ranks, ties)
}

/// The probabilities of `W+ = 0, 1, …, n(n+1)/2` under the null (scipy's `_get_wilcoxon_distr`).
fn exact_pmf(n: usize) -> Vec<f64> {
    let max = n * (n + 1) / 2;
    let mut counts = vec![0.0f64; max + 1];
    counts[0] = 1.0;
    let mut top = 0;
    for k in 1..=n {
        top += k;
        for s in (k..=top).rev() {
            counts[s] += counts[s - k];
        }
    }
    let total = 2f64.powi(n as i32);
    counts.iter().map(|c| c / total).collect()
}

/// Standard normal survival function `P(Z > z)`.
fn normal_sf(z: f64) -> f64 {
    0.5 * libm::erfc(z / std::f64::consts::SQRT_2)
}

/// The Wilcoxon signed-rank test of paired samples `x`, `y` (e.g. one AUC per subject for two
/// decoders). See the module doc for the method.
pub fn wilcoxon(x: &[f64], y: &[f64], alternative: Alternative) -> Result<Wilcoxon, StatsError> {
    if x.len() != y.len() {
        return Err(StatsError::Length {
            x: x.len(),
            y: y.len(),
        });
    }
    if x.is_empty() {
        return Err(StatsError::Empty);
    }
    if let Some(index) = (0..x.len()).find(|&i| !(x[i].is_finite() && y[i].is_finite())) {
        return Err(StatsError::NotFinite {
            index,
            x: x[index],
            y: y[index],
        });
    }
    let d_all: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    let n_all = d_all.len();
    let d: Vec<f64> = d_all.iter().copied().filter(|&v| v != 0.0).collect();
    if d.is_empty() {
        return Err(StatsError::AllZero);
    }
    let n_zero = n_all - d.len();
    let abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    let (ranks, tie_correct) = average_ranks(&abs);
    let has_ties = tie_correct > 0.0;
    let r_plus: f64 = d
        .iter()
        .zip(&ranks)
        .filter(|(v, _)| **v > 0.0)
        .map(|(_, r)| r)
        .sum();
    let r_minus: f64 = d
        .iter()
        .zip(&ranks)
        .filter(|(v, _)| **v < 0.0)
        .map(|(_, r)| r)
        .sum();
    let n = d.len();
    let statistic = match alternative {
        Alternative::TwoSided => r_plus.min(r_minus),
        _ => r_plus,
    };
    let (pvalue, method) = if !(has_ties || n_zero > 0) && n_all <= 50 {
        (exact_p(n, r_plus, alternative), WilcoxonMethod::Exact)
    } else if n_all <= 13 {
        (
            permutation_p(&d, &ranks, r_plus, alternative),
            WilcoxonMethod::Permutation,
        )
    } else {
        let nf = n as f64;
        let mn = nf * (nf + 1.0) * 0.25;
        let se = ((nf * (nf + 1.0) * (2.0 * nf + 1.0) - tie_correct / 2.0) / 24.0).sqrt();
        let z = (r_plus - mn) / se;
        let p = match alternative {
            Alternative::Greater => normal_sf(z),
            Alternative::Less => normal_sf(-z),
            Alternative::TwoSided => (2.0 * normal_sf(z.abs())).min(1.0),
        };
        (p, WilcoxonMethod::Normal)
    };
    Ok(Wilcoxon {
        statistic,
        pvalue,
        method,
        n,
    })
}

/// scipy's `WilcoxonDistribution.cdf/sf`, summing from the side it sums from.
fn exact_p(n: usize, r_plus: f64, alternative: Alternative) -> f64 {
    let pmf = exact_pmf(n);
    let mean = n as f64 * (n as f64 + 1.0) / 4.0;
    let sum = |lo: i64, hi: i64| -> f64 {
        let lo = lo.max(0) as usize;
        let hi = hi.min(pmf.len() as i64 - 1);
        if hi < lo as i64 {
            return 0.0;
        }
        pmf[lo..=hi as usize].iter().sum()
    };
    let top = pmf.len() as i64 - 1;
    let cdf = |k: i64| -> f64 {
        if k as f64 <= mean {
            sum(0, k)
        } else {
            1.0 - sum(k + 1, top)
        }
    };
    let sf = |k: i64| -> f64 {
        if k as f64 <= mean {
            sum(k, top)
        } else {
            1.0 - sum(0, k - 1)
        }
    };
    let lo = r_plus.ceil() as i64;
    let hi = r_plus.floor() as i64;
    match alternative {
        Alternative::Less => cdf(lo),
        Alternative::Greater => sf(hi),
        Alternative::TwoSided => (2.0 * sf(hi).min(cdf(lo))).clamp(0.0, 1.0),
    }
}

/// The exact sign-flip permutation p-value of `W+` (zeros already dropped: flipping them
/// changes nothing, so each arrangement of the non-zero signs stands for `2^n_zero` equal
/// ones, which cancel in the proportions).
fn permutation_p(d: &[f64], ranks: &[f64], observed: f64, alternative: Alternative) -> f64 {
    let n = d.len();
    // scipy's tolerance for theoretically equal values: |100·eps·observed|.
    let gamma = (f64::EPSILON * 100.0 * observed).abs();
    let (mut less, mut greater) = (0usize, 0usize);
    let total = 1usize << n;
    for mask in 0..total {
        // Bit k set: difference k is positive in this arrangement.
        let w: f64 = (0..n)
            .filter(|k| mask >> k & 1 == 1)
            .map(|k| ranks[k])
            .sum();
        if w <= observed + gamma {
            less += 1;
        }
        if w >= observed - gamma {
            greater += 1;
        }
    }
    let (pl, pg) = (less as f64 / total as f64, greater as f64 / total as f64);
    match alternative {
        Alternative::Less => pl,
        Alternative::Greater => pg,
        Alternative::TwoSided => (2.0 * pl.min(pg)).min(1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exact_distribution_is_the_subset_sums_of_one_to_n() {
        let pmf = exact_pmf(3);
        // Subsets of {1,2,3}: sums 0,1,2,3,3,4,5,6.
        let want = [1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0].map(|c| c / 8.0);
        assert_eq!(pmf, want);
        assert!((exact_pmf(20).iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn average_ranks_and_tie_correction() {
        let (r, t) = average_ranks(&[3.0, 1.0, 3.0, 2.0]);
        assert_eq!(r, vec![3.5, 1.0, 3.5, 2.0]);
        assert_eq!(t, 6.0);
    }

    #[test]
    fn bad_input_is_named() {
        assert!(matches!(
            wilcoxon(&[1.0], &[1.0, 2.0], Alternative::TwoSided),
            Err(StatsError::Length { .. })
        ));
        assert!(matches!(
            wilcoxon(&[1.0, f64::NAN], &[1.0, 2.0], Alternative::TwoSided),
            Err(StatsError::NotFinite { index: 1, .. })
        ));
        assert!(matches!(
            wilcoxon(&[1.0, 2.0], &[1.0, 2.0], Alternative::TwoSided),
            Err(StatsError::AllZero)
        ));
    }
}
