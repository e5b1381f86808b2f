//! `oddball train` and `oddball evaluate`: fit decoding pipelines on recordings and score them on
//! held-out recordings (or by cross-validation), never letting test data into any fitted step —
//! nor into the choice of hyper-parameters (`--tune`: a grid search by cross-validation on the
//! training recordings only).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use ndarray::Array1;
use oddball_decode::metrics::{roc_auc, speller_accuracy_by_repetitions, Itr, ScoredFlash};
use oddball_decode::pipeline::{Model, Pipeline, PipelineParams, Preprocess, PRESETS};
use oddball_decode::tuning::{cv_folds, preset_grid, tune, Folds, TuningReport};
use oddball_io::Recording;
use oddball_signal::Epochs;
use serde::Serialize;

#[derive(Debug, clap::Args)]
pub struct TrainArgs {
    /// Training recordings (targets flagged).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Pipeline preset: lda, toeplitz-lda, riemann, lda+riemann (score fusion), stack
    /// (toeplitz-lda + riemann + mdm, stacked), mdm, paper, paper-svm, paper-knn.
    #[arg(long, default_value = "riemann")]
    pub pipeline: String,
    /// Where to write the model (JSON).
    #[arg(short, long, default_value = "model.json")]
    pub output: PathBuf,
    /// Choose the preset's hyper-parameters from a small grid by cross-validation on the
    /// training files (folds keep speller characters whole); the model records the choice.
    #[arg(long)]
    pub tune: bool,
    /// Folds of the tuning cross-validation.
    #[arg(long, default_value_t = 5, requires = "tune")]
    pub folds: usize,
}

#[derive(Debug, clap::Args)]
pub struct EvaluateArgs {
    /// Training recordings.
    #[arg(long, num_args = 1.., required_unless_present = "model")]
    pub train: Vec<PathBuf>,
    /// Score the test recordings with this saved model (from `oddball train`) instead of fitting.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["train", "pipeline", "tune"], requires = "test")]
    pub model: Option<PathBuf>,
    /// Test recordings; without them, k-fold cross-validation on the training data.
    #[arg(long, num_args = 1..)]
    pub test: Vec<PathBuf>,
    /// Pipeline preset, or `all`.
    #[arg(long, default_value = "all")]
    pub pipeline: String,
    /// Folds of the cross-validation (without test files) and of the tuning (`--tune`); speller
    /// data is split by character, other data stratified by label.
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// Choose each preset's hyper-parameters from a small grid by cross-validation on the
    /// training files only (nested inside each fold when there are no test files).
    #[arg(long)]
    pub tune: bool,
    /// Draw character accuracy vs repetitions per preset (speller test files) to this .png/.svg.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Also write the results as JSON here.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

/// Reads, detrends, band-passes (zero-phase) and epochs each recording.
pub fn load_epochs(paths: &[PathBuf], pre: &Preprocess) -> Result<(Vec<Recording>, Vec<Epochs>)> {
    let mut recs = Vec::new();
    let mut eps = Vec::new();
    for path in paths {
        let rec = oddball_io::read(path).with_context(|| format!("reading {}", path.display()))?;
        let epochs =
            preprocess(&rec, pre).with_context(|| format!("epoching {}", path.display()))?;
        recs.push(rec);
        eps.push(epochs);
    }
    Ok((recs, eps))
}

/// The model's preprocessing ([`Preprocess::params`]: one path for every command): offline,
/// each channel's mean removed and a zero-phase band-pass; causal (models trained online), one
/// forward pass from the first sample, as the streaming filter does. Then epochs, with the
/// model's rejection.
fn preprocess(rec: &Recording, pre: &Preprocess) -> Result<Epochs> {
    let (epochs, _dropped) = pre.params().epochs(&rec.raw)?;
    Ok(epochs)
}

fn labels(epochs: &Epochs) -> Result<Vec<bool>> {
    epochs
        .events()
        .iter()
        .enumerate()
        .map(|(i, e)| {
            e.target
                .with_context(|| format!("epoch {i} (code {}) has no target flag", e.code))
        })
        .collect()
}

/// The speller character of every epoch (numbered across files), so that cross-validation keeps
/// a character's overlapping flashes in one fold; `None` unless every file is a speller whose
/// flashes were all epoched and there are at least two characters.
fn character_groups(recs: &[Recording], eps: &[Epochs]) -> Option<Vec<usize>> {
    let mut groups = Vec::new();
    let mut next = 0;
    for (rec, ep) in recs.iter().zip(eps) {
        let speller = rec.speller.as_ref()?;
        if ep.n_epochs() != rec.raw.events().len() {
            return None;
        }
        let events = oddball_signal::Events::new(ep.events().to_vec());
        for block in speller.character_blocks(&events) {
            groups.extend(std::iter::repeat_n(next, block.len()));
            next += 1;
        }
    }
    (next >= 2 && groups.len() == eps.iter().map(Epochs::n_epochs).sum::<usize>()).then_some(groups)
}

/// A progress bar over `len` fits on stderr; indicatif hides it when stderr is not a terminal
/// (or `TERM` is unset or `dumb`), so logs and pipes stay clean.
fn progress(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} fits {elapsed} (eta {eta})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

fn fold_note(grouped: bool) -> &'static str {
    if grouped {
        "folds keep speller characters whole"
    } else {
        "folds stratified by label"
    }
}

