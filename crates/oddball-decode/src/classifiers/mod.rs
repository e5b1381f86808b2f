//! Binary classifiers, each scoring an epoch by a continuous decision value (larger = more
//! target-like) and P(target), and the registry of those a pipeline may end in.
//!
//! Each classifier lives in its own file with its [`FitClassifier`] (settings → fitted) and
//! [`crate::traits::Scorer`] implementations. [`ClassifierParams`] / [`Classifier`] are the
//! tagged forms a saved model names them by, generated from the one `registry!` list below.
//! The tags are the variant names, as saved by every model format so far.
//!
//! # Adding a classifier
//! 1. Write `classifiers/NAME.rs` with `NameParams` (settings: `Clone`, `PartialEq`, `Default`,
//!    serde) implementing [`FitClassifier`] with `type Fitted = Name`, and `Name` (fitted, serde)
//!    implementing [`crate::traits::Scorer`]. A classifier of feature rows with inherent
//!    `NameParams::fit(rows, y)`, `Name::decision_function` and `Name::predict_proba` gets both
//!    impls from one line, `crate::traits::rows_classifier!(NameParams => Name, "name");` (as
//!    `lda`, `logistic` and `blda` do). A hyper-parameter grid, if any, is
//!    [`FitClassifier::grid`] (none by default).
//! 2. Add ONE line at the end of the `registry!` list:
//!    `Name(NAME::NameParams => NAME::Name), mod NAME, preset Name = "name";`
//!    * `mod NAME` declares the module (the file beside this one);
//!    * `preset Name = "name"` (optional) also makes it a [`crate::preset::Preset`] on the
//!      amplitude front of `lda` (bin-averaged amplitudes), listed after the other classifier
//!      presets, parsed and printed as `name`, tuned over the amplitude bin widths × the
//!      classifier's grid.
//!
//! Nothing else changes: the saved-model tag, the pipeline's dispatch, the preset's name,
//! parsing, help text and grid all come from that line.

use serde::{Deserialize, Serialize};

use crate::traits::{FeatureView, FitClassifier, Scorer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Generates the modules, the settings enum, the fitted enum, their dispatch and
/// `with_classifier_presets!` (the classifier presets, put first in [`crate::preset`]'s list)
/// from one list of `Tag(Settings => Fitted)[, mod module][, preset Preset = "name"];`. The
/// leading `$` is passed through to the generated macro.
macro_rules! registry {
    (
        $d:tt
        $($(#[$doc:meta])* $tag:ident($params:ty => $fitted:ty)
            $(, mod $m:ident)? $(, preset $ptag:ident = $pname:literal)?;)*
    ) => {
        $($(pub mod $m;)?)*

        /// Calls `presets!` with the classifier presets of the registry first, then the
        /// tokens given (the other presets).
        macro_rules! with_classifier_presets {
            ($d($d rest:tt)*) => {
                presets! {
                    $($(
                        #[doc = concat!("`", $pname, "`: [`ClassifierParams::", stringify!($tag),
                            "`] on bin-averaged amplitudes (bins of round(sfreq/25) samples).")]
                        $ptag = $pname => $tag,
                    )?)*
                    ;
                    $d($d rest)*
                }
            };
        }
        pub(crate) use with_classifier_presets;

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

            /// The classifier's own tuning grid: (label, settings) per point, empty when it
            /// has nothing to tune ([`FitClassifier::grid`]).
            pub fn grid(&self) -> Vec<(String, Self)> {
                match self {
                    $(Self::$tag(p) => p
                        .grid()
                        .into_iter()
                        .map(|(label, q)| (label, Self::$tag(q)))
                        .collect(),)*
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

registry! { $
    /// Shrinkage LDA.
    Lda(lda::LdaParams => lda::Lda), mod lda, preset Lda = "lda";
    /// Block-Toeplitz shrinkage LDA on channel-major spatio-temporal features (amplitudes); the
    /// channel count is the epochs' (after channel selection).
    ToeplitzLda(toeplitz_lda::ToeplitzLdaParams => toeplitz_lda::ToeplitzLda), mod toeplitz_lda,
        preset ToeplitzLda = "toeplitz-lda";
    Logistic(logistic::LogisticParams => logistic::Logistic), mod logistic;
    Svm(svm::SvmParams => svm::Svm), mod svm;
    Knn(knn::KnnParams => knn::Knn), mod knn;
    /// Soft vote of members' P(target) (the paper's multi-classifier).
    Vote(ensemble::SoftVoteParams => ensemble::SoftVote), mod ensemble;
    /// Minimum distance to (Riemannian) mean on SPD matrices
    /// ([`crate::features::FeatureParams::XdawnCovariances`]).
    Mdm(crate::riemann::MdmParams => crate::riemann::Mdm);
    Blda(blda::BldaParams => blda::Blda), mod blda, preset Blda = "blda";
}
