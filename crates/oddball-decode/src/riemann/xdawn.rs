//! xDAWN spatial filters and xDAWN covariance matrices, as pyRiemann 0.12's `Xdawn` and
//! `XdawnCovariances`.
//!
//! [`XdawnParams::fit`] on epochs `(n_epochs, n_channels, n_times)` in µV with labels (`true` =
//! target), for each class in the order non-target, target (pyRiemann's `np.unique` order of
//! `[False, True]`):
//! * noise covariance `C_x` = the estimator applied to all epochs concatenated in time
//!   (`(n_channels, n_epochs·n_times)`; pyRiemann's default `"scm"`, centred and `/ N`);
//! * evoked prototype `P` = mean of the class's epochs `(n_channels, n_times)`, signal covariance
//!   `C = estimator(P)`;
//! * generalized eigenvectors of `C v = λ C_x v` sorted by decreasing `λ`, each scaled to unit
//!   Euclidean norm; the first `k = min(nfilter, n_channels)` are the class's filters (rows of
//!   [`Xdawn::filters`]); the patterns are the matching columns of `(Vᵀ)⁻¹`; the evoked responses are
//!   `filters · P`.
//!
//! Eigenvector signs are arbitrary in LAPACK (and so in pyRiemann); here each filter is made to have
//! its largest-magnitude coefficient positive, so fits are reproducible. Results equal pyRiemann's
//! up to one sign per filter (which the golden test aligns).
//!
//! [`XdawnCovariancesParams::fit`] fits an [`Xdawn`] (with `xdawn_estimator`) and
//! [`XdawnCovariances::transform`] builds, per epoch `X`, the super-trial `[evokeds ; filters · X]`
//! `(4k, n_times)` and its covariance with `estimator` → SPD `(4k, 4k)` in µV² — `2·k·n_classes`
//! with the two classes. pyRiemann's class default for `estimator` is `"scm"`; this crate's default
//! is OAS (`XdawnCovariances(nfilter=4, estimator="oas")`, the usual P300 setting), which keeps the
//! matrices well conditioned.
//!
//! Written here: no well-kept Rust crate implements xDAWN; checked against pyRiemann 0.12 in
//! `tests/linear_riemann_golden.rs`.

use nalgebra::DMatrix;
use ndarray::{Array2, Array3, ArrayView2, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::linalg::{
    check_finite, check_labels, copy_transposed_into, generalized_eigh, to_array2,
};
use crate::riemann::covariance::{estimate_columns, CovEstimator};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Settings of the xDAWN spatial filters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct XdawnParams {
    /// Filters kept per class (at most `n_channels` are used).
    pub nfilter: usize,
    /// Estimator of the signal and noise covariances.
    pub estimator: CovEstimator,
}

impl Default for XdawnParams {
    fn default() -> Self {
        Self {
            nfilter: 4,
            estimator: CovEstimator::Scm,
        }
    }
}

/// Fitted xDAWN spatial filters for the two classes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Xdawn {
    /// `(2k, n_channels)`: rows `0..k` non-target filters, `k..2k` target filters.
    filters: Array2<f64>,
    /// `(2k, n_channels)`: the spatial patterns (forward model) of the filters.
    patterns: Array2<f64>,
    /// `(2k, n_times)`: filtered evoked responses, µV.
    evokeds: Array2<f64>,
}