/// The tuning table: every candidate's cross-validated AUC, the chosen one marked.
fn print_tuning(name: &str, r: &TuningReport, indent: &str) {
    println!(
        "{indent}tuning {name}: {}-fold CV on the training data ({}), mean epoch AUC",
        r.n_folds,
        fold_note(r.grouped)
    );
    for c in &r.candidates {
        let folds: Vec<String> = c.fold_auc.iter().map(|a| format!("{a:.3}")).collect();
        println!(
            "{indent}  {} {:<28} CV AUC {:.3}  (folds {})",
            if c.label == r.chosen { "*" } else { " " },
            c.label,
            c.cv_auc,
            folds.join(" ")
        );
    }
    println!("{indent}  chosen: {}", r.chosen);
}

pub fn run_train(args: &TrainArgs) -> Result<()> {
    let pre = Preprocess::peer();
    let (recs, eps) = load_epochs(&args.files, &pre)?;
    let epochs = Epochs::concatenate(&eps)?;
    let y = labels(&epochs)?;
    let groups = character_groups(&recs, &eps);
    let (params, tuning) = if args.tune {
        let grid = preset_grid(&args.pipeline, epochs.sfreq())?;
        let folds = cv_folds(&y, groups.as_deref(), args.folds)?;
        let pb = progress((grid.len() * folds.n_folds()) as u64, &args.pipeline);
        let (params, report) = tune(
            &grid,
            epochs.data().view(),
            &y,
            groups.as_deref(),
            args.folds,
            &mut || pb.inc(1),
        )
        .with_context(|| format!("tuning {}", args.pipeline))?;
        pb.finish_and_clear();
        print_tuning(&args.pipeline, &report, "");
        (params, Some(report))
    } else {
        (
            PipelineParams::preset(&args.pipeline, epochs.sfreq())?,
            None,
        )
    };
    let t0 = Instant::now();
    let pipeline = params.fit_grouped(epochs.data().view(), &y, groups.as_deref())?;
    let fit_s = t0.elapsed().as_secs_f64();
    let mut model = Model::new(
        pre,
        epochs.sfreq(),
        recs[0].raw.ch_names().to_vec(),
        pipeline,
    );
    model.tuning = tuning;
    std::fs::write(&args.output, model.to_json())
        .with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "trained {}{} on {} epochs ({} targets) from {} file(s) in {:.3} s; wrote {}",
        args.pipeline,
        model
            .tuning
            .as_ref()
            .map(|t| format!(" ({})", t.chosen))
            .unwrap_or_default(),
        epochs.n_epochs(),
        y.iter().filter(|&&t| t).count(),
        args.files.len(),
        fit_s,
        args.output.display()
    );
    Ok(())
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}

