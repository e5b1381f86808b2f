//! `oddball train` and `oddball evaluate`: the arguments, the progress bars, the files, and
//! printing. The fitting, cross-validation, tuning and scoring are `oddball_eval::evaluate`'s
//! (and its `unsupervised` and `sessions`), the text printed is `oddball_eval::text`'s.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::progress::{bar, Bar};
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_eval::evaluate::{self, EvaluateParams, PipelineResult, Progress, TrainingSet};
use oddball_eval::text::{self, Narration};
use oddball_eval::{dataset, sessions, unsupervised};
use oddball_io::ReadOptions;
use oddball_session::record::is_session;

use crate::load::{load_epochs, load_model, with_flags, EventArgs, Layout};
use crate::preset_arg::{list_help, one_help, preset, PipelineList, DEFAULT_PIPELINE};
use oddball_decode::preset::Preset;

#[derive(Debug, clap::Args)]
pub struct TrainArgs {
    #[arg(
        required = true,
        help = concat!("Training recordings (targets flagged): ", crate::load::formats!(), ".")
    )]
    pub files: Vec<PathBuf>,
    #[arg(long, default_value = DEFAULT_PIPELINE, value_parser = preset, help = one_help())]
    pub pipeline: Preset,
    /// Where to write the model (JSON).
    #[arg(
        short,
        long,
        visible_alias = "output",
        value_name = "FILE",
        default_value = "model.json",
        value_parser = crate::args::output_file
    )]
    pub out: PathBuf,
    /// Choose the preset's hyper-parameters from a small grid by cross-validation on the
    /// training files (folds keep speller characters whole); the model records the choice.
    #[arg(long)]
    pub tune: bool,
    /// Folds of the tuning cross-validation.
    #[arg(long, default_value_t = 5, requires = "tune")]
    pub folds: usize,
    #[command(flatten)]
    pub events: EventArgs,
}

#[derive(Debug, clap::Args)]
pub struct EvaluateArgs {
    #[arg(
        long,
        num_args = 1..,
        required_unless_present_any = ["model", "unsupervised"],
        help = concat!("Training recordings: ", crate::load::formats!(), ".")
    )]
    pub train: Vec<PathBuf>,
    /// Decode the test recordings (speller runs, played in order as one session) without
    /// labels and without training files: each character decided by the model fitted (EM over
    /// one row + one column per character) on the characters so far, then all re-decided by the
    /// final model; the labels only score the result.
    #[arg(long, requires = "test", conflicts_with_all = ["train", "model", "tune", "plot"])]
    pub unsupervised: bool,
    /// With --unsupervised: where each refit's EM starts (the likeliest result kept) —
    /// `template`: every epoch's score by a P300 template (a positive wave at 350 ms, sd 80 ms,
    /// seen through the band-pass), the last fit and, once there are as many epochs as features,
    /// 32 random starts, as a session without calibration starts; `random`: the last fit and the
    /// 32 random starts only.
    #[arg(long, value_enum, default_value_t = EmStart::Template, requires = "unsupervised")]
    pub em_start: EmStart,
    /// With --unsupervised: the covariance's label-free part — `ledoit-wolf`: the Ledoit–Wolf
    /// shrunk total covariance; `block-toeplitz`: that made block-Toeplitz over channels and time
    /// lags (the time-stationary structure of `toeplitz-lda`).
    #[arg(long, value_enum, default_value_t = CovarianceArg::LedoitWolf, requires = "unsupervised")]
    pub covariance: CovarianceArg,
    /// With --unsupervised: band-pass causally, as a live session (`oddball decode
    /// --calibration none`, `demo --calibration none`) can, instead of zero-phase.
    #[arg(long, requires = "unsupervised")]
    pub causal: bool,
    /// With --unsupervised: a pooled start of other people's recordings as one more start of
    /// every refit — `none`; `pooled` (the one shipped, built from the public recordings, so
    /// not independent of them); or a file (`oddball benchmark … --write-pooled FILE`).
    #[arg(
        long,
        value_name = "none|pooled|FILE",
        default_value = "none",
        requires = "unsupervised"
    )]
    pub transfer: String,
    /// Score the test recordings with this saved model (from `oddball train`) instead of fitting;
    /// oddball session files (`session.dat` of `oddball demo`) get every online decision
    /// recomputed.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["train", "pipeline", "tune"], requires = "test")]
    pub model: Option<PathBuf>,
    #[arg(
        long,
        num_args = 1..,
        help = concat!(
            "Test recordings (",
            crate::load::formats!(),
            "); without them, k-fold cross-validation on the training data."
        )
    )]
    pub test: Vec<PathBuf>,
    /// The text each test recording spelled, for speller runs recorded without labels (e.g.
    /// the BCI Competition's test runs): one per test file, comma-separated (e.g. HAM,PIE).
    #[arg(
        long,
        value_name = "TEXT[,TEXT…]",
        value_delimiter = ',',
        requires = "test"
    )]
    pub test_text: Vec<String>,
    #[arg(long, default_value = DEFAULT_PIPELINE, value_name = "NAME[,NAME…]|all", help = list_help())]
    pub pipeline: PipelineList,
    /// Folds of the cross-validation (without test files) and of the tuning (`--tune`); speller
    /// data is split by character, other data stratified by label.
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// Choose each preset's hyper-parameters from a small grid by cross-validation on the
    /// training files only (nested inside each fold when there are no test files).
    #[arg(long)]
    pub tune: bool,
    /// Draw character accuracy vs repetitions per preset (speller test files) to this .png/.svg.
    #[arg(long, value_name = "FILE", value_parser = crate::args::plot_file)]
    pub plot: Option<PathBuf>,
    /// Also write the results as JSON here.
    #[arg(short, long, visible_alias = "json", value_name = "FILE", value_parser = crate::args::output_file)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub events: EventArgs,
}

