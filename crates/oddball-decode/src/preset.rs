//! The named pipelines: one list generates the [`Preset`] enum, its names, parsing, help text and
//! [`Preset::ALL`]; each preset's settings ([`Preset::params`]) and tuning grid
//! ([`Preset::grid`]) are written side by side here.
//!
//! Two kinds of line make the list. A classifier on the amplitude front (`lda`,
//! `toeplitz-lda`) is declared by its line in the classifier registry
//! ([`crate::classifiers`]): its settings are the classifier's defaults after
//! [`AmplitudeFeatures::for_sfreq`], its grid the amplitude bin widths crossed with the
//! classifier's own grid ([`crate::traits::FitClassifier::grid`]). The other presets are the
//! lines of the `presets!` list below, each naming the function that builds its settings and the
//! one that builds its grid. The classifier presets come first in [`Preset::ALL`] (the order
//! reports list them).

use std::fmt;
use std::str::FromStr;

use crate::classifiers::ensemble::{MemberParams, SoftVoteParams};
use crate::classifiers::knn::KnnParams;
use crate::classifiers::logistic::LogisticParams;
use crate::classifiers::svm::{Calibration, SvmParams};
use crate::classifiers::ClassifierParams;
use crate::features::amplitude::{AmplitudeFeatures, PaperFeatures};
use crate::features::bins::samples_per;
use crate::features::pca::PcaParams;
use crate::features::scaler::StandardScalerParams;
use crate::features::FeatureParams;
use crate::pipeline::{Fusion, PipelineParams, SingleParams};
use crate::riemann::xdawn::XdawnCovariancesParams;
use crate::riemann::{MdmParams, TangentSpaceParams, XdawnCovFeaturesParams, XdawnTangentParams};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// One point of a tuning grid: pipeline settings and a short label naming what differs.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub label: String,
    pub params: PipelineParams,
}

/// An optional gloss of the list: `None`, or `Some` of the literal.
macro_rules! gloss {
    () => {
        None
    };
    ($g:literal) => {
        Some($g)
    };
}