impl XdawnParams {
    /// Fits on `epochs` `(n_epochs, n_channels, n_times)` with labels `y` (`true` = target).
    pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Xdawn> {
        if self.nfilter == 0 {
            return Err(DecodeError::InvalidParameter {
                name: "nfilter",
                value: "0".to_string(),
                reason: "at least one filter per class".to_string(),
            });
        }
        let (n_epochs, n_channels, n_times) = epochs.dim();
        check_labels(n_epochs, y)?;
        if n_channels == 0 || n_times < 2 {
            return Err(DecodeError::ShapeMismatch {
                what: "xDAWN epochs".to_string(),
                expected: "at least 1 channel and 2 time samples".to_string(),
                got: format!("({n_epochs}, {n_channels}, {n_times})"),
            });
        }
        check_finite("xDAWN epochs", epochs.iter())?;
        let k = self.nfilter.min(n_channels);

        // Noise covariance of all epochs concatenated in time.
        let mut all = DMatrix::zeros(n_epochs * n_times, n_channels);
        for (e, epoch) in epochs.outer_iter().enumerate() {
            for c in 0..n_channels {
                for t in 0..n_times {
                    all[(e * n_times + t, c)] = epoch[[c, t]];
                }
            }
        }
        let mut noise = DMatrix::zeros(n_channels, n_channels);
        estimate_columns(self.estimator, &mut all, &mut noise);

        let mut filters = Array2::zeros((2 * k, n_channels));
        let mut patterns = Array2::zeros((2 * k, n_channels));
        let mut evokeds = Array2::zeros((2 * k, n_times));
        for (ci, class) in [false, true].into_iter().enumerate() {
            // Prototype P as a data matrix (n_times, n_channels).
            let mut proto = DMatrix::zeros(n_times, n_channels);
            let mut count = 0usize;
            for (epoch, _) in epochs.outer_iter().zip(y).filter(|(_, &t)| t == class) {
                count += 1;
                for c in 0..n_channels {
                    for t in 0..n_times {
                        proto[(t, c)] += epoch[[c, t]];
                    }
                }
            }
            proto /= count as f64;
            let mut centred = proto.clone();
            let mut signal = DMatrix::zeros(n_channels, n_channels);
            estimate_columns(self.estimator, &mut centred, &mut signal);

            let (_, v_asc) = generalized_eigh("xDAWN signal/noise covariances", &signal, &noise)?;
            // Decreasing eigenvalue order, unit norm, largest-magnitude coefficient positive.
            let mut v = DMatrix::zeros(n_channels, n_channels);
            for j in 0..n_channels {
                let src = v_asc.column(n_channels - 1 - j);
                let norm = src.norm();
                let imax = src.iamax();
                let sign = if src[imax] < 0.0 { -1.0 } else { 1.0 };
                v.set_column(j, &(src * (sign / norm)));
            }
            let a =
                v.transpose()
                    .try_inverse()
                    .ok_or_else(|| DecodeError::NotPositiveDefinite {
                        what: "xDAWN filter matrix (singular)".to_string(),
                    })?;
            for f in 0..k {
                let row = ci * k + f;
                for c in 0..n_channels {
                    filters[[row, c]] = v[(c, f)];
                    patterns[[row, c]] = a[(c, f)];
                }
                for t in 0..n_times {
                    evokeds[[row, t]] = (0..n_channels).map(|c| v[(c, f)] * proto[(t, c)]).sum();
                }
            }
        }
        Ok(Xdawn {
            filters,
            patterns,
            evokeds,
        })
    }
}

impl Xdawn {
    /// `(2k, n_channels)`: rows `0..k` non-target filters, `k..2k` target filters.
    pub fn filters(&self) -> ArrayView2<'_, f64> {
        self.filters.view()
    }

    /// `(2k, n_channels)`: the spatial patterns (columns of `(Vᵀ)⁻¹`) of the filters.
    pub fn patterns(&self) -> ArrayView2<'_, f64> {
        self.patterns.view()
    }

    /// `(2k, n_times)`: the filtered class-mean responses, µV.
    pub fn evokeds(&self) -> ArrayView2<'_, f64> {
        self.evokeds.view()
    }

    /// Number of filters `2k` (both classes).
    pub fn n_components(&self) -> usize {
        self.filters.nrows()
    }

    /// Number of channels the filters apply to.
    pub fn n_channels(&self) -> usize {
        self.filters.ncols()
    }

    /// Number of time samples per epoch seen in fitting.
    pub fn n_times(&self) -> usize {
        self.evokeds.ncols()
    }

    /// Spatially filtered epochs `(n_epochs, 2k, n_times)` = `filters · X` per epoch.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array3<f64>> {
        let (n_epochs, n_channels, n_times) = epochs.dim();
        if n_channels != self.n_channels() {
            return Err(DecodeError::ShapeMismatch {
                what: "xDAWN input channels".to_string(),
                expected: self.n_channels().to_string(),
                got: n_channels.to_string(),
            });
        }
        check_finite("xDAWN input", epochs.iter())?;
        let mut out = Array3::zeros((n_epochs, self.n_components(), n_times));
        for (x, mut dst) in epochs.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            dst.assign(&self.filters.dot(&x));
        }
        Ok(out)
    }
}

/// Settings of the xDAWN covariance matrices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct XdawnCovariancesParams {
    /// xDAWN filters kept per class.
    pub nfilter: usize,
    /// Estimator of the super-trial covariance (default OAS).
    pub estimator: CovEstimator,
    /// Estimator inside xDAWN (default SCM, pyRiemann's).
    pub xdawn_estimator: CovEstimator,
}

impl Default for XdawnCovariancesParams {
    fn default() -> Self {
        Self {
            nfilter: 4,
            estimator: CovEstimator::Oas,
            xdawn_estimator: CovEstimator::Scm,
        }
    }
}

