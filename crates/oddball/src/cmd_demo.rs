//! `oddball demo`: the whole closed loop with no hardware, as a copy task with fixed commands
//! (the letter G by default). A subject (simulated, over any `--source`, or real EEG replayed)
//! watches the four-bulb panel; the session calibrates, trains a pipeline, then decodes each
//! intended command and the arm draws it.
//!
//! Writes a report folder: `decisions.csv`, `summary.json`, `pen_trace.png`, `erp.png` (the
//! calibration epochs), `model.json`, and for live sessions the raw session `session.dat`
//! (BCI2000, float32; `session.easy` when the EEG came over NIC's TCP stream) that
//! `oddball evaluate --model model.json --test session.dat` re-evaluates to the same decisions.
//! In this process, every file depends only on the options (same seed, same bytes); wall-clock
//! times are printed, never written.

use std::fmt::Write as _;
use std::fs;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use oddball_arm::{planned_path, Command, Vector2};
use oddball_decode::decision::DecisionRule;
use oddball_decode::metrics::Itr;
use oddball_live::clock::Clock;
use oddball_live::source::SourceSpec;
use oddball_session::engine::CalibrationReport;
use oddball_session::replay::{self, REPLAY_NOTE};
use oddball_session::task::{run_copy, Pilot, Step};
use serde::Serialize;

use crate::args::{commands_arg, SessionOptions, SourceArgs, LETTER_G};
use crate::pilot::{live_subject, prepare, write_decisions_csv};

/// Options of `oddball demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    #[command(flatten)]
    pub session: SessionOptions,
    /// Comma-separated intended commands (up, down, left, right); the paper's letter G by default.
    #[arg(long, default_value = LETTER_G, value_parser = commands_arg)]
    pub commands: std::vec::Vec<Command>,
    #[command(flatten)]
    pub source: SourceArgs,
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/demo")]
    pub out: PathBuf,
}

/// One decision as reported.
#[derive(Debug, Clone, Serialize)]
struct Row {
    index: usize,
    intended: Option<Command>,
    decided: Option<Command>,
    abstained: bool,
    rounds: usize,
    confidence: f64,
    seconds: f64,
    arm_refusal: Option<String>,
    /// Pen (x, z) in metres when the decision was made, before its command.
    pen_m: Option<[f64; 2]>,
}

/// Accuracy, rounds and ITR of a list of decisions.
#[derive(Debug, Clone, Serialize)]
struct Scores {
    rule: String,
    decisions: usize,
    correct: usize,
    abstained: usize,
    accuracy: f64,
    mean_rounds: f64,
    itr: Itr,
}

fn scores(rows: &[Row], rule: &DecisionRule) -> Scores {
    let n = rows.len().max(1) as f64;
    let correct = rows
        .iter()
        .filter(|r| r.decided.is_some() && r.decided == r.intended)
        .count();
    let accuracy = correct as f64 / n;
    let seconds = rows.iter().map(|r| r.seconds).sum::<f64>() / n;
    Scores {
        rule: rule_name(rule),
        decisions: rows.len(),
        correct,
        abstained: rows.iter().filter(|r| r.abstained).count(),
        accuracy,
        mean_rounds: rows.iter().map(|r| r.rounds as f64).sum::<f64>() / n,
        itr: Itr::new(4, accuracy, seconds),
    }
}

fn rule_name(rule: &DecisionRule) -> String {
    match rule {
        DecisionRule::Fixed { rounds } => format!("fixed {rounds} rounds"),
        DecisionRule::Dynamic {
            threshold,
            max_rounds,
            ..
        } => format!("dynamic stopping (p >= {threshold}, at most {max_rounds} rounds)"),
    }
}

/// The pen's corners against the path of the commands the arm executed.
#[derive(Debug, Clone, Serialize)]
struct PenReport {
    /// Pen at each decision and at the end, metres.
    corners_m: Vec<[f64; 2]>,
    /// Where the executed commands put the reference, metres.
    expected_m: Vec<[f64; 2]>,
    max_corner_error_mm: f64,
    /// Every decision was the intended command and the arm executed it.
    drew_intended_path: bool,
}

#[derive(Debug, Serialize)]
struct Summary<'a> {
    subject: &'a str,
    pipeline: &'a str,
    seed: u64,
    commands: Vec<Command>,
    calibration: CalibrationSummary,
    result: &'a Scores,
    #[serde(skip_serializing_if = "Option::is_none")]
    fixed_rounds_for_comparison: Option<&'a Scores>,
    simulated_seconds: f64,
    pen: PenReport,
    decisions: &'a [Row],
    files: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    note: Option<&'a str>,
}

/// The calibration report without its wall-clock fit time (the files must not depend on it).
#[derive(Debug, Serialize)]
struct CalibrationSummary {
    trials: usize,
    epochs: usize,
    targets: usize,
    rejected: usize,
    cv_auc: f64,
    d_prime: f64,
}

