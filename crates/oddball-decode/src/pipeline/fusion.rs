//! Score fusion: single pipelines fitted on the same epochs whose decision values are combined,
//! each adding `w · (s − c) / σ` ([`FusionTerm`]) to the fused score.

use ndarray::parallel::prelude::*;
use ndarray::{Array1, Array2};
use serde::{Deserialize, Serialize};

use super::single::{Single, SingleParams};
use super::source::EpochSource;
use crate::classifiers::logistic::LogisticParams;
use crate::features::scaler::StandardScalerParams;
use crate::model_selection::Split;
use crate::traits::FeatureData;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// How a score fusion combines its pipelines' decision values `s_i`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Fusion {
    /// `Σ s_i / σ_i`, `σ_i` the standard deviation of `s_i` over the training epochs: each
    /// pipeline counts equally, nothing is fitted.
    #[default]
    Standardised,
    /// Stacking (scikit-learn's `StackingClassifier` with `cv`, a logistic-regression final
    /// estimator on standardised scores): each pipeline is fitted on the training part of
    /// `n_folds` inner folds ([`crate::model_selection::cv_folds`]: speller characters kept whole when the
    /// fit is given groups, otherwise stratified) and scores the held-out part; a logistic
    /// regression (`C = 1`) on those out-of-fold scores, each standardised by its mean and
    /// standard deviation, learns the weights. The pipelines are then fitted on all the epochs,
    /// and the fused score is `b + Σ w_i (s_i − m_i) / σ_i` (log-odds of target).
    Stacked { n_folds: usize },
}

impl Fusion {
    pub(crate) fn is_standardised(&self) -> bool {
        *self == Fusion::Standardised
    }
}

/// A pipeline's share `weight · (s − center) / scale` of a fused score. Standardised: the
/// standard deviation of the decision values on the training epochs, centre 0, weight 1;
/// stacked: the out-of-fold scores' mean and standard deviation and the logistic regression's
/// weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusionTerm {
    pub scale: f64,
    pub center: f64,
    pub weight: f64,
}

impl FusionTerm {
    /// No change: `s` itself.
    pub const UNIT: FusionTerm = FusionTerm {
        scale: 1.0,
        center: 0.0,
        weight: 1.0,
    };

    /// `w · (s − c) / σ` of every score.
    pub(crate) fn apply(&self, s: Array1<f64>) -> Array1<f64> {
        let (c, sd, w) = (self.center, self.scale, self.weight);
        s.mapv_into(|v| w * ((v - c) / sd))
    }
}

/// A single pipeline fused with a [`Pipeline`](super::Pipeline)'s main one.
#[derive(Debug, Clone)]
pub struct FusedMember {
    pub(crate) single: Single,
    /// The settings it was fitted with (absent in models saved before they were kept).
    pub(crate) params: Option<SingleParams>,
    pub(crate) term: FusionTerm,
}

impl FusedMember {
    pub fn name(&self) -> &str {
        self.single.name()
    }
}

/// The fusion terms of a fusion's pipelines fitted on `epochs` (`fitted`, the main one first, of
/// the settings `singles`), in that order, and the fused score's offset.
pub(super) fn fit_terms(
    fusion: Fusion,
    singles: &[&SingleParams],
    fitted: &[&Single],
    epochs: EpochSource<'_>,
    y: &[bool],
    groups: Option<&[usize]>,
) -> Result<(Vec<FusionTerm>, f64)> {
    match fusion {
        Fusion::Standardised => {
            let mut terms = Vec::with_capacity(fitted.len());
            for single in fitted {
                terms.push(FusionTerm {
                    scale: training_score_sd(single, epochs)?,
                    ..FusionTerm::UNIT
                });
            }
            Ok((terms, 0.0))
        }
        Fusion::Stacked { n_folds } => {
            let stack = fit_stacker(singles, epochs, y, groups, n_folds)?;
            let terms = (0..fitted.len())
                .map(|k| FusionTerm {
                    center: stack.center[k],
                    scale: stack.scale[k],
                    weight: stack.weight[k],
                })
                .collect();
            Ok((terms, stack.intercept))
        }
    }
}

/// Standard deviation of `single`'s decision values on its training `epochs` (its unit in a
/// score fusion).
fn training_score_sd(single: &Single, epochs: EpochSource<'_>) -> Result<f64> {
    let scores = single.decision_function_source(epochs)?;
    let sd = scores.std(0.0);
    if sd.is_finite() && sd > 0.0 {
        Ok(sd)
    } else {
        Err(DecodeError::InvalidParameter {
            name: "fused",
            value: single.name.clone(),
            reason: format!(
                "its training scores have no spread (standard deviation {sd}): nothing to fuse"
            ),
        })
    }
}

