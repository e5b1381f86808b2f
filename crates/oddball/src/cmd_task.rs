//! `oddball task track|draw`: the paper's point-to-point target tracking and drawing tasks with a
//! simulated or replayed subject, and the metrics a BCI study reports.
//!
//! Writes a report folder like `oddball demo`: `decisions.csv`, `summary.json`, `model.json`,
//! `erp.png`, `pen_trace.png` (the arm, and the pen trace over the intended path with the
//! executed path and the wrong and abstained decisions marked), `task.png` (tracking: targets,
//! the path taken and the minimal path; drawing: the pen panel alone, under the task's result),
//! and for simulated subjects the raw session `session.dat`.

use std::fs;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use oddball_arm::{ArmSim, Vector2};
use oddball_live::panel::PanelConfig;
use oddball_live::source::AnySource;
use oddball_session::decision::Decision;
use oddball_session::report::{
    accuracy_over_time, accuracy_over_time_text, draw_text, executed_path, missed_decisions,
};
use oddball_session::tasks::{
    check_drawing, drawing_path, run_drawing, run_tracking, task_targets, Pilot, TrackParams,
};
use serde::Serialize;

use crate::args::{PanelOptions, SessionOptions, SourceArgs};
use crate::pilot::{prepare, write_decisions_csv, AnyPilot, Prepared};

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

/// What a task shows on the panel: its targets and planned path, metres.
struct TaskView {
    targets_m: Vec<[f64; 2]>,
    plan_m: Vec<[f64; 2]>,
}

/// The calibrated pilot of a task; with `--serve`, the panel shows the task and the session
/// runs in real time in front of it (calibration ran unpaced).
fn prepare_task(
    opts: &SessionOptions,
    source: &SourceArgs,
    what: &str,
    panel: &PanelOptions,
    view: impl Fn(&ArmSim) -> Result<TaskView>,
) -> Result<Prepared> {
    let (_, rule) = opts.rules()?;
    match (crate::pilot::replay_files(opts)?, opts.preset()) {
        (Some(files), _) => {
            if panel.serve.is_some() {
                anyhow::bail!("--serve: the panel runs with simulated subjects; a replayed recording's flashes are already fixed");
            }
            println!(
                "oddball task {what}: replaying {} (calibration {}), pipeline {}",
                files.test_names(),
                files.calibration_names(),
                opts.pipeline
            );
        }
        (None, preset) => println!(
            "oddball task {what}: {} simulated subject (seed {}), pipeline {}",
            preset.expect("a simulated preset when not replaying"),
            opts.seed,
            opts.pipeline
        ),
    }
    let mut prep = prepare(opts, source, rule, opts.realtime, |_, replay| {
        println!(
            "{} decisions available in the recording",
            replay.remaining()
        );
        Ok(())
    })?;
    if let AnyPilot::Live(session) = &mut prep.pilot {
        let arm = Pilot::arm(session).clone();
        let v = view(&arm)?;
        let config = PanelConfig::for_arm(
            &arm,
            &session.params().paradigm,
            v.targets_m,
            v.plan_m,
            format!("task {what} · {} subject · {}", prep.subject, opts.pipeline),
        );
        let clock = session.subject().clock();
        if let Some(p) = panel.start(config, clock)? {
            // The task runs in real time in front of the page; calibration ran unpaced.
            let subject = session.subject_mut();
            if let AnySource::Sim(sim) = subject.source_mut() {
                sim.pace_from_now(source.sim_latency_ms);
            }
            subject.attach_panel(p);
        }
    }
    Ok(prep)
}

