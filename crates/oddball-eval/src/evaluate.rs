//! Scoring pipelines on epoched recordings: held-out test recordings, k-fold cross-validation
//! (with the hyper-parameter search nested in each fold), and speller character accuracy by
//! repetitions with the Wolpaw ITR — never letting test data into any fitted step, nor into the
//! choice of hyper-parameters ([`oddball_decode::model_selection::tuning`] sees the training epochs only).
//!
//! The input is [`EpochedRecording`]s (the epochs of one recording each, cut by
//! `oddball_signal::preprocess`): the training ones as one [`TrainingSet`] (pooled once, moved
//! rather than copied), the test ones as they are; [`evaluate`] runs a list of presets,
//! [`train`] fits one.
//! Both report what they do through a [`Progress`] callback (fits made, tuning tables, each
//! preset's [`PipelineResult`]) and print nothing.

use std::borrow::Cow;
use std::time::Instant;

use ndarray::Array1;
use oddball_io::Speller;
use oddball_signal::{Epochs, Events, SignalError};
use serde::Serialize;

use oddball_decode::decision::{DecisionModel, DecisionRule, ScoreModelParams};
use oddball_decode::metrics::{
    character_of_flashes, roc_auc, speller_accuracy_by_repetitions, Itr, ScoredFlash,
};
use oddball_decode::model::Model;
use oddball_decode::model_selection::tuning::{cv_folds, tune_cached, Folds, TuningReport};
use oddball_decode::model_selection::{cross_val_predict, cross_val_scores};
use oddball_decode::pipeline::FrontCache;
use oddball_decode::pipeline::{Pipeline, PipelineParams};
use oddball_decode::preprocess::Preprocess;
use oddball_decode::preset::Preset;
use oddball_decode::DecodeError;

