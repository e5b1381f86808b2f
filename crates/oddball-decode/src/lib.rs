//! P300 decoding: from epochs `(n_epochs, n_channels, n_times)` to target evidence per epoch.
//!
//! Conventions shared by every module:
//! * Unfitted settings and fitted models are different types: `XxxParams::fit(...) -> Result<Xxx>`.
//! * Epoch input is `ArrayView3<f64>` `(n_epochs, n_channels, n_times)` in µV; feature matrices are
//!   `Array2<f64>` `(n_epochs, n_features)`; labels are `&[bool]` (`true` = target).
//! * Classifiers give a continuous score per epoch (`decision_function`, larger = more target-like)
//!   and `predict_proba` = P(target).
//! * Fitted models derive `Serialize`/`Deserialize` so pipelines save and load.
//! * Pipeline steps share the traits of [`traits`] (settings `fit` into a fitted
//!   [`traits::Transformer`] or [`traits::Scorer`]); features between steps are rows or, for
//!   the Riemannian classifiers, SPD matrices `(n_epochs, n, n)` ([`traits::FeatureData`]).
//!
//! Modules by role, as scikit-learn and pyRiemann group them: [`features`] (amplitude, EMD,
//! Hilbert, wavelet, PCA, scaler, channel selection), [`classifiers`] (SVM, k-NN, soft vote,
//! LDA, block-Toeplitz LDA, logistic regression), [`riemann`] (covariances, xDAWN, Riemannian
//! mean, tangent space, MDM), [`model_selection`] (folds, tuning); [`pipeline`] chains them,
//! [`preset`] names them, [`model`] saves them, [`decision`] turns scores into choices and
//! [`metrics`] measures them, [`stopping`] picks the stopping rule that maximises the bit rate,
//! [`adaptive`] follows a session online and [`unsupervised`] decodes without labels (EM over
//! the paradigm's constraint). Reading files, scoring presets on recordings and benchmarks over
//! data sets are the evaluation harness's (`oddball-eval`), as MOABB's are beside scikit-learn. Every module is named by its one path
//! (`oddball_decode::classifiers::svm`, `oddball_decode::model_selection::tuning`, …).
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

pub mod adaptive;
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
pub mod stopping;
#[cfg(test)]
mod testutil;
pub mod traits;
pub mod unsupervised;

pub use error::DecodeError;
