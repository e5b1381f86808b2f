//! `oddball`: a P300 brain–computer interface that steers a simulated robot arm.
//!
//! Subcommands live in `cmd_*.rs`; errors are printed as a chain (`error: …: caused by …`) and the
//! process exits with status 1 (2 for command-line usage errors, which clap reports itself). A
//! session (`demo`, `task`, `online`) that stopped before its end — a signal, the operator's
//! abort, the amplifier lost, a replayed recording's end — keeps and writes what it has and
//! exits with status 3 ([`STOPPED`]); 0 means it ran to its end. A second signal ends the process
//! at once (130). A reader that closes standard output early (`oddball inspect FILE | head -1`)
//! ends the program quietly with status 0, as in other command-line tools.

// The doc comments of the clap arguments are `--help` text (`[default: <out>/arm.png]`), not
// rustdoc markup.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod args;
mod cmd_arm;
mod cmd_benchmark;
mod cmd_decode;
mod cmd_demo;
mod cmd_export;
mod cmd_inspect;
mod cmd_online;
mod cmd_simulate;
mod cmd_task;
mod cmd_train;
mod load;
mod preset_arg;
mod progress;

#[derive(Debug, Parser)]
#[command(
    name = "oddball",
    version = version(),
    about = "P300 brain-computer interface driving a simulated robot arm"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The version; for `--version` also what LSL can do here (liblsl is loaded only then).