/// Why an evaluation could not run.
#[derive(Debug, thiserror::Error)]
pub enum EvaluateError {
    /// An epoch's event carries no target flag, so it cannot be scored.
    #[error("epoch {index} (code {code}) has no target flag")]
    Unlabelled { index: usize, code: u32 },
    /// A speller recording lost epochs: its characters' flashes would shift.
    #[error("{recording}: {dropped} of {n_events} flashes could not be epoched, so its characters cannot be scored")]
    DroppedFlashes {
        recording: String,
        dropped: usize,
        n_events: usize,
    },
    /// The hyper-parameter search of a preset failed (`fold`: 1-based outer fold).
    #[error("tuning {preset}{}", .fold.map(|f| format!(" in fold {f}")).unwrap_or_default())]
    Tuning {
        preset: Preset,
        fold: Option<usize>,
        #[source]
        source: DecodeError,
    },
    /// A test recording does not have the model's channels or rate.
    #[error("scoring {recording} with {model}")]
    Layout {
        recording: String,
        model: String,
        #[source]
        source: DecodeError,
    },
    #[error(transparent)]
    Decode(#[from] DecodeError),
    #[error(transparent)]
    Signal(#[from] SignalError),
}

type Result<T> = std::result::Result<T, EvaluateError>;

/// The epochs of one recording, as evaluation sees them.
#[derive(Debug, Clone)]
pub struct EpochedRecording {
    /// Names the recording in errors (e.g. its path).
    pub name: String,
    pub epochs: Epochs,
    /// The speller layout of a P300-speller recording.
    pub speller: Option<Speller>,
    /// Events the recording holds (more than `epochs` when some could not be epoched).
    pub n_events: usize,
}

/// What an evaluation or a training run is doing, for a progress display.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// Before anything: every fit the run will make, and the folds of the cross-validation
    /// (when there are no test recordings).
    Plan {
        fits: usize,
        cross_validation: Option<&'a Folds>,
    },
    /// A preset starts.
    Preset(Preset),
    /// One pipeline was fitted.
    Fit,
    /// A preset's hyper-parameters were chosen; `fold` is (1-based outer fold, number of outer
    /// folds) when the search ran inside a cross-validation fold.
    Tuned {
        preset: Preset,
        fold: Option<(usize, usize)>,
        report: &'a TuningReport,
    },
    /// A preset's result.
    Scored(&'a PipelineResult),
}

/// One preset's scores.
#[derive(Debug, Clone, Serialize)]
pub struct PipelineResult {
    pub pipeline: String,
    /// Epoch ROC-AUC on the test data (mean over folds under cross-validation).
    pub auc: f64,
    pub auc_folds: Vec<f64>,
    /// Speller character accuracy for 1..N repetitions (test files that are spellers; pooled
    /// over the characters of all of them).
    pub speller_accuracy: Option<Vec<f64>>,
    /// Cells of the speller matrix (chance accuracy is one over this).
    pub speller_choices: Option<usize>,
    /// Characters scored (speller test files), the denominator of `speller_accuracy`.
    pub speller_n_chars: Option<usize>,
    /// Characters picked with all repetitions.
    pub speller_text: Option<String>,
    /// Fewest repetitions from which every character stays right with every further repetition
    /// (a curve that reaches 100 % and drops again counts from after its last drop), if any.
    pub reps_for_all_correct: Option<usize>,
    /// The best Wolpaw ITR over repetitions, each character's time being its repetitions plus
    /// the recording's pause between characters ([`SpellerScores::seconds_per_character`]).
    pub itr_at_best: Option<Itr>,
    pub fit_s: f64,
    pub score_epochs_per_s: f64,
    /// `--tune` with test files: the settings chosen on the training files.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tuning: Option<TuningReport>,
    /// `--tune` under cross-validation: the settings chosen inside each outer fold.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tuning_per_fold: Option<Vec<TuningReport>>,
}

impl PipelineResult {
    /// The result of `pipeline` scored on epochs alone: its AUC (`auc`, by fold `auc_folds`), the
    /// seconds its fit took and the epochs it scored per second; nothing of spelling or tuning.
    fn epochs_only(
        pipeline: String,
        auc: f64,
        auc_folds: Vec<f64>,
        fit_s: f64,
        score_epochs_per_s: f64,
    ) -> Self {
        PipelineResult {
            pipeline,
            auc,
            auc_folds,
            speller_accuracy: None,
            speller_choices: None,
            speller_n_chars: None,
            speller_text: None,
            reps_for_all_correct: None,
            itr_at_best: None,
            fit_s,
            score_epochs_per_s,
            tuning: None,
            tuning_per_fold: None,
        }
    }
}

/// Settings of an evaluation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EvaluateParams {
    /// Presets, scored in this order.
    pub presets: Vec<Preset>,
    /// Folds of the cross-validation (without test recordings) and of the tuning.
    pub folds: usize,
    /// Choose each preset's hyper-parameters by cross-validation on the training data only.
    pub tune: bool,
}

/// The target flag of every epoch.
pub fn labels(epochs: &Epochs) -> Result<Vec<bool>> {
    epochs
        .events()
        .iter()
        .enumerate()
        .map(|(index, e)| {
            e.target.ok_or(EvaluateError::Unlabelled {
                index,
                code: e.code,
            })
        })
        .collect()
}

/// The speller character of every epoch (numbered across recordings), so that cross-validation
/// keeps a character's overlapping flashes in one fold; `None` unless every recording is a
/// speller whose flashes were all epoched and there are at least two characters.
pub fn character_groups(recs: &[EpochedRecording]) -> Option<Vec<usize>> {
    let mut groups = Vec::new();
    let mut next = 0;
    for rec in recs {
        let speller = rec.speller.as_ref()?;
        if rec.epochs.n_epochs() != rec.n_events {
            return None;
        }
        let chars = character_of_flashes(speller, rec.epochs.n_epochs());
        let n_chars = chars.last().map_or(0, |&c| c + 1);
        groups.extend(chars.into_iter().map(|c| next + c));
        next += n_chars;
    }
    (next >= 2 && groups.len() == recs.iter().map(|r| r.epochs.n_epochs()).sum::<usize>())
        .then_some(groups)
}

/// Training recordings as one set: their epochs pooled, the labels and the speller characters
/// (what [`evaluate`], [`train`] and [`train_with`] fit on, and their cross-validation splits).
#[derive(Debug, Clone)]
pub struct TrainingSet<'a> {
    epochs: Cow<'a, Epochs>,
    y: Vec<bool>,
    groups: Option<Vec<usize>>,
}

impl TrainingSet<'static> {
    /// Moves the recordings' epochs into one set: one recording's are taken as they are, and
    /// several are pooled with each freed as it is copied ([`Epochs::pool`]), so the set never
    /// sits beside a second copy of its epochs.
    pub fn pool(recs: Vec<EpochedRecording>) -> Result<Self> {
        let groups = character_groups(&recs);
        let mut parts: Vec<Epochs> = recs.into_iter().map(|r| r.epochs).collect();
        let epochs = if parts.len() == 1 {
            parts.pop().expect("one part")
        } else {
            Epochs::pool(parts)?
        };
        let y = labels(&epochs)?;
        Ok(Self {
            epochs: Cow::Owned(epochs),
            y,
            groups,
        })
    }
}