#[derive(Debug, Serialize)]
struct PipelineResult {
    pipeline: String,
    /// Epoch ROC-AUC on the test data (mean over folds under cross-validation).
    auc: f64,
    auc_folds: Vec<f64>,
    /// Speller character accuracy for 1..N repetitions (test files that are spellers; pooled
    /// over the characters of all of them).
    speller_accuracy: Option<Vec<f64>>,
    /// Cells of the speller matrix (chance accuracy is one over this).
    speller_choices: Option<usize>,
    /// Characters picked with all repetitions.
    speller_text: Option<String>,
    /// Fewest repetitions from which every character stays right with every further repetition
    /// (a curve that reaches 100 % and drops again counts from after its last drop), if any.
    reps_for_all_correct: Option<usize>,
    itr_at_best: Option<Itr>,
    fit_s: f64,
    score_epochs_per_s: f64,
    /// `--tune` with test files: the settings chosen on the training files.
    #[serde(skip_serializing_if = "Option::is_none")]
    tuning: Option<TuningReport>,
    /// `--tune` under cross-validation: the settings chosen inside each outer fold.
    #[serde(skip_serializing_if = "Option::is_none")]
    tuning_per_fold: Option<Vec<TuningReport>>,
}

pub fn run_evaluate(args: &EvaluateArgs) -> Result<()> {
    if let Some(path) = &args.model {
        let model = load_model(path)?;
        if let Some(first) = args.test.first() {
            let rec =
                oddball_io::read(first).with_context(|| format!("reading {}", first.display()))?;
            if oddball_session::record::is_session(&rec) {
                return evaluate_sessions(args, &model, path);
            }
        }
        let (test_recs, test_eps) = load_epochs(&args.test, &model.preprocess)?;
        for rec in &test_recs {
            model
                .check_layout(rec.raw.ch_names(), rec.raw.sfreq())
                .with_context(|| {
                    format!("scoring {} with {}", rec.path.display(), path.display())
                })?;
        }
        let mut r = score_test(&model.pipeline, 0.0, &test_recs, &test_eps)?;
        r.tuning = model.tuning.clone();
        print_row(&r);
        return finish(args, &[r]);
    }
    let pre = Preprocess::peer();
    let names: Vec<String> = if args.pipeline == "all" {
        PRESETS.iter().map(|s| s.to_string()).collect()
    } else {
        vec![args.pipeline.clone()]
    };
    let (train_recs, train_eps) = load_epochs(&args.train, &pre)?;
    let train = Epochs::concatenate(&train_eps)?;
    let ytr = labels(&train)?;
    let groups = character_groups(&train_recs, &train_eps);
    let (test_recs, test_eps) = load_epochs(&args.test, &pre)?;
    let grids = names
        .iter()
        .map(|n| {
            if args.tune {
                preset_grid(n, train.sfreq()).map(|g| g.len())
            } else {
                PipelineParams::preset(n, train.sfreq()).map(|_| 0)
            }
        })
        .collect::<Result<Vec<usize>, _>>()?;
    // Every fit the run will make, for the progress bar.
    let outer = if args.test.is_empty() {
        Some(cv_folds(&ytr, groups.as_deref(), args.folds)?)
    } else {
        None
    };
    let fits_per_grid_point: usize = match &outer {
        None if args.tune => cv_folds(&ytr, groups.as_deref(), args.folds)?.n_folds(),
        None => 0,
        Some(f) if args.tune => (0..f.n_folds())
            .map(|k| {
                let (tr, _) = f.split(k);
                let y: Vec<bool> = tr.iter().map(|&i| ytr[i]).collect();
                let g: Option<Vec<usize>> =
                    groups.as_ref().map(|g| tr.iter().map(|&i| g[i]).collect());
                cv_folds(&y, g.as_deref(), args.folds).map(|f| f.n_folds())
            })
            .sum::<Result<usize, _>>()?,
        Some(_) => 0,
    };
    let final_fits = outer.as_ref().map_or(1, Folds::n_folds);
    let total: usize = grids
        .iter()
        .map(|&g| g * fits_per_grid_point + final_fits)
        .sum();
    let pb = progress(total as u64, "evaluate");
    if let Some(f) = &outer {
        pb.suspend(|| {
            println!(
                "{}-fold cross-validation on the training data ({})",
                f.n_folds(),
                fold_note(f.grouped())
            )
        });
    }
    let mut results = Vec::new();
    for name in &names {
        pb.set_message(name.clone());
        let r = match &outer {
            Some(folds) => cross_validate(name, &train, &ytr, groups.as_deref(), folds, args, &pb)?,
            None => {
                let (params, tuning) = if args.tune {
                    let grid = preset_grid(name, train.sfreq())?;
                    let (params, report) = tune(
                        &grid,
                        train.data().view(),
                        &ytr,
                        groups.as_deref(),
                        args.folds,
                        &mut || pb.inc(1),
                    )
                    .with_context(|| format!("tuning {name}"))?;
                    pb.suspend(|| print_tuning(name, &report, ""));
                    (params, Some(report))
                } else {
                    (PipelineParams::preset(name, train.sfreq())?, None)
                };
                let mut r = held_out(
                    &params,
                    &train,
                    &ytr,
                    groups.as_deref(),
                    &test_recs,
                    &test_eps,
                )?;
                pb.inc(1);
                r.tuning = tuning;
                r
            }
        };
        pb.suspend(|| print_row(&r));
        results.push(r);
    }
    pb.finish_and_clear();
    finish(args, &results)
}

