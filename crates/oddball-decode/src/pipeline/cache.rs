//! Features of every epoch of one data set, computed once for the fronts that learn nothing
//! ([`FrontCache`]), and the pipelines fitted and scored through it
//! ([`PipelineParams::fit_score_cached`], [`PipelineParams::fit_cached`]).

use std::sync::Arc;

use ndarray::Array1;

use super::single::{Front, Neck, Necked, SingleParams};
use super::{Pipeline, PipelineParams};
use crate::features::Features;
use crate::linalg::check_labels;
use crate::traits::FeatureData;
use crate::DecodeError;

use super::source::EpochSource;

type Result<T> = std::result::Result<T, DecodeError>;

/// Features of every epoch of one data set for the fronts that learn nothing (no channel
/// selection, a stateless feature map: amplitude bins, the paper's EMD + Hilbert + wavelet
/// features), each computed once and shared by every fold, grid point and preset with that
/// front. A subset's rows are selected, never recomputed — the same rows the front gives the
/// subset's epochs alone, since it learns nothing from them. Fronts that learn (channel
/// selection, xDAWN) are never cached: they must be fitted inside each training split.
#[derive(Debug)]
pub struct FrontCache<'a> {
    epochs: EpochSource<'a>,
    /// Each front's settings, its fitted map, its features of all epochs and the seconds per
    /// epoch they took.
    entries: Vec<(SingleParams, Features, FeatureData, f64)>,
    /// Features of a cached front through a scaler and PCA fitted on one split's training
    /// part: (settings, training indices, test indices, result).
    necks: Vec<NeckEntry>,
}

/// A cached neck: its settings, the split's training and test indices, the result.
type NeckEntry = (SingleParams, Vec<usize>, Vec<usize>, Arc<Necked>);

/// Most necked splits a [`FrontCache`] keeps (nested cross-validation of the paper's three
/// presets needs outer folds × (inner folds + 1), 30 at 5 × 5).
const MAX_NECKS: usize = 512;

/// Scores from [`PipelineParams::fit_score_cached`] and the seconds fitting and scoring took; a
/// cached front's share is its measured seconds per epoch times the epochs of each part.
#[derive(Debug, Clone)]
pub struct CachedScores {
    pub scores: Array1<f64>,
    pub fit_s: f64,
    pub score_s: f64,
}

impl<'a> FrontCache<'a> {
    /// An empty cache over `epochs` `(n_epochs, n_channels, n_times)`: an array or [`oddball_signal::Epochs`].
    pub fn new(epochs: impl Into<EpochSource<'a>>) -> Self {
        Self {
            epochs: epochs.into(),
            entries: Vec::new(),
            necks: Vec::new(),
        }
    }

    /// The cached neck of `p` for the split (`train`, `test`), indices into the cache's epochs.
    pub(crate) fn necked(
        &self,
        p: &SingleParams,
        train: &[usize],
        test: &[usize],
    ) -> Option<Arc<Necked>> {
        self.necks
            .iter()
            .find(|(q, tr, te, _)| q.same_neck(p) && tr == train && te == test)
            .map(|(_, _, _, n)| n.clone())
    }

    /// Keeps a neck fitted on a cached front's features (up to [`MAX_NECKS`]).
    pub(crate) fn keep_necked(
        &mut self,
        p: &SingleParams,
        train: Vec<usize>,
        test: Vec<usize>,
        necked: Arc<Necked>,
    ) {
        if self.necks.len() < MAX_NECKS && self.necked(p, &train, &test).is_none() {
            self.necks.push((p.clone(), train, test, necked));
        }
    }

    /// The epochs the cache serves.
    pub fn epochs(&self) -> EpochSource<'a> {
        self.epochs
    }

    /// The features of every epoch of the cached front at `index` (from [`Self::entry`]).
    pub(crate) fn features(&self, index: usize) -> &FeatureData {
        &self.entries[index].2
    }

    /// The index of `p`'s front among the cached ones, computing its features of all epochs
    /// (timed) on first use; `None` when the front learns from its training data.
    pub(crate) fn entry(&mut self, p: &SingleParams) -> Option<Result<usize>> {
        if let Some(i) = self.entries.iter().position(|(q, ..)| q.same_front(p)) {
            return Some(Ok(i));
        }
        let t0 = std::time::Instant::now();
        Some(p.stateless_features(self.epochs)?.map(|(f, x)| {
            let per_epoch = t0.elapsed().as_secs_f64() / self.epochs.dim().0.max(1) as f64;
            self.entries.push((p.clone(), f, x, per_epoch));
            self.entries.len() - 1
        }))
    }

    /// Splits whose scaler and PCA are cached so far.
    pub fn n_necks(&self) -> usize {
        self.necks.len()
    }

    /// Fronts cached so far.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether nothing is cached yet.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

