//! The one cross-validation spine, as scikit-learn's `cross_val_predict`: pipelines fitted on
//! the training part of every fold ([`Split`], from [`Folds::splits`]) and scoring its test part
//! through one [`FrontCache`] ([`cross_val_scores`]), and the out-of-fold score of
//! every epoch ([`cross_val_predict`]). Evaluation's cross-validation and decision models, the
//! grid search ([`super::tuning`]) and the stacker's inner folds
//! ([`crate::pipeline::Fusion::Stacked`]) all take their folds' parts from here.

use crate::pipeline::{CachedScores, FrontCache, PipelineParams};
use crate::DecodeError;

use super::folds::{Folds, Split};

type Result<T> = std::result::Result<T, DecodeError>;

/// One fold's scores of its test part.
#[derive(Debug, Clone)]
pub struct FoldScores {
    pub split: Split,
    pub scores: CachedScores,
}

/// Each fold's test scores by the pipeline `params_for` gives for it (e.g. the same settings in
/// every fold, or settings tuned on the fold's training part), fitted on the fold's training
/// part through `cache` ([`PipelineParams::fit_score_cached`]: the same scores as a fit on
/// copies of the fold's epochs). `on_fit` is called after each fold's fit. Folds run in order.
pub fn cross_val_scores<'c, E: From<DecodeError>>(
    cache: &mut FrontCache<'c>,
    y: &[bool],
    groups: Option<&[usize]>,
    folds: &Folds,
    mut params_for: impl FnMut(&mut FrontCache<'c>, &Split) -> std::result::Result<PipelineParams, E>,
    mut on_fit: impl FnMut(),
) -> std::result::Result<Vec<FoldScores>, E> {
    let mut out = Vec::with_capacity(folds.n_folds());
    for split in folds.splits(y, groups) {
        let params = params_for(cache, &split)?;
        let scores = params.fit_score_cached(
            cache,
            &split.train,
            &split.y_train,
            split.groups_train.as_deref(),
            &split.test,
        )?;
        on_fit();
        out.push(FoldScores { split, scores });
    }
    Ok(out)
}

/// Every epoch's score by `params` fitted on the other folds (scikit-learn's
/// `cross_val_predict` with `decision_function`), through `cache` (over the epochs labelled
/// `y`); `groups` are kept together in the fits (a stack's inner folds), as in a final fit.
pub fn cross_val_predict(
    params: &PipelineParams,
    cache: &mut FrontCache<'_>,
    y: &[bool],
    groups: Option<&[usize]>,
    folds: &Folds,
    on_fit: impl FnMut(),
) -> Result<Vec<f64>> {
    let per_fold = cross_val_scores(cache, y, groups, folds, |_, _| Ok(params.clone()), on_fit)?;
    let mut oof = vec![0.0; y.len()];
    for f in per_fold {
        for (&i, &v) in f.split.test.iter().zip(f.scores.scores.iter()) {
            oof[i] = v;
        }
    }
    Ok(oof)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model_selection::cv_folds;
    use crate::preset::Preset;
    use ndarray::Axis;

    #[test]
    fn splits_partition_the_epochs_and_carry_their_labels() {
        let (_, y) = crate::testutil::synthetic_p300(60, 1, 6, 1, 3.0, 4.0);
        let groups: Vec<usize> = (0..60).map(|i| i / 12).collect();
        let folds = cv_folds(&y, Some(&groups), 3).unwrap();
        let mut seen = vec![0; 60];
        for (f, s) in folds.splits(&y, Some(&groups)).enumerate() {
            assert_eq!(s.fold, f);
            assert_eq!(s.train.len() + s.test.len(), 60);
            for &i in &s.test {
                seen[i] += 1;
            }
            let yt: Vec<bool> = s.test.iter().map(|&i| y[i]).collect();
            assert_eq!(s.y_test, yt);
            let gt: Vec<usize> = s.train.iter().map(|&i| groups[i]).collect();
            assert_eq!(s.groups_train.as_deref(), Some(&gt[..]));
        }
        assert!(seen.iter().all(|&n| n == 1), "every epoch tested once");
    }

    /// The spine's out-of-fold scores are those of each fold's pipeline fitted on copies of the
    /// fold's training epochs.
    #[test]
    fn cross_val_predict_equals_fits_on_each_fold() {
        let (x, y) = crate::testutil::synthetic_p300(96, 2, 6, 1, 3.0, 4.0);
        let folds = cv_folds(&y, None, 3).unwrap();
        for preset in [Preset::Lda, Preset::Mdm] {
            let p = preset.params(64.0).unwrap();
            let mut fits = 0;
            let oof =
                cross_val_predict(&p, &mut FrontCache::new(x.view()), &y, None, &folds, || {
                    fits += 1
                })
                .unwrap();
            assert_eq!(fits, 3);
            for s in folds.splits(&y, None) {
                let m = p
                    .fit(x.select(Axis(0), &s.train).view(), &s.y_train)
                    .unwrap();
                let want = m
                    .decision_function(x.select(Axis(0), &s.test).view())
                    .unwrap();
                let got: Vec<f64> = s.test.iter().map(|&i| oof[i]).collect();
                assert_eq!(got, want.to_vec(), "{preset}, fold {}", s.fold);
            }
        }
    }
}
