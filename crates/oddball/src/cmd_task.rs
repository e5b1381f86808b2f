//! `oddball task track|draw`: the paper's point-to-point target tracking and drawing tasks with a
//! simulated or replayed subject, and the metrics a BCI study reports.
//!
//! Writes a report folder like `oddball demo`: `decisions.csv`, `summary.json`, `model.json`,
//! `erp.png`, `pen_trace.png` (the arm, and the pen trace over the planned path), `task.png`
//! (tracking: targets, the path taken and the minimal path), and for simulated subjects the raw
//! session `session.dat`.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use oddball_arm::{ArmConfig, ArmSim, Command, Vector2};
use oddball_live::live::{LiveSubject, SimSource};
use oddball_live::panel::Clock;
use oddball_session::engine::{CalibrationReport, Session};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::record::save_session;
use oddball_session::replay::{stream_epochs, ReplaySource};
use oddball_session::subject::SubjectParams;
use oddball_session::task::{
    drawing_path, run_drawing, run_tracking, task_targets, DrawReport, Pilot, ReplayPilot, Step,
    TrackParams, TrackReport,
};
use oddball_session::SessionError;
use oddball_signal::Epochs;
use serde::Serialize;

use crate::cmd_demo::{calibrated, calibrated_replay, SessionOptions, REPLAY_NOTE};
use crate::cmd_online::{panel_config, PanelOptions};

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
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/track")]
    pub out: PathBuf,
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
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/draw")]
    pub out: PathBuf,
}

/// A simulated session (its subject a live source: run unpaced, or paced with the browser
/// panel after calibration) or a replayed recording, as one pilot.
#[allow(clippy::large_enum_variant)]
enum AnyPilot {
    Sim(Session<LiveSubject<SimSource>>),
    Replay(ReplayPilot),
}

impl Pilot for AnyPilot {
    fn decide(&mut self, intended: Command) -> Result<Option<Step>, SessionError> {
        match self {
            AnyPilot::Sim(s) => Pilot::decide(s, intended),
            AnyPilot::Replay(r) => r.decide(intended),
        }
    }
    fn arm(&self) -> &ArmSim {
        match self {
            AnyPilot::Sim(s) => Pilot::arm(s),
            AnyPilot::Replay(r) => r.arm(),
        }
    }
    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        match self {
            AnyPilot::Sim(s) => s.wait(seconds),
            AnyPilot::Replay(r) => r.wait(seconds),
        }
    }
    fn time_s(&self) -> f64 {
        match self {
            AnyPilot::Sim(s) => Pilot::time_s(s),
            AnyPilot::Replay(r) => r.time_s(),
        }
    }
}

/// The calibrated pilot, its calibration, the calibration epochs and the model (JSON).
struct Prepared {
    pilot: AnyPilot,
    calibration: CalibrationReport,
    erp: Epochs,
    model_json: String,
    subject: String,
    pen_start: Vector2<f64>,
}

/// What a task shows on the panel: its targets and planned path, metres.
struct TaskView {
    targets_m: Vec<[f64; 2]>,
    plan_m: Vec<[f64; 2]>,
}

