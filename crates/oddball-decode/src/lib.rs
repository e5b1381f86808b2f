//! P300 decoding: from epochs `(n_epochs, n_channels, n_times)` to target evidence per epoch.
//!
//! Conventions shared by every module:
//! * Unfitted settings and fitted models are different types: `XxxParams::fit(...) -> Result<Xxx>`.
//! * Epoch input is `ArrayView3<f64>` `(n_epochs, n_channels, n_times)` in µV; feature matrices are
//!   `Array2<f64>` `(n_epochs, n_features)`; labels are `&[bool]` (`true` = target).
//! * Classifiers give a continuous score per epoch (`decision_function`, larger = more target-like)
//!   and `predict_proba` = P(target).
//! * Fitted models derive `Serialize`/`Deserialize` so pipelines save and load.

pub mod amplitude;
pub mod channel_select;
pub mod covariance;
pub mod decision;
pub mod emd;
pub mod ensemble;
mod error;
pub mod hilbert;
pub mod knn;
pub mod lda;
mod linalg;
pub mod logistic;
pub mod metrics;
pub mod pca;
pub mod pipeline;
pub mod preprocess;
pub mod riemann;
pub mod scaler;
pub mod svm;
#[cfg(test)]
mod testutil;
pub mod toeplitz_lda;
pub mod tuning;
pub mod wavelet;
pub mod xdawn;

pub use error::DecodeError;
