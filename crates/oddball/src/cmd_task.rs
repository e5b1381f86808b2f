//! `oddball task track|draw`: the paper's point-to-point target tracking and drawing tasks with a
//! simulated or replayed subject, and the metrics a BCI study reports.
//!
//! Writes a report folder like `oddball demo`: `decisions.csv`, `summary.json`, `model.json`,
//! `erp.png`, `pen_trace.png` (the arm, and the pen trace over the intended path with the
//! executed path and the wrong and abstained decisions marked), `task.png` (tracking: targets,
//! the path taken and the minimal path; drawing: the pen panel alone, under the task's result),
//! and for simulated subjects the raw session `session.dat`.

use std::time::Instant;

use anyhow::{Context, Result};
use oddball_app::task::TaskRun;
use oddball_session::tasks::TrackParams;

use crate::args::{app_error, PanelOptions, SessionOptions, SourceArgs};

/// Options of `oddball task`.
#[derive(Debug, clap::Args)]
pub struct TaskArgs {
    #[command(subcommand)]
    pub task: TaskKind,
}

#[derive(Debug, clap::Subcommand)]
pub enum TaskKind {
    /// Steer the pen to targets on the board, one after another.
    Track(TrackArgs),
    /// Draw letters and digits with the built-in stroke font.
    Draw(DrawArgs),
}

#[derive(Debug, clap::Args)]
pub struct TrackArgs {
    #[command(flatten)]
    pub session: SessionOptions,
    /// Seeded targets to place (each 2–5 steps from the previous one).
    #[arg(long, default_value_t = 10)]
    pub targets: usize,
    /// An explicit target "x,z" in metres (repeat for several); snapped to the step grid.
    #[arg(long = "target", value_name = "X,Z")]
    pub target: Vec<String>,
    /// The settled pen must be this close to the target, millimetres.
    #[arg(long, default_value_t = 1.0)]
    pub tolerance_mm: f64,
    #[command(flatten)]
    pub panel: PanelOptions,
    #[command(flatten)]
    pub source: SourceArgs,
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/track", value_parser = crate::args::output_dir)]
    pub out: std::path::PathBuf,
}

#[derive(Debug, clap::Args)]
pub struct DrawArgs {
    #[command(flatten)]
    pub session: SessionOptions,
    /// Text to draw: A–Z, 0–9 and spaces.
    #[arg(long = "draw", value_name = "TEXT", default_value = "HI")]
    pub text: String,
    #[command(flatten)]
    pub panel: PanelOptions,
    #[command(flatten)]
    pub source: SourceArgs,
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/draw", value_parser = crate::args::output_dir)]
    pub out: std::path::PathBuf,
}

/// Runs the task; `Some(reason)` when it stopped before its end.
pub fn run(args: &TaskArgs) -> Result<Option<String>> {
    let wall = Instant::now();
    let mut out = std::io::stdout();
    let (session, done) = match &args.task {
        TaskKind::Track(a) => {
            let params = track_params(a)?;
            let run = task_run(&a.session, &a.source, &a.panel, &a.out)?;
            (&a.session, run.track(&params, &mut out))
        }
        TaskKind::Draw(a) => {
            let run = task_run(&a.session, &a.source, &a.panel, &a.out)?;
            (&a.session, run.draw(&a.text, &mut out))
        }
    };
    let stopped = done.map_err(|e| app_error(e, session))?;
    eprintln!("wall time {:.2} s", wall.elapsed().as_secs_f64());
    Ok(stopped)
}

fn task_run(
    session: &SessionOptions,
    source: &SourceArgs,
    panel: &PanelOptions,
    out: &std::path::Path,
) -> Result<TaskRun> {
    Ok(TaskRun {
        settings: session.settings(),
        source: source.settings()?,
        panel: panel.settings(),
        out: out.to_path_buf(),
    })
}

fn parse_target(s: &str) -> Result<[f64; 2]> {
    let (x, z) = s
        .split_once(',')
        .with_context(|| format!("--target {s}: expected X,Z in metres"))?;
    let p = [
        x.trim()
            .parse::<f64>()
            .with_context(|| format!("--target {s}: x"))?,
        z.trim()
            .parse::<f64>()
            .with_context(|| format!("--target {s}: z"))?,
    ];
    if !p.iter().all(|v| v.is_finite()) {
        anyhow::bail!("--target {s}: not a finite position");
    }
    Ok(p)
}

/// The tracking task's parameters (checked against the arm by the run, before any EEG work).
fn track_params(args: &TrackArgs) -> Result<TrackParams> {
    let targets = if args.target.is_empty() {
        None
    } else {
        Some(
            args.target
                .iter()
                .map(|t| parse_target(t))
                .collect::<Result<Vec<_>>>()?,
        )
    };
    Ok(TrackParams {
        n_targets: args.targets,
        seed: args.session.seed,
        targets,
        tolerance_m: args.tolerance_mm * 1e-3,
        ..TrackParams::default()
    })
}
