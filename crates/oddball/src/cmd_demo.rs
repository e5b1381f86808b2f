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

use std::fs;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use oddball_arm::{Command, Vector2};
use oddball_decode::stopping::Expected;
use oddball_live::clock::Clock;
use oddball_live::source::SourceSpec;
use oddball_session::paradigm::FourBulbParams;
use oddball_session::replay::{self, REPLAY_NOTE};
use oddball_session::report::{
    accuracy_over_time, accuracy_over_time_text, numbered, pen_report, report_text, row_text,
    rule_name, scores, CalibrationSummary, PenReport, Row, Scores, Stretch,
};
use oddball_session::tasks::{run_copy, Pilot};
use oddball_session::timing::{stopping_text, time_report, time_text, TimeReport};
use serde::Serialize;

use crate::args::{commands_arg, SessionOptions, SourceArgs, COMMANDS_HELP, STROKE_G};
use crate::pilot::{prepare, write_decisions_csv, AnyPilot};

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
    decisions: Vec<Row<'a>>,
    /// Accuracy of decisions 1–10, 11–20, …
    accuracy_over_time: Vec<Stretch>,
    /// Without calibration: [right, decisions] when the last fit re-decides every decision.
    #[serde(skip_serializing_if = "Option::is_none")]
    posthoc_correct: Option<[usize; 2]>,
    files: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    note: Option<String>,
    paradigm: FourBulbParams,
    time_per_decision: TimeReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    stopping_chosen: Option<Expected>,
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let wall = Instant::now();
    let commands = &args.commands;
    let (fixed, rule) = args.session.rules()?;
    args.session.check_commands(&args.commands)?;
    let opts = &args.session;
    let replay_files = crate::pilot::replay_files(opts)?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;

    let mut comparison = None;
    let mut note = None;
    let rule_label = if opts.optimise_stopping {
        format!(
            "stopping chosen from calibration for bits/min (at most {} rounds)",
            opts.round_limit
        )
    } else {
        rule_name(&rule)
    };
    match (&replay_files, opts.preset()) {
        (Some(files), _) => {
            println!(
                "oddball demo: replaying {} (calibration {}), pipeline {}, {}",
                files.test_names(),
                files.calibration_names(),
                opts.pipeline,
                rule_label
            );
            note = Some(REPLAY_NOTE.to_string());
        }
        (None, preset) => {
            println!(
                "oddball demo: {} simulated subject (seed {}), pipeline {}, {}; {}",
                preset.expect("a simulated preset when not replaying"),
                opts.seed,
                opts.pipeline,
                rule_label,
                match &opts.model {
                    Some(m) => format!("model {}", m.display()),
                    None => format!(
                        "calibration: {} decisions per bulb",
                        opts.calibration_per_bulb
                    ),
                }
            );
            if let SourceSpec::Nic(addr) = &args.source.source {
                println!(
                    "reading EEG from the NIC stream at {addr} ({}, {} channels)",
                    args.source.nic.nic_mode.name(),
                    args.source.nic.nic_channels
                );
            } else if (opts.dynamic_stopping || opts.optimise_stopping)
                && args.source.source == SourceSpec::Sim
            {
                // The same subject and calibration (same seed), online with fixed rounds.
                let plan = opts.plan(&args.source, fixed, false, opts.session_model(fixed)?)?;
                let (mut quiet, _, _) = opts.open(&plan, Clock::new(), false)?;
                let steps = run_copy(&mut quiet, commands, false, 1.5, |_| false, |_, _| {})?.steps;
                comparison = Some(scores(&steps, &fixed));
            }
        }
    }
    let mut replay_rule = None;
    let mut prep = prepare(opts, &args.source, rule, opts.realtime, |r, _| {
        replay_rule = Some(r.params.decoder.rule);
        if rule != fixed {
            let mut p = r.params.clone();
            p.decoder.rule = fixed;
            let d: Vec<_> = replay::replay(&r.test, &r.model, commands, &p)?
                .into_iter()
                .map(|(d, _)| d)
                .collect();
            comparison = Some(scores(&d, &fixed));
        }
        Ok(())
    })?;
    // The rule calibration chose (--optimise-stopping), else the one given.
    let (rule, stopping) = match &prep.pilot {
        AnyPilot::Live(s) => (s.params().decoder.rule, s.stopping().copied()),
        AnyPilot::Replay(_) => (replay_rule.unwrap_or(rule), None),
    };
    let paradigm = opts.paradigm();
    println!("panel timing: {}", paradigm.describe());
    if let Some(e) = &stopping {
        println!("{}", stopping_text(e));
    }
    // A replayed recording cycles the commands until its decisions are used up.
    let cycle = replay_files.is_some();
    let steps = run_copy(
        &mut prep.pilot,
        commands,
        cycle,
        1.5,
        |_| false,
        |i, s| {
            println!("{}", row_text(i + 1, s));
        },
    )?
    .steps;
    if let Some(end) = oddball_live::stop::reason() {
        // Stopped early: what was decided and recorded is kept and written below.
        println!("stopped after {} decision(s): {end}", steps.len());
        note = Some(match note {
            Some(n) => format!("{n}; stopped early: {end}"),
            None => format!("stopped early: {end}"),
        });
    }
    let rows = &steps;
    if let Some(h) = prep.stream_health() {
        println!("stream: {h}");
    }
    let simulated_seconds = prep.pilot.time_s();
    let result = scores(rows, &rule);
    let time = time_report(rows, &paradigm);
    let arm = prep.pilot.arm().clone();
    let pen = pen_report(&arm, prep.pen_start, rows);
    let over_time = accuracy_over_time(rows, 10);
    let posthoc = crate::pilot::posthoc(&prep);
    let adaptation = crate::pilot::adaptation(&prep);
    write_decisions_csv(&args.out.join("decisions.csv"), &steps)?;
    oddball_io::write_atomic(
        args.out.join("model.json"),
        crate::pilot::model_json(&prep)?,
    )
    .with_context(|| format!("writing {}", args.out.join("model.json").display()))?;
    // An uncalibrated session has no labelled epochs to draw.
    let erp_png = args.out.join("erp.png");
    if prep.erp.n_epochs() > 0 {
        oddball_plot::task::draw_calibration_erp(&erp_png, &prep.erp)
            .with_context(|| format!("drawing {}", erp_png.display()))?;
    }
    let xz = |v: &[[f64; 2]]| -> Vec<Vector2<f64>> {
        v.iter().map(|p| Vector2::new(p[0], p[1])).collect()
    };
    let (intended, executed) = (xz(&pen.intended_m), xz(&pen.executed_m));
    let paths = oddball_plot::arm::SessionPaths {
        intended: &intended,
        executed: &executed,
        missed: &pen.missed,
        numbered: true,
    };
    let pen_png = args.out.join("pen_trace.png");
    oddball_plot::arm::draw_pen_trace(&arm, &paths, &pen_png)
        .with_context(|| format!("drawing {}", pen_png.display()))?;
    let calibration = CalibrationSummary::from(&prep.calibration);
    let subject_label = prep.subject.clone();
    let fit_seconds = prep.calibration.fit_seconds;
    let session_file = crate::pilot::save_session(prep, &args.out, "demo over")?;
    let mut files = vec![
        "decisions.csv".to_string(),
        "summary.json".into(),
        "model.json".into(),
        "pen_trace.png".into(),
    ];
    if erp_png.exists() {
        files.insert(3, "erp.png".into());
    }
    if let Some(f) = session_file.as_ref().and_then(|p| p.file_name()) {
        files.push(f.to_string_lossy().into_owned());
    }
    let summary = Summary {
        subject: &subject_label,
        pipeline: opts.pipeline.name(),
        seed: opts.seed,
        commands: commands.clone(),
        calibration,
        result: &result,
        fixed_rounds_for_comparison: comparison.as_ref(),
        simulated_seconds,
        pen: pen.clone(),
        decisions: numbered(rows),
        accuracy_over_time: over_time.clone(),
        posthoc_correct: posthoc.map(|(r, n)| [r, n]),
        files,
        note,
        paradigm,
        time_per_decision: time,
        stopping_chosen: stopping,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    oddball_io::write_atomic(args.out.join("summary.json"), json + "\n")
        .with_context(|| format!("writing {}", args.out.join("summary.json").display()))?;

    print!(
        "{}",
        report_text(simulated_seconds, &result, comparison.as_ref(), &pen)
    );
    println!("{}", accuracy_over_time_text(&over_time));
    if let Some(a) = adaptation {
        println!(
            "online adaptation: {} decisions taken in, {} undone by the drift guard, {} too unsure (posterior < 0.9)",
            a.accepted, a.rejected, a.unsure
        );
    }
    if let Some((right, n)) = posthoc {
        println!("post hoc: the last unsupervised fit re-decides {right}/{n} decisions right");
    }
    println!("{}", time_text(&time, &paradigm));
    println!("report in {}", args.out.display());
    // Wall-clock time goes to stderr: stdout, like every file, depends only on the options.
    eprintln!(
        "wall time {:.2} s (calibration fit {:.2} s)",
        wall.elapsed().as_secs_f64(),
        fit_seconds,
    );
    Ok(())
}
