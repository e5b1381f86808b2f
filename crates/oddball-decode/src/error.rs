//! The one error type of `oddball-decode`: each variant carries the values at fault.

/// What went wrong while fitting or applying a decoder.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    #[error("{what}: expected {expected}, got {got}")]
    ShapeMismatch {
        what: String,
        expected: String,
        got: String,
    },
    #[error("fitting needs epochs of both classes; got {n_targets} targets and {n_nontargets} non-targets")]
    NeedBothClasses {
        n_targets: usize,
        n_nontargets: usize,
    },
    #[error("{n_samples} samples for {n_labels} labels")]
    LabelCount { n_samples: usize, n_labels: usize },
    #[error("parameter {name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    #[error("{what} is not symmetric positive definite")]
    NotPositiveDefinite { what: String },
    #[error("{what} did not converge in {iterations} iterations")]
    NoConvergence { what: String, iterations: usize },
    #[error("non-finite value in {what}")]
    NonFinite { what: String },
    #[error("the model has not seen enough data: {what}")]
    TooFewSamples { what: String },
    /// More training samples than a method can hold (a dense kernel matrix grows with their
    /// square).
    #[error("{what} fits at most {max} training epochs ({reason}); these data have {n}: use another pipeline (lda, toeplitz-lda, riemann) or fewer epochs")]
    TooManySamples {
        what: &'static str,
        n: usize,
        max: usize,
        reason: String,
    },
    #[error("model file: {reason}")]
    ModelFormat { reason: String },
    #[error("model format version {} cannot be read by this oddball (it reads versions 1 to {expected}; a newer oddball wrote it?)", match .found { Some(v) => v.to_string(), None => "(none given)".to_string() })]
    ModelVersion { found: Option<u32>, expected: u32 },
    #[error("recording layout differs from the model's: the model expects {expected}, the data has {got}")]
    LayoutMismatch { expected: String, got: String },
    #[error("linfa: {0}")]
    Linfa(String),
}
