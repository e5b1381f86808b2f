//! The interface every pipeline step shares, linfa-style: unfitted settings `fit` into a fitted
//! type, which transforms epochs into features ([`Transformer`]) or scores features
//! ([`Scorer`]).
//!
//! * A feature map's settings implement [`FitTransformer`]: fitted on training epochs
//!   `(n_epochs, n_channels, n_times)` and labels, they give a [`Transformer`] from epochs to
//!   [`FeatureData`].
//! * A classifier's settings implement [`FitClassifier`]: fitted on training features they give a
//!   [`Scorer`], whose decision function is a continuous score per epoch (larger = more
//!   target-like) and whose `predict_proba` is P(target).
//! * Features are rows `(n_epochs, n_features)` or SPD matrices `(n_epochs, n, n)` (xDAWN
//!   covariances, the input of [`crate::riemann::Mdm`]); each step says which it takes.
//!
//! The registries of [`crate::features`] and [`crate::classifiers`] list the steps a saved
//! model may name; a new classifier implements [`FitClassifier`] and [`Scorer`] (or
//! [`ProbabilisticClassifier`] on rows) in its own file and adds one line to its registry.

use ndarray::{Array1, Array2, Array3, ArrayView2, ArrayView3, Axis};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// A fitted binary classifier of feature rows `(n_samples, n_features)` that scores and gives
/// P(target); a member of a [`crate::classifiers::ensemble::SoftVote`].
pub trait ProbabilisticClassifier {
    /// P(target) per row of `x` `(n_samples, n_features)`.
    fn predict_proba(&self, x: ArrayView2<f64>) -> Result<Array1<f64>>;
    /// Continuous score per row, larger = more target-like.
    fn decision_function(&self, x: ArrayView2<f64>) -> Result<Array1<f64>>;
    /// The rows a distance-based member measures queries against (see the module docs); `None`
    /// for any other member.
    fn distance_rows(&self) -> Option<ArrayView2<'_, f64>> {
        None
    }
    /// [`Self::predict_proba`] from the squared distances `(n_samples, n_rows)` to
    /// [`Self::distance_rows`], as `linalg::sq_distances` computes them.
    fn predict_proba_from_sq_distances(&self, d2: Array2<f64>) -> Result<Array1<f64>> {
        let _ = d2;
        Err(DecodeError::InvalidParameter {
            name: "member",
            value: "not distance-based".into(),
            reason: "this member does not score from distances".into(),
        })
    }
}

/// Features of a batch of epochs, as a feature map gives them.
#[derive(Debug, Clone, PartialEq)]
pub enum FeatureData {
    /// Rows `(n_epochs, n_features)`.
    Rows(Array2<f64>),
    /// Symmetric positive-definite matrices `(n_epochs, n, n)`.
    Spd(Array3<f64>),
}

