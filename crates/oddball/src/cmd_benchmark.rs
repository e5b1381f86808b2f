//! `oddball benchmark`: the arguments, the progress bar and the files. The evaluation itself is
//! `oddball_eval::benchmark`'s, the tables printed `oddball_eval::text`'s.

use std::path::PathBuf;
use std::str::FromStr;

use anyhow::{Context, Result};
use oddball_decode::pipeline::Preprocess;
use oddball_eval::benchmark::{self, BenchmarkError, BenchmarkParams, Progress, Protocol};
use oddball_eval::pooled::Transfer;
use oddball_eval::text;
use oddball_io::Manifest;

use crate::load::write_out;
use crate::preset_arg::{list_help, PipelineList, DEFAULT_PIPELINE};

/// `--protocol a,b` or `all`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProtocolList(pub Vec<Protocol>);

impl FromStr for ProtocolList {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        crate::preset_arg::list(s, &Protocol::ALL, str::parse).map(Self)
    }
}

#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example:\n  oddball benchmark datasets/*.toml --pipeline all --protocol \
                        train-test,within-session --json bench.json --csv bench.csv --plot \
                        bench.png"
)]
pub struct BenchmarkArgs {
    /// Dataset manifests (TOML: subjects, train/test runs, event mapping, speller geometry;
    /// shipped ones in datasets/), or BIDS data set roots (a folder with
    /// dataset_description.json: subjects and sessions from its tree, events and speller from
    /// each run's sidecars; no train/test split, so train-test is skipped for it).
    #[arg(required = true, value_name = "MANIFEST")]
    pub manifests: Vec<PathBuf>,
    #[arg(long, default_value = DEFAULT_PIPELINE, value_name = "NAME[,NAME…]|all", help = list_help())]
    pub pipeline: PipelineList,
    /// Evaluation protocols, comma-separated, or `all`: train-test (the manifest's train runs →
    /// its test runs), within-session (k-fold CV in each session), cross-subject (leave one
    /// subject out), unsupervised (a speller subject's runs in order as one unlabelled session:
    /// characters right online and post hoc, AUC; no preset).
    #[arg(long, default_value = "train-test", value_name = "NAME[,NAME…]|all")]
    pub protocol: ProtocolList,
    /// Folds of the within-session cross-validation.
    #[arg(long, default_value_t = 5)]
    pub folds: usize,
    /// The folder the manifests' run paths are relative to, instead of each manifest's `root`
    /// (a BIDS root's runs are in its own tree).
    #[arg(long, value_name = "DIR")]
    pub data: Option<PathBuf>,
    /// Threads for the evaluations (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write every row, the summary and the comparisons as JSON here.
    #[arg(long, value_name = "FILE", value_parser = crate::args::output_file)]
    pub json: Option<PathBuf>,
    /// Write every row as CSV here.
    #[arg(long, value_name = "FILE", value_parser = crate::args::output_file)]
    pub csv: Option<PathBuf>,
    /// Draw per-subject AUC per preset and mean character accuracy vs repetitions (.png/.svg).
    #[arg(long, value_name = "FILE", value_parser = crate::args::plot_file)]
    pub plot: Option<PathBuf>,
    /// The unsupervised protocol's pooled start, one more start of every refit: `none`;
    /// `pooled` (the one shipped); `lodo` (leave one data set out: built per data set from the
    /// labelled recordings of every other manifest given); or a file (`--write-pooled`).
    #[arg(long, value_name = "none|pooled|lodo|FILE", default_value = "none")]
    pub transfer: String,
    /// Build the pooled start from every subject of the manifests (labelled; zero-phase and
    /// causal), write it here and stop (the shipped one is `oddball benchmark datasets/*.toml
    /// --write-pooled crates/oddball-decode/src/unsupervised/pooled.json`).
    #[arg(long, value_name = "FILE", value_parser = crate::args::output_file)]
    pub write_pooled: Option<PathBuf>,
}

pub fn run(args: &BenchmarkArgs) -> Result<()> {
    // Everything checked before any EEG is read: the output files (their folders and the
    // plot's format, when the command line is parsed), the threads, the manifests, the plan.
    if args.threads == Some(0) {
        anyhow::bail!("--threads must be at least 1");
    }
    let manifests = args
        .manifests
        .iter()
        .map(|m| -> Result<Manifest> {
            if m.join("dataset_description.json").is_file() {
                return Ok(oddball_io::bids::dataset_manifest(m)?);
            }
            Ok(Manifest::load_with_root(m, args.data.as_deref())?)
        })
        .collect::<Result<Vec<_>>>()?;
    let transfer = match args.transfer.as_str() {
        "lodo" => Transfer::LeaveOneDataSetOut,
        other => match crate::load::pooled_start(other)? {
            Some(s) => Transfer::Given(s),
            None => Transfer::None,
        },
    };
    let params = BenchmarkParams {
        presets: args.pipeline.0.clone(),
        protocols: args.protocol.0.clone(),
        folds: args.folds,
        preprocess: Preprocess::peer(),
        transfer,
    };
    if let Some(path) = &args.write_pooled {
        let start = oddball_eval::pooled::build(&manifests, &params.preprocess, &|_| {})?;
        write_out(path, start.to_json())?;
        return Ok(());
    }
    let plan = params.plan(&manifests).map_err(|e| match e {
        BenchmarkError::Folds(k) => {
            anyhow::anyhow!("--folds {k}: cross-validation needs at least 2 folds")
        }
        e => e.into(),
    })?;
    for s in &plan.skipped {
        println!("skipped: {s}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()
        .context("starting the worker threads")?;
    let bar = crate::progress::bar(0, "{msg} [{bar:30}] {pos}/{len} {elapsed} (eta {eta})");
    let on = |p: Progress<'_>| match p {
        Progress::Plan { subjects, units } => {
            bar.set_length((subjects + units) as u64);
            bar.set_message(format!("reading {subjects} subjects, {units} evaluations"));
        }
        Progress::Loaded { .. } | Progress::Done { .. } => bar.inc(1),
        Progress::Resampled { run, resampled, of } => {
            bar.suspend(|| eprint!("{}", text::resampled(run, resampled, of)))
        }
    };
    let report = pool.install(|| benchmark::run(&params, &manifests, &on));
    bar.finish_and_clear();
    let report = report?;
    for s in report.skipped.iter().skip(plan.skipped.len()) {
        println!("skipped: {s}");
    }
    print!("{}", text::benchmark(&report));
    if let Some(path) = &args.json {
        write_out(path, serde_json::to_string_pretty(&report)?)?;
    }
    if let Some(path) = &args.csv {
        write_out(path, benchmark::to_csv(&report.results))?;
    }
    if let Some(path) = &args.plot {
        oddball_plot::benchmark::draw_benchmark(path, &report, None)
            .with_context(|| format!("drawing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn protocol_lists() {
        let l: ProtocolList = "within-session,train-test,train-test".parse().unwrap();
        assert_eq!(l.0, [Protocol::WithinSession, Protocol::TrainTest]);
        assert_eq!("all".parse::<ProtocolList>().unwrap().0.len(), 4);
        assert!("nope"
            .parse::<ProtocolList>()
            .unwrap_err()
            .contains("or all"));
    }
}
