//! `oddball demo`: the whole closed loop with no hardware, as a copy task with fixed commands
//! (by default the letter G of the drawing task's stroke font; `--commands paper-g` gives the
//! paper's six commands, which on equal steps trace a square). A subject (simulated, over any
//! `--source`, or real EEG replayed) watches the four-bulb panel; the session calibrates, trains a pipeline, then decodes each
//! intended command and the arm draws it.
//!
//! Writes a report folder: `decisions.csv`, `summary.json`, `pen_trace.png`, `erp.png` (the
//! calibration epochs), `model.json`, and for live sessions the raw session `session.dat`
//! (BCI2000, float32; `session.easy` when the EEG came over NIC's TCP stream) that
//! `oddball evaluate --model model.json --test session.dat` re-evaluates to the same decisions.
//! In this process, every file depends only on the options (same seed, same bytes); wall-clock
//! times are printed, never written.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use oddball_app::demo::Demo;
use oddball_arm::Command;

use crate::args::{app_error, commands_arg, SessionOptions, SourceArgs, COMMANDS_HELP, STROKE_G};

/// Options of `oddball demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    #[command(flatten)]
    pub session: SessionOptions,
    #[arg(long, default_value = STROKE_G, value_parser = commands_arg, help = COMMANDS_HELP)]
    pub commands: std::vec::Vec<Command>,
    #[command(flatten)]
    pub source: SourceArgs,
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/demo", value_parser = crate::args::output_dir)]
    pub out: PathBuf,
}

/// Runs the demo; `Some(reason)` when it stopped before its last command.
pub fn run(args: &DemoArgs) -> Result<Option<String>> {
    let wall = Instant::now();
    let demo = Demo {
        settings: args.session.settings(),
        source: args.source.settings()?,
        commands: args.commands.clone(),
        out: args.out.clone(),
    };
    let done = demo
        .run(&mut std::io::stdout())
        .map_err(|e| app_error(e, &args.session))?;
    // Wall-clock time goes to stderr: stdout, like every file, depends only on the options.
    eprintln!(
        "wall time {:.2} s (calibration fit {:.2} s)",
        wall.elapsed().as_secs_f64(),
        done.fit_seconds,
    );
    Ok(done.stopped)
}
