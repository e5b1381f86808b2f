//! Choosing a pipeline's hyper-parameters by cross-validation on the training data only.
//!
//! * [`Preset::grid`](crate::preset::Preset::grid): a small grid of settings around each preset
//!   (its defaults included), written beside the preset's settings in [`crate::preset`]:
//!   - `lda`, `toeplitz-lda` (and every classifier preset on amplitudes): the amplitude bin
//!     width, round(sfreq/32), round(sfreq/25) (the default) and round(sfreq/20) samples, ×
//!     the classifier's own grid (none for these two);
//!   - `lda+riemann`, `stack`: none (the stack learns its weights by its own inner folds);
//!   - `riemann`: xDAWN filters per class {2, 4, 6} × logistic-regression `C` {0.1, 1, 10};
//!   - `mdm`: xDAWN filters per class {2, 4, 6};
//!   - `paper`, `paper-svm`: the RBF SVM's `C` {1, 10} × γ {1, 0.5} × scikit-learn's `'scale'`;
//!   - `paper-knn`: neighbours k {3, 5, 9}.
//! * [`cv_folds`]: k folds that keep each group (a speller character: its flashes overlap in time
//!   and share one attended symbol) in one fold, contiguous runs of groups per fold; without
//!   groups, scikit-learn's `StratifiedKFold(k)` without shuffling ([`super::folds::stratified_folds`]:
//!   each class dealt to folds in contiguous blocks, so neighbouring, overlapping epochs mostly
//!   stay together). `k` is lowered to the number of groups (or to the smaller class's size).
//! * [`grid_search`]: mean epoch ROC-AUC over the folds for each candidate; the best mean wins
//!   (ties to the earlier candidate). Every fitted step (channel selection, xDAWN, tangent space,
//!   scaler, PCA, classifier) is fitted on the training part of each fold only. Candidates that
//!   share their front (channel selection + features) share its fit in each fold, and a front that
//!   learns nothing (amplitude or paper features) is computed once for all epochs; both give the
//!   same scores as fitting each candidate's whole pipeline per fold (a test checks this).
//!   [`grid_search_cached`] and [`tune_cached`] take those features from a
//!   [`FrontCache`] over a larger data set, shared with other searches (nested
//!   cross-validation's outer folds, other presets); the folds of a search run in parallel
//!   (rayon), which changes no score.
//!
//! The functions only ever see the data they are given: the caller passes the training epochs,
//! and held-out test data can't influence the choice.

use ndarray::ArrayView3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

use crate::metrics::roc_auc;
use crate::pipeline::{FrontCache, Necked, PipelineParams};
use crate::DecodeError;

pub use crate::preset::Candidate;

pub use super::folds::{cv_folds, Folds};
use super::Split;

type Result<T> = std::result::Result<T, DecodeError>;

/// Cross-validated scores of a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSearch {
    /// Index of the candidate with the best mean AUC (the earliest on ties).
    pub best: usize,
    /// Mean epoch ROC-AUC over the folds, per candidate.
    pub mean_auc: Vec<f64>,
    /// Epoch ROC-AUC of each fold, per candidate.
    pub fold_auc: Vec<Vec<f64>>,
    pub n_folds: usize,
    /// Whether folds kept groups together.
    pub grouped: bool,
}

/// Scores each candidate by `k`-fold cross-validation ([`cv_folds`]) on `epochs`
/// `(n_epochs, n_channels, n_times)` labelled `y`, groups optional; see the module doc.
pub fn grid_search(
    candidates: &[PipelineParams],
    epochs: ArrayView3<f64>,
    y: &[bool],
    groups: Option<&[usize]>,
    k: usize,
) -> Result<GridSearch> {
    grid_search_with(candidates, epochs, y, groups, k, &mut || {})
}

/// [`grid_search`], calling `on_fit` after each (candidate, fold) fit — for a progress bar.
pub fn grid_search_with(
    candidates: &[PipelineParams],
    epochs: ArrayView3<f64>,
    y: &[bool],
    groups: Option<&[usize]>,
    k: usize,
    on_fit: &mut dyn FnMut(),
) -> Result<GridSearch> {
    let all: Vec<usize> = (0..epochs.dim().0).collect();
    grid_search_cached(
        candidates,
        &mut FrontCache::new(epochs),
        &all,
        y,
        groups,
        k,
        on_fit,
    )
}

