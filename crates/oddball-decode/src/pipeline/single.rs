//! One pipeline without fusion: its settings ([`SingleParams`]) fitted step by step into a
//! [`Single`] — `[channel selection] → features → [StandardScaler] → [PCA] → classifier` —
//! and the fitted parts the cached fits reuse (front, neck, head).

use ndarray::{s, Array1, ArrayView3};

use super::source::EpochSource;
use crate::classifiers::{Classifier, ClassifierParams};
use crate::features::channel_select::{ChannelSelection, ChannelSelectionParams};
use crate::features::pca::{Pca, PcaParams};
use crate::features::scaler::{StandardScaler, StandardScalerParams};
use crate::features::{FeatureParams, Features};
use crate::linalg::check_labels;
use crate::traits::{FeatureData, FeatureView};
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Unfitted settings of one pipeline (no fusion).
#[derive(Debug, Clone, PartialEq)]
pub struct SingleParams {
    /// A name for reports (the preset's name, or any).
    pub name: String,
    pub channel_selection: Option<ChannelSelectionParams>,
    pub features: FeatureParams,
    pub scaler: Option<StandardScalerParams>,
    pub pca: Option<PcaParams>,
    pub classifier: ClassifierParams,
    /// Multiplies the RBF SVMs' `γ = 'scale'`: 1 is scikit-learn's `'scale'`; otherwise the
    /// γ is resolved once on the training features (the Platt-calibration folds inside share it).
    pub svm_gamma_scale: f64,
}

