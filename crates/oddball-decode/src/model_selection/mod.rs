//! Model selection, as scikit-learn's `model_selection`: cross-validation folds ([`folds`]) and
//! the choice of a pipeline's hyper-parameters by grid search on the training data ([`tuning`]).

pub mod folds;
pub mod tuning;

pub use folds::{cv_folds, Folds};