/// What a run reports: the progress bar, and above it what [`Narration`] says.
struct Report {
    what: String,
    bar: Option<Bar>,
    text: Narration,
}

impl Report {
    fn new(what: &str, text: Narration) -> Self {
        Self {
            what: what.to_string(),
            bar: None,
            text,
        }
    }

    fn on(&mut self, p: Progress<'_>) {
        if let Progress::Plan { fits, .. } = p {
            let b = bar(
                fits as u64,
                "{msg} [{bar:30}] {pos}/{len} fits {elapsed} (eta {eta})",
            );
            b.set_message(self.what.clone());
            self.bar = Some(b);
        }
        match (p, &self.bar) {
            (Progress::Preset(name), Some(b)) => b.set_message(name.to_string()),
            (Progress::Fit, Some(b)) => b.inc(1),
            _ => {}
        }
        let text = self.text.on(&p);
        match &self.bar {
            Some(b) if !text.is_empty() => b.suspend(|| print!("{text}")),
            _ => print!("{text}"),
        }
    }

    fn finish(self) {
        if let Some(b) = self.bar {
            b.finish_and_clear();
        }
    }
}

pub fn run_train(args: &TrainArgs) -> Result<()> {
    let pre = Preprocess::peer();
    let set = TrainingSet::pool(load_epochs(&args.files, &pre, &args.events, &[], None)?.0)?;
    let t0 = std::time::Instant::now();
    let (name, folds) = (args.pipeline.name(), args.tune.then_some(args.folds));
    let mut report = Report::new(
        name,
        Narration::training(name, "zero-phase band-passed epochs"),
    );
    let trained = evaluate::train(args.pipeline, &set, folds, &mut |p| report.on(p));
    report.finish();
    let trained = trained?;
    let ch_names = set.epochs().ch_names().to_vec();
    // The zero-phase epochs go before the causal ones come (one set in memory at a time).
    drop(set);
    // What a session runs: the same settings on the causally band-passed epochs.
    let causal = pre.as_causal();
    let live_set =
        TrainingSet::pool(load_epochs(&args.files, &causal, &args.events, &[], None)?.0)?;
    let mut report = Report::new(
        name,
        Narration::training(name, "causally band-passed epochs (as a session runs it)"),
    );
    let live = evaluate::train_with(
        &trained.params,
        &live_set,
        folds.unwrap_or(evaluate::DECISION_FOLDS),
        &mut |p| report.on(p),
    );
    report.finish();
    let live = live.context("fitting the live (causal) model")?;
    drop(live_set);
    // Said once the model is written; the time is the training's.
    let seconds = t0.elapsed().as_secs_f64();
    let said = text::trained(name, &trained, &live, args.files.len(), seconds, &args.out);
    let model = evaluate::session_model(pre, ch_names, trained, live);
    oddball_io::write_atomic(&args.out, model.to_json())
        .with_context(|| format!("writing {}", args.out.display()))?;
    print!("{said}");
    Ok(())
}