impl SingleParams {
    /// Fits every step on `epochs` labelled `y`.
    pub fn fit(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Single> {
        self.fit_source(EpochSource::Array(epochs), y)
    }

    /// [`Self::fit`] on an [`EpochSource`], with the same result. An array is read as it is.
    /// Windows are read without a copy of all of them where the front allows: one that learns
    /// nothing computes its features a part at a time; an xDAWN front reading every `k`-th
    /// sample is fitted on a copy of those samples; the channel selection on a copy of the
    /// target epochs (all it reads), a feature map after it that learns nothing a part at a
    /// time. Any other front reads a copy of all the epochs.
    pub fn fit_source(&self, epochs: EpochSource<'_>, y: &[bool]) -> Result<Single> {
        let (n_epochs, n_channels, n_times) = epochs.dim();
        check_labels(n_epochs, y)?;
        let (front, x) = self.fit_front_source(epochs, y)?;
        let head = self.fit_head(x, y, front.n_channels(n_channels))?;
        Ok(self.assemble(front, head, n_channels, n_times))
    }

    /// The fitted pipeline of a fitted front and head, for epochs `(n_channels, n_times)`.
    pub(super) fn assemble(
        &self,
        front: Front,
        head: Head,
        n_channels: usize,
        n_times: usize,
    ) -> Single {
        let Front { channels, features } = front;
        let Head {
            scaler,
            pca,
            classifier,
        } = head;
        Single {
            name: self.name.clone(),
            n_channels,
            n_times,
            channels,
            features,
            scaler,
            pca,
            classifier,
        }
    }

    /// [`Self::fit_front`] on an [`EpochSource`], with the same result, reading it as
    /// [`Self::fit_source`] says.
    pub(crate) fn fit_front_source(
        &self,
        epochs: EpochSource<'_>,
        y: &[bool],
    ) -> Result<(Front, FeatureData)> {
        if let Some(all) = epochs.as_view() {
            return self.fit_front(all, y);
        }
        let n_epochs = epochs.dim().0;
        if y.len() != n_epochs {
            return Err(DecodeError::LabelCount {
                n_samples: n_epochs,
                n_labels: y.len(),
            });
        }
        let all: Vec<usize> = (0..n_epochs).collect();
        if let Some((k, p)) = self.decimated() {
            let (mut front, x) = p.fit_front(epochs.gather(&all, k).view(), y)?;
            set_step(&mut front.features, k)?;
            return Ok((front, x));
        }
        let targets: Vec<usize> = (0..n_epochs).filter(|&i| y[i]).collect();
        if !self.features.is_stateless() || targets.is_empty() {
            return self.fit_front(epochs.gather(&all, 1).view(), y);
        }
        let channels = match &self.channel_selection {
            None => None,
            Some(c) => Some(c.fit(
                epochs.gather(&targets, 1).view(),
                &vec![true; targets.len()],
            )?),
        };
        self.stateless_front(channels, epochs)
    }

    /// The front of a feature map that learns nothing behind `channels` (fitted, or none), with
    /// the features of every epoch of `epochs`, computed a part at a time when they are windows.
    fn stateless_front(
        &self,
        channels: Option<ChannelSelection>,
        epochs: EpochSource<'_>,
    ) -> Result<(Front, FeatureData)> {
        let n_front = channels
            .as_ref()
            .map_or(epochs.dim().1, |c| c.selected.len());
        // Nothing to learn: fitted on no epochs, the map is its settings.
        let features = self
            .features
            .fit(epochs.gather(&[], 1).slice(s![.., ..n_front, ..]), &[])?;
        let front = Front { channels, features };
        let x = epochs.map_chunks(&mut |chunk| front.transform(chunk))?;
        Ok((front, x))
    }

    /// Fits the channel selection and the features on `epochs`; returns them with the features
    /// of `epochs`.
    pub(crate) fn fit_front(
        &self,
        epochs: ArrayView3<f64>,
        y: &[bool],
    ) -> Result<(Front, FeatureData)> {
        let channels = self
            .channel_selection
            .map(|p| p.fit(epochs, y))
            .transpose()?;
        let selected;
        let epochs = match &channels {
            Some(c) => {
                selected = c.transform(epochs)?;
                selected.view()
            }
            None => epochs.view(),
        };
        let features = self.features.fit(epochs, y)?;
        let x = features.transform(epochs)?;
        Ok((Front { channels, features }, x))
    }

    /// Whether `other` has the same channel selection and features (so one fitted front
    /// serves both).
    pub(crate) fn same_front(&self, other: &Self) -> bool {
        self.channel_selection == other.channel_selection && self.features == other.features
    }

    /// Fits the steps after the features (scaler, PCA, classifier) on features `x` of epochs
    /// with `n_channels` channels (after channel selection).
    pub(crate) fn fit_head(&self, x: FeatureData, y: &[bool], n_channels: usize) -> Result<Head> {
        let (neck, x) = self.fit_neck(x)?;
        self.fit_classifier(neck, x.view(), y, n_channels)
    }

    /// Whether `other` has the same front, scaler and PCA (so one fitted neck serves both:
    /// the grid points of an SVM's `C` and `γ`, or the paper's three presets).
    pub(crate) fn same_neck(&self, other: &Self) -> bool {
        self.same_front(other) && self.scaler == other.scaler && self.pca == other.pca
    }

    /// Whether a neck is fitted at all (a scaler or a PCA).
    pub(crate) fn has_neck(&self) -> bool {
        self.scaler.is_some() || self.pca.is_some()
    }

    /// The neck fitted on `xtr`, and both parts through it, timed.
    pub(crate) fn neck_split(&self, xtr: FeatureData, xte: FeatureData) -> Result<Necked> {
        let t0 = std::time::Instant::now();
        let (neck, xtr) = self.fit_neck(xtr)?;
        let fit_s = t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        let xte = neck.transform(xte)?;
        Ok(Necked {
            xtr,
            xte,
            fit_s,
            transform_s: t1.elapsed().as_secs_f64(),
        })
    }

    /// Fits the classifier on necked training features and scores the necked test features;
    /// the scores, and the seconds the fit and the scoring took.
    pub(crate) fn classifier_scores(
        &self,
        necked: &Necked,
        y: &[bool],
        n_channels: usize,
    ) -> Result<(Array1<f64>, f64, f64)> {
        let t0 = std::time::Instant::now();
        let classifier = with_gamma_factor(
            &self.classifier,
            necked.xtr.view(),
            self.svm_gamma_scale,
        )?
        .fit(necked.xtr.view(), y, n_channels)?;
        let fit_s = t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        let scores = classifier.scorer().decision_function(necked.xte.view())?;
        Ok((scores, fit_s, t1.elapsed().as_secs_f64()))
    }

    /// Fits the scaler and the PCA on features `x`; returns them with `x` through them.
    pub(crate) fn fit_neck(&self, x: FeatureData) -> Result<(Neck, FeatureData)> {
        let mut x = x;
        let scaler = match &self.scaler {
            Some(p) => {
                let rows = x.into_rows("StandardScaler")?;
                let s = p.fit(rows.view())?;
                x = FeatureData::Rows(s.transform(rows.view())?);
                Some(s)
            }
            None => None,
        };
        let pca = match &self.pca {
            Some(p) => {
                let rows = x.into_rows("PCA")?;
                let m = p.fit(rows.view())?;
                x = FeatureData::Rows(m.transform(rows.view())?);
                Some(m)
            }
            None => None,
        };
        Ok((Neck { scaler, pca }, x))
    }

    /// Fits the classifier on features `x` already through `neck`.
    pub(crate) fn fit_classifier(
        &self,
        neck: Neck,
        x: FeatureView<'_>,
        y: &[bool],
        n_channels: usize,
    ) -> Result<Head> {
        let classifier =
            with_gamma_factor(&self.classifier, x, self.svm_gamma_scale)?.fit(x, y, n_channels)?;
        Ok(Head {
            scaler: neck.scaler,
            pca: neck.pca,
            classifier,
        })
    }

    /// When it reads only every `k`-th sample of an epoch (no channel selection, an xDAWN front
    /// with step `k > 1`): `k` and the same settings reading every sample. Fitted on epochs
    /// decimated by `k`, those give the scores these give on the full epochs, while a copy of
    /// a fold's epochs holds a `k`-th of the samples.
    pub(crate) fn decimated(&self) -> Option<(usize, SingleParams)> {
        if self.channel_selection.is_some() {
            return None;
        }
        let mut p = self.clone();
        let step = match &mut p.features {
            FeatureParams::XdawnTangent(x) => &mut x.step,
            FeatureParams::XdawnCovariances(x) => &mut x.step,
            _ => return None,
        };
        let k = std::mem::replace(step, 1);
        (k > 1).then_some((k, p))
    }

    /// Whether the front learns nothing (no channel selection, a stateless feature map).
    pub(crate) fn has_stateless_front(&self) -> bool {
        self.channel_selection.is_none() && self.features.is_stateless()
    }

    /// When the front learns nothing (no channel selection, a stateless feature map): the
    /// fitted map and the features of every epoch of `epochs`, the same rows whatever the
    /// training split. `None` otherwise.
    pub(crate) fn stateless_features(
        &self,
        epochs: EpochSource<'_>,
    ) -> Option<Result<(Features, FeatureData)>> {
        self.has_stateless_front().then(|| {
            self.stateless_front(None, epochs)
                .map(|(front, x)| (front.features, x))
        })
    }
}

/// One split's features through a neck fitted on its training part, and the seconds the fit
/// and the test part's transform took.
#[derive(Debug)]
pub(crate) struct Necked {
    pub(crate) xtr: FeatureData,
    pub(crate) xte: FeatureData,
    pub(crate) fit_s: f64,
    pub(crate) transform_s: f64,
}

/// scikit-learn's `gamma='scale'` of the features `x`: `1 / (n_features · Var(X))` (1 when the
/// variance is 0), as [`crate::classifiers::svm`] resolves it.
fn gamma_scale(x: FeatureView<'_>) -> f64 {
    let (sum, len, n_features) = match x {
        FeatureView::Rows(r) => (r.sum(), r.len(), r.ncols()),
        FeatureView::Spd(m) => (m.sum(), m.len(), m.dim().1 * m.dim().2),
    };
    let n = len as f64;
    let mean = sum / n;
    let sq = |v: &f64| (v - mean) * (v - mean);
    let var = match x {
        FeatureView::Rows(r) => r.iter().map(sq).sum::<f64>(),
        FeatureView::Spd(m) => m.iter().map(sq).sum::<f64>(),
    } / n;
    if var > 0.0 {
        1.0 / (n_features as f64 * var)
    } else {
        1.0
    }
}

/// The same settings with every RBF SVM's `γ = 'scale'` replaced by `factor ×` the scale γ of
/// the training features `x` (unchanged when `factor` is 1).
fn with_gamma_factor(
    classifier: &ClassifierParams,
    x: FeatureView<'_>,
    factor: f64,
) -> Result<ClassifierParams> {
    if !(factor.is_finite() && factor > 0.0) {
        return Err(DecodeError::InvalidParameter {
            name: "svm_gamma_scale",
            value: factor.to_string(),
            reason: "must be finite and > 0".into(),
        });
    }
    if factor == 1.0 || x.is_empty() {
        return Ok(classifier.clone());
    }
    Ok(classifier.with_scale_gamma(factor * gamma_scale(x)))
}

/// The fitted channel selection and features.
#[derive(Debug)]
pub(crate) struct Front {
    pub(super) channels: Option<ChannelSelection>,
    pub(super) features: Features,
}

impl Front {
    /// Channels the features see, of `n_channels` given.
    pub(crate) fn n_channels(&self, n_channels: usize) -> usize {
        self.channels
            .as_ref()
            .map_or(n_channels, |c| c.selected.len())
    }