/// [`grid_search_with`] on the epochs at `subset` of `cache`'s epochs (labels `y` and groups
/// for the subset): a front that learns nothing takes its features from `cache`, shared with
/// every other search, fold and preset on the same epochs.
pub fn grid_search_cached(
    candidates: &[PipelineParams],
    cache: &mut FrontCache<'_>,
    subset: &[usize],
    y: &[bool],
    groups: Option<&[usize]>,
    k: usize,
    on_fit: &mut dyn FnMut(),
) -> Result<GridSearch> {
    if candidates.is_empty() {
        return Err(DecodeError::InvalidParameter {
            name: "candidates",
            value: "[]".into(),
            reason: "a grid search needs at least one candidate".into(),
        });
    }
    if y.len() != subset.len() {
        return Err(DecodeError::LabelCount {
            n_samples: subset.len(),
            n_labels: y.len(),
        });
    }
    let folds = cv_folds(y, groups, k)?;
    let n = candidates.len();
    let mut fold_auc = vec![vec![0.0; folds.n_folds()]; n];
    let mut done = vec![false; n];
    // Indices into the cache's epochs of the subset's epochs at `idx`.
    let full = |idx: &[usize]| -> Vec<usize> { idx.iter().map(|&i| subset[i]).collect() };
    let epochs = cache.epochs();
    // The labels and groups of each fold's two parts.
    let parts: Vec<Split> = folds.splits(y, groups).collect();
    // The folds of one candidate group run in parallel (rayon); each is fitted on its own
    // training part only, so the scores do not depend on the number of threads.
    for i in 0..n {
        if done[i] {
            continue;
        }
        if !candidates[i].fused.is_empty() {
            // A score fusion is fitted whole in each fold (its fronts differ).
            let aucs = parts
                .par_iter()
                .map(|p| {
                    let m = candidates[i].fit_source(
                        epochs.subset(&full(&p.train), 1).source(),
                        &p.y_train,
                        p.groups_train.as_deref(),
                    )?;
                    let scores =
                        m.decision_function_source(epochs.subset(&full(&p.test), 1).source())?;
                    roc_auc(&scores.to_vec(), &p.y_test)
                })
                .collect::<Result<Vec<f64>>>()?;
            for (f, auc) in aucs.into_iter().enumerate() {
                fold_auc[i][f] = auc;
                on_fit();
            }
            done[i] = true;
            continue;
        }
        let members: Vec<usize> = (i..n)
            .filter(|&j| {
                !done[j]
                    && candidates[j].fused.is_empty()
                    && candidates[i].main.same_front(&candidates[j].main)
            })
            .collect();
        // A cached front's features, read by the folds at their indices into the cache's
        // epochs (no copy of the subset's rows first).
        let shared = cache
            .entry(&candidates[i].main)
            .transpose()?
            .map(|k| cache.features(k));
        let n_in = epochs.dim().1;
        // Members with the same scaler and PCA share one neck per fold; with a cached front
        // it comes from (and goes to) the cache, shared with other searches and presets.
        let mut groups_of_neck: Vec<Vec<usize>> = Vec::new();
        for &j in &members {
            match groups_of_neck
                .iter_mut()
                .find(|g| candidates[g[0]].main.same_neck(&candidates[j].main))
            {
                Some(g) => g.push(j),
                None => groups_of_neck.push(vec![j]),
            }
        }
        let split_of = |p: &Split| (full(&p.train), full(&p.test));
        let known: Vec<Vec<Option<Arc<Necked>>>> = parts
            .iter()
            .map(|p| {
                let (tr, te) = split_of(p);
                groups_of_neck
                    .iter()
                    .map(|g| {
                        let q = &candidates[g[0]].main;
                        (shared.is_some() && q.has_neck())
                            .then(|| cache.necked(q, &tr, &te))
                            .flatten()
                    })
                    .collect()
            })
            .collect();
        type FoldOut = (Vec<(usize, f64)>, Vec<(usize, Arc<Necked>)>);
        let outs = parts
            .par_iter()
            .zip(known.par_iter())
            .map(|(p, known)| -> Result<FoldOut> {
                let (xtr, xte, n_front) = match &shared {
                    Some(x) => (x.select(&full(&p.train)), x.select(&full(&p.test)), n_in),
                    None => {
                        let (front, xtr) = candidates[i].main.fit_front_source(
                            epochs.subset(&full(&p.train), 1).source(),
                            &p.y_train,
                        )?;
                        let xte = epochs
                            .subset(&full(&p.test), 1)
                            .source()
                            .map_chunks(&mut |chunk| front.transform(chunk))?;
                        (xtr, xte, front.n_channels(n_in))
                    }
                };
                let mut aucs = Vec::new();
                let mut fitted = Vec::new();
                // The last group to fit a neck takes the fold's features, the others copies.
                let last_fit = (0..groups_of_neck.len())
                    .rev()
                    .find(|&gi| known[gi].is_none());
                let mut features = Some((xtr, xte));
                for (gi, g) in groups_of_neck.iter().enumerate() {
                    let q = &candidates[g[0]].main;
                    let necked = match &known[gi] {
                        Some(k) => k.clone(),
                        None => {
                            let (xtr, xte) = if Some(gi) == last_fit {
                                features.take().expect("taken by the last group only")
                            } else {
                                let (xtr, xte) = features.as_ref().expect("not taken yet");
                                (xtr.clone(), xte.clone())
                            };
                            let k = Arc::new(q.neck_split(xtr, xte)?);
                            if shared.is_some() && q.has_neck() {
                                fitted.push((gi, k.clone()));
                            }
                            k
                        }
                    };
                    for &j in g {
                        let (scores, _, _) = candidates[j]
                            .main
                            .classifier_scores(&necked, &p.y_train, n_front)?;
                        aucs.push((j, roc_auc(&scores.to_vec(), &p.y_test)?));
                    }
                }
                Ok((aucs, fitted))
            })
            .collect::<Result<Vec<FoldOut>>>()?;
        for (f, (aucs, fitted)) in outs.into_iter().enumerate() {
            for (j, auc) in aucs {
                fold_auc[j][f] = auc;
                on_fit();
            }
            let (tr, te) = split_of(&parts[f]);
            for (gi, k) in fitted {
                cache.keep_necked(
                    &candidates[groups_of_neck[gi][0]].main,
                    tr.clone(),
                    te.clone(),
                    k,
                );
            }
        }
        for &j in &members {
            done[j] = true;
        }
    }
    let mean_auc: Vec<f64> = fold_auc
        .iter()
        .map(|a| a.iter().sum::<f64>() / a.len() as f64)
        .collect();
    let best = (0..n).fold(0, |b, j| if mean_auc[j] > mean_auc[b] { j } else { b });
    Ok(GridSearch {
        best,
        mean_auc,
        fold_auc,
        n_folds: folds.n_folds(),
        grouped: folds.grouped(),
    })
}