pub fn run(args: &TaskArgs) -> Result<()> {
    match &args.task {
        TaskKind::Track(a) => run_track(a),
        TaskKind::Draw(a) => run_draw(a),
    }
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

fn run_track(args: &TrackArgs) -> Result<()> {
    let wall = Instant::now();
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
    let params = TrackParams {
        n_targets: args.targets,
        seed: args.session.seed,
        targets,
        tolerance_m: args.tolerance_mm * 1e-3,
        ..TrackParams::default()
    };
    // Before calibrating: the targets, tolerance and count (TrackParams::check).
    params
        .check(&args.session.arm()?)
        .context("checking --target/--targets/--tolerance-mm")?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let mut prep = prepare_task(&args.session, &args.source, "track", &args.panel, |arm| {
        Ok(TaskView {
            targets_m: task_targets(arm, &params)
                .iter()
                .map(|p| [p[0], p[1]])
                .collect(),
            plan_m: Vec::new(),
        })
    })?;
    let report = run_tracking(&mut prep.pilot, &params)?;
    print!("{report}");
    let targets: Vec<Vector2<f64>> = report
        .targets
        .iter()
        .map(|t| Vector2::new(t.target_m[0], t.target_m[1]))
        .collect();
    let step_m = prep.pilot.arm().settings().step_m;
    let intended = oddball_session::tasks::intended_track_path(prep.pen_start, &targets, step_m);
    write_common(&args.out, &prep, &report.steps, &intended, None)?;
    oddball_plot::task::draw_track(&args.out.join("task.png"), prep.pilot.arm(), &report)
        .context("drawing task.png")?;
    write_summary(&args.out, "track", &args.session, &prep, &report)?;
    finish(prep, &args.out, wall)
}

fn run_draw(args: &DrawArgs) -> Result<()> {
    let wall = Instant::now();
    // Before calibrating: the text must fit the board at this step.
    args.session.rules()?;
    check_drawing(&args.session.arm()?, &args.text).map_err(|e| {
        crate::args::off_board(e, &format!("--draw {:?}", args.text), "shorter text")
    })?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let mut prep = prepare_task(&args.session, &args.source, "draw", &args.panel, |arm| {
        Ok(TaskView {
            targets_m: Vec::new(),
            plan_m: drawing_path(arm, &args.text)?
                .iter()
                .map(|p| [p[0], p[1]])
                .collect(),
        })
    })?;
    let report = run_drawing(&mut prep.pilot, &args.text, 3, 1.0)
        .with_context(|| format!("drawing {:?}", args.text))?;
    print!("{}", draw_text(&report));
    let plan: Vec<Vector2<f64>> = report
        .plan_path_m
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    let title = format!(
        "Drawing {:?}: {} in {} decisions (plan {}), pen within {:.3} mm of the plan",
        report.text,
        if report.completed {
            "completed"
        } else {
            "NOT completed"
        },
        report.decisions,
        report.min_decisions,
        report.max_deviation_m * 1e3
    );
    write_common(&args.out, &prep, &report.steps, &plan, Some(&title))?;
    write_summary(&args.out, "draw", &args.session, &prep, &report)?;
    finish(prep, &args.out, wall)
}

/// decisions.csv, model.json, erp.png (after a labelled calibration) and pen_trace.png (the
/// `intended` path, the executed one and the missed decisions), and with `task_title` the pen
/// panel alone as task.png; prints the accuracy over time.
fn write_common(
    out: &Path,
    prep: &Prepared,
    steps: &[Decision],
    intended: &[Vector2<f64>],
    task_title: Option<&str>,
) -> Result<()> {
    write_decisions_csv(&out.join("decisions.csv"), steps)?;
    oddball_io::write_atomic(out.join("model.json"), crate::pilot::model_json(prep)?)
        .context("writing model.json")?;
    let rows = steps;
    println!("{}", accuracy_over_time_text(&accuracy_over_time(rows, 10)));
    // An uncalibrated session has no labelled epochs to draw.
    if prep.erp.n_epochs() > 0 {
        let erp_png = out.join("erp.png");
        oddball_plot::task::draw_calibration_erp(&erp_png, &prep.erp)
            .with_context(|| format!("drawing {}", erp_png.display()))?;
    }
    let arm = prep.pilot.arm();
    let step_m = arm.settings().step_m;
    let executed = executed_path(prep.pen_start, rows, step_m);
    let missed = missed_decisions(prep.pen_start, rows, step_m);
    let paths = oddball_plot::arm::SessionPaths {
        intended,
        executed: &executed,
        missed: &missed,
        numbered: false,
    };
    let pen_png = out.join("pen_trace.png");
    oddball_plot::arm::draw_pen_trace(arm, &paths, &pen_png)
        .with_context(|| format!("drawing {}", pen_png.display()))?;
    if let Some(title) = task_title {
        let task_png = out.join("task.png");
        oddball_plot::arm::draw_pen_paths(arm, &paths, title, &task_png)
            .with_context(|| format!("drawing {}", task_png.display()))?;
    }
    Ok(())
}

/// summary.json: what ran, the calibration and the task's report.
fn write_summary<T: Serialize>(
    out: &Path,
    task: &'static str,
    opts: &SessionOptions,
    prep: &Prepared,
    report: &T,
) -> Result<()> {
    let summary = prep.task_summary(task, opts.pipeline.name(), opts.seed, report);
    let json = serde_json::to_string_pretty(&summary)?;
    oddball_io::write_atomic(out.join("summary.json"), json + "\n").context("writing summary.json")
}

/// Saves a live session's raw EEG and prints the wall time.
fn finish(prep: Prepared, out: &Path, wall: Instant) -> Result<()> {
    crate::pilot::save_session(
        prep,
        out,
        &format!("task over: report in {}", out.display()),
    )?;
    println!("report in {}", out.display());
    eprintln!("wall time {:.2} s", wall.elapsed().as_secs_f64());
    Ok(())
}