/// A view of [`FeatureData`].
#[derive(Debug, Clone, Copy)]
pub enum FeatureView<'a> {
    Rows(ArrayView2<'a, f64>),
    Spd(ArrayView3<'a, f64>),
}

impl FeatureData {
    pub fn view(&self) -> FeatureView<'_> {
        match self {
            FeatureData::Rows(x) => FeatureView::Rows(x.view()),
            FeatureData::Spd(x) => FeatureView::Spd(x.view()),
        }
    }

    /// Number of epochs.
    pub fn n_epochs(&self) -> usize {
        self.view().n_epochs()
    }

    /// The epochs at `indices`, in that order.
    pub fn select(&self, indices: &[usize]) -> Self {
        match self {
            FeatureData::Rows(x) => FeatureData::Rows(x.select(Axis(0), indices)),
            FeatureData::Spd(x) => FeatureData::Spd(x.select(Axis(0), indices)),
        }
    }

    /// The epochs of `parts` in order, one after another (parts of the same kind and width:
    /// the features of consecutive chunks of epochs by one map).
    pub fn concatenate(parts: Vec<FeatureData>) -> Result<Self> {
        let mismatch = |e: ndarray::ShapeError| DecodeError::ShapeMismatch {
            what: "feature parts".into(),
            expected: "parts of one map".into(),
            got: e.to_string(),
        };
        if parts.iter().all(|p| matches!(p, FeatureData::Rows(_))) {
            let views: Vec<_> = parts
                .iter()
                .map(|p| match p {
                    FeatureData::Rows(x) => x.view(),
                    FeatureData::Spd(_) => unreachable!("all rows"),
                })
                .collect();
            return Ok(FeatureData::Rows(
                ndarray::concatenate(Axis(0), &views).map_err(mismatch)?,
            ));
        }
        let mut views = Vec::with_capacity(parts.len());
        for p in &parts {
            match p {
                FeatureData::Spd(x) => views.push(x.view()),
                FeatureData::Rows(x) => {
                    return Err(wrong_kind("concatenate", "SPD matrices", x.ndim()))
                }
            }
        }
        Ok(FeatureData::Spd(
            ndarray::concatenate(Axis(0), &views).map_err(mismatch)?,
        ))
    }

    /// The rows, for a step that takes rows (`what` names it in the error otherwise).
    pub fn into_rows(self, what: &str) -> Result<Array2<f64>> {
        match self {
            FeatureData::Rows(x) => Ok(x),
            FeatureData::Spd(x) => Err(wrong_kind(what, "feature rows", x.ndim())),
        }
    }
}

impl<'a> FeatureView<'a> {
    /// Number of epochs.
    pub fn n_epochs(&self) -> usize {
        match self {
            FeatureView::Rows(x) => x.nrows(),
            FeatureView::Spd(x) => x.dim().0,
        }
    }

    /// Whether there are no values at all.
    pub fn is_empty(&self) -> bool {
        match self {
            FeatureView::Rows(x) => x.is_empty(),
            FeatureView::Spd(x) => x.is_empty(),
        }
    }

    /// The rows, for a step that takes rows (`what` names it in the error otherwise).
    pub fn rows(self, what: &str) -> Result<ArrayView2<'a, f64>> {
        match self {
            FeatureView::Rows(x) => Ok(x),
            FeatureView::Spd(x) => Err(wrong_kind(what, "feature rows", x.ndim())),
        }
    }

    /// The SPD matrices, for a step that takes matrices (`what` names it in the error otherwise).
    pub fn spd(self, what: &str) -> Result<ArrayView3<'a, f64>> {
        match self {
            FeatureView::Spd(x) => Ok(x),
            FeatureView::Rows(x) => Err(wrong_kind(what, "SPD matrices", x.ndim())),
        }
    }
}

fn wrong_kind(what: &str, expected: &str, ndim: usize) -> DecodeError {
    DecodeError::ShapeMismatch {
        what: format!("{what} input"),
        expected: expected.into(),
        got: format!("a {ndim}-dimensional feature array"),
    }
}

/// Unfitted settings of a feature map from epochs.
pub trait FitTransformer {
    type Fitted: Transformer;
    /// Fits on training `epochs` `(n_epochs, n_channels, n_times)` labelled `y`.
    fn fit_transformer(&self, epochs: ArrayView3<f64>, y: &[bool]) -> Result<Self::Fitted>;
    /// Whether the map learns nothing from the training data (so the features of any epoch can
    /// be computed once, whatever the training split).
    fn is_stateless(&self) -> bool {
        false
    }
}

/// A fitted feature map from epochs `(n_epochs, n_channels, n_times)`.
pub trait Transformer {
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData>;
}

impl<T: Transformer + ?Sized> Transformer for Box<T> {
    fn transform_epochs(&self, epochs: ArrayView3<f64>) -> Result<FeatureData> {
        (**self).transform_epochs(epochs)
    }
}