fn prepare(
    opts: &SessionOptions,
    what: &str,
    panel: &PanelOptions,
    view: impl Fn(&ArmSim) -> Result<TaskView>,
) -> Result<Prepared> {
    let (_, rule) = opts.rules()?;
    let preset = opts.preset()?;
    if panel.serve.is_some() && preset.is_none() {
        anyhow::bail!("--serve: the panel runs with simulated subjects; a replayed recording's flashes are already fixed");
    }
    match (opts.replay_files()?, preset) {
        (Some((file, cal)), _) => {
            println!(
                "oddball task {what}: replaying {} (calibration {}), pipeline {}",
                file.display(),
                cal.display(),
                opts.pipeline
            );
            let r = calibrated_replay(opts, &file, &cal, rule)?;
            let source = ReplaySource::new(&r.test, &r.model, &r.params)
                .with_context(|| format!("replaying {}", file.display()))?;
            println!(
                "{} decisions available in the recording",
                source.remaining()
            );
            let mut arm = ArmSim::from_config(&ArmConfig::default())?;
            arm.set_recording(true);
            let pen_start = arm.pen();
            let epochs = stream_epochs(&r.calibration_recording, &r.params.preprocess, 20)?;
            let erp = crate::cmd_demo::epochs_of(&r.calibration_recording, &epochs)?;
            Ok(Prepared {
                pilot: AnyPilot::Replay(ReplayPilot::new(source, arm, FourBulbParams::paper())),
                calibration: r.calibration,
                erp,
                model_json: r.model.to_json(),
                subject: format!("replay:{}", file.display()),
                pen_start,
            })
        }
        (None, preset) => {
            let preset = preset.expect("a simulated preset when not replaying");
            println!(
                "oddball task {what}: {preset} simulated subject (seed {}), pipeline {}",
                opts.seed, opts.pipeline
            );
            let sim = SubjectParams::preset(preset)
                .with_seed(opts.seed)
                .build()
                .context("building the simulated subject")?;
            let clock = Clock::new();
            let subject = LiveSubject::new(
                SimSource::unpaced(sim, clock),
                FourBulbParams::paper(),
                clock,
            );
            let (mut session, calibration, pen_start) = calibrated(opts, subject, rule, true)?;
            let arm = Pilot::arm(&session).clone();
            let v = view(&arm)?;
            let config = panel_config(
                &arm,
                &session.params().paradigm,
                v.targets_m,
                v.plan_m,
                format!("task {what} · {preset} subject · {}", opts.pipeline),
            );
            if let Some(p) = panel.start(config, clock)? {
                // The task runs in real time in front of the page; calibration ran unpaced.
                let subject = session.subject_mut();
                subject.source_mut().pace_from_now(250.0);
                subject.attach_panel(p);
            }
            let erp = session.calibration_epochs()?;
            let model_json = session
                .model()
                .map(|m| m.to_json())
                .context("the session has no model")?;
            Ok(Prepared {
                pilot: AnyPilot::Sim(session),
                calibration,
                erp,
                model_json,
                subject: preset.to_string(),
                pen_start,
            })
        }
    }
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
    if !(args.tolerance_mm.is_finite() && args.tolerance_mm > 0.0) {
        anyhow::bail!("--tolerance-mm must be a positive number");
    }
    let params = TrackParams {
        n_targets: args.targets,
        seed: args.session.seed,
        targets,
        tolerance_m: args.tolerance_mm * 1e-3,
        ..TrackParams::default()
    };
    let mut prep = prepare(&args.session, "track", &args.panel, |arm| {
        Ok(TaskView {
            targets_m: task_targets(arm, &params)
                .iter()
                .map(|p| [p[0], p[1]])
                .collect(),
            plan_m: Vec::new(),
        })
    })?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let report = run_tracking(&mut prep.pilot, &params)?;
    print!("{report}");
    let expected: Vec<Vector2<f64>> = std::iter::once(prep.pen_start)
        .chain(
            report
                .targets
                .iter()
                .flat_map(|t| t.path_m.iter().skip(1).map(|p| Vector2::new(p[0], p[1]))),
        )
        .collect();
    write_common(&args.out, &prep, &report.steps, &expected)?;
    draw_track(&args.out.join("task.png"), prep.pilot.arm(), &report)
        .context("drawing task.png")?;
    write_summary(&args.out, "track", &args.session, &prep, &report)?;
    finish(prep, &args.out, wall)
}

fn run_draw(args: &DrawArgs) -> Result<()> {
    let wall = Instant::now();
    let mut prep = prepare(&args.session, "draw", &args.panel, |arm| {
        Ok(TaskView {
            targets_m: Vec::new(),
            plan_m: drawing_path(arm, &args.text)?
                .iter()
                .map(|p| [p[0], p[1]])
                .collect(),
        })
    })?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let report = run_drawing(&mut prep.pilot, &args.text, 3, 1.0)
        .with_context(|| format!("drawing {:?}", args.text))?;
    print!("{}", draw_text(&report));
    let expected: Vec<Vector2<f64>> = report
        .plan_path_m
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    write_common(&args.out, &prep, &report.steps, &expected)?;
    write_summary(&args.out, "draw", &args.session, &prep, &report)?;
    finish(prep, &args.out, wall)
}

/// decisions.csv, model.json, erp.png and pen_trace.png.
fn write_common(
    out: &Path,
    prep: &Prepared,
    steps: &[Step],
    expected: &[Vector2<f64>],
) -> Result<()> {
    let mut csv =
        String::from("decision,intended,decided,abstained,rounds,confidence,seconds,arm_refusal\n");
    for (i, s) in steps.iter().enumerate() {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.6},{:.4},{}",
            i + 1,
            s.intended,
            s.decided.map(|c| c.to_string()).unwrap_or_default(),
            s.abstained,
            s.rounds,
            s.confidence,
            s.seconds,
            s.arm_refusal.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    fs::write(out.join("decisions.csv"), csv).context("writing decisions.csv")?;
    fs::write(out.join("model.json"), &prep.model_json).context("writing model.json")?;
    let (target, nontarget) = crate::cmd_demo::split_targets(&prep.erp);
    crate::plot_erp::draw_erp(
        &out.join("erp.png"),
        &target,
        &nontarget,
        "calibration epochs, causal 1–15 Hz",
    )
    .context("drawing erp.png")?;
    let arm = prep.pilot.arm();
    let keys = crate::cmd_arm::configurations_at(arm, &[0.0, arm.time_s()]);
    crate::cmd_arm::draw(arm, &keys, expected, &out.join("pen_trace.png"))
        .context("drawing pen_trace.png")
}