/// A stacked fusion's learned combination, one entry per pipeline (the main one first).
struct Stacker {
    center: Vec<f64>,
    scale: Vec<f64>,
    weight: Vec<f64>,
    intercept: f64,
}

/// Stacking weights from out-of-fold scores (see [`Fusion::Stacked`]).
fn fit_stacker(
    singles: &[&SingleParams],
    epochs: EpochSource<'_>,
    y: &[bool],
    groups: Option<&[usize]>,
    n_folds: usize,
) -> Result<Stacker> {
    let folds = crate::model_selection::cv_folds(y, groups, n_folds)?;
    let n = y.len();
    let n_channels = epochs.dim().1;
    // The features of a pipeline whose front learns nothing are computed once for every fold
    // (the rows its fit on a fold's epochs would compute); a pipeline reading every k-th
    // sample is fitted on copies of those samples. The scores are the same as fitting each
    // on a full copy of the fold's epochs.
    let stateless = singles
        .iter()
        .map(|p| {
            p.stateless_features(epochs)
                .map(|r| r.map(|(_, x)| x))
                .transpose()
        })
        .collect::<Result<Vec<Option<FeatureData>>>>()?;
    let decimated: Vec<Option<(usize, SingleParams)>> =
        singles.iter().map(|p| p.decimated()).collect();
    let per_fold = (0..folds.n_folds())
        .into_par_iter()
        .map(|f| {
            let Split {
                train: tr,
                test: te,
                y_train: ytr,
                ..
            } = folds.split_of(f, y, None);
            let scores = singles
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    if let Some(x) = &stateless[k] {
                        let necked = p.neck_split(x.select(&tr), x.select(&te))?;
                        return Ok(p.classifier_scores(&necked, &ytr, n_channels)?.0);
                    }
                    let (step, p) = match &decimated[k] {
                        Some((step, q)) => (*step, q),
                        None => (1, *p),
                    };
                    // The fold's training epochs are freed before its test epochs are copied
                    // (two folds run at once on two threads).
                    let model = p.fit(epochs.gather(&tr, step).view(), &ytr)?;
                    model.decision_function(epochs.gather(&te, step).view())
                })
                .collect::<Result<Vec<Array1<f64>>>>()?;
            Ok((te, scores))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut oof = Array2::zeros((n, singles.len()));
    for (te, scores) in per_fold {
        for (k, s) in scores.iter().enumerate() {
            for (&i, &v) in te.iter().zip(s) {
                oof[[i, k]] = v;
            }
        }
    }
    let scaler = StandardScalerParams::default().fit(oof.view())?;
    let z = scaler.transform(oof.view())?;
    let lr = LogisticParams::default().fit(z.view(), y)?;
    Ok(Stacker {
        center: scaler.mean.to_vec(),
        scale: scaler.scale.to_vec(),
        weight: lr.coef().to_vec(),
        intercept: lr.intercept(),
    })
}

/// A fusion's score scales are finite and positive, its members take the epochs of `main` (a
/// file could say anything): `main` with its `term`, the `fused` members and the `intercept`.
pub(super) fn check_terms(
    main: &Single,
    term: &FusionTerm,
    fused: &[FusedMember],
    intercept: f64,
) -> Result<()> {
    if fused.is_empty() {
        return Ok(());
    }
    if !intercept.is_finite() {
        return Err(DecodeError::ModelFormat {
            reason: format!("fusion intercept {intercept} must be finite"),
        });
    }
    let all = std::iter::once((main, term)).chain(fused.iter().map(|m| (&m.single, &m.term)));
    for (p, t) in all {
        if !(t.scale.is_finite() && t.scale > 0.0) {
            return Err(DecodeError::ModelFormat {
                reason: format!(
                    "fused pipeline {}: score scale {} (must be finite and > 0)",
                    p.name, t.scale
                ),
            });
        }
        if !(t.center.is_finite() && t.weight.is_finite()) {
            return Err(DecodeError::ModelFormat {
                reason: format!(
                    "fused pipeline {}: score centre {} and weight {} must be finite",
                    p.name, t.center, t.weight
                ),
            });
        }
        if p.epoch_shape() != main.epoch_shape() {
            return Err(DecodeError::ModelFormat {
                reason: format!(
                    "fused pipeline {} expects epochs {:?}, the model {:?}",
                    p.name,
                    p.epoch_shape(),
                    main.epoch_shape()
                ),
            });
        }
    }
    Ok(())
}