impl XdawnCovariancesParams {
    /// Fits the xDAWN filters and prototypes on training epochs `(n_epochs, n_channels, n_times)`.
    pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<XdawnCovariances> {
        let xdawn = XdawnParams {
            nfilter: self.nfilter,
            estimator: self.xdawn_estimator,
        }
        .fit(epochs, y)?;
        Ok(XdawnCovariances::new(xdawn, self.estimator))
    }
}

/// Fitted xDAWN covariance estimator: epochs → SPD `(4k, 4k)`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(from = "XdawnCovariancesRepr", into = "XdawnCovariancesRepr")]
pub struct XdawnCovariances {
    xdawn: Xdawn,
    estimator: CovEstimator,
    /// `filtersᵀ` `(n_channels, 2k)`.
    filters_t: DMatrix<f64>,
    /// `evokedsᵀ` `(n_times, 2k)`.
    evokeds_t: DMatrix<f64>,
}

#[derive(Serialize, Deserialize)]
struct XdawnCovariancesRepr {
    xdawn: Xdawn,
    estimator: CovEstimator,
}

impl From<XdawnCovariancesRepr> for XdawnCovariances {
    fn from(r: XdawnCovariancesRepr) -> Self {
        Self::new(r.xdawn, r.estimator)
    }
}

impl From<XdawnCovariances> for XdawnCovariancesRepr {
    fn from(x: XdawnCovariances) -> Self {
        Self {
            xdawn: x.xdawn,
            estimator: x.estimator,
        }
    }
}

/// Reusable buffers for [`XdawnCovariances`] on one epoch (one per thread in batches).
#[derive(Debug, Default)]
pub(crate) struct Buffers {
    xt: DMatrix<f64>,
    super_trial: DMatrix<f64>,
    cov: DMatrix<f64>,
}

impl XdawnCovariances {
    fn new(xdawn: Xdawn, estimator: CovEstimator) -> Self {
        let filters_t = DMatrix::from_fn(xdawn.n_channels(), xdawn.n_components(), |c, f| {
            xdawn.filters[[f, c]]
        });
        let evokeds_t = DMatrix::from_fn(xdawn.n_times(), xdawn.n_components(), |t, f| {
            xdawn.evokeds[[f, t]]
        });
        Self {
            xdawn,
            estimator,
            filters_t,
            evokeds_t,
        }
    }

    /// The fitted xDAWN filters and prototypes.
    pub fn xdawn(&self) -> &Xdawn {
        &self.xdawn
    }

    /// The super-trial covariance estimator.
    pub fn estimator(&self) -> CovEstimator {
        self.estimator
    }

    /// Side `4k` of the output matrices.
    pub fn size(&self) -> usize {
        2 * self.xdawn.n_components()
    }

    /// SPD matrices `(n_epochs, 4k, 4k)` (µV²) of `epochs` `(n_epochs, n_channels, n_times)`.
    pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<Array3<f64>> {
        let (n_epochs, n_channels, n_times) = epochs.dim();
        self.check_epoch(n_channels, n_times)?;
        check_finite("xDAWN covariance input", epochs.iter())?;
        let m = self.size();
        let mut out = Array3::zeros((n_epochs, m, m));
        let mut buf = Buffers::default();
        for (x, mut dst) in epochs.outer_iter().zip(out.axis_iter_mut(Axis(0))) {
            self.covariance_into(x, &mut buf);
            dst.indexed_iter_mut()
                .for_each(|((i, j), v)| *v = buf.cov[(i, j)]);
        }
        Ok(out)
    }

    /// SPD matrix `(4k, 4k)` of one epoch `(n_channels, n_times)`.
    pub fn transform_epoch(&self, epoch: ArrayView2<f64>) -> Result<Array2<f64>> {
        self.check_epoch(epoch.nrows(), epoch.ncols())?;
        check_finite("xDAWN covariance input", epoch.iter())?;
        let mut buf = Buffers::default();
        self.covariance_into(epoch, &mut buf);
        Ok(to_array2(&buf.cov))
    }