    /// Features of `epochs`.
    pub(crate) fn transform(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        match &self.channels {
            Some(c) => self.features.transform(c.transform(epochs)?.view()),
            None => self.features.transform(epochs),
        }
    }
}

/// The fitted scaler and PCA of a pipeline: what lies between its features and its classifier.
#[derive(Debug, Clone, Default)]
pub(crate) struct Neck {
    scaler: Option<StandardScaler>,
    pca: Option<Pca>,
}

impl Neck {
    /// Features `x` through the scaler and the PCA.
    pub(crate) fn transform(&self, x: FeatureData) -> Result<FeatureData> {
        scale_and_project(self.scaler.as_ref(), self.pca.as_ref(), x)
    }
}

/// The fitted steps after the features.
#[derive(Debug)]
pub(crate) struct Head {
    scaler: Option<StandardScaler>,
    pca: Option<Pca>,
    classifier: Classifier,
}

/// Features `x` through the optional scaler and PCA.
fn scale_and_project(
    scaler: Option<&StandardScaler>,
    pca: Option<&Pca>,
    mut x: FeatureData,
) -> Result<FeatureData> {
    if let Some(s) = scaler {
        x = FeatureData::Rows(s.transform(x.into_rows("StandardScaler")?.view())?);
    }
    if let Some(p) = pca {
        x = FeatureData::Rows(p.transform(x.into_rows("PCA")?.view())?);
    }
    Ok(x)
}

/// One fitted pipeline (no fusion).
#[derive(Debug, Clone)]
pub struct Single {
    pub(crate) name: String,
    pub(crate) n_channels: usize,
    pub(crate) n_times: usize,
    pub(crate) channels: Option<ChannelSelection>,
    pub(crate) features: Features,
    pub(crate) scaler: Option<StandardScaler>,
    pub(crate) pca: Option<Pca>,
    pub(crate) classifier: Classifier,
}

impl Single {
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Channels and samples per epoch it was fitted on.
    pub fn epoch_shape(&self) -> (usize, usize) {
        (self.n_channels, self.n_times)
    }