impl PipelineParams {
    /// Scores of the epochs at `test` by this pipeline fitted on the epochs at `train` (indices
    /// into `cache`'s epochs, labels `y_train`, groups for a stack's inner folds). A single
    /// pipeline whose front learns nothing takes its features from `cache`; any other is fitted
    /// whole — the scores are the same either way.
    pub fn fit_score_cached(
        &self,
        cache: &mut FrontCache<'_>,
        train: &[usize],
        y_train: &[bool],
        groups: Option<&[usize]>,
        test: &[usize],
    ) -> Result<CachedScores> {
        if self.fused.is_empty() {
            if let Some(i) = cache.entry(&self.main) {
                let i = i?;
                check_labels(train.len(), y_train)?;
                let per_epoch = cache.entries[i].3;
                // A neck (scaler, PCA) fitted on this split by another preset is reused.
                let necked = match cache.necked(&self.main, train, test) {
                    Some(k) => k,
                    None => {
                        let x = &cache.entries[i].2;
                        let k = Arc::new(self.main.neck_split(x.select(train), x.select(test))?);
                        if self.main.has_neck() {
                            cache.keep_necked(&self.main, train.to_vec(), test.to_vec(), k.clone());
                        }
                        k
                    }
                };
                let n_channels = cache.epochs().dim().1;
                let (scores, clf_fit_s, clf_score_s) =
                    self.main.classifier_scores(&necked, y_train, n_channels)?;
                return Ok(CachedScores {
                    scores,
                    fit_s: clf_fit_s + necked.fit_s + per_epoch * train.len() as f64,
                    score_s: clf_score_s + necked.transform_s + per_epoch * test.len() as f64,
                });
            }
        }
        let epochs = cache.epochs();
        // A pipeline that reads every k-th sample only is fitted and scored on copies of those
        // samples; any other on the parts' windows (read as `fit_source` reads them) or on
        // copies of an array's epochs.
        let decimated = self.decimated();
        let (k, params) = match &decimated {
            Some((k, p)) => (*k, p),
            None => (1, self),
        };
        let t0 = std::time::Instant::now();
        let model = params.fit_source(epochs.subset(train, k).source(), y_train, groups)?;
        let fit_s = t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        let scores = model.decision_function_source(epochs.subset(test, k).source())?;
        Ok(CachedScores {
            scores,
            fit_s,
            score_s: t1.elapsed().as_secs_f64(),
        })
    }

    /// [`Self::fit_grouped`] on all of `cache`'s epochs (labels `y`, `groups` for a stack's inner
    /// folds), with the same result. A single pipeline whose front learns nothing takes its
    /// features from `cache` (computed a part at a time from windows, shared with the
    /// cross-validation); one reading every `k`-th sample is fitted on a copy of those samples;
    /// any other, when the epochs are windows, on a copy of all of them.
    pub fn fit_cached(
        &self,
        cache: &mut FrontCache<'_>,
        y: &[bool],
        groups: Option<&[usize]>,
    ) -> Result<Pipeline> {
        let source = cache.epochs();
        let (n_epochs, n_channels, n_times) = source.dim();
        if self.fused.is_empty() {
            if let Some(i) = cache.entry(&self.main) {
                let i = i?;
                check_labels(n_epochs, y)?;
                let (_, features, x, _) = &cache.entries[i];
                // Without a scaler or PCA the classifier reads the cached rows as they are.
                let head = if self.main.has_neck() {
                    self.main.fit_head(x.clone(), y, n_channels)?
                } else {
                    self.main
                        .fit_classifier(Neck::default(), x.view(), y, n_channels)?
                };
                let front = Front {
                    channels: None,
                    features: features.clone(),
                };
                let single = self.main.assemble(front, head, n_channels, n_times);
                return Ok(self.unfused(single));
            }
        }
        self.fit_source(source, y, groups)
    }

    /// When the pipeline reads only every `k`-th sample of an epoch (a single pipeline reading
    /// every `k`-th, see [`SingleParams::decimated`]): `k` and the same settings reading every
    /// sample.
    pub(super) fn decimated(&self) -> Option<(usize, PipelineParams)> {
        if !self.fused.is_empty() {
            return None;
        }
        let (k, main) = self.main.decimated()?;
        Some((
            k,
            PipelineParams {
                main,
                ..self.clone()
            },
        ))
    }
}
