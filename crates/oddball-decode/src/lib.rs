//! P300 decoding: from epochs `(n_epochs, n_channels, n_times)` to target evidence per epoch.
//!
//! Conventions shared by every module:
//! * Unfitted settings and fitted models are different types: `XxxParams::fit(...) -> Result<Xxx>`.
//! * Epoch input is `ArrayView3<f64>` `(n_epochs, n_channels, n_times)` in µV; feature matrices are
//!   `Array2<f64>` `(n_epochs, n_features)`; labels are `&[bool]` (`true` = target).
//! * Classifiers give a continuous score per epoch (`decision_function`, larger = more target-like)
//!   and `predict_proba` = P(target).
//! * Fitted models derive `Serialize`/`Deserialize` so pipelines save and load.

pub mod classifiers;
pub mod decision;
mod error;
pub mod features;
mod linalg;
pub mod metrics;
pub mod model;
pub mod model_selection;
pub mod pipeline;
pub mod preprocess;
pub mod preset;
pub mod riemann;
#[cfg(test)]
mod testutil;
pub mod traits;

// The modules at their paths before the grouping by role.
pub use classifiers::{ensemble, knn, lda, logistic, svm, toeplitz_lda};
pub use features::{amplitude, channel_select, emd, hilbert, pca, scaler, wavelet};
pub use model_selection::tuning;
pub use riemann::{covariance, xdawn};

pub use error::DecodeError;