    /// The classifier's input for `epochs`: rows `(n_epochs, n_features)`, or SPD matrices
    /// `(n_epochs, n, n)` for MDM.
    pub fn features(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        let (_, n_channels, n_times) = epochs.dim();
        if (n_channels, n_times) != (self.n_channels, self.n_times) {
            return Err(DecodeError::ShapeMismatch {
                what: "epochs (n_channels, n_times)".into(),
                expected: format!("({}, {})", self.n_channels, self.n_times),
                got: format!("({n_channels}, {n_times})"),
            });
        }
        let selected;
        let epochs = match &self.channels {
            Some(c) => {
                selected = c.transform(epochs)?;
                selected.view()
            }
            None => epochs.view(),
        };
        let x = self.features.transform(epochs)?;
        scale_and_project(self.scaler.as_ref(), self.pca.as_ref(), x)
    }

    /// Decision values of `epochs`.
    pub fn decision_function(&self, epochs: ArrayView3<f64>) -> Result<Array1<f64>> {
        let x = self.features(epochs)?;
        self.classifier.scorer().decision_function(x.view())
    }

    /// [`Self::decision_function`] of an [`EpochSource`], a part at a time when it is not an
    /// array.
    pub(crate) fn decision_function_source(&self, epochs: EpochSource<'_>) -> Result<Array1<f64>> {
        epochs.map_scores(|chunk| self.decision_function(chunk))
    }
}

/// An xDAWN front fitted reading every sample of epochs decimated by `k` (by the settings
/// [`SingleParams::decimated`] gives), made the same front reading every `k`-th sample.
fn set_step(features: &mut Features, k: usize) -> Result<()> {
    let step = match features {
        Features::XdawnTangent(x) => &mut x.step,
        Features::XdawnCovariances(x) => &mut x.step,
        _ => {
            return Err(DecodeError::InvalidParameter {
                name: "step",
                value: k.to_string(),
                reason: "only an xDAWN front reads every k-th sample".into(),
            })
        }
    };
    if *step != 1 {
        return Err(DecodeError::InvalidParameter {
            name: "step",
            value: step.to_string(),
            reason: "a decimated fit reads every sample of its decimated epochs".into(),
        });
    }
    *step = k;
    Ok(())
}
