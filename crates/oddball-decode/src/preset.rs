//! The named pipelines: one enum, parsed from and printed as the names the command line takes,
//! whose settings ([`Preset::params`]) and tuning grid ([`crate::tuning::preset_grid`]) are
//! matched here and in tuning only.

use std::fmt;
use std::str::FromStr;

use crate::amplitude::{AmplitudeFeatures, PaperFeatures};
use crate::classifiers::ClassifierParams;
use crate::ensemble::SoftVoteParams;
use crate::features::FeatureParams;
use crate::knn::KnnParams;
use crate::lda::LdaParams;
use crate::logistic::LogisticParams;
use crate::pca::PcaParams;
use crate::pipeline::{Fusion, PipelineParams, SingleParams};
use crate::riemann::{MdmParams, TangentSpaceParams, XdawnCovFeaturesParams, XdawnTangentParams};
use crate::scaler::StandardScalerParams;
use crate::svm::{Calibration, SvmParams};
use crate::toeplitz_lda::ToeplitzLdaParams;
use crate::xdawn::XdawnCovariancesParams;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// A named pipeline for epochs sampled at `sfreq` Hz ([`Preset::params`]):
/// * `lda`: shrinkage LDA on bin-averaged amplitudes (bins of round(sfreq/25) samples);
/// * `toeplitz-lda`: block-Toeplitz shrinkage LDA ([`crate::toeplitz_lda`]) on the `lda`
///   preset's amplitudes;
/// * `riemann`: every round(sfreq/64)-th sample → XdawnCovariances(4 filters, OAS) →
///   tangent space → logistic regression (pyRiemann's ERP pipeline);
/// * `lda+riemann`: score fusion of `lda` and `riemann` (each pipeline's decision value
///   divided by its standard deviation on the training epochs, then summed; no weights to
///   tune);
/// * `stack`: `toeplitz-lda`, `riemann` and `mdm` stacked ([`Fusion::Stacked`], 5 inner
///   folds): a logistic regression learns their weights from out-of-fold scores on the
///   training epochs;
/// * `mdm`: the same XdawnCovariances → minimum distance to (Riemannian) mean (pyRiemann's
///   `MDM`), scored `d²(C, M_non-target) − d²(C, M_target)`;
/// * `paper`: the paper's amplitude + HHT + wavelet features → StandardScaler → PCA (95 %
///   variance) → soft vote of an RBF SVM and a 3-NN;
/// * `paper-svm`, `paper-knn`: the same features with one of the two members alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    Lda,
    ToeplitzLda,
    Riemann,
    LdaRiemann,
    Stack,
    Mdm,
    Paper,
    PaperSvm,
    PaperKnn,
}

impl Preset {
    /// Every preset, in the order reports list them.
    pub const ALL: [Preset; 9] = [
        Preset::Lda,
        Preset::ToeplitzLda,
        Preset::Riemann,
        Preset::LdaRiemann,
        Preset::Stack,
        Preset::Mdm,
        Preset::Paper,
        Preset::PaperSvm,
        Preset::PaperKnn,
    ];

    /// The name the command line takes.
    pub const fn name(self) -> &'static str {
        match self {
            Preset::Lda => "lda",
            Preset::ToeplitzLda => "toeplitz-lda",
            Preset::Riemann => "riemann",
            Preset::LdaRiemann => "lda+riemann",
            Preset::Stack => "stack",
            Preset::Mdm => "mdm",
            Preset::Paper => "paper",
            Preset::PaperSvm => "paper-svm",
            Preset::PaperKnn => "paper-knn",
        }
    }

    /// The preset's settings for epochs sampled at `sfreq` Hz (see [`Preset`]).
    pub fn params(self, sfreq: f64) -> Result<PipelineParams> {
        let single = |features, scaler, pca, classifier| SingleParams {
            name: self.name().to_string(),
            channel_selection: None,
            features,
            scaler,
            pca,
            classifier,
            svm_gamma_scale: 1.0,
        };
        let paper_front = |classifier| -> Result<SingleParams> {
            Ok(single(
                FeatureParams::Paper(PaperFeatures::for_sfreq(sfreq)?),
                Some(StandardScalerParams::default()),
                Some(PcaParams::variance_fraction(0.95)),
                classifier,
            ))
        };
        let xdawn_step = crate::amplitude::samples_per(sfreq, 64.0);
        let amplitudes = || AmplitudeFeatures::for_sfreq(sfreq).map(FeatureParams::Amplitude);
        let member = |p: Preset| p.params(sfreq).map(|p| p.main);
        let main = match self {
            Preset::Lda => single(
                amplitudes()?,
                None,
                None,
                ClassifierParams::Lda(LdaParams::default()),
            ),
            Preset::ToeplitzLda | Preset::Stack => single(
                amplitudes()?,
                None,
                None,
                ClassifierParams::ToeplitzLda(ToeplitzLdaParams::default()),
            ),
            Preset::Riemann => single(
                FeatureParams::XdawnTangent(XdawnTangentParams {
                    step: xdawn_step,
                    xdawn: XdawnCovariancesParams::default(),
                    tangent: TangentSpaceParams::default(),
                }),
                None,
                None,
                ClassifierParams::Logistic(LogisticParams::default()),
            ),
            Preset::Mdm => single(
                FeatureParams::XdawnCovariances(XdawnCovFeaturesParams {
                    step: xdawn_step,
                    xdawn: XdawnCovariancesParams::default(),
                }),
                None,
                None,
                ClassifierParams::Mdm(MdmParams::default()),
            ),
            Preset::Paper => paper_front(ClassifierParams::Vote(SoftVoteParams::paper()))?,
            // Alone, the SVM's decision value is the score: no probability calibration needed.
            Preset::PaperSvm => paper_front(ClassifierParams::Svm(SvmParams {
                calibration: Calibration::None,
                ..SvmParams::default()
            }))?,
            Preset::PaperKnn => paper_front(ClassifierParams::Knn(KnnParams::default()))?,
            Preset::LdaRiemann => {
                let mut p = member(Preset::Lda)?;
                p.name = self.name().to_string();
                p
            }
        };
        let (fused, fusion) = match self {
            Preset::LdaRiemann => (vec![member(Preset::Riemann)?], Fusion::Standardised),
            Preset::Stack => (
                vec![member(Preset::Riemann)?, member(Preset::Mdm)?],
                Fusion::Stacked { n_folds: 5 },
            ),
            _ => (Vec::new(), Fusion::Standardised),
        };
        Ok(PipelineParams {
            main,
            fused,
            fusion,
        })
    }
}

/// The names [`Preset`] parses, in [`Preset::ALL`]'s order.
pub const PRESETS: [&str; Preset::ALL.len()] = {
    let mut out = [""; Preset::ALL.len()];
    let mut i = 0;
    while i < out.len() {
        out[i] = Preset::ALL[i].name();
        i += 1;
    }
    out
};

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Preset {
    type Err = DecodeError;
    fn from_str(s: &str) -> Result<Self> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| DecodeError::InvalidParameter {
                name: "pipeline",
                value: s.to_string(),
                reason: format!("unknown preset; known: {}", PRESETS.join(", ")),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_unknown_ones_are_errors() {
        for p in Preset::ALL {
            assert_eq!(p.to_string().parse::<Preset>().unwrap(), p);
        }
        assert_eq!(PRESETS[3], "lda+riemann");
        assert!(matches!(
            "nope".parse::<Preset>(),
            Err(DecodeError::InvalidParameter {
                name: "pipeline",
                ..
            })
        ));
    }
}