/// Generates [`Preset`] and everything read from its list. Called (through
/// `crate::classifiers::with_classifier_presets!`, which puts the classifier registry's presets
/// first) with `classifiers: Tag = "name" => ClassifierTag, …; Tag = "name" ("gloss")? { params,
/// grid }, …`; the optional gloss is what the preset's name alone does not say, for help texts.
macro_rules! presets {
    (
        $($(#[$cdoc:meta])* $ctag:ident = $cname:literal => $cls:ident,)*
        ;
        $($(#[$fdoc:meta])* $ftag:ident = $fname:literal $(($gloss:literal))? { $params:ident, $grid:ident },)*
    ) => {
        /// A named pipeline for epochs sampled at `sfreq` Hz ([`Preset::params`]); each variant
        /// says what it runs, [`Preset::ALL`] lists them in the order reports use.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum Preset {
            $($(#[$cdoc])* $ctag,)*
            $($(#[$fdoc])* $ftag,)*
        }

        impl Preset {
            /// Every preset, in the order reports list them.
            pub const ALL: &'static [Preset] = &[$(Preset::$ctag,)* $(Preset::$ftag,)*];

            /// The name the command line takes.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Preset::$ctag => $cname,)*
                    $(Preset::$ftag => $fname,)*
                }
            }

            /// What the name alone does not say (for help texts), if anything.
            pub const fn gloss(self) -> Option<&'static str> {
                match self {
                    $(Preset::$ctag => None,)*
                    $(Preset::$ftag => gloss!($($gloss)?),)*
                }
            }

            /// The preset's settings for epochs sampled at `sfreq` Hz (see [`Preset`]).
            pub fn params(self, sfreq: f64) -> Result<PipelineParams> {
                match self {
                    $(Preset::$ctag => on_amplitudes(
                        self,
                        ClassifierParams::$cls(Default::default()),
                        sfreq,
                    ),)*
                    $(Preset::$ftag => $params(self, sfreq),)*
                }
            }

            /// The grid the preset is tuned over at `sfreq` Hz (see
            /// [`crate::model_selection::tuning`]); the preset's own settings are one of the
            /// candidates.
            pub fn grid(self, sfreq: f64) -> Result<Vec<Candidate>> {
                let base = self.params(sfreq)?;
                match self {
                    $(Preset::$ctag => amplitude_grid(base, sfreq),)*
                    $(Preset::$ftag => $grid(self, base, sfreq),)*
                }
            }
        }
    };
}

crate::classifiers::with_classifier_presets! {
    /// `riemann`: every round(sfreq/64)-th sample → XdawnCovariances(4 filters, OAS) → tangent
    /// space → logistic regression (pyRiemann's ERP pipeline).
    Riemann = "riemann" { riemann, xdawn_grid },
    /// `lda+riemann`: score fusion of `lda` and `riemann` (each pipeline's decision value
    /// divided by its standard deviation on the training epochs, then summed; no weights to
    /// tune).
    LdaRiemann = "lda+riemann" ("score fusion") { lda_riemann, no_grid },
    /// `stack`: `toeplitz-lda`, `riemann` and `mdm` stacked ([`Fusion::Stacked`], 5 inner
    /// folds): a logistic regression learns their weights from out-of-fold scores on the
    /// training epochs.
    Stack = "stack" ("toeplitz-lda + riemann + mdm, stacked") { stack, no_grid },
    /// `mdm`: the same XdawnCovariances → minimum distance to (Riemannian) mean (pyRiemann's
    /// `MDM`), scored `d²(C, M_non-target) − d²(C, M_target)`.
    Mdm = "mdm" { mdm, xdawn_grid },
    /// `paper`: the paper's amplitude + HHT + wavelet features → StandardScaler → PCA (95 %
    /// variance) → soft vote of an RBF SVM and a 3-NN.
    Paper = "paper" { paper, svm_grid },
    /// `paper-svm`: the paper's front with the RBF SVM alone.
    PaperSvm = "paper-svm" { paper_svm, svm_grid },
    /// `paper-knn`: the paper's front with the 3-NN alone.
    PaperKnn = "paper-knn" { paper_knn, knn_grid },
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

impl Preset {
    /// The names, comma-separated, for help and error messages.
    pub fn names() -> String {
        PRESETS.join(", ")
    }

    /// The names with their glosses, comma-separated, for help texts: `lda+riemann (score
    /// fusion)`.
    pub fn described() -> String {
        Preset::ALL
            .iter()
            .map(|p| match p.gloss() {
                Some(g) => format!("{} ({g})", p.name()),
                None => p.name().to_string(),
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Preset {
    type Err = DecodeError;
    fn from_str(s: &str) -> Result<Self> {
        Preset::ALL
            .iter()
            .copied()
            .find(|p| p.name() == s)
            .ok_or_else(|| DecodeError::InvalidParameter {
                name: "pipeline",
                value: s.to_string(),
                reason: format!("unknown preset; known: {}", Preset::names()),
            })
    }
}

/// A preset is saved as its name.
impl serde::Serialize for Preset {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Preset {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let name = <std::borrow::Cow<'de, str>>::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

impl PipelineParams {
    /// The [`Preset`] named `name` for epochs sampled at `sfreq` Hz.
    pub fn preset(name: &str, sfreq: f64) -> Result<Self> {
        name.parse::<Preset>()?.params(sfreq)
    }
}

/// A pipeline of `preset`'s name without channel selection.
fn single(
    preset: Preset,
    features: FeatureParams,
    scaler: Option<StandardScalerParams>,
    pca: Option<PcaParams>,
    classifier: ClassifierParams,
) -> PipelineParams {
    SingleParams {
        name: preset.name().to_string(),
        channel_selection: None,
        features,
        scaler,
        pca,
        classifier,
        svm_gamma_scale: 1.0,
    }
    .into()
}

/// A classifier on bin-averaged amplitudes (bins of round(sfreq/25) samples), as `lda`.
fn on_amplitudes(
    preset: Preset,
    classifier: ClassifierParams,
    sfreq: f64,
) -> Result<PipelineParams> {
    let features = FeatureParams::Amplitude(AmplitudeFeatures::for_sfreq(sfreq)?);
    Ok(single(preset, features, None, None, classifier))
}

/// The amplitude bin width, round(sfreq/32), round(sfreq/25) (the default) and round(sfreq/20)
/// samples, crossed with the classifier's own grid (none for `lda` and `toeplitz-lda`).
fn amplitude_grid(base: PipelineParams, sfreq: f64) -> Result<Vec<Candidate>> {
    let mut bins: Vec<usize> = [32.0, 25.0, 20.0]
        .iter()
        .map(|&f| samples_per(sfreq, f))
        .collect();
    bins.dedup();
    let classifiers = base.main.classifier.grid();
    let mut out = Vec::new();
    for bin in bins {
        let label = format!("bin {bin} samples ({:.0} ms)", 1000.0 * bin as f64 / sfreq);
        let mut p = base.clone();
        p.main.features = FeatureParams::Amplitude(AmplitudeFeatures::bin_mean(bin)?);
        if classifiers.is_empty() {
            out.push(Candidate { label, params: p });
            continue;
        }
        for (what, c) in &classifiers {
            let mut p = p.clone();
            p.main.classifier = c.clone();
            out.push(Candidate {
                label: format!("{label}, {what}"),
                params: p,
            });
        }
    }
    Ok(out)
}

/// A fusion's members keep their presets' settings: the one candidate is the preset.
fn no_grid(preset: Preset, base: PipelineParams, _sfreq: f64) -> Result<Vec<Candidate>> {
    let label = match preset {
        Preset::LdaRiemann => "lda + riemann, equal weights (no grid)",
        // Stacking learns its weights by its own inner cross-validation.
        _ => "toeplitz-lda + riemann + mdm, stacked (no grid)",
    };
    Ok(vec![Candidate {
        label: label.into(),
        params: base,
    }])
}

/// Every round(sfreq/64)-th sample: the xDAWN presets' decimation.
fn xdawn_step(sfreq: f64) -> usize {
    samples_per(sfreq, 64.0)
}

fn riemann(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    let features = FeatureParams::XdawnTangent(XdawnTangentParams {
        step: xdawn_step(sfreq),
        xdawn: XdawnCovariancesParams::default(),
        tangent: TangentSpaceParams::default(),
    });
    let classifier = ClassifierParams::Logistic(LogisticParams::default());
    Ok(single(preset, features, None, None, classifier))
}

fn mdm(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    let features = FeatureParams::XdawnCovariances(XdawnCovFeaturesParams {
        step: xdawn_step(sfreq),
        xdawn: XdawnCovariancesParams::default(),
    });
    let classifier = ClassifierParams::Mdm(MdmParams::default());
    Ok(single(preset, features, None, None, classifier))
}

/// xDAWN filters per class {2, 4, 6}, for `riemann` crossed with the logistic regression's `C`
/// {0.1, 1, 10}.
fn xdawn_grid(preset: Preset, base: PipelineParams, _sfreq: f64) -> Result<Vec<Candidate>> {
    let cs: &[f64] = if preset == Preset::Riemann {
        &[0.1, 1.0, 10.0]
    } else {
        &[1.0]
    };
    let mut out = Vec::new();
    for nfilter in [2, 4, 6] {
        for &c in cs {
            let mut p = base.clone();
            match &mut p.main.features {
                FeatureParams::XdawnTangent(f) => f.xdawn.nfilter = nfilter,
                FeatureParams::XdawnCovariances(f) => f.xdawn.nfilter = nfilter,
                _ => unreachable!("the {preset} preset has xDAWN features"),
            }
            let label = if let ClassifierParams::Logistic(l) = &mut p.main.classifier {
                l.c = c;
                format!("nfilter {nfilter}, C {c}")
            } else {
                format!("nfilter {nfilter}")
            };
            out.push(Candidate { label, params: p });
        }
    }
    Ok(out)
}

/// `preset`'s main pipeline under its own name, fused with `members` by `fusion`.
fn fused(
    preset: Preset,
    main: Preset,
    members: &[Preset],
    fusion: Fusion,
    sfreq: f64,
) -> Result<PipelineParams> {
    let mut main = main.params(sfreq)?.main;
    main.name = preset.name().to_string();
    Ok(PipelineParams {
        main,
        fused: members
            .iter()
            .map(|m| m.params(sfreq).map(|p| p.main))
            .collect::<Result<_>>()?,
        fusion,
    })
}

fn lda_riemann(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    fused(
        preset,
        Preset::Lda,
        &[Preset::Riemann],
        Fusion::Standardised,
        sfreq,
    )
}

fn stack(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    fused(
        preset,
        Preset::ToeplitzLda,
        &[Preset::Riemann, Preset::Mdm],
        Fusion::Stacked { n_folds: 5 },
        sfreq,
    )
}

/// The paper's amplitude + HHT + wavelet features → StandardScaler → PCA (95 % variance).
fn paper_front(preset: Preset, classifier: ClassifierParams, sfreq: f64) -> Result<PipelineParams> {
    Ok(single(
        preset,
        FeatureParams::Paper(PaperFeatures::for_sfreq(sfreq)?),
        Some(StandardScalerParams::default()),
        Some(PcaParams::variance_fraction(0.95)),
        classifier,
    ))
}

fn paper(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    paper_front(
        preset,
        ClassifierParams::Vote(SoftVoteParams::paper()),
        sfreq,
    )
}

fn paper_svm(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    // Alone, the SVM's decision value is the score: no probability calibration needed.
    let svm = SvmParams {
        calibration: Calibration::None,
        ..SvmParams::default()
    };
    paper_front(preset, ClassifierParams::Svm(svm), sfreq)
}

fn paper_knn(preset: Preset, sfreq: f64) -> Result<PipelineParams> {
    paper_front(preset, ClassifierParams::Knn(KnnParams::default()), sfreq)
}

/// The RBF SVM's `C` {1, 10} × γ {1, 0.5} × scikit-learn's `'scale'`.
fn svm_grid(preset: Preset, base: PipelineParams, _sfreq: f64) -> Result<Vec<Candidate>> {
    let mut out = Vec::new();
    for c in [1.0, 10.0] {
        for factor in [1.0, 0.5] {
            let mut p = base.clone();
            let set = |s: &mut SvmParams| s.c = c;
            match &mut p.main.classifier {
                ClassifierParams::Svm(s) => set(s),
                ClassifierParams::Vote(v) => {
                    for m in &mut v.members {
                        if let MemberParams::Svm(s) = m {
                            set(s);
                        }
                    }
                }
                _ => unreachable!("the {preset} preset has an SVM"),
            }
            p.main.svm_gamma_scale = factor;
            out.push(Candidate {
                label: format!("C {c}, gamma {factor}×scale"),
                params: p,
            });
        }
    }
    Ok(out)
}

/// Neighbours k {3, 5, 9}.
fn knn_grid(_preset: Preset, base: PipelineParams, _sfreq: f64) -> Result<Vec<Candidate>> {
    Ok([3, 5, 9]
        .into_iter()
        .map(|k| {
            let mut p = base.clone();
            p.main.classifier = ClassifierParams::Knn(KnnParams { k });
            Candidate {
                label: format!("k {k}"),
                params: p,
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_saved_as_their_names() {
        for &p in Preset::ALL {
            let json = serde_json::to_string(&p).unwrap();
            assert_eq!(json, format!("\"{}\"", p.name()));
            assert_eq!(serde_json::from_str::<Preset>(&json).unwrap(), p);
        }
        let e = serde_json::from_str::<Preset>("\"no-such\"").unwrap_err();
        assert!(e.to_string().contains("unknown preset"), "{e}");
    }

    #[test]
    fn names_parse_back_and_unknown_ones_are_errors() {
        for &p in Preset::ALL {
            assert_eq!(p.to_string().parse::<Preset>().unwrap(), p);
        }
        // The report order: the classifier presets first (a new one after these two), then
        // the others as listed.
        let known = [
            "lda",
            "toeplitz-lda",
            "riemann",
            "lda+riemann",
            "stack",
            "mdm",
            "paper",
            "paper-svm",
            "paper-knn",
        ];
        let at: Vec<usize> = known
            .iter()
            .map(|n| PRESETS.iter().position(|p| p == n).unwrap())
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{PRESETS:?}");
        assert_eq!(PRESETS[..2], ["lda", "toeplitz-lda"]);
        assert_eq!(PRESETS.len(), Preset::ALL.len());
        assert!(matches!(
            "nope".parse::<Preset>(),
            Err(DecodeError::InvalidParameter {
                name: "pipeline",
                ..
            })
        ));
    }

    #[test]
    fn every_preset_has_a_grid_holding_its_defaults() {
        for &p in Preset::ALL {
            let grid = p.grid(256.0).unwrap();
            // The fusions have nothing of their own to tune.
            let least = if matches!(p, Preset::LdaRiemann | Preset::Stack) {
                1
            } else {
                3
            };
            assert!(grid.len() >= least, "{p}: {} candidates", grid.len());
            let default = p.params(256.0).unwrap();
            assert!(
                grid.iter().any(|c| c.params == default),
                "{p}: the preset's own settings are a candidate"
            );
            let mut labels: Vec<&str> = grid.iter().map(|c| c.label.as_str()).collect();
            labels.sort_unstable();
            labels.dedup();
            assert_eq!(labels.len(), grid.len(), "{p}: labels are distinct");
        }
        let lda = Preset::Lda.grid(256.0).unwrap();
        assert_eq!(lda[0].label, "bin 8 samples (31 ms)");
    }
}