impl<'a> TrainingSet<'a> {
    /// The recordings' epochs as one set, the recordings staying the caller's: one recording's
    /// are borrowed; several held as windows share their recordings (nothing is copied);
    /// other epochs are copied into one set.
    pub fn of(recs: &'a [EpochedRecording]) -> Result<Self> {
        let epochs = match recs {
            [one] => Cow::Borrowed(&one.epochs),
            _ => Cow::Owned(Epochs::concatenate(
                &recs.iter().map(|r| &r.epochs).collect::<Vec<_>>(),
            )?),
        };
        let y = labels(&epochs)?;
        Ok(Self {
            epochs,
            y,
            groups: character_groups(recs),
        })
    }

    /// The pooled epochs, the recordings' in order.
    pub fn epochs(&self) -> &Epochs {
        &self.epochs
    }

    /// The target flag of every epoch.
    pub fn labels(&self) -> &[bool] {
        &self.y
    }

    /// The speller character of every epoch (see [`character_groups`]).
    pub fn groups(&self) -> Option<&[usize]> {
        self.groups.as_deref()
    }
}

/// A fitted pipeline and how it was made.
#[derive(Debug, Clone)]
pub struct Trained {
    pub pipeline: Pipeline,
    /// The settings it was fitted with (the tuned ones with tuning).
    pub params: PipelineParams,
    /// With tuning: the choice and every candidate's cross-validated AUC.
    pub tuning: Option<TuningReport>,
    /// How its scores become decisions in a session: the score model fitted on the
    /// out-of-fold scores of the training epochs (as a session fits it after calibration), the
    /// paper's rule (5 fixed rounds; a session sets its own).
    pub decision: DecisionModel,
    /// ROC-AUC of those out-of-fold scores, and the folds they came from.
    pub cv_auc: f64,
    pub cv_folds: usize,
    pub fit_s: f64,
    pub n_epochs: usize,
    pub n_targets: usize,
    pub sfreq: f64,
}

/// Folds of the out-of-fold scores [`train`] fits the decision model on (without `--tune`).
pub const DECISION_FOLDS: usize = 5;

