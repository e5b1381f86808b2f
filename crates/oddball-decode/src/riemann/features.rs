//! The Riemannian feature maps of the `riemann` and `mdm` presets: every `step`-th sample of each
//! epoch, then xDAWN covariances `(n, n)` ([`XdawnCovFeatures`], SPD matrices for
//! [`crate::riemann::Mdm`]) or their tangent-space vectors ([`XdawnTangent`], rows).

use nalgebra::DMatrix;
use ndarray::parallel::prelude::*;
use ndarray::{s, Array2, Array3, ArrayView3, Axis};
use serde::{Deserialize, Serialize};

use crate::riemann::xdawn::{XdawnCovariances, XdawnCovariancesParams};
use crate::riemann::{TangentSpace, TangentSpaceParams};
use crate::traits::{FeatureData, FitTransformer, Transformer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Every `step`-th sample, then xDAWN covariances, then the Riemannian tangent space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdawnTangentParams {
    pub step: usize,
    pub xdawn: XdawnCovariancesParams,
    pub tangent: TangentSpaceParams,
}

/// Every `step`-th sample, then xDAWN covariances `(n, n)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdawnCovFeaturesParams {
    pub step: usize,
    pub xdawn: XdawnCovariancesParams,
}

/// Fitted xDAWN covariances on epochs decimated by `step`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct XdawnCovFeatures {
    pub step: usize,
    pub xdawn: XdawnCovariances,
}

/// Fitted xDAWN covariances and tangent space, on epochs decimated by `step`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct XdawnTangent {
    pub step: usize,
    pub xdawn: XdawnCovariances,
    pub tangent: TangentSpace,
}

/// Every `step`-th sample of each epoch, as a view (no copy).
fn every_nth(epochs: ArrayView3<'_, f64>, step: usize) -> ArrayView3<'_, f64> {
    epochs.slice_move(s![.., .., ..;step])
}

fn check_step(step: usize) -> Result<()> {
    if step == 0 {
        return Err(DecodeError::InvalidParameter {
            name: "step",
            value: "0".into(),
            reason: "the decimation step must be at least 1".into(),
        });
    }
    Ok(())
}

impl FitTransformer for XdawnCovFeaturesParams {
    type Fitted = XdawnCovFeatures;
    fn fit_transformer(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<XdawnCovFeatures> {
        check_step(self.step)?;
        let x = every_nth(epochs, self.step);
        Ok(XdawnCovFeatures {
            step: self.step,
            xdawn: self.xdawn.fit(x.view(), y)?,
        })
    }
}

impl FitTransformer for XdawnTangentParams {
    type Fitted = XdawnTangent;
    fn fit_transformer(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<XdawnTangent> {
        check_step(self.step)?;
        let x = every_nth(epochs, self.step);
        let xdawn = self.xdawn.fit(x.view(), y)?;
        let covs = xdawn.transform(x.view())?;
        let tangent = self.tangent.fit(covs.view())?;
        Ok(XdawnTangent {
            step: self.step,
            xdawn,
            tangent,
        })
    }
}

impl Transformer for XdawnTangent {
    /// Tangent vectors `(n_epochs, n(n+1)/2)`.
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        let x = every_nth(epochs, self.step);
        let n_features = self.tangent.n_features();
        let mut out = Array2::zeros((x.dim().0, n_features));
        // Epochs are independent: groups of four spread over rayon's threads, each group's
        // whitened covariances decomposed at once (the same numbers as one by one, see
        // `linalg::eigen4`); each thread reuses its own buffers.
        out.axis_chunks_iter_mut(Axis(0), 4)
            .into_par_iter()
            .zip(x.axis_chunks_iter(Axis(0), 4).into_par_iter())
            .try_for_each_init(
                || {
                    (
                        crate::riemann::xdawn::Buffers::default(),
                        crate::riemann::Scratch::default(),
                        <[DMatrix<f64>; 4]>::default(),
                        <[DMatrix<f64>; 4]>::default(),
                    )
                },
                |(buf, scratch, covs, pool), (mut rows, group)| -> Result<()> {
                    if group.dim().0 < 4 {
                        for (row, epoch) in rows.axis_iter_mut(Axis(0)).zip(group.outer_iter()) {
                            let cov = self.xdawn.covariance_of(epoch, buf)?;
                            self.tangent.vectorize_symmetric_into(cov, scratch, row)?;
                        }
                        return Ok(());
                    }
                    for (slot, epoch) in covs.iter_mut().zip(group.outer_iter()) {
                        let cov = self.xdawn.covariance_of(epoch, buf)?;
                        if slot.shape() == cov.shape() {
                            slot.copy_from(cov);
                        } else {
                            *slot = cov.clone();
                        }
                    }
                    self.tangent
                        .vectorize4_into(covs, pool, scratch, rows.view_mut())
                },
            )?;
        Ok(FeatureData::Rows(out))
    }
}

impl Transformer for XdawnCovFeatures {
    /// Covariance matrices `(n_epochs, n, n)`.
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        let x = every_nth(epochs, self.step);
        let n = self.xdawn.size();
        let mut out = Array3::zeros((x.dim().0, n, n));
        out.axis_iter_mut(Axis(0))
            .into_par_iter()
            .zip(x.axis_iter(Axis(0)).into_par_iter())
            .try_for_each_init(
                crate::riemann::xdawn::Buffers::default,
                |buf, (mut m, epoch)| -> Result<()> {
                    let cov = self.xdawn.covariance_of(epoch, buf)?;
                    m.iter_mut().zip(cov.iter()).for_each(|(o, &v)| *o = v);
                    Ok(())
                },
            )?;
        Ok(FeatureData::Spd(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The batched transform (four whitened covariances decomposed at once) gives exactly the
    /// numbers of the one-at-a-time composition, for a count that leaves a remainder group.
    #[test]
    fn tangent_features_in_groups_of_four_equal_one_at_a_time() {
        let (x, y) = crate::testutil::synthetic_p300(43, 7, 6, 1, 3.0, 4.0);
        let params = XdawnTangentParams {
            step: 2,
            xdawn: XdawnCovariancesParams::default(),
            tangent: TangentSpaceParams::default(),
        };
        let fitted = params.fit_transformer(x.view(), &y).unwrap();
        let FeatureData::Rows(batched) = fitted.transform_epochs(x.view()).unwrap() else {
            panic!("tangent vectors are rows");
        };
        let covs = fitted.xdawn.transform(every_nth(x.view(), 2)).unwrap();
        assert_eq!(batched.nrows(), 43);
        for (i, cov) in covs.outer_iter().enumerate() {
            let one = fitted.tangent.transform_one(cov).unwrap();
            assert_eq!(batched.row(i), one, "epoch {i}");
        }
    }
}
