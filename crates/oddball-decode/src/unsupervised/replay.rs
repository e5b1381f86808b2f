//! A recording decoded as a live session without calibration would decode it: after each trial's
//! last epoch the model is refitted on every epoch so far — EM from a given score per epoch
//! (the [`super::P300Template`]'s, as a session starts), or warm-started from the previous model
//! plus the random initialisations — and the trial is decided with it ("online"); the final
//! model re-decides every trial ("post hoc").

use crate::pipeline::EpochSource;
use crate::traits::FeatureData;
use ndarray::{s, ArrayView3};

use super::{
    argmax, Constraint, Init, PooledScorer, Result, Unsupervised, UnsupervisedError,
    UnsupervisedParams,
};

/// One trial as decided online.
#[derive(Debug, Clone, PartialEq)]
pub struct OnlineChoice {
    /// The trial's number as given.
    pub trial: usize,
    /// The most probable code of each constraint set.
    pub codes: Vec<u32>,
    /// Its posterior, per set.
    pub confidence: Vec<f64>,
    /// Where the refit that decided it started (the likeliest initialisation).
    pub init: Init,
}

/// Where every refit of a replay may start, besides the last fit and the random starts.
#[derive(Debug, Clone, Copy)]
pub enum Start<'a> {
    /// A score per epoch of the whole recording (e.g. the P300 template's), cut to the
    /// epochs so far.
    Scores(&'a [f64]),
    /// A pooled start, scored at each refit on the epochs so far (its scaling is theirs).
    Pooled(&'a PooledScorer),
}

/// The online decisions and the final model.
#[derive(Debug, Clone)]
pub struct Replay {
    pub online: Vec<OnlineChoice>,
    /// Fitted on every epoch: its [`Unsupervised::choices`] are the post-hoc decisions.
    pub model: Unsupervised,
}

/// Replays `epochs` (in the order they were recorded, each trial's epochs contiguous) with their
/// stimulus `codes` and `trials`, every refit from the warm start and random initialisations;
/// `on_trial(k, n)` is told when trial `k` of `n` is decided.
pub fn replay(
    params: &UnsupervisedParams,
    epochs: ArrayView3<f64>,
    codes: &[u32],
    trials: &[usize],
    constraint: &Constraint,
    on_trial: &mut dyn FnMut(usize, usize),
) -> Result<Replay> {
    replay_from(params, epochs, codes, trials, constraint, None, on_trial)
}

/// [`replay`] with `start`, a score per epoch, as one more initialisation of every refit
/// ([`UnsupervisedParams::fit_features_from`]).
pub fn replay_from<'a>(
    params: &UnsupervisedParams,
    epochs: impl Into<EpochSource<'a>>,
    codes: &[u32],
    trials: &[usize],
    constraint: &Constraint,
    start: Option<&[f64]>,
    on_trial: &mut dyn FnMut(usize, usize),
) -> Result<Replay> {
    let starts: Vec<Start<'_>> = start.map(Start::Scores).into_iter().collect();
    replay_starts(params, epochs, codes, trials, constraint, &starts, on_trial)
}

/// [`replay`] with `starts`, each one more initialisation of every refit, in order
/// ([`UnsupervisedParams::fit_features_starts`]).
pub fn replay_starts<'a>(
    params: &UnsupervisedParams,
    epochs: impl Into<EpochSource<'a>>,
    codes: &[u32],
    trials: &[usize],
    constraint: &Constraint,
    starts: &[Start<'_>],
    on_trial: &mut dyn FnMut(usize, usize),
) -> Result<Replay> {
    let epochs: EpochSource<'_> = epochs.into();
    let n = epochs.dim().0;
    for start in starts {
        if let Start::Scores(s) = start {
            if s.len() != n {
                return Err(UnsupervisedError::InitLength {
                    n_epochs: n,
                    n_scores: s.len(),
                });
            }
        }
    }
    if codes.len() != n || trials.len() != n {
        return Err(UnsupervisedError::Length {
            n_epochs: n,
            n_codes: codes.len(),
            n_trials: trials.len(),
        });
    }
    // Ends (exclusive) of each trial's run of epochs.
    let mut ends: Vec<usize> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for i in 0..n {
        if i > 0 && trials[i] != trials[i - 1] {
            ends.push(i);
        }
        if (i == 0 || trials[i] != trials[i - 1]) && !seen.insert(trials[i]) {
            return Err(UnsupervisedError::TrialsNotContiguous {
                trial: trials[i],
                index: i,
            });
        }
    }
    if n > 0 {
        ends.push(n);
    }
    // Features of a part of the epochs at a time when they are windows.
    let x = epochs
        .map_chunks(&mut |chunk| Ok(FeatureData::Rows(params.features.transform(chunk)?)))?
        .into_rows("unsupervised features")?;
    let mut model: Option<Unsupervised> = None;
    let mut online = Vec::with_capacity(ends.len());
    for (k, &end) in ends.iter().enumerate() {
        let so_far = x.slice(s![..end, ..]);
        let scores = starts
            .iter()
            .map(|start| match start {
                Start::Scores(s) => Ok(s[..end].to_vec()),
                Start::Pooled(p) => p.scores(so_far),
            })
            .collect::<Result<Vec<Vec<f64>>>>()?;
        let refs: Vec<&[f64]> = scores.iter().map(Vec::as_slice).collect();
        let fitted = params.fit_features_starts(
            so_far,
            &codes[..end],
            &trials[..end],
            constraint,
            model.as_ref(),
            &refs,
        )?;
        let last = fitted.trials().last().expect("a trial per end");
        online.push(OnlineChoice {
            trial: last.trial,
            codes: last
                .sets
                .iter()
                .zip(constraint.sets())
                .map(|(p, c)| c[argmax(p)])
                .collect(),
            confidence: last.sets.iter().map(|p| p[argmax(p)]).collect(),
            init: fitted.init().0,
        });
        model = Some(fitted);
        on_trial(k, ends.len());
    }
    let model = model.ok_or(UnsupervisedError::TooFewEpochs { n_epochs: 0 })?;
    Ok(Replay { online, model })
}