    /// SPD matrix `(4k, 4k)` of one epoch, computed in `buf` (no allocation once `buf` has
    /// seen an epoch of this shape).
    pub(crate) fn covariance_of<'b>(
        &self,
        epoch: ArrayView2<f64>,
        buf: &'b mut Buffers,
    ) -> Result<&'b DMatrix<f64>> {
        self.check_epoch(epoch.nrows(), epoch.ncols())?;
        check_finite("xDAWN covariance input", epoch.iter())?;
        self.covariance_into(epoch, buf);
        Ok(&buf.cov)
    }

    fn check_epoch(&self, n_channels: usize, n_times: usize) -> Result<()> {
        let (ec, et) = (self.xdawn.n_channels(), self.xdawn.n_times());
        if n_channels != ec || n_times != et {
            return Err(DecodeError::ShapeMismatch {
                what: "xDAWN covariance input epoch".to_string(),
                expected: format!("({ec}, {et})"),
                got: format!("({n_channels}, {n_times})"),
            });
        }
        Ok(())
    }

    /// Super-trial `[evokeds ; filters·X]` as a data matrix `(n_times, 4k)` and its covariance.
    fn covariance_into(&self, x: ArrayView2<f64>, buf: &mut Buffers) {
        let n_times = x.ncols();
        let nc = self.xdawn.n_components();
        copy_transposed_into(x, &mut buf.xt);
        if buf.super_trial.nrows() != n_times || buf.super_trial.ncols() != 2 * nc {
            buf.super_trial = DMatrix::zeros(n_times, 2 * nc);
        }
        buf.super_trial
            .columns_mut(0, nc)
            .copy_from(&self.evokeds_t);
        buf.super_trial
            .columns_mut(nc, nc)
            .gemm(1.0, &buf.xt, &self.filters_t, 0.0);
        estimate_columns(self.estimator, &mut buf.super_trial, &mut buf.cov);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two channels; the target response lives on channel 0 only, noise on both.
    fn toy() -> (Array3<f64>, Vec<bool>) {
        let (n_epochs, n_times) = (40, 20);
        let mut x = Array3::zeros((n_epochs, 3, n_times));
        let y: Vec<bool> = (0..n_epochs).map(|e| e % 4 == 0).collect();
        let mut s = 12345u64;
        let mut noise = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for e in 0..n_epochs {
            for t in 0..n_times {
                let common = noise();
                x[[e, 0, t]] = common + 0.3 * noise();
                x[[e, 1, t]] = common + 0.3 * noise();
                x[[e, 2, t]] = noise();
                if y[e] {
                    x[[e, 0, t]] += 2.0 * (-((t as f64 - 10.0) / 3.0).powi(2)).exp();
                }
            }
        }
        (x, y)
    }

    #[test]
    fn filters_are_unit_norm_with_positive_peak_and_patterns_invert() {
        let (x, y) = toy();
        let xd = XdawnParams {
            nfilter: 3,
            ..Default::default()
        }
        .fit(x.view(), &y)
        .unwrap();
        assert_eq!(xd.filters().dim(), (6, 3));
        for (ci, f) in xd.filters().outer_iter().enumerate() {
            assert!((f.dot(&f) - 1.0).abs() < 1e-12);
            let max = f
                .iter()
                .fold(0.0f64, |m, v| if v.abs() > m.abs() { *v } else { m });
            assert!(max > 0.0);
            // Vᵀ A = I within a class block.
            let block = ci / 3;
            for (pj, p) in xd
                .patterns()
                .outer_iter()
                .enumerate()
                .skip(block * 3)
                .take(3)
            {
                let expect = if pj == ci { 1.0 } else { 0.0 };
                assert!((f.dot(&p) - expect).abs() < 1e-10);
            }
        }
        // The target's first filter enhances channel 0 against the common noise: it must differ
        // channels 0 and 1 (opposite signs), cancelling the common component.
        let filters = xd.filters();
        let f = filters.row(3);
        assert!(f[0] * f[1] < 0.0, "{f}");
    }

    #[test]
    fn covariances_have_size_4k_are_spd_and_serialize() {
        let (x, y) = toy();
        let xc = XdawnCovariancesParams {
            nfilter: 2,
            ..Default::default()
        }
        .fit(x.view(), &y)
        .unwrap();
        assert_eq!(xc.size(), 8);
        let covs = xc.transform(x.view()).unwrap();
        assert_eq!(covs.dim(), (40, 8, 8));
        let one = xc.transform_epoch(x.index_axis(Axis(0), 5)).unwrap();
        assert_eq!(one, covs.index_axis(Axis(0), 5));
        for c in covs.outer_iter() {
            let m = crate::linalg::to_dmatrix(c);
            assert!(crate::linalg::sym_eigenvalues("t", &m).unwrap().min() > 0.0);
        }
        let json = serde_json::to_string(&xc).unwrap();
        let back: XdawnCovariances = serde_json::from_str(&json).unwrap();
        // serde_json's float parsing may be off by an ulp.
        let again = back.transform(x.view()).unwrap();
        let peak = covs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(again
            .iter()
            .zip(covs.iter())
            .all(|(a, b)| (a - b).abs() < 1e-12 * peak));
    }

    #[test]
    fn errors() {
        let (x, y) = toy();
        assert!(matches!(
            XdawnParams::default().fit(x.view(), &[false; 40]),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        let xc = XdawnCovariancesParams::default().fit(x.view(), &y).unwrap();
        assert!(matches!(
            xc.transform(Array3::zeros((1, 2, 20)).view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
    }
}