/// Unfitted settings of a classifier.
pub trait FitClassifier: Clone {
    type Fitted: Scorer;
    /// Fits on the training features `x` of epochs with `n_channels` channels (after channel
    /// selection; only a classifier of spatio-temporal features reads it), labelled `y`.
    fn fit_classifier(
        &self,
        x: FeatureView<'_>,
        y: &[bool],
        n_channels: usize,
    ) -> Result<Self::Fitted>;
    /// The same settings with an RBF kernel's `γ = 'scale'` replaced by `gamma` (unchanged for
    /// a classifier without one).
    fn with_scale_gamma(&self, gamma: f64) -> Self {
        let _ = gamma;
        self.clone()
    }
    /// The settings a preset of this classifier is tuned over (besides its front's), each with
    /// a short label naming what differs; none by default.
    fn grid(&self) -> Vec<(String, Self)> {
        Vec::new()
    }
}

/// A fitted classifier's decision function.
pub trait Scorer {
    /// Continuous score per epoch, larger = more target-like.
    fn decision_function(&self, x: FeatureView<'_>) -> Result<Array1<f64>>;
    /// P(target) per epoch.
    fn predict_proba(&self, x: FeatureView<'_>) -> Result<Array1<f64>>;
}

/// Every classifier of feature rows scores [`FeatureData::Rows`].
impl<T: ProbabilisticClassifier> Scorer for T {
    fn decision_function(&self, x: FeatureView<'_>) -> Result<Array1<f64>> {
        ProbabilisticClassifier::decision_function(self, x.rows("classifier")?)
    }
    fn predict_proba(&self, x: FeatureView<'_>) -> Result<Array1<f64>> {
        ProbabilisticClassifier::predict_proba(self, x.rows("classifier")?)
    }
}

/// Implements [`ProbabilisticClassifier`] for the fitted classifier `$fitted` by its inherent
/// `predict_proba` and `decision_function`, and [`FitClassifier`] for its settings `$params` by
/// their inherent `fit(rows, y)` (`$what` names the step when the features are not rows): all a
/// classifier of feature rows needs when it reads no channel count, no distances and no γ.
macro_rules! rows_classifier {
    ($params:ty => $fitted:ident, $what:literal) => {
        impl $crate::traits::ProbabilisticClassifier for $fitted {
            fn predict_proba(
                &self,
                x: ndarray::ArrayView2<f64>,
            ) -> std::result::Result<ndarray::Array1<f64>, $crate::DecodeError> {
                $fitted::predict_proba(self, x)
            }
            fn decision_function(
                &self,
                x: ndarray::ArrayView2<f64>,
            ) -> std::result::Result<ndarray::Array1<f64>, $crate::DecodeError> {
                $fitted::decision_function(self, x)
            }
        }

        impl $crate::traits::FitClassifier for $params {
            type Fitted = $fitted;
            fn fit_classifier(
                &self,
                x: $crate::traits::FeatureView<'_>,
                y: &[bool],
                _: usize,
            ) -> std::result::Result<$fitted, $crate::DecodeError> {
                self.fit(x.rows($what)?, y)
            }
        }
    };
}
pub(crate) use rows_classifier;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classifiers::lda::LdaParams;
    use crate::classifiers::ClassifierParams;
    use crate::riemann::MdmParams;

    #[test]
    fn a_step_given_the_wrong_kind_of_features_names_itself() {
        let rows = FeatureData::Rows(Array2::from_shape_fn((6, 2), |(i, j)| (i * 2 + j) as f64));
        let y = [true, false, true, false, true, false];
        let mdm = ClassifierParams::Mdm(MdmParams::default()).fit(rows.view(), &y, 2);
        assert!(
            matches!(&mdm, Err(DecodeError::ShapeMismatch { what, .. }) if what == "MDM input"),
            "{mdm:?}"
        );
        let lda = ClassifierParams::Lda(LdaParams::default())
            .fit(rows.view(), &y, 2)
            .unwrap();
        let spd = FeatureData::Spd(Array3::from_shape_fn((2, 2, 2), |(_, i, j)| {
            f64::from(u8::from(i == j))
        }));
        assert!(matches!(
            lda.scorer().decision_function(spd.view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        assert_eq!(spd.select(&[1, 1, 0]).n_epochs(), 3);
        assert!(spd.into_rows("PCA").is_err());
    }
}