impl From<&CalibrationReport> for CalibrationSummary {
    fn from(c: &CalibrationReport) -> Self {
        Self {
            trials: c.n_trials,
            epochs: c.n_epochs,
            targets: c.n_targets,
            rejected: c.n_rejected,
            cv_auc: c.cv_auc,
            d_prime: c.d_prime,
        }
    }
}

impl Row {
    fn of(index: usize, s: &Step) -> Self {
        Self {
            index,
            intended: Some(s.intended),
            decided: s.decided,
            abstained: s.abstained,
            rounds: s.rounds,
            confidence: s.confidence,
            seconds: s.seconds,
            arm_refusal: s.arm_refusal.clone(),
            pen_m: s.pen_m,
        }
    }
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let wall = Instant::now();
    let commands = &args.commands;
    let (fixed, rule) = args.session.rules()?;
    let opts = &args.session;
    let replay_files = opts.replay_files()?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;

    let mut comparison = None;
    let mut note = None;
    match (&replay_files, opts.preset()) {
        (Some((file, cal)), _) => {
            println!(
                "oddball demo: replaying {} (calibration {}), pipeline {}, {}",
                file.display(),
                cal.display(),
                opts.pipeline,
                rule_name(&rule)
            );
            note = Some(REPLAY_NOTE);
        }
        (None, preset) => {
            println!(
                "oddball demo: {} simulated subject (seed {}), pipeline {}, {}; calibration: {} decisions per bulb",
                preset.expect("a simulated preset when not replaying"),
                opts.seed,
                opts.pipeline,
                rule_name(&rule),
                opts.calibration_per_bulb
            );
            if let SourceSpec::Nic(addr) = &args.source.source {
                println!(
                    "reading EEG from the NIC stream at {addr} ({}, {} channels)",
                    args.source.nic.nic_mode.name(),
                    args.source.nic.nic_channels
                );
            } else if opts.dynamic_stopping && args.source.source == SourceSpec::Sim {
                // The same subject and calibration (same seed), online with fixed rounds.
                let subject = live_subject(opts, &args.source, false, Clock::new())?;
                let (mut quiet, _, _) = opts.calibrated(subject, fixed, false)?;
                let steps = run_copy(&mut quiet, commands, false, 1.5, |_| false, |_, _| {})?.steps;
                let rows: Vec<Row> = steps
                    .iter()
                    .enumerate()
                    .map(|(i, s)| Row::of(i + 1, s))
                    .collect();
                comparison = Some(scores(&rows, &fixed));
            }
        }
    }
    let mut prep = prepare(opts, &args.source, rule, opts.realtime, |r, _| {
        if rule != fixed {
            let mut p = r.params.clone();
            p.rule = fixed;
            let d = replay::replay(&r.test, &r.model, commands, &p)?;
            let rows: Vec<Row> = d
                .iter()
                .enumerate()
                .map(|(i, d)| Row {
                    index: i + 1,
                    intended: Some(d.intended),
                    decided: d.decided(&p.paradigm),
                    abstained: d.outcome == oddball_session::engine::TrialOutcome::Abstained,
                    rounds: d.rounds,
                    confidence: d.confidence(),
                    seconds: d.seconds,
                    arm_refusal: None,
                    pen_m: None,
                })
                .collect();
            comparison = Some(scores(&rows, &fixed));
        }
        Ok(())
    })?;
    // A replayed recording cycles the commands until its decisions are used up.
    let cycle = replay_files.is_some();
    let steps = run_copy(
        &mut prep.pilot,
        commands,
        cycle,
        1.5,
        |_| false,
        |i, s| {
            println!("{}", row_text(&Row::of(i + 1, s)));
        },
    )?
    .steps;
    let rows: Vec<Row> = steps
        .iter()
        .enumerate()
        .map(|(i, s)| Row::of(i + 1, s))
        .collect();
    if let Some(h) = prep.stream_health() {
        println!("stream: {h}");
    }
    let simulated_seconds = prep.pilot.time_s();
    let result = scores(&rows, &rule);
    let arm = prep.pilot.arm().clone();
    let pen = pen_report(&arm, prep.pen_start, &rows);
    write_decisions_csv(&args.out.join("decisions.csv"), &steps)?;
    fs::write(args.out.join("model.json"), &prep.model_json)
        .with_context(|| format!("writing {}", args.out.join("model.json").display()))?;
    let erp_png = args.out.join("erp.png");
    oddball_plot::task::draw_calibration_erp(&erp_png, &prep.erp)
        .with_context(|| format!("drawing {}", erp_png.display()))?;
    let expected: Vec<Vector2<f64>> = pen
        .expected_m
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    let pen_png = args.out.join("pen_trace.png");
    oddball_plot::arm::draw_pen_trace(&arm, &expected, &pen_png)
        .with_context(|| format!("drawing {}", pen_png.display()))?;
    let calibration = CalibrationSummary::from(&prep.calibration);
    let subject_label = prep.subject.clone();
    let fit_seconds = prep.calibration.fit_seconds;
    let session_file = prep.save_session(&args.out, "demo over")?;
    let mut files = vec![
        "decisions.csv".to_string(),
        "summary.json".into(),
        "model.json".into(),
        "erp.png".into(),
        "pen_trace.png".into(),
    ];
    if let Some(f) = session_file.as_ref().and_then(|p| p.file_name()) {
        files.push(f.to_string_lossy().into_owned());
    }
    let summary = Summary {
        subject: &subject_label,
        pipeline: &opts.pipeline,
        seed: opts.seed,
        commands: commands.clone(),
        calibration,
        result: &result,
        fixed_rounds_for_comparison: comparison.as_ref(),
        simulated_seconds,
        pen: pen.clone(),
        decisions: &rows,
        files,
        note,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    fs::write(args.out.join("summary.json"), json + "\n")
        .with_context(|| format!("writing {}", args.out.join("summary.json").display()))?;

    print!(
        "{}",
        report_text(simulated_seconds, &result, comparison.as_ref(), &pen)
    );
    println!("report in {}", args.out.display());
    // Wall-clock time goes to stderr: stdout, like every file, depends only on the options.
    eprintln!(
        "wall time {:.2} s (calibration fit {:.2} s)",
        wall.elapsed().as_secs_f64(),
        fit_seconds,
    );
    Ok(())
}

/// Corners: the pen after each executed command (at the next decision, or at the end)
/// against where the executed commands put the reference.
fn pen_report(arm: &oddball_arm::ArmSim, pen_start: Vector2<f64>, rows: &[Row]) -> PenReport {
    let executed = rows
        .iter()
        .filter_map(|r| r.decided.filter(|_| r.arm_refusal.is_none()));
    let expected = planned_path(pen_start, executed, arm.settings().step_m);
    let end_pen = [arm.pen()[0], arm.pen()[1]];
    let mut measured = Vec::new();
    let mut errors = Vec::new();
    let mut intended_ok = true;
    let mut target = expected.iter().skip(1);
    for (k, row) in rows.iter().enumerate() {
        let executed = row.decided.filter(|_| row.arm_refusal.is_none());
        intended_ok &= executed.is_some() && row.decided == row.intended;
        if executed.is_some() {
            let target = target.next().expect("one target per executed command");
            // The pen when the next decision comes (or at the end) shows where this one left it.
            let pen = rows.get(k + 1).and_then(|r| r.pen_m).unwrap_or(end_pen);
            measured.push(pen);
            errors.push((Vector2::new(pen[0], pen[1]) - target).norm());
        }
    }
    PenReport {
        corners_m: measured,
        expected_m: expected.iter().map(|p| [p[0], p[1]]).collect(),
        max_corner_error_mm: errors.iter().copied().fold(0.0, f64::max) * 1000.0,
        drew_intended_path: intended_ok,
    }
}

fn row_text(r: &Row) -> String {
    let name = |c: Option<Command>| c.map_or("—".to_string(), |c| c.to_string());
    let decided = if r.abstained {
        "abstain".to_string()
    } else {
        name(r.decided)
    };
    let mark = if r.decided.is_some() && r.decided == r.intended {
        "ok"
    } else {
        "WRONG"
    };
    let mut s = format!(
        "decision {:>2}: intended {:<5} decided {:<7} {:<5} rounds {}  confidence {:.3}  {:.2} s",
        r.index,
        name(r.intended),
        decided,
        mark,
        r.rounds,
        r.confidence,
        r.seconds
    );
    if let Some(e) = &r.arm_refusal {
        let _ = write!(s, "  (arm refused: {e})");
    }
    s
}

fn report_text(
    simulated_seconds: f64,
    result: &Scores,
    comparison: Option<&Scores>,
    pen: &PenReport,
) -> String {
    let mut s = String::new();
    let line = |s: &mut String, sc: &Scores| {
        let _ = writeln!(
            s,
            "  {:<48} accuracy {:>5.1} % ({}/{}, {} abstained)  mean rounds {:.2}  {:.2} s/decision  ITR {:.2} bits/decision, {:.2} bits/min",
            sc.rule,
            100.0 * sc.accuracy,
            sc.correct,
            sc.decisions,
            sc.abstained,
            sc.mean_rounds,
            sc.itr.seconds_per_selection,
            sc.itr.bits_per_selection,
            sc.itr.bits_per_minute
        );
    };
    let _ = writeln!(
        s,
        "command accuracy and information transfer rate (Wolpaw, 4 choices):"
    );
    line(&mut s, result);
    if let Some(c) = comparison {
        line(&mut s, c);
    }
    let _ = writeln!(
        s,
        "pen: {} corners, max error {:.1e} mm from the path of the executed commands; {}",
        pen.corners_m.len(),
        pen.max_corner_error_mm,
        if pen.drew_intended_path {
            "drew the intended path"
        } else {
            "did NOT draw the intended path (wrong, abstained or refused decisions)"
        }
    );
    let _ = writeln!(s, "simulated time {:.1} s", simulated_seconds);
    s
}
