//! P300 decoding: from epochs `(n_epochs, n_channels, n_times)` to target evidence per epoch.
//!
//! Conventions shared by every module:
//! * Unfitted settings and fitted models are different types: `XxxParams::fit(...) -> Result<Xxx>`.
//! * Epoch input is `ArrayView3<f64>` `(n_epochs, n_channels, n_times)` in µV; feature matrices are
//!   `Array2<f64>` `(n_epochs, n_features)`; labels are `&[bool]` (`true` = target).
//! * Classifiers give a continuous score per epoch (`decision_function`, larger = more target-like)
//!   and `predict_proba` = P(target).
//! * Fitted models derive `Serialize`/`Deserialize` so pipelines save and load.
//!
//! # Example
//! The ROC AUC of target scores: 1 when every target scores above every non-target, 0.5 for a
//! tie, and the share of (target, non-target) pairs in the right order in general:
//! ```
//! use oddball_decode::metrics::roc_auc;
//!
//! let labels = [true, false, true, false];
//! assert_eq!(roc_auc(&[0.9, 0.1, 0.8, 0.3], &labels)?, 1.0);
//! assert_eq!(roc_auc(&[0.5; 4], &labels)?, 0.5);
//! assert_eq!(roc_auc(&[0.9, 0.85, 0.2, 0.1], &labels)?, 0.75);
//! # Ok::<(), oddball_decode::DecodeError>(())
//! ```

pub mod amplitude;
pub mod channel_select;
pub mod covariance;
pub mod decision;
pub mod emd;
pub mod ensemble;
mod error;
pub mod evaluate;
pub mod hilbert;
pub mod knn;
pub mod lda;
mod linalg;
pub mod logistic;
pub mod metrics;
pub mod pca;
pub mod pipeline;
pub mod riemann;
pub mod scaler;
pub mod stats;
pub mod svm;
#[cfg(test)]
mod testutil;
pub mod toeplitz_lda;
pub mod tuning;
pub mod wavelet;
pub mod xdawn;

pub use error::DecodeError;