/// summary.json: what ran, the calibration and the task's report.
fn write_summary<T: Serialize>(
    out: &Path,
    task: &'static str,
    opts: &SessionOptions,
    prep: &Prepared,
    report: &T,
) -> Result<()> {
    #[derive(Serialize)]
    struct Summary<'a, T> {
        task: &'static str,
        subject: &'a str,
        pipeline: &'a str,
        seed: u64,
        calibration: &'a CalibrationReport,
        #[serde(skip_serializing_if = "Option::is_none")]
        note: Option<&'static str>,
        report: &'a T,
    }
    let summary = Summary {
        task,
        subject: &prep.subject,
        pipeline: &opts.pipeline,
        seed: opts.seed,
        calibration: &prep.calibration,
        note: matches!(prep.pilot, AnyPilot::Replay(_)).then_some(REPLAY_NOTE),
        report,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    fs::write(out.join("summary.json"), json + "\n").context("writing summary.json")
}

/// Saves a simulated session's raw EEG and prints the wall time.
fn finish(prep: Prepared, out: &Path, wall: Instant) -> Result<()> {
    if let AnyPilot::Sim(mut session) = prep.pilot {
        session
            .subject_mut()
            .end(&format!("task over: report in {}", out.display()));
        let paradigm = session.params().paradigm;
        let (log, _, _) = session.finish();
        let path = out.join("session.dat");
        save_session(&path, &log, &paradigm)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    println!("report in {}", out.display());
    eprintln!("wall time {:.2} s", wall.elapsed().as_secs_f64());
    Ok(())
}

fn draw_text(r: &DrawReport) -> String {
    format!(
        "drew {:?}: {} in {} decisions (plan {} moves); pen trace from the plan: mean {:.4} mm, max {:.4} mm\n{}",
        r.text,
        if r.completed { "completed" } else { "NOT completed" },
        r.decisions,
        r.min_decisions,
        r.mean_deviation_m * 1e3,
        r.max_deviation_m * 1e3,
        r.totals
    )
}

/// Targets (numbered), the pen's path and each target's minimal path (x first, then z).
fn draw_track(path: &Path, arm: &ArmSim, r: &TrackReport) -> Result<()> {
    let trace: Vec<(f64, f64)> = arm
        .trace()
        .points()
        .iter()
        .map(|p| (p.p[0], p.p[1]))
        .collect();
    let mut xs: Vec<f64> = trace.iter().map(|p| p.0).collect();
    let mut zs: Vec<f64> = trace.iter().map(|p| p.1).collect();
    for t in &r.targets {
        xs.push(t.target_m[0]);
        zs.push(t.target_m[1]);
    }
    let (x0, x1) = bounds(&xs);
    let (z0, z1) = bounds(&zs);
    let span = (x1 - x0).max(z1 - z0) * 0.5 + 0.01;
    let (cx, cz) = ((x0 + x1) / 2.0, (z0 + z1) / 2.0);
    crate::with_backend!(path, (900, 900), |root| {
        use plotters::prelude::*;
        let err = |e: &dyn std::fmt::Debug| anyhow::anyhow!("{e:?}");
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "Tracking: {}/{} targets reached (black: pen, dashed: minimal path)",
                    r.n_reached, r.n_attempted
                ),
                (crate::plot::FONT_FAMILY, 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(cx - span..cx + span, cz - span..cz + span)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("z (m)")
            .label_style((crate::plot::FONT_FAMILY, 13))
            .draw()
            .map_err(|e| err(&e))?;
        for t in &r.targets {
            let (a, b) = (t.start_m, t.target_m);
            let corner = (b[0], a[1]);
            for seg in [((a[0], a[1]), corner), (corner, (b[0], b[1]))] {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![seg.0, seg.1],
                        6,
                        4,
                        RGBColor(240, 140, 60).stroke_width(3),
                    ))
                    .map_err(|e| err(&e))?;
            }
        }
        chart
            .draw_series(
                trace
                    .windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], BLACK.stroke_width(2))),
            )
            .map_err(|e| err(&e))?;
        chart
            .draw_series(r.targets.iter().map(|t| {
                let colour = if t.success {
                    RGBColor(30, 140, 60)
                } else {
                    RGBColor(200, 30, 30)
                };
                EmptyElement::at((t.target_m[0], t.target_m[1]))
                    + Circle::new((0, 0), 8, colour.stroke_width(3))
                    + Text::new(
                        t.index.to_string(),
                        (10, -20),
                        (crate::plot::FONT_FAMILY, 16),
                    )
            }))
            .map_err(|e| err(&e))?;
        Ok(())
    })
}

fn bounds(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}