pub fn run_evaluate(args: &EvaluateArgs) -> Result<()> {
    if args.unsupervised {
        return evaluate_unsupervised(args);
    }
    if let Some(path) = &args.model {
        let model = load_model(path)?;
        if let Some(first) = args.test.first() {
            if is_session(&dataset::read(first, &ReadOptions::default()).map_err(with_flags)?) {
                return evaluate_sessions(args, &model, path);
            }
        }
        // The data is matched to the model (channels by name, rate) before any filtering.
        let layout = Layout::of_model(&model, path);
        let (test, _) = load_epochs(
            &args.test,
            &model.preprocess,
            &args.events,
            &args.test_text,
            Some(&layout),
        )?;
        let r = evaluate::score_model(&model, &path.display().to_string(), &test)?;
        print!("{}{}", text::RESULT_HEADER, text::result_row(&r));
        return finish(args, &[r]);
    }
    let pre = Preprocess::peer();
    let (train, layout) = load_epochs(&args.train, &pre, &args.events, &[], None)?;
    let (test, _) = load_epochs(
        &args.test,
        &pre,
        &args.events,
        &args.test_text,
        layout.as_ref(),
    )?;
    let params = EvaluateParams {
        presets: args.pipeline.0.clone(),
        folds: args.folds,
        tune: args.tune,
    };
    let train = TrainingSet::pool(train)?;
    let mut report = Report::new("evaluate", Narration::evaluating());
    let results = evaluate::evaluate(&params, &train, &test, &mut |p| report.on(p));
    report.finish();
    finish(args, &results?)
}

/// The plot (if asked) and the JSON (if asked).
fn finish(args: &EvaluateArgs, results: &[PipelineResult]) -> Result<()> {
    if let Some(path) = &args.plot {
        if results.iter().any(|r| r.speller_accuracy.is_some()) {
            oddball_plot::accuracy::draw_accuracy(path, results)?;
            println!("wrote {}", path.display());
        } else {
            print!("{}", text::no_accuracy_plot(args.test.is_empty()));
        }
    }
    write_json(args, results)
}

fn write_json(args: &EvaluateArgs, results: &(impl serde::Serialize + ?Sized)) -> Result<()> {
    match &args.out {
        Some(path) => crate::load::write_out(path, serde_json::to_string_pretty(results)?),
        None => Ok(()),
    }
}

/// Re-evaluates oddball session files (`oddball demo` writes `session.dat`) with a model:
/// every online decision recomputed from the raw EEG, compared with the recorded one.
fn evaluate_sessions(args: &EvaluateArgs, model: &Model, model_path: &Path) -> Result<()> {
    let mut results = Vec::new();
    for path in &args.test {
        let r = sessions::redecide(path, model, model_path)?;
        print!("{}", text::redecided(&r));
        results.push(r.result);
    }
    write_json(args, &results)
}

/// Where an unsupervised replay's EM starts (`--em-start`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum EmStart {
    Template,
    Random,
}

/// The unsupervised decoder's covariance (`--covariance`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CovarianceArg {
    LedoitWolf,
    BlockToeplitz,
}

/// `evaluate --unsupervised`: the test recordings as one unlabelled session.
fn evaluate_unsupervised(args: &EvaluateArgs) -> Result<()> {
    let pre = if args.causal {
        Preprocess::peer().as_causal()
    } else {
        Preprocess::peer()
    };
    // The pooled start is read and checked before any EEG.
    let transfer = crate::load::pooled_start(&args.transfer)?;
    let (test, _) = load_epochs(&args.test, &pre, &args.events, &args.test_text, None)?;
    let settings = unsupervised::ReplaySettings {
        template: args.em_start == EmStart::Template,
        transfer: transfer.as_ref(),
        block_toeplitz: args.covariance == CovarianceArg::BlockToeplitz,
    };
    let mut shown: Option<Bar> = None;
    let r = unsupervised::replay(&pre, &test, &settings, &mut |k, n| {
        shown
            .get_or_insert_with(|| {
                bar(
                    n as u64,
                    "unsupervised [{bar:30}] {pos}/{len} characters {elapsed}",
                )
            })
            .set_position(k as u64 + 1);
    });
    if let Some(b) = shown {
        b.finish_and_clear();
    }
    let r = r.map_err(|e| match e {
        e @ unsupervised::ReplayError::Unscorable { .. } => {
            anyhow::anyhow!("{e}; give it with --test-text")
        }
        e @ unsupervised::ReplayError::NotSpeller { .. } => {
            anyhow::anyhow!("{e}; a data set's manifest can give its geometry: --manifest FILE")
        }
        e => e.into(),
    })?;
    print!("{}", text::unsupervised(&r));
    if let Some(path) = &args.out {
        let v = serde_json::json!({ "unsupervised": r });
        std::fs::write(path, serde_json::to_string_pretty(&v)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