/// A candidate's cross-validated score, as reported and saved with a tuned model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    pub label: String,
    /// Mean epoch ROC-AUC over the folds.
    pub cv_auc: f64,
    pub fold_auc: Vec<f64>,
}

/// How a pipeline's settings were chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuningReport {
    /// Label of the chosen candidate.
    pub chosen: String,
    /// Every candidate, in grid order.
    pub candidates: Vec<CandidateScore>,
    pub n_folds: usize,
    /// Whether the folds kept groups (speller characters) together; otherwise they were
    /// stratified by label.
    pub grouped: bool,
}

/// Grid search over `candidates` ([`grid_search_with`]); returns the chosen settings and the
/// report.
pub fn tune(
    candidates: &[Candidate],
    epochs: ArrayView3<f64>,
    y: &[bool],
    groups: Option<&[usize]>,
    k: usize,
    on_fit: &mut dyn FnMut(),
) -> Result<(PipelineParams, TuningReport)> {
    let all: Vec<usize> = (0..epochs.dim().0).collect();
    tune_cached(
        candidates,
        &mut FrontCache::new(epochs),
        &all,
        y,
        groups,
        k,
        on_fit,
    )
}

/// [`tune`] on the epochs at `subset` of `cache`'s epochs ([`grid_search_cached`]).
pub fn tune_cached(
    candidates: &[Candidate],
    cache: &mut FrontCache<'_>,
    subset: &[usize],
    y: &[bool],
    groups: Option<&[usize]>,
    k: usize,
    on_fit: &mut dyn FnMut(),
) -> Result<(PipelineParams, TuningReport)> {
    let params: Vec<PipelineParams> = candidates.iter().map(|c| c.params.clone()).collect();
    let g = grid_search_cached(&params, cache, subset, y, groups, k, on_fit)?;
    let report = TuningReport {
        chosen: candidates[g.best].label.clone(),
        candidates: candidates
            .iter()
            .zip(g.mean_auc.iter().zip(&g.fold_auc))
            .map(|(c, (&m, f))| CandidateScore {
                label: c.label.clone(),
                cv_auc: m,
                fold_auc: f.clone(),
            })
            .collect(),
        n_folds: g.n_folds,
        grouped: g.grouped,
    };
    Ok((params[g.best].clone(), report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::amplitude::AmplitudeFeatures;
    use crate::features::FeatureParams;
    use crate::preset::Preset;
    use ndarray::{Array3, Axis};

    /// Synthetic epochs at 64 Hz: targets (every 6th) carry a bump at 300 ms; groups of 24.
    fn synthetic(n_epochs: usize, seed: u64) -> (Array3<f64>, Vec<bool>, Vec<usize>) {
        let (x, y) = crate::testutil::synthetic_p300(n_epochs, seed, 6, 1, 3.0, 4.0);
        let groups = (0..n_epochs).map(|i| i / 24).collect();
        (x, y, groups)
    }

    #[test]
    fn grouped_folds_keep_groups_whole_and_hold_both_classes() {
        let (_, y, groups) = synthetic(24 * 7, 1);
        let f = cv_folds(&y, Some(&groups), 5).unwrap();
        assert!(f.grouped() && f.n_folds() == 5);
        for g in 0..7 {
            let folds: Vec<usize> = (0..y.len())
                .filter(|&i| groups[i] == g)
                .map(|i| f.fold_of()[i])
                .collect();
            assert!(folds.iter().all(|&x| x == folds[0]), "group {g} split");
        }
        // Contiguous runs of groups, every fold used.
        let per_group: Vec<usize> = (0..7).map(|g| f.fold_of()[g * 24]).collect();
        assert!(per_group.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(per_group.last(), Some(&4));
        // k is lowered to the number of groups.
        let g3: Vec<usize> = (0..72).map(|i| i / 24).collect();
        assert_eq!(cv_folds(&y[..72], Some(&g3), 5).unwrap().n_folds(), 3);
        // One group cannot be cross-validated.
        assert!(cv_folds(&y[..24], Some(&[0; 24]), 5).is_err());
        // A fold without targets is refused with the reason.
        let mut y2 = y.clone();
        y2[..24].iter_mut().for_each(|t| *t = false);
        let err = cv_folds(&y2, Some(&groups), 7).unwrap_err();
        assert!(err.to_string().contains("both classes"), "{err}");
    }

    #[test]
    fn stratified_folds_without_groups() {
        let (_, y, _) = synthetic(60, 1);
        let f = cv_folds(&y, None, 4).unwrap();
        assert!(!f.grouped());
        for k in 0..4 {
            let (_, te) = f.split(k);
            let t = te.iter().filter(|&&i| y[i]).count();
            assert!((2..=3).contains(&t), "fold {k}: {t} targets");
        }
        // 10 targets: 20 folds are lowered to 10.
        assert_eq!(cv_folds(&y, None, 20).unwrap().n_folds(), 10);
        assert!(cv_folds(&y, None, 1).is_err());
    }

    #[test]
    fn the_informative_candidate_wins() {
        let (x, y, groups) = synthetic(24 * 6, 2);
        let base = Preset::Lda.params(64.0).unwrap();
        // Only the first sample of each channel: no sight of the 300 ms bump.
        let mut blind = base.clone();
        blind.main.features = FeatureParams::Amplitude(AmplitudeFeatures::decimate(64).unwrap());
        let g = grid_search(&[blind, base], x.view(), &y, Some(&groups), 3).unwrap();
        assert_eq!(g.best, 1, "{:?}", g.mean_auc);
        assert!(
            g.mean_auc[0] < 0.7 && g.mean_auc[1] > 0.9,
            "{:?}",
            g.mean_auc
        );
        assert_eq!(g.fold_auc[1].len(), 3);
    }

    /// Shared fronts and features computed once give the same scores as fitting each
    /// candidate's whole pipeline on each fold's training part.
    #[test]
    fn shared_fits_equal_whole_pipeline_fits() {
        let (x, y, groups) = synthetic(24 * 5, 3);
        let mut cands: Vec<PipelineParams> = Preset::Riemann
            .grid(64.0)
            .unwrap()
            .into_iter()
            .filter(|c| c.label.starts_with("nfilter 2"))
            .map(|c| c.params)
            .collect();
        cands.extend(
            Preset::Lda
                .grid(64.0)
                .unwrap()
                .into_iter()
                .map(|c| c.params),
        );
        cands.push(Preset::Mdm.params(64.0).unwrap());
        let mut fits = 0;
        let g =
            grid_search_with(&cands, x.view(), &y, Some(&groups), 3, &mut || fits += 1).unwrap();
        assert_eq!(fits, cands.len() * 3);
        let folds = cv_folds(&y, Some(&groups), 3).unwrap();
        for (j, p) in cands.iter().enumerate() {
            for f in 0..3 {
                let (tr, te) = folds.split(f);
                let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
                let yte: Vec<bool> = te.iter().map(|&i| y[i]).collect();
                let m = p.fit(x.select(Axis(0), &tr).view(), &ytr).unwrap();
                let s = m.decision_function(x.select(Axis(0), &te).view()).unwrap();
                let auc = roc_auc(&s.to_vec(), &yte).unwrap();
                assert_eq!(g.fold_auc[j][f], auc, "candidate {j}, fold {f}");
            }
        }
    }

    /// One cache shared by several presets' searches on different subsets (as nested
    /// cross-validation shares it across outer folds and presets) gives exactly the scores of
    /// searches and fits that compute everything from the subset's own epochs.
    #[test]
    fn a_shared_front_cache_changes_no_score() {
        let (x, y, groups) = synthetic(24 * 4, 5);
        let mut cache = FrontCache::new(x.view());
        let outer = cv_folds(&y, Some(&groups), 2).unwrap();
        for name in [
            Preset::Lda,
            Preset::PaperKnn,
            Preset::PaperSvm,
            Preset::Riemann,
            Preset::LdaRiemann,
        ] {
            let grid: Vec<PipelineParams> = name
                .grid(64.0)
                .unwrap()
                .into_iter()
                .map(|c| c.params)
                .collect();
            for f in 0..2 {
                let (tr, te) = outer.split(f);
                let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
                let gtr: Vec<usize> = tr.iter().map(|&i| groups[i]).collect();
                let xtr = x.select(Axis(0), &tr);
                let cached =
                    grid_search_cached(&grid, &mut cache, &tr, &ytr, Some(&gtr), 2, &mut || {})
                        .unwrap();
                let alone =
                    grid_search_with(&grid, xtr.view(), &ytr, Some(&gtr), 2, &mut || {}).unwrap();
                assert_eq!(cached.fold_auc, alone.fold_auc, "{name}, outer fold {f}");
                let p = &grid[cached.best];
                let s = p
                    .fit_score_cached(&mut cache, &tr, &ytr, Some(&gtr), &te)
                    .unwrap();
                let m = p.fit_grouped(xtr.view(), &ytr, Some(&gtr)).unwrap();
                let whole = m.decision_function(x.select(Axis(0), &te).view()).unwrap();
                assert_eq!(s.scores, whole, "{name}, outer fold {f}");
                assert!(s.fit_s >= 0.0 && s.score_s >= 0.0);
            }
        }
        // Amplitude bins of 2 and 3 samples (64/25 and 64/20 both round to 3) and the paper's
        // features: three fronts, each computed once; riemann's xDAWN learns and is never cached.
        assert_eq!(cache.len(), 3);
        // The paper presets' scaler + PCA: one per split (2 outer folds × (2 inner + 1)), the
        // ones paper-knn fitted reused by paper-svm's six grid points.
        assert_eq!(cache.n_necks(), 6);
    }

    #[test]
    fn tune_reports_every_candidate_and_returns_the_chosen_settings() {
        let (x, y, groups) = synthetic(24 * 4, 4);
        let grid = Preset::Mdm.grid(64.0).unwrap();
        let (chosen, report) = tune(&grid, x.view(), &y, Some(&groups), 4, &mut || {}).unwrap();
        assert_eq!(report.candidates.len(), 3);
        assert_eq!(report.n_folds, 4);
        assert!(report.grouped);
        let best = grid.iter().position(|c| c.label == report.chosen).unwrap();
        assert_eq!(grid[best].params, chosen);
        assert!(report
            .candidates
            .iter()
            .all(|c| c.cv_auc <= report.candidates[best].cv_auc));
        let back: TuningReport =
            serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
        assert_eq!(back, report);
    }
}
