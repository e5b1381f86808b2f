//! Why an unsupervised fit could not run.

use crate::DecodeError;

/// Why an unsupervised fit could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UnsupervisedError {
    #[error("{n_epochs} epochs but {n_codes} stimulus codes and {n_trials} trial numbers")]
    Length {
        n_epochs: usize,
        n_codes: usize,
        n_trials: usize,
    },
    #[error("{n_scores} initial scores for {n_epochs} epochs")]
    InitLength { n_epochs: usize, n_scores: usize },
    #[error("epoch {index}: stimulus code {code} is in none of the choice sets {sets:?}")]
    UnknownCode {
        index: usize,
        code: u32,
        sets: Vec<Vec<u32>>,
    },
    #[error("choice set {set} has {n_codes} codes; a choice needs at least two")]
    TooFewChoices { set: usize, n_codes: usize },
    #[error("stimulus code {code} is in more than one choice set")]
    SharedCode { code: u32 },
    #[error("decoy code {code} {what}: a decoy is a flash nobody attends, in no choice set, listed once")]
    Decoy { code: u32, what: &'static str },
    #[error("an unsupervised fit needs at least two epochs, got {n_epochs}")]
    TooFewEpochs { n_epochs: usize },
    #[error("non-finite feature {feature} in epoch {epoch}")]
    NonFinite { epoch: usize, feature: usize },
    #[error("the shrunk feature covariance of {n_epochs} epochs × {n_features} features is not positive definite")]
    NotPositiveDefinite { n_epochs: usize, n_features: usize },
    #[error("trial {trial} resumes at epoch {index} after another trial: a trial's epochs must be contiguous")]
    TrialsNotContiguous { trial: usize, index: usize },
    #[error("the EM degenerated: {what}")]
    Degenerate { what: String },
    #[error("parameter {name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        reason: String,
    },
    #[error("pooled start: {what}")]
    InvalidPooled { what: String },
    #[error(
        "the pooled start names none of the session's channels {session:?} (it has {pattern:?})"
    )]
    NoSharedChannels {
        session: Vec<String>,
        pattern: Vec<String>,
    },
    #[error(
        "{recordings}: no channel is named by its position ({channels:?}), so none can be pooled"
    )]
    NoNamedChannels {
        recordings: String,
        channels: Vec<String>,
    },
    #[error("{n_epochs} epochs but {got} {what}")]
    EpochCount {
        what: &'static str,
        n_epochs: usize,
        got: usize,
    },
    #[error("epoch {index} is in group {group}, but there are {n_groups} groups")]
    UnknownGroup {
        index: usize,
        group: usize,
        n_groups: usize,
    },
    #[error("group {group} has no epochs")]
    EmptyGroup { group: usize },
    #[error("target proportions {proportions:?}: label proportions identify the class means only with at least two groups of different proportions")]
    NotIdentified { proportions: Vec<f64> },
    #[error(transparent)]
    Decode(#[from] DecodeError),
}

pub(crate) type Result<T> = std::result::Result<T, UnsupervisedError>;
