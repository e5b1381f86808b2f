//! Model selection, as scikit-learn's `model_selection`: cross-validation folds ([`folds`], the
//! one home of every fold rule), the cross-validation spine that fits and scores on them
//! ([`cross_val`]) and the choice of a pipeline's hyper-parameters by grid search on the training
//! data ([`tuning`]).

pub mod cross_val;
pub mod folds;
pub mod tuning;

pub use cross_val::{cross_val_predict, cross_val_scores, FoldScores};
pub use folds::{cv_folds, interleaved_folds, Folds, Split};
