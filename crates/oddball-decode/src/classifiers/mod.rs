//! Binary classifiers, each scoring an epoch by a continuous decision value (larger = more
//! target-like) and P(target), and the registry of those a pipeline may end in.
//!
//! Each classifier lives in its own file with its [`FitClassifier`] (settings → fitted) and
//! [`crate::traits::Scorer`] implementations. [`ClassifierParams`] / [`Classifier`] are the
//! tagged forms a saved model names them by, generated from the one `registry!` list below:
//! a new classifier adds its file and one line there. The tags are the variant names, as saved
//! by every model format so far.

pub mod ensemble;
pub mod knn;
pub mod lda;
pub mod logistic;
pub mod svm;
pub mod toeplitz_lda;

use serde::{Deserialize, Serialize};

use crate::traits::{FeatureView, FitClassifier, Scorer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Generates the settings enum, the fitted enum and their dispatch from one list of
/// `Tag(Settings => Fitted)`.
macro_rules! registry {
    ($($(#[$doc:meta])* $tag:ident($params:ty => $fitted:ty),)*) => {
        /// The classifier at the end of a pipeline (unfitted settings).
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        pub enum ClassifierParams {
            $($(#[$doc])* $tag($params),)*
        }

        /// A fitted classifier.
        #[derive(Debug, Clone, Serialize, Deserialize)]
        pub enum Classifier {
            $($tag($fitted),)*
        }

        impl ClassifierParams {
            /// Fits on the features `x` of epochs with `n_channels` channels.
            pub fn fit(
                &self,
                x: FeatureView<'_>,
                y: &[bool],
                n_channels: usize,
            ) -> Result<Classifier> {
                Ok(match self {
                    $(Self::$tag(p) => Classifier::$tag(p.fit_classifier(x, y, n_channels)?),)*
                })
            }

            /// The same settings with every RBF kernel's `γ = 'scale'` replaced by `gamma`.
            pub fn with_scale_gamma(&self, gamma: f64) -> Self {
                match self {
                    $(Self::$tag(p) => Self::$tag(p.with_scale_gamma(gamma)),)*
                }
            }
        }

        impl Classifier {
            /// The fitted classifier's decision function.
            pub fn scorer(&self) -> &dyn Scorer {
                match self {
                    $(Self::$tag(m) => m,)*
                }
            }
        }
    };
}

registry! {
    Lda(lda::LdaParams => lda::Lda),
    /// Block-Toeplitz shrinkage LDA on channel-major spatio-temporal features (amplitudes); the
    /// channel count is the epochs' (after channel selection).
    ToeplitzLda(toeplitz_lda::ToeplitzLdaParams => toeplitz_lda::ToeplitzLda),
    Logistic(logistic::LogisticParams => logistic::Logistic),
    Svm(svm::SvmParams => svm::Svm),
    Knn(knn::KnnParams => knn::Knn),
    /// Soft vote of members' P(target) (the paper's multi-classifier).
    Vote(ensemble::SoftVoteParams => ensemble::SoftVote),
    /// Minimum distance to (Riemannian) mean on SPD matrices
    /// ([`crate::features::FeatureParams::XdawnCovariances`]).
    Mdm(crate::riemann::MdmParams => crate::riemann::Mdm),
}
