//! `oddball train` and `oddball evaluate`: fit decoding pipelines on recordings and score them on
//! held-out recordings (or by cross-validation), never letting test data into any fitted step.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use ndarray::Array1;
use oddball_decode::metrics::{roc_auc, speller_accuracy_by_repetitions, Itr, ScoredFlash};
use oddball_decode::pipeline::{Model, Pipeline, PipelineParams, Preprocess, PRESETS};
use oddball_io::Recording;
use oddball_signal::detrend::{detrend, DetrendKind};
use oddball_signal::epochs::{EpochsParams, Reject};
use oddball_signal::Epochs;
use serde::Serialize;

#[derive(Debug, clap::Args)]
pub struct TrainArgs {
    /// Training recordings (targets flagged).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Pipeline preset: lda, riemann, paper, paper-svm, paper-knn.
    #[arg(long, default_value = "riemann")]
    pub pipeline: String,
    /// Where to write the model (JSON).
    #[arg(short, long, default_value = "model.json")]
    pub output: PathBuf,
}

#[derive(Debug, clap::Args)]
pub struct EvaluateArgs {
    /// Training recordings.
    #[arg(long, num_args = 1.., required_unless_present = "model")]
    pub train: Vec<PathBuf>,
    /// Score the test recordings with this saved model (from `oddball train`) instead of fitting.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["train", "pipeline"], requires = "test")]
    pub model: Option<PathBuf>,
    /// Test recordings; without them, stratified k-fold cross-validation on the training data.
    #[arg(long, num_args = 1..)]
    pub test: Vec<PathBuf>,
    /// Pipeline preset, or `all`.
    #[arg(long, default_value = "all")]
    pub pipeline: String,
    /// Folds of the cross-validation (when no test files are given).
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
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

/// Offline: remove each channel's mean, zero-phase band-pass. Causal (models trained online):
/// one forward pass from the first sample, as the streaming filter does. Then epochs, with the
/// model's peak-to-peak rejection if it has one.
fn preprocess(rec: &Recording, pre: &Preprocess) -> Result<Epochs> {
    let mut raw = rec.raw.clone();
    let filter = pre.band.design(raw.sfreq())?;
    if pre.causal {
        let filtered = filter.sosfilt(raw.data().view(), true);
        raw.data_mut().assign(&filtered);
    } else {
        detrend(raw.data_mut(), DetrendKind::Constant);
        filter.apply_raw(&mut raw)?;
    }
    let mut params = EpochsParams::new(pre.tmin, pre.tmax);
    if let Some(t) = pre.reject_peak_to_peak_uv {
        params = params.with_reject(Reject::PeakToPeak(t));
    }
    let (epochs, _dropped) = params.cut(&raw)?;
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

pub fn run_train(args: &TrainArgs) -> Result<()> {
    let pre = Preprocess::peer();
    let (recs, eps) = load_epochs(&args.files, &pre)?;
    let epochs = Epochs::concatenate(&eps)?;
    let y = labels(&epochs)?;
    let params = PipelineParams::preset(&args.pipeline, epochs.sfreq())?;
    let t0 = Instant::now();
    let pipeline = params.fit(epochs.data().view(), &y)?;
    let fit_s = t0.elapsed().as_secs_f64();
    let model = Model::new(
        pre,
        epochs.sfreq(),
        recs[0].raw.ch_names().to_vec(),
        pipeline,
    );
    std::fs::write(&args.output, model.to_json())
        .with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "trained {} on {} epochs ({} targets) from {} file(s) in {:.3} s; wrote {}",
        args.pipeline,
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
    /// Speller character accuracy for 1..N repetitions (test files that are spellers).
    speller_accuracy: Option<Vec<f64>>,
    /// Characters picked with all repetitions.
    speller_text: Option<String>,
    /// Fewest repetitions at which every character is right, if any.
    reps_for_all_correct: Option<usize>,
    itr_at_best: Option<Itr>,
    fit_s: f64,
    score_epochs_per_s: f64,
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
        let r = score_test(&model.pipeline, 0.0, &test_recs, &test_eps)?;
        print_row(&r);
        return write_json(args, &[r]);
    }
    let pre = Preprocess::peer();
    let names: Vec<String> = if args.pipeline == "all" {
        PRESETS.iter().map(|s| s.to_string()).collect()
    } else {
        vec![args.pipeline.clone()]
    };
    let (_, train_eps) = load_epochs(&args.train, &pre)?;
    let train = Epochs::concatenate(&train_eps)?;
    let ytr = labels(&train)?;
    let (test_recs, test_eps) = load_epochs(&args.test, &pre)?;
    let mut results = Vec::new();
    for name in &names {
        let params = PipelineParams::preset(name, train.sfreq())?;
        let r = if args.test.is_empty() {
            cross_validate(&params, &train, &ytr, args.folds)?
        } else {
            held_out(&params, &train, &ytr, &test_recs, &test_eps)?
        };
        print_row(&r);
        results.push(r);
    }
    write_json(args, &results)
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
        "{:<10} AUC {:.3}  fit {:>7.3} s  {:>9.0} epochs/s{}{}{}",
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
    );
}