fn version() -> &'static str {
    const VERSION: &str = env!("CARGO_PKG_VERSION");
    if std::env::args_os()
        .skip(1)
        .any(|a| a == "--version" || a == "-V")
    {
        let lsl = oddball_live::lsl::library_status();
        return Box::leak(format!("{VERSION} (LSL: {lsl})").into_boxed_str());
    }
    VERSION
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The whole closed loop without hardware: calibrate, then steer the arm through the letter G.
    #[command(after_help = "Examples:
  oddball demo                                   # simulated subject, report in out/demo
  oddball demo --subject hard --dynamic-stopping --out out/hard
  oddball demo --model m.json                    # no calibration: a model from `oddball train`
  oddball demo --subject replay:../shared/data/bci2000-samplefiles-p300/eeg3_2.dat
  D=../shared/data/bci-competition-ii-iib   # BCI II IIb: test runs, training runs, their texts
  oddball demo --subject replay:$D/AAS012R03.mat,$D/AAS012R04.mat \\
    --calibration $D/AAS010R01.mat,$D/AAS010R02.mat,$D/AAS011R01.mat,$D/AAS011R02.mat \\
    --test-text HAM,PIE --paradigm fast --optimise-stopping --round-limit 5")]
    Demo(cmd_demo::DemoArgs),
    /// Tasks: steer the pen to targets (track) or draw text (draw), with study metrics.
    #[command(after_help = "Examples:
  oddball task track --targets 5
  oddball task draw --draw HI
  oddball task draw --draw HELLO --step 0.01     # smaller steps so the text fits the board")]
    Task(cmd_task::TaskArgs),
    /// A live session: EEG from a live stream, the stimulus panel in a browser, recorded as it runs.
    #[command(after_help = "Examples:
  oddball online --source sim --calibrate --serve 127.0.0.1:8080
  oddball online --source lsl:type=EEG --calibrate --serve 127.0.0.1:8080
  oddball online --source nic:127.0.0.1:1234 --model out/demo/model.json")]
    Online(Box<cmd_online::OnlineArgs>),
    /// Decode another program's P300 session: EEG and its stimulus markers over LSL in, decisions out (LSL outlet, JSON lines).
    #[command(after_help = "Examples:
  oddball decode --source lsl:EEG --markers lsl:MARKERS --paradigm paradigms/speller-6x6.toml --model M.json --out decisions.jsonl
  oddball decode --source lsl:type=EEG --markers lsl:type=Markers --paradigm paradigms/four-bulb.toml --calibration none
  oddball decode --source replay:eeg3_2.dat --markers recording --paradigm paradigms/speller-6x6-rows-first.toml --model M.json --fast")]
    Decode(Box<cmd_decode::DecodeArgs>),
    /// Serve the simulated subject as a live amplifier stream: NIC's TCP protocol or an LSL outlet.
    #[command(after_help = "Examples:
  oddball simulate --nic 127.0.0.1:1234          # then: oddball demo --source nic:127.0.0.1:1234
  oddball simulate --lsl oddball-sim          ")]
    Simulate(cmd_simulate::SimulateArgs),
    /// Summarise EEG recordings: channels, sfreq, events, targets, spelled text; optionally plot ERPs.
    #[command(after_help = "Examples:
  oddball inspect eeg3_1.dat --plot erp.png
  oddball inspect muse.csv --target-events 2 --nontarget-events 1")]
    Inspect(cmd_inspect::InspectArgs),
    /// Fit a decoding pipeline on recordings and save the model (JSON).
    #[command(after_help = "Examples:
  oddball train eeg3_1.dat --pipeline lda -o model.json
  oddball train run1.csv run2.csv --target-events 2 --nontarget-events 1 --tune -o model.json")]
    Train(cmd_train::TrainArgs),
    /// Score pipelines on held-out recordings (or by cross-validation): AUC, speller accuracy vs repetitions, ITR.
    #[command(after_help = "Examples:
  oddball evaluate --train eeg3_1.dat --test eeg3_2.dat --pipeline all --plot accuracy.png
  oddball evaluate --train session.dat --pipeline lda,riemann --tune   # nested cross-validation
  oddball evaluate --test eeg3_2.dat --model model.json")]
    Evaluate(cmd_train::EvaluateArgs),
    /// Every preset on every subject of dataset manifests (MOABB's protocols): per-subject rows, means, paired tests, JSON/CSV/plot.
    #[command(after_help = "Examples:
  oddball benchmark datasets/bci2000-eeg3.toml --pipeline all --json results.json --plot results.png
  oddball benchmark datasets/*.toml --protocol within-session --folds 5")]
    Benchmark(cmd_benchmark::BenchmarkArgs),
    /// Write recordings as a BIDS-EEG data set (EDF+, sidecars, events with targets and codes).
    #[command(after_help = "Examples:
  oddball export --bids bids/ --subject PXB eeg3_1.dat eeg3_2.dat     # runs 1 and 2 of task eeg31
  oddball export --bids bids/ --subject 1 --session 1 --task visualp300 run1.csv run2.csv \\
      --target-events 2 --nontarget-events 1 --line-freq 60
  oddball export --bids bids/ --subject 01 --task online out/online/session.xdf   # the XDF under sourcedata/")]
    Export(cmd_export::ExportArgs),
    /// Simulate the 2-DoF arm following direction commands (the paper's G by default).
    #[command(after_help = "Examples:
  oddball arm                                    # the paper's six commands
  oddball arm --commands up,up,right --step 0.01 --plot arm.svg")]
    Arm(cmd_arm::ArmArgs),
}

/// Whether `err` (or one of its causes) is a write into a closed pipe.
fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// `print!` panics when standard output is a closed pipe (Rust ignores SIGPIPE); that panic
/// ends the program with status 0 instead, every other panic is reported as usual.
fn exit_quietly_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.starts_with("failed printing to stdout")
            && message.to_ascii_lowercase().contains("broken pipe")
        {
            std::process::exit(0);
        }
        default(info);
    }));
}

/// SIGINT and SIGTERM ask a live session to stop (`oddball_live::stop`): it closes its
/// recording and writes what it has. A second signal ends the process at once (exit 130).
fn stop_on_signals() {
    let flag = oddball_live::stop::flag();
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // The first signal sets the flag; the conditional exit fires once it is set.
        let _ = signal_hook::flag::register_conditional_shutdown(signal, 130, flag.clone());
        let _ = signal_hook::flag::register(signal, flag.clone());
    }
}

/// The flags that fix an error the libraries state as a fact (they name no flag).
fn flag_hint(err: &anyhow::Error) -> Option<&'static str> {
    let unlabelled = err.chain().any(|c| {
        matches!(
            c.downcast_ref::<oddball_eval::dataset::DatasetError>(),
            Some(oddball_eval::dataset::DatasetError::Unlabelled { .. })
        )
    });
    unlabelled.then_some(
        "with the command line: --target-events and --nontarget-events (codes or marker texts, \
         e.g. --target-events 2 --nontarget-events 1), or --test-text for a speller run",
    )
}

/// The exit status of a session that stopped before its end, what it had kept and written.
const STOPPED: u8 = 3;

fn main() -> ExitCode {
    exit_quietly_on_broken_pipe();
    let cli = Cli::parse();
    if matches!(
        cli.command,
        Command::Demo(_) | Command::Task(_) | Command::Online(_) | Command::Decode(_)
    ) {
        stop_on_signals();
    }
    let done = |r: anyhow::Result<()>| r.map(|()| None);
    let result = match cli.command {
        Command::Demo(args) => cmd_demo::run(&args),
        Command::Task(args) => cmd_task::run(&args),
        Command::Online(args) => cmd_online::run(&args),
        Command::Decode(args) => cmd_decode::run(&args),
        Command::Simulate(args) => done(cmd_simulate::run(&args)),
        Command::Inspect(args) => done(cmd_inspect::run(&args)),
        Command::Train(args) => done(cmd_train::run_train(&args)),
        Command::Evaluate(args) => done(cmd_train::run_evaluate(&args)),
        Command::Benchmark(args) => done(cmd_benchmark::run(&args)),
        Command::Arm(args) => done(cmd_arm::run(&args)),
        Command::Export(args) => done(cmd_export::run(&args)),
    };
    match result {
        Ok(None) => ExitCode::SUCCESS,
        Ok(Some(_stopped)) => ExitCode::from(STOPPED),
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("oddball: error: {err}");
            // A cause whose text the previous message already quotes adds nothing.
            let mut previous = err.to_string();
            for cause in err.chain().skip(1) {
                let text = cause.to_string();
                if !previous.contains(&text) {
                    eprintln!("  caused by: {text}");
                }
                previous = text;
            }
            if let Some(hint) = flag_hint(&err) {
                eprintln!("  {hint}");
            }
            ExitCode::FAILURE
        }
    }
}
