//! Feature extraction, as scikit-learn's transformers: maps from epochs `(n_epochs, n_channels,
//! n_times)` to features (amplitudes, the paper's Hilbert–Huang and wavelet map; the Riemannian
//! maps live in [`crate::riemann`]), the steps on feature rows (standard scaling, PCA), and
//! channel selection; and the registry of the feature maps a pipeline may start with.
//!
//! [`FeatureParams`] / [`Features`] are the tagged forms a saved model names the maps by,
//! generated from the one `registry!` list below (a new map: its file with its
//! [`FitTransformer`] and [`crate::traits::Transformer`] implementations, and one line there).
//! The tags are the variant names, as saved by every model format so far.

pub mod amplitude;
pub mod bins;
pub mod channel_select;
pub mod emd;
pub mod hilbert;
pub mod pca;
mod rows;
pub mod scaler;
pub mod wavelet;

use ndarray::ArrayView3;
use serde::{Deserialize, Serialize};

use crate::traits::{FeatureData, FitTransformer, Transformer};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Generates the settings enum, the fitted enum and their dispatch from one list of
/// `Tag(Settings => Fitted)`.
macro_rules! registry {
    ($($(#[$doc:meta])* $tag:ident($params:ty => $fitted:ty),)*) => {
        /// How an epoch becomes features (unfitted settings).
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        pub enum FeatureParams {
            $($(#[$doc])* $tag($params),)*
        }

        /// Fitted features.
        #[derive(Debug, Clone, Serialize, Deserialize)]
        pub enum Features {
            $($tag($fitted),)*
        }

        impl FeatureParams {
            /// Whether the map learns nothing from the training data (so features of any epoch
            /// can be computed once, whatever the training split).
            pub fn is_stateless(&self) -> bool {
                match self {
                    $(Self::$tag(p) => p.is_stateless(),)*
                }
            }

            /// Fits on training `epochs` labelled `y`.
            pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Features> {
                Ok(match self {
                    $(Self::$tag(p) => Features::$tag(p.fit_transformer(epochs, y)?.into()),)*
                })
            }
        }

        impl Features {
            /// Features of `epochs`.
            pub fn transform(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
                match self {
                    $(Self::$tag(f) => f.transform_epochs(epochs),)*
                }
            }
        }
    };
}

registry! {
    /// Bin-averaged or decimated samples, flattened channel-major.
    Amplitude(amplitude::AmplitudeFeatures => amplitude::AmplitudeFeatures),
    /// The paper's map: amplitudes + Hilbert–Huang (first IMF's instantaneous amplitude and
    /// frequency) + bior2.2 wavelet approximation and detail.
    Paper(amplitude::PaperFeatures => amplitude::PaperFeatures),
    /// Every `step`-th sample, then xDAWN covariances, then the Riemannian tangent space.
    XdawnTangent(crate::riemann::XdawnTangentParams => Box<crate::riemann::XdawnTangent>),
    /// Every `step`-th sample, then xDAWN covariances `(n, n)` as SPD matrices — the input of
    /// [`crate::classifiers::ClassifierParams::Mdm`].
    XdawnCovariances(crate::riemann::XdawnCovFeaturesParams => Box<crate::riemann::XdawnCovFeatures>),
}