fn held_out(
    params: &PipelineParams,
    train: &Epochs,
    ytr: &[bool],
    test_recs: &[Recording],
    test_eps: &[Epochs],
) -> Result<PipelineResult> {
    let t0 = Instant::now();
    let model = params.fit(train.data().view(), ytr)?;
    let fit_s = t0.elapsed().as_secs_f64();
    score_test(&model, fit_s, test_recs, test_eps)
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
    let mut speller_accuracy: Option<Vec<f64>> = None;
    let mut speller_text = None;
    let mut itr_at_best = None;
    let mut reps_for_all_correct = None;
    for (rec, ep) in test_recs.iter().zip(test_eps) {
        let t1 = Instant::now();
        let scores: Array1<f64> = model.decision_function(ep.data().view())?;
        score_s += t1.elapsed().as_secs_f64();
        let y = labels(ep)?;
        if let Some(speller) = &rec.speller {
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
            let max_reps =
                blocks.iter().map(|b| b.len()).min().unwrap_or(0) / (rows.len() + cols.len());
            let (acc, picks) = speller_accuracy_by_repetitions(&blocks, &rows, &cols, max_reps)?;
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
            let n_choices = rows.len() * cols.len();
            let best = acc
                .iter()
                .enumerate()
                .map(|(i, &a)| {
                    let t = (i + 1) as f64 * (rows.len() + cols.len()) as f64 * soa;
                    Itr::new(n_choices, a, t)
                })
                .max_by(|a, b| a.bits_per_minute.total_cmp(&b.bits_per_minute));
            reps_for_all_correct = acc.iter().position(|&a| a >= 1.0).map(|i| i + 1);
            itr_at_best = best;
            speller_accuracy = Some(acc);
            speller_text = Some(text);
        }
        all_scores.extend(scores.iter().copied());
        all_y.extend(y);
    }
    let auc = roc_auc(&all_scores, &all_y)?;
    Ok(PipelineResult {
        pipeline: model.name().to_string(),
        auc,
        auc_folds: vec![auc],
        speller_accuracy,
        speller_text,
        reps_for_all_correct,
        itr_at_best,
        fit_s,
        score_epochs_per_s: all_scores.len() as f64 / score_s.max(1e-12),
    })
}

/// Stratified k-fold (epochs dealt to folds in order within each class, no shuffling).
fn cross_validate(
    params: &PipelineParams,
    data: &Epochs,
    y: &[bool],
    folds: usize,
) -> Result<PipelineResult> {
    if folds < 2 {
        bail!("cross-validation needs at least 2 folds, got {folds}");
    }
    let mut fold_of = vec![0usize; y.len()];
    let (mut nt, mut nn) = (0, 0);
    for (i, &t) in y.iter().enumerate() {
        let k = if t { &mut nt } else { &mut nn };
        fold_of[i] = *k % folds;
        *k += 1;
    }
    let mut aucs = Vec::new();
    let mut fit_s = 0.0;
    let mut score_s = 0.0;
    let mut n_scored = 0;
    for f in 0..folds {
        let tr: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] != f).collect();
        let te: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] == f).collect();
        let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
        let yte: Vec<bool> = te.iter().map(|&i| y[i]).collect();
        let t0 = Instant::now();
        let model = params.fit(data.select(&tr).data().view(), &ytr)?;
        fit_s += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let s = model.decision_function(data.select(&te).data().view())?;
        score_s += t1.elapsed().as_secs_f64();
        n_scored += te.len();
        aucs.push(roc_auc(s.as_slice().expect("contiguous"), &yte)?);
    }
    Ok(PipelineResult {
        pipeline: params.name.clone(),
        auc: aucs.iter().sum::<f64>() / aucs.len() as f64,
        auc_folds: aucs,
        speller_accuracy: None,
        speller_text: None,
        reps_for_all_correct: None,
        itr_at_best: None,
        fit_s: fit_s / folds as f64,
        score_epochs_per_s: n_scored as f64 / score_s.max(1e-12),
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