/// The plot (if asked) and the JSON (if asked).
fn finish(args: &EvaluateArgs, results: &[PipelineResult]) -> Result<()> {
    if let Some(path) = &args.plot {
        if results.iter().any(|r| r.speller_accuracy.is_some()) {
            draw_accuracy(path, results)?;
            println!("wrote {}", path.display());
        } else {
            println!(
                "no accuracy-vs-repetitions plot: {} (it needs speller test files)",
                if args.test.is_empty() {
                    "cross-validation has no test files"
                } else {
                    "the test files are not spellers"
                }
            );
        }
    }
    write_json(args, results)
}

fn write_json(args: &EvaluateArgs, results: &[PipelineResult]) -> Result<()> {
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(results)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn print_row(r: &PipelineResult) {
    let acc = r
        .speller_accuracy
        .as_ref()
        .map(|a| {
            a.iter()
                .map(|v| format!("{:.0}", v * 100.0))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .unwrap_or_default();
    println!(
        "{:<10} AUC {:.3}  fit {:>7.3} s  {:>9.0} epochs/s{}{}{}{}",
        r.pipeline,
        r.auc,
        r.fit_s,
        r.score_epochs_per_s,
        if acc.is_empty() {
            String::new()
        } else {
            format!("  chars % by reps: {acc}")
        },
        r.speller_text
            .as_ref()
            .map(|t| format!("  picks {t}"))
            .unwrap_or_default(),
        r.reps_for_all_correct
            .map(|n| format!("  all right from {n} reps"))
            .unwrap_or_default(),
        r.tuning
            .as_ref()
            .map(|t| format!("  [{}]", t.chosen))
            .unwrap_or_default(),
    );
}

fn held_out(
    params: &PipelineParams,
    train: &Epochs,
    ytr: &[bool],
    groups: Option<&[usize]>,
    test_recs: &[Recording],
    test_eps: &[Epochs],
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let model = params.fit_grouped(train.data().view(), ytr, groups)?;
    let fit_s = t0.elapsed().as_secs_f64();
    score_test(&model, fit_s, test_recs, test_eps)
}

/// One speller test file's scores.
struct SpellerScores {
    accuracy: Vec<f64>,
    text: String,
    n_chars: usize,
    n_choices: usize,
    /// Seconds of one repetition (every row and column flashed once).
    seconds_per_repetition: f64,
}

fn score_speller(
    rec: &Recording,
    speller: &oddball_io::Speller,
    ep: &Epochs,
    scores: &Array1<f64>,
) -> Result<SpellerScores> {
    // Characters are consecutive runs of flashes; a dropped epoch would shift every
    // later character onto the wrong flashes.
    if ep.n_epochs() != rec.raw.events().len() {
        bail!(
            "{}: {} of {} flashes could not be epoched, so its characters cannot be scored",
            rec.path.display(),
            rec.raw.events().len() - ep.n_epochs(),
            rec.raw.events().len()
        );
    }
    let events = oddball_signal::Events::new(ep.events().to_vec());
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
    let blocks: Vec<Vec<ScoredFlash>> = speller
        .character_blocks(&events)
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
    let soa = gaps.get(gaps.len() / 2).copied().unwrap_or(0) as f64 / ep.sfreq();
    Ok(SpellerScores {
        accuracy,
        text,
        n_chars: blocks.len(),
        n_choices: rows.len() * cols.len(),
        seconds_per_repetition: (rows.len() + cols.len()) as f64 * soa,
    })
}

fn score_test(
    model: &Pipeline,
    fit_s: f64,
    test_recs: &[Recording],
    test_eps: &[Epochs],
) -> Result<PipelineResult> {
    let mut all_scores = Vec::new();
    let mut all_y = Vec::new();
    let mut score_s = 0.0;
    let mut spellers = Vec::new();
    for (rec, ep) in test_recs.iter().zip(test_eps) {
        let t1 = Instant::now();
        let scores: Array1<f64> = model.decision_function(ep.data().view())?;
        score_s += t1.elapsed().as_secs_f64();
        let y = labels(ep)?;
        if let Some(speller) = &rec.speller {
            spellers.push(score_speller(rec, speller, ep, &scores)?);
        }
        all_scores.extend(scores.iter().copied());
        all_y.extend(y);
    }
    let auc = roc_auc(&all_scores, &all_y)?;
    // Speller files pooled: accuracy over all their characters, up to the fewest repetitions.
    let mut result = PipelineResult {
        pipeline: model.name().to_string(),
        auc,
        auc_folds: vec![auc],
        speller_accuracy: None,
        speller_choices: None,
        speller_text: None,
        reps_for_all_correct: None,
        itr_at_best: None,
        fit_s,
        score_epochs_per_s: all_scores.len() as f64 / score_s.max(1e-12),
        tuning: None,
        tuning_per_fold: None,
    };
    if let Some(first) = spellers.first() {
        let n_chars: usize = spellers.iter().map(|s| s.n_chars).sum();
        let reps = spellers.iter().map(|s| s.accuracy.len()).min().unwrap_or(0);
        let acc: Vec<f64> = (0..reps)
            .map(|r| {
                spellers
                    .iter()
                    .map(|s| s.accuracy[r] * s.n_chars as f64)
                    .sum::<f64>()
                    / n_chars.max(1) as f64
            })
            .collect();
        let per_rep = spellers
            .iter()
            .map(|s| s.seconds_per_repetition * s.n_chars as f64)
            .sum::<f64>()
            / n_chars.max(1) as f64;
        result.itr_at_best = acc
            .iter()
            .enumerate()
            .map(|(i, &a)| Itr::new(first.n_choices, a, (i + 1) as f64 * per_rep))
            .max_by(|a, b| a.bits_per_minute.total_cmp(&b.bits_per_minute));
        result.reps_for_all_correct = reps_from_which_all_correct(&acc);
        result.speller_choices = Some(first.n_choices);
        result.speller_text = Some(spellers.iter().map(|s| s.text.as_str()).collect());
        result.speller_accuracy = Some(acc);
    }
    Ok(result)
}

/// k-fold cross-validation on the training data with `folds` (speller characters kept whole, or
/// stratified by label). With `--tune`, the grid search runs inside each fold's training part.
/// The first repetition count (1-based) from which the accuracy stays at 100 % up to the last
/// repetition scored, if the last is 100 %.
fn reps_from_which_all_correct(acc: &[f64]) -> Option<usize> {
    match acc.iter().rposition(|&a| a < 1.0) {
        None => (!acc.is_empty()).then_some(1),
        Some(i) => (i + 1 < acc.len()).then_some(i + 2),
    }
}

fn cross_validate(
    name: &str,
    data: &Epochs,
    y: &[bool],
    groups: Option<&[usize]>,
    folds: &Folds,
    args: &EvaluateArgs,
    pb: &ProgressBar,
) -> Result<PipelineResult> {
    let mut aucs = Vec::new();
    let mut fit_s = 0.0;
    let mut score_s = 0.0;
    let mut n_scored = 0;
    let mut reports = Vec::new();
    for f in 0..folds.n_folds() {
        let (tr, te) = folds.split(f);
        let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
        let yte: Vec<bool> = te.iter().map(|&i| y[i]).collect();
        let train = data.select(&tr);
        let gtr: Option<Vec<usize>> = groups.map(|g| tr.iter().map(|&i| g[i]).collect());
        let params = if args.tune {
            let grid = preset_grid(name, data.sfreq())?;
            let (params, report) = tune(
                &grid,
                train.data().view(),
                &ytr,
                gtr.as_deref(),
                args.folds,
                &mut || pb.inc(1),
            )
            .with_context(|| format!("tuning {name} in fold {}", f + 1))?;
            pb.suspend(|| {
                println!("fold {}/{}:", f + 1, folds.n_folds());
                print_tuning(name, &report, "  ");
            });
            reports.push(report);
            params
        } else {
            PipelineParams::preset(name, data.sfreq())?
        };
        let t0 = Instant::now();
        let model = params.fit_grouped(train.data().view(), &ytr, gtr.as_deref())?;
        fit_s += t0.elapsed().as_secs_f64();
        pb.inc(1);
        let t1 = Instant::now();
        let s = model.decision_function(data.select(&te).data().view())?;
        score_s += t1.elapsed().as_secs_f64();
        n_scored += te.len();
        aucs.push(roc_auc(&s.to_vec(), &yte)?);
    }
    Ok(PipelineResult {
        pipeline: name.to_string(),
        auc: aucs.iter().sum::<f64>() / aucs.len() as f64,
        auc_folds: aucs,
        speller_accuracy: None,
        speller_choices: None,
        speller_text: None,
        reps_for_all_correct: None,
        itr_at_best: None,
        fit_s: fit_s / folds.n_folds() as f64,
        score_epochs_per_s: n_scored as f64 / score_s.max(1e-12),
        tuning: None,
        tuning_per_fold: args.tune.then_some(reports),
    })
}

/// Character accuracy (%) vs repetitions, one line per preset, chance level dashed.
fn draw_accuracy(path: &Path, results: &[PipelineResult]) -> Result<()> {
    let curves: Vec<(&str, &[f64])> = results
        .iter()
        .filter_map(|r| Some((r.pipeline.as_str(), r.speller_accuracy.as_deref()?)))
        .collect();
    let n_reps = curves
        .iter()
        .map(|(_, a)| a.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let n_choices = results.iter().find_map(|r| r.speller_choices).unwrap_or(36);
    let chance = 100.0 / n_choices as f64;
    let n_chars = results
        .iter()
        .find_map(|r| r.speller_text.as_ref().map(|t| t.chars().count()))
        .unwrap_or(0);
    crate::with_backend!(path, (900, 600), |root| {
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("character accuracy vs repetitions ({n_chars} characters)"),
                (crate::plot::FONT_FAMILY, 22),
            )
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d(0.5f64..n_reps as f64 + 0.5, 0f64..105.0)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_labels(n_reps.min(20))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_labels(11)
            .y_label_formatter(&|y| format!("{y:.0}"))
            .x_desc("repetitions (flashes of every row and column)")
            .y_desc("characters right, %")
            .label_style((crate::plot::FONT_FAMILY, 14))
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        // Earlier curves drawn wider, so curves that coincide stay visible under later ones.
        for (i, (name, acc)) in curves.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let width = 2 + (curves.len() - 1 - i) as u32;
            let points: Vec<(f64, f64)> = acc
                .iter()
                .enumerate()
                .map(|(r, a)| ((r + 1) as f64, 100.0 * a))
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), color.stroke_width(width)))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                });
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|&p| Circle::new(p, 2 + width / 2, color.filled())),
                )
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        chart
            .draw_series(DashedLineSeries::new(
                [(0.5, chance), (n_reps as f64 + 0.5, chance)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .label(format!("chance (1/{n_choices} = {chance:.1} %)"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::MiddleRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((crate::plot::FONT_FAMILY, 14))
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(())
    })
}

/// Re-evaluates oddball session files (`oddball demo` writes `session.dat`) with a model:
/// every online decision recomputed from the raw EEG, compared with the recorded one.
fn evaluate_sessions(args: &EvaluateArgs, model: &Model, model_path: &Path) -> Result<()> {
    use oddball_session::engine::TrialOutcome;
    use oddball_session::record::{read_session, reevaluate};

    #[derive(Serialize)]
    struct SessionResult {
        file: PathBuf,
        decisions: Vec<oddball_session::record::Redecision>,
        identical_to_recorded: usize,
        accuracy: f64,
        itr: Itr,
    }
    let mut results = Vec::new();
    for path in &args.test {
        let rec = oddball_io::read(path).with_context(|| format!("reading {}", path.display()))?;
        let saved = read_session(&rec).with_context(|| format!("reading {}", path.display()))?;
        let decisions = reevaluate(&rec, &saved, model).with_context(|| {
            format!(
                "re-evaluating {} with {}",
                path.display(),
                model_path.display()
            )
        })?;
        let name = |c: Option<u32>| {
            c.and_then(|c| saved.bulbs.get(c as usize - 1))
                .map_or("—".to_string(), |b| b.to_string())
        };
        println!("{}:", path.display());
        for d in &decisions {
            let decided = match d.outcome {
                TrialOutcome::Chosen { code } => name(Some(code)),
                _ => "abstain".into(),
            };
            println!(
                "  trial {:>3}: intended {:<5} decided {:<7} rounds {}  recorded {:<7} {}",
                d.number,
                name(d.intended),
                decided,
                d.rounds,
                if d.recorded.is_some() {
                    name(d.recorded)
                } else {
                    "abstain".into()
                },
                if d.decided() == d.recorded {
                    "same"
                } else {
                    "DIFFERENT"
                }
            );
        }
        let same = decisions
            .iter()
            .filter(|d| d.decided() == d.recorded)
            .count();
        let n = decisions.len().max(1) as f64;
        let correct = decisions
            .iter()
            .filter(|d| d.decided().is_some() && d.decided() == d.intended)
            .count();
        let seconds = decisions.iter().map(|d| d.seconds).sum::<f64>() / n;
        let accuracy = correct as f64 / n;
        let itr = Itr::new(4, accuracy, seconds);
        println!(
            "  {} online decisions: {same} identical to the recorded ones; accuracy {:.1} % ({correct}/{}), ITR {:.2} bits/decision, {:.2} bits/min",
            decisions.len(),
            100.0 * accuracy,
            decisions.len(),
            itr.bits_per_selection,
            itr.bits_per_minute
        );
        results.push(SessionResult {
            file: path.clone(),
            identical_to_recorded: same,
            decisions,
            accuracy,
            itr,
        });
    }
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&results)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::reps_from_which_all_correct as reps;

    #[test]
    fn repetitions_count_from_the_last_miss() {
        assert_eq!(reps(&[0.5, 1.0, 1.0]), Some(2));
        assert_eq!(reps(&[1.0, 1.0]), Some(1));
        // reached at 2, lost at 3 and 4: all right only from 5 on
        assert_eq!(reps(&[0.0, 1.0, 0.5, 0.5, 1.0, 1.0]), Some(5));
        assert_eq!(reps(&[1.0, 0.75]), None);
        assert_eq!(reps(&[]), None);
    }
}