/// Fits `preset` on all epochs of `recs`; with `tune_folds`, its hyper-parameters are first
/// chosen by that many folds of cross-validation (speller characters kept whole). The decision
/// model is fitted on out-of-fold scores of the chosen settings (`tune_folds` folds, else
/// [`DECISION_FOLDS`]), so its evidence is not over-confident.
pub fn train(
    preset: Preset,
    set: &TrainingSet<'_>,
    tune_folds: Option<usize>,
    on: &mut dyn FnMut(Progress<'_>),
) -> Result<Trained> {
    let (epochs, y, groups) = (set.epochs(), set.labels(), set.groups());
    let folds = cv_folds(y, groups, tune_folds.unwrap_or(DECISION_FOLDS))?;
    // The features of a front that learns nothing, computed once for the search, the decision
    // model's folds and the final fit.
    let mut cache = FrontCache::new(epochs);
    let (params, tuning) = match tune_folds {
        Some(k) => {
            let grid = preset.grid(epochs.sfreq())?;
            on(Progress::Plan {
                fits: (grid.len() + 1) * folds.n_folds(),
                cross_validation: None,
            });
            let all: Vec<usize> = (0..y.len()).collect();
            let (params, report) = tune_cached(&grid, &mut cache, &all, y, groups, k, &mut || {
                on(Progress::Fit)
            })
            .map_err(|source| EvaluateError::Tuning {
                preset,
                fold: None,
                source,
            })?;
            on(Progress::Tuned {
                preset,
                fold: None,
                report: &report,
            });
            (params, Some(report))
        }
        None => {
            on(Progress::Plan {
                fits: folds.n_folds(),
                cross_validation: None,
            });
            (preset.params(epochs.sfreq())?, None)
        }
    };
    let mut trained = fit_with_decision(&params, &mut cache, epochs, y, groups, &folds, on)?;
    trained.tuning = tuning;
    Ok(trained)
}

/// The model `oddball train` writes: `trained` (fitted on epochs cut by `pre`, zero-phase) with
/// its tuning and decision model, carrying as its live model `live` (the same settings fitted
/// on the causally band-passed epochs, `pre.as_causal()`), which a session runs.
pub fn session_model(
    pre: Preprocess,
    ch_names: Vec<String>,
    trained: Trained,
    live: Trained,
) -> Model {
    let mut live_model = Model::new(pre.as_causal(), live.sfreq, ch_names.clone(), live.pipeline);
    live_model.decision = Some(live.decision);
    let mut model = Model::new(pre, trained.sfreq, ch_names, trained.pipeline);
    model.tuning = trained.tuning;
    model.decision = Some(trained.decision);
    model.live = Some(Box::new(live_model));
    model
}

/// Fits `params` (already chosen) on all epochs of `recs` with its decision model from
/// `k`-fold out-of-fold scores (speller characters kept whole): what [`train`] does after
/// tuning, e.g. for the same settings on differently pre-processed epochs.
pub fn train_with(
    params: &PipelineParams,
    set: &TrainingSet<'_>,
    k: usize,
    on: &mut dyn FnMut(Progress<'_>),
) -> Result<Trained> {
    let (epochs, y, groups) = (set.epochs(), set.labels(), set.groups());
    let folds = cv_folds(y, groups, k)?;
    on(Progress::Plan {
        fits: folds.n_folds(),
        cross_validation: None,
    });
    fit_with_decision(
        params,
        &mut FrontCache::new(epochs),
        epochs,
        y,
        groups,
        &folds,
        on,
    )
}

/// The decision model on `folds`' out-of-fold scores and the final fit, both through `cache`
/// (over `epochs`).
fn fit_with_decision(
    params: &PipelineParams,
    cache: &mut FrontCache<'_>,
    epochs: &Epochs,
    y: &[bool],
    groups: Option<&[usize]>,
    folds: &Folds,
    on: &mut dyn FnMut(Progress<'_>),
) -> Result<Trained> {
    let oof = cross_val_predict(params, cache, y, groups, folds, || on(Progress::Fit))?;
    let cv_auc = roc_auc(&oof, y)?;
    let decision = DecisionModel {
        scores: ScoreModelParams::default().fit(&oof, y)?,
        rule: DecisionRule::Fixed { rounds: 5 },
    };
    let t0 = Instant::now();
    let pipeline = params.fit_cached(cache, y, groups)?;
    let fit_s = t0.elapsed().as_secs_f64();
    Ok(Trained {
        pipeline,
        params: params.clone(),
        tuning: None,
        decision,
        cv_auc,
        cv_folds: folds.n_folds(),
        fit_s,
        n_epochs: epochs.n_epochs(),
        n_targets: y.iter().filter(|&&t| t).count(),
        sfreq: epochs.sfreq(),
    })
}

/// Scores every preset of `params`: fitted on `train` and scored on `test`, or by k-fold
/// cross-validation on `train` when `test` is empty.
pub fn evaluate(
    params: &EvaluateParams,
    train: &TrainingSet<'_>,
    test: &[EpochedRecording],
    on: &mut dyn FnMut(Progress<'_>),
) -> Result<Vec<PipelineResult>> {
    let (train_epochs, ytr, groups) = (train.epochs(), train.labels(), train.groups());
    let grids = params
        .presets
        .iter()
        .map(|n| {
            if params.tune {
                n.grid(train_epochs.sfreq()).map(|g| g.len())
            } else {
                n.params(train_epochs.sfreq()).map(|_| 0)
            }
        })
        .collect::<std::result::Result<Vec<usize>, _>>()?;
    let outer = if test.is_empty() {
        Some(cv_folds(ytr, groups, params.folds)?)
    } else {
        None
    };
    // Every fit the run will make.
    let fits_per_grid_point: usize = match &outer {
        None if params.tune => cv_folds(ytr, groups, params.folds)?.n_folds(),
        None => 0,
        Some(f) if params.tune => (0..f.n_folds())
            .map(|k| {
                let (tr, _) = f.split(k);
                let y: Vec<bool> = tr.iter().map(|&i| ytr[i]).collect();
                let g: Option<Vec<usize>> = groups.map(|g| tr.iter().map(|&i| g[i]).collect());
                cv_folds(&y, g.as_deref(), params.folds).map(|f| f.n_folds())
            })
            .sum::<std::result::Result<usize, _>>()?,
        Some(_) => 0,
    };
    let final_fits = outer.as_ref().map_or(1, Folds::n_folds);
    on(Progress::Plan {
        fits: grids
            .iter()
            .map(|&g| g * fits_per_grid_point + final_fits)
            .sum(),
        cross_validation: outer.as_ref(),
    });
    let mut results = Vec::new();
    // One home for the training epochs' features of fronts that learn nothing: every preset,
    // fold and grid point with such a front shares them.
    let mut cache = FrontCache::new(train_epochs);
    let all: Vec<usize> = (0..ytr.len()).collect();
    for &name in &params.presets {
        on(Progress::Preset(name));
        let r = match &outer {
            Some(folds) => cross_validate(
                name,
                train_epochs,
                ytr,
                groups,
                folds,
                params.tune.then_some(params.folds),
                &mut cache,
                on,
            )?,
            None => {
                let (p, tuning) = if params.tune {
                    let grid = name.grid(train_epochs.sfreq())?;
                    let (p, report) = tune_cached(
                        &grid,
                        &mut cache,
                        &all,
                        ytr,
                        groups,
                        params.folds,
                        &mut || on(Progress::Fit),
                    )
                    .map_err(|source| EvaluateError::Tuning {
                        preset: name,
                        fold: None,
                        source,
                    })?;
                    on(Progress::Tuned {
                        preset: name,
                        fold: None,
                        report: &report,
                    });
                    (p, Some(report))
                } else {
                    (name.params(train_epochs.sfreq())?, None)
                };
                let mut r = held_out(&p, &mut cache, ytr, groups, test)?;
                on(Progress::Fit);
                r.tuning = tuning;
                r
            }
        };
        on(Progress::Scored(&r));
        results.push(r);
    }
    Ok(results)
}

/// Fits `params` on the training epochs (`cache`'s) and scores the test recordings.
pub fn held_out(
    params: &PipelineParams,
    cache: &mut FrontCache<'_>,
    ytr: &[bool],
    groups: Option<&[usize]>,
    test: &[EpochedRecording],
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let model = params.fit_cached(cache, ytr, groups)?;
    let fit_s = t0.elapsed().as_secs_f64();
    score_test(&model, fit_s, test)
}

/// One speller recording's scores.
#[derive(Debug, Clone, PartialEq)]
pub struct SpellerScores {
    /// Character accuracy for 1..N repetitions.
    pub accuracy: Vec<f64>,
    /// The characters picked with all repetitions.
    pub text: String,
    pub n_chars: usize,
    /// Cells of the matrix.
    pub n_choices: usize,
    /// Seconds of one repetition (every row and column flashed once).
    pub seconds_per_repetition: f64,
    /// Seconds between characters beyond the flashes (the pause in which the speller shows the
    /// choice and the next target): the median of the gaps from a character's last flash to the
    /// next character's first, less one flash onset asynchrony; 0 with one character.
    pub seconds_between_characters: f64,
}

impl SpellerScores {
    /// Seconds one character takes with `reps` repetitions, the pause between characters
    /// included (the time per selection of the Wolpaw ITR).
    pub fn seconds_per_character(&self, reps: usize) -> f64 {
        reps as f64 * self.seconds_per_repetition + self.seconds_between_characters
    }
}

/// Character accuracy by repetitions over several speller files' characters pooled (each file
/// weighted by its characters), up to the fewest repetitions any file has.
pub fn pooled_accuracy(spellers: &[SpellerScores]) -> Vec<f64> {
    let n_chars: usize = spellers.iter().map(|s| s.n_chars).sum();
    let reps = spellers.iter().map(|s| s.accuracy.len()).min().unwrap_or(0);
    (0..reps)
        .map(|r| {
            spellers
                .iter()
                .map(|s| s.accuracy[r] * s.n_chars as f64)
                .sum::<f64>()
                / n_chars.max(1) as f64
        })
        .collect()
}

/// Character accuracy by repetitions of a speller recording from its epochs' `scores`; every
/// flash must have been epoched.
pub fn score_speller(
    rec: &EpochedRecording,
    speller: &Speller,
    scores: &Array1<f64>,
) -> Result<SpellerScores> {
    let ep = &rec.epochs;
    // Characters are consecutive runs of flashes; a dropped epoch would shift every
    // later character onto the wrong flashes.
    if ep.n_epochs() != rec.n_events {
        return Err(EvaluateError::DroppedFlashes {
            recording: rec.name.clone(),
            dropped: rec.n_events - ep.n_epochs(),
            n_events: rec.n_events,
        });
    }
    let events = Events::new(ep.events().to_vec());
    let flashes: Vec<ScoredFlash> = ep
        .events()
        .iter()
        .zip(scores.iter())
        .map(|(e, &score)| ScoredFlash {
            code: e.code,
            target: e.target == Some(true),
            score,
        })
        .collect();
    // Character blocks are consecutive runs of epochs: cut the flashes the same way.
    let mut rest = flashes.as_slice();
    let char_events = speller.character_blocks(&events);
    let blocks: Vec<Vec<ScoredFlash>> = char_events
        .iter()
        .map(|b| {
            let (head, tail) = rest.split_at(b.len());
            rest = tail;
            head.to_vec()
        })
        .collect();
    let rows: Vec<u32> = (0..speller.n_rows())
        .map(|r| speller.code_of_row(r))
        .collect();
    let cols: Vec<u32> = (0..speller.n_cols())
        .map(|c| speller.code_of_col(c))
        .collect();
    let max_reps = blocks.iter().map(|b| b.len()).min().unwrap_or(0) / (rows.len() + cols.len());
    let (accuracy, picks) = speller_accuracy_by_repetitions(&blocks, &rows, &cols, max_reps)?;
    let text: String = picks
        .iter()
        .map(|&(r, c)| {
            speller
                .row_of_code(r)
                .zip(speller.col_of_code(c))
                .and_then(|(r, c)| speller.symbol(r, c))
                .unwrap_or("?")
                .to_string()
        })
        .collect();
    // Seconds per selection from the recorded flash rate: r repetitions of all codes.
    let onsets: Vec<usize> = ep.events().iter().map(|e| e.onset).collect();
    let mut gaps: Vec<usize> = onsets.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let soa_samples = gaps.get(gaps.len() / 2).copied().unwrap_or(0);
    let soa = soa_samples as f64 / ep.sfreq();
    // The pause: from each character's last flash to the next one's first, less one SOA.
    let mut pauses: Vec<usize> = char_events
        .windows(2)
        .filter_map(|b| {
            let last = b[0].last()?.onset;
            let next = b[1].first()?.onset;
            Some(next.saturating_sub(last).saturating_sub(soa_samples))
        })
        .collect();
    pauses.sort_unstable();
    let pause = pauses.get(pauses.len() / 2).copied().unwrap_or(0) as f64 / ep.sfreq();
    Ok(SpellerScores {
        accuracy,
        text,
        n_chars: blocks.len(),
        n_choices: rows.len() * cols.len(),
        seconds_per_repetition: (rows.len() + cols.len()) as f64 * soa,
        seconds_between_characters: pause,
    })
}

/// Scores the test recordings with a fitted pipeline (`fit_s`: how long its fit took): the
/// epoch AUC over all of them, and for speller recordings the character accuracy by
/// repetitions pooled over their characters, the spelled text and the best ITR.
pub fn score_test(
    model: &Pipeline,
    fit_s: f64,
    test: &[EpochedRecording],
) -> Result<PipelineResult> {
    let mut all_scores = Vec::new();
    let mut all_y = Vec::new();
    let mut score_s = 0.0;
    let mut spellers = Vec::new();
    for rec in test {
        let ep = &rec.epochs;
        let t1 = Instant::now();
        let scores: Array1<f64> = model.decision_function_source(ep.into())?;
        score_s += t1.elapsed().as_secs_f64();
        let y = labels(ep)?;
        if let Some(speller) = &rec.speller {
            spellers.push(score_speller(rec, speller, &scores)?);
        }
        all_scores.extend(scores.iter().copied());
        all_y.extend(y);
    }
    let auc = roc_auc(&all_scores, &all_y)?;
    // Speller files pooled: accuracy over all their characters, up to the fewest repetitions.
    let mut result = PipelineResult::epochs_only(
        model.name().to_string(),
        auc,
        vec![auc],
        fit_s,
        all_scores.len() as f64 / score_s.max(1e-12),
    );
    if let Some(first) = spellers.first() {
        let n_chars: usize = spellers.iter().map(|s| s.n_chars).sum();
        let acc = pooled_accuracy(&spellers);
        // Seconds per character with r repetitions, averaged over the files' characters.
        let per_char = |r: usize| {
            spellers
                .iter()
                .map(|s| s.seconds_per_character(r) * s.n_chars as f64)
                .sum::<f64>()
                / n_chars.max(1) as f64
        };
        result.itr_at_best = acc
            .iter()
            .enumerate()
            .map(|(i, &a)| Itr::new(first.n_choices, a, per_char(i + 1)))
            .max_by(|a, b| a.bits_per_minute.total_cmp(&b.bits_per_minute));
        result.reps_for_all_correct = reps_from_which_all_correct(&acc);
        result.speller_choices = Some(first.n_choices);
        result.speller_n_chars = Some(n_chars);
        result.speller_text = Some(spellers.iter().map(|s| s.text.as_str()).collect());
        result.speller_accuracy = Some(acc);
    }
    Ok(result)
}

/// Scores the test recordings with a saved `model` (named `name` in errors) as [`score_test`]
/// does, each recording first checked to have its channels and rate; the result carries the
/// model's tuning.
pub fn score_model(model: &Model, name: &str, test: &[EpochedRecording]) -> Result<PipelineResult> {
    for rec in test {
        model
            .check_layout(rec.epochs.ch_names(), rec.epochs.sfreq())
            .map_err(|source| EvaluateError::Layout {
                recording: rec.name.clone(),
                model: name.to_string(),
                source,
            })?;
    }
    let mut r = score_test(&model.pipeline, 0.0, test)?;
    r.tuning = model.tuning.clone();
    Ok(r)
}

/// The first repetition count (1-based) from which the accuracy stays at 100 % up to the last
/// repetition scored, if the last is 100 %.
pub fn reps_from_which_all_correct(acc: &[f64]) -> Option<usize> {
    match acc.iter().rposition(|&a| a < 1.0) {
        None => (!acc.is_empty()).then_some(1),
        Some(i) => (i + 1 < acc.len()).then_some(i + 2),
    }
}

/// k-fold cross-validation of `name` on `data` with `folds` (speller characters kept whole, or
/// stratified by label). With `tune_folds`, the grid search runs inside each fold's training
/// part with that many inner folds.
///
/// `cache` holds `data`'s features for fronts that learn nothing: shared across folds, grid
/// points and presets, it spares recomputing them (the paper's EMD features above all) without
/// changing a score.
#[allow(clippy::too_many_arguments)] // the data, its labels and groups, the folds, the cache, progress
pub fn cross_validate(
    name: Preset,
    data: &Epochs,
    y: &[bool],
    groups: Option<&[usize]>,
    folds: &Folds,
    tune_folds: Option<usize>,
    cache: &mut FrontCache<'_>,
    on: &mut dyn FnMut(Progress<'_>),
) -> Result<PipelineResult> {
    if cache.epochs().dim() != data.dim() {
        return Err(EvaluateError::Decode(DecodeError::InvalidParameter {
            name: "cache",
            value: format!("{:?}", cache.epochs().dim()),
            reason: format!("a cache over other epochs than {:?}", data.dim()),
        }));
    }
    let reports = std::cell::RefCell::new(Vec::new());
    let on = std::cell::RefCell::new(on);
    let per_fold = cross_val_scores(
        cache,
        y,
        groups,
        folds,
        |cache, split| -> Result<PipelineParams> {
            let Some(k) = tune_folds else {
                return Ok(name.params(data.sfreq())?);
            };
            let grid = name.grid(data.sfreq())?;
            let (params, report) = tune_cached(
                &grid,
                cache,
                &split.train,
                &split.y_train,
                split.groups_train.as_deref(),
                k,
                &mut || (on.borrow_mut())(Progress::Fit),
            )
            .map_err(|source| EvaluateError::Tuning {
                preset: name,
                fold: Some(split.fold + 1),
                source,
            })?;
            (on.borrow_mut())(Progress::Tuned {
                preset: name,
                fold: Some((split.fold + 1, folds.n_folds())),
                report: &report,
            });
            reports.borrow_mut().push(report);
            Ok(params)
        },
        || (on.borrow_mut())(Progress::Fit),
    )?;
    let reports = reports.into_inner();
    let mut aucs = Vec::new();
    let mut fit_s = 0.0;
    let mut score_s = 0.0;
    let mut n_scored = 0;
    for f in &per_fold {
        fit_s += f.scores.fit_s;
        score_s += f.scores.score_s;
        n_scored += f.split.test.len();
        aucs.push(roc_auc(&f.scores.scores.to_vec(), &f.split.y_test)?);
    }
    let mut result = PipelineResult::epochs_only(
        name.to_string(),
        aucs.iter().sum::<f64>() / aucs.len() as f64,
        aucs,
        fit_s / folds.n_folds() as f64,
        n_scored as f64 / score_s.max(1e-12),
    );
    result.tuning_per_fold = tune_folds.is_some().then_some(reports);
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;
    use oddball_signal::Event;

    #[test]
    fn repetitions_count_from_the_last_miss() {
        let reps = reps_from_which_all_correct;
        assert_eq!(reps(&[0.5, 1.0, 1.0]), Some(2));
        assert_eq!(reps(&[1.0, 1.0]), Some(1));
        // reached at 2, lost at 3 and 4: all right only from 5 on
        assert_eq!(reps(&[0.0, 1.0, 0.5, 0.5, 1.0, 1.0]), Some(5));
        assert_eq!(reps(&[1.0, 0.75]), None);
        assert_eq!(reps(&[]), None);
    }

    fn epochs(targets: &[Option<bool>]) -> Epochs {
        let n = targets.len();
        let events = targets
            .iter()
            .enumerate()
            .map(|(i, &t)| Event {
                target: t,
                ..Event::new(i * 10, 1)
            })
            .collect();
        Epochs::new(
            ndarray::Array3::zeros((n, 1, 4)),
            64.0,
            0.0,
            vec!["Cz".into()],
            events,
        )
        .unwrap()
    }

    #[test]
    fn a_characters_time_counts_the_pause_between_characters() {
        // 2 × 2 speller, 2 repetitions (8 flashes) per character, a flash every 10 samples,
        // then 100 samples from a character's last flash to the next one's first.
        let mut speller = Speller::from_rows(&["AB", "CD"]).unwrap();
        speller.flashes_per_character = Some(8);
        let mut onsets = Vec::new();
        for c in 0..3 {
            for k in 0..8 {
                onsets.push(c * (70 + 100) + k * 10);
            }
        }
        let events: Vec<Event> = onsets
            .iter()
            .enumerate()
            .map(|(i, &t)| Event::new(t, (i % 4) as u32 + 1).with_target(i % 2 == 0))
            .collect();
        let n = events.len();
        let ep = Epochs::new(
            ndarray::Array3::zeros((n, 1, 4)),
            100.0,
            0.0,
            vec!["Cz".into()],
            events,
        )
        .unwrap();
        let rec = EpochedRecording {
            name: "x".into(),
            epochs: ep,
            speller: Some(speller.clone()),
            n_events: n,
        };
        let s = score_speller(&rec, &speller, &Array1::zeros(n)).unwrap();
        assert_eq!(s.n_chars, 3);
        assert!((s.seconds_per_repetition - 0.4).abs() < 1e-12);
        // 100 samples less one 10-sample SOA at 100 Hz.
        assert!((s.seconds_between_characters - 0.9).abs() < 1e-12);
        assert!((s.seconds_per_character(2) - 1.7).abs() < 1e-12);
    }

    /// A 2 × 2 speller recording of `chars` characters (8 flashes each), every flash epoched.
    fn speller_recording(name: &str, chars: usize) -> EpochedRecording {
        let mut speller = Speller::from_rows(&["AB", "CD"]).unwrap();
        speller.flashes_per_character = Some(8);
        let n = 8 * chars;
        let events: Vec<Event> = (0..n)
            .map(|i| Event::new(i * 10 + (i / 8) * 100, (i % 4) as u32 + 1).with_target(i % 4 == 0))
            .collect();
        let data = ndarray::Array3::from_shape_fn((n, 1, 4), |(e, _, t)| (e * 4 + t) as f64);
        EpochedRecording {
            name: name.into(),
            epochs: Epochs::new(data, 100.0, 0.0, vec!["Cz".into()], events).unwrap(),
            speller: Some(speller),
            n_events: n,
        }
    }

    #[test]
    fn a_pooled_training_set_is_the_copied_one() {
        let recs = vec![speller_recording("a", 2), speller_recording("b", 3)];
        let copied = TrainingSet::of(&recs).unwrap();
        let moved = TrainingSet::pool(recs.clone()).unwrap();
        assert_eq!(moved.epochs(), copied.epochs());
        assert_eq!(moved.labels(), copied.labels());
        assert_eq!(moved.groups(), copied.groups());
        // Characters are numbered across the recordings: 2 + 3.
        let groups = moved.groups().unwrap();
        assert_eq!(groups.len(), 40);
        assert_eq!((groups[0], groups[16], groups[39]), (0, 2, 4));
        // One recording is taken whole (moved), or borrowed.
        let one = TrainingSet::pool(vec![recs[0].clone()]).unwrap();
        assert_eq!(one.epochs(), &recs[0].epochs);
        assert!(matches!(
            TrainingSet::of(&recs[..1]).unwrap().epochs,
            Cow::Borrowed(_)
        ));
        assert!(TrainingSet::pool(Vec::new()).is_err());
    }

    #[test]
    fn unlabelled_epochs_and_dropped_speller_flashes_are_named() {
        assert_eq!(
            labels(&epochs(&[Some(true), Some(false)])).unwrap(),
            [true, false]
        );
        let err = labels(&epochs(&[Some(true), None])).unwrap_err();
        assert_eq!(err.to_string(), "epoch 1 (code 1) has no target flag");
        let speller = Speller::from_rows(&["AB", "CD"]).unwrap();
        let rec = EpochedRecording {
            name: "x.dat".into(),
            epochs: epochs(&[Some(true), Some(false)]),
            speller: Some(speller.clone()),
            n_events: 3,
        };
        let err = score_speller(&rec, &speller, &Array1::zeros(2)).unwrap_err();
        assert!(
            matches!(
                err,
                EvaluateError::DroppedFlashes {
                    dropped: 1,
                    n_events: 3,
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(character_groups(&[rec]), None);
    }
}
