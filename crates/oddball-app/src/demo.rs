//! The demo: the whole closed loop with no hardware, as a copy task with fixed commands. A
//! subject (simulated, over any source, or real EEG replayed) watches the four-bulb panel; the
//! session calibrates, trains a pipeline, then decodes each intended command and the arm draws
//! it. Writes the report folder ([`crate::report`]) and `summary.json`.

use std::io::Write;
use std::path::PathBuf;

use oddball_arm::{Command, Vector2};
use oddball_decode::stopping::Expected;
use oddball_live::clock::Clock;
use oddball_live::source::SourceSpec;
use oddball_session::replay::{self, REPLAY_NOTE};
use oddball_session::report::{
    accuracy_over_time, accuracy_over_time_text, headline, headline_text, numbered, pen_report,
    report_text, row_text, rule_name, scores, BitsBy, CalibrationSummary, PenReport, Row, Scores,
    SessionFacts, Stretch,
};
use oddball_session::tasks::{run_copy, Pilot};
use oddball_session::timing::{stopping_text, time_report, time_text, TimeReport};
use serde::Serialize;

use crate::error::Result;
use crate::pilot::{adaptation, posthoc, prepare, AnyPilot};
use crate::replayed::ReplayFiles;
use crate::report::{self, drawn};
use crate::settings::CalibrationSpec;
use crate::settings::{SessionSettings, SourceSettings};

/// A demo to run.
#[derive(Debug, Clone)]
pub struct Demo {
    pub settings: SessionSettings,
    pub source: SourceSettings,
    /// The intended commands.
    pub commands: Vec<Command>,
    /// The report folder.
    pub out: PathBuf,
}

/// What a demo leaves to say after its report: the calibration's fit time (wall clock, so never
/// written to a file), and why it stopped before its last command, if it did.
#[derive(Debug, Clone)]
pub struct DemoOutcome {
    pub fit_seconds: f64,
    pub stopped: Option<String>,
}

#[derive(Debug, Serialize)]
struct Summary<'a> {
    #[serde(flatten)]
    facts: SessionFacts<'a>,
    commands: Vec<Command>,
    result: &'a Scores,
    /// Bits delivered in the first 5 and 10 minutes after the session started (its calibration
    /// included); empty for a replay.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    bits_since_start: Vec<BitsBy>,
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
    time_per_decision: TimeReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    stopping_chosen: Option<Expected>,
}

impl Demo {
    /// Runs the demo, saying on `out` what it does, decision by decision.
    pub fn run(&self, out: &mut dyn Write) -> Result<DemoOutcome> {
        let opts = &self.settings;
        let commands = &self.commands;
        let (fixed, rule) = opts.rules()?;
        opts.check_commands(commands)?;
        let replay_files = ReplayFiles::of(opts)?;
        report::create_dir(&self.out)?;

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
                writeln!(
                    out,
                    "oddball demo: replaying {} (calibration {}), pipeline {}, {}",
                    files.test_names(),
                    files.calibration_names(),
                    opts.pipeline,
                    rule_label
                )?;
                note = Some(REPLAY_NOTE.to_string());
            }
            (None, preset) => {
                writeln!(
                    out,
                    "oddball demo: {} simulated subject (seed {}), pipeline {}, {}; {}",
                    preset.expect("a simulated preset when not replaying"),
                    opts.seed,
                    opts.pipeline,
                    rule_label,
                    match (&opts.model, &opts.calibration) {
                        (Some(m), _) => format!("model {}", m.display()),
                        (None, CalibrationSpec::None) => "no calibration".to_string(),
                        (None, _) => format!(
                            "calibration: {} decisions per bulb",
                            opts.calibration_per_bulb
                        ),
                    }
                )?;
                if let SourceSpec::Nic(addr) = &self.source.source {
                    writeln!(
                        out,
                        "reading EEG from the NIC stream at {addr} ({}, {} channels)",
                        self.source.nic.mode.name(),
                        self.source.nic.n_channels
                    )?;
                } else if (opts.dynamic_stopping || opts.optimise_stopping)
                    && self.source.source == SourceSpec::Sim
                {
                    // The same subject and calibration (same seed), online with fixed rounds.
                    let plan = opts.plan(&self.source, fixed, false, opts.session_model(fixed)?)?;
                    let (mut quiet, _, _) = opts.open(&plan, Clock::new(), false, out)?;
                    let steps =
                        run_copy(&mut quiet, commands, false, 1.5, |_| false, |_, _| {})?.steps;
                    comparison = Some(scores(&steps, &fixed));
                }
            }
        }
        let mut replay_rule = None;
        let mut prep = prepare(
            opts,
            replay_files.as_ref(),
            &self.source,
            rule,
            opts.realtime,
            out,
            |r, _, _| {
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
            },
        )?;
        // The rule calibration chose (optimised stopping), else the one given.
        let (rule, stopping) = match &prep.pilot {
            AnyPilot::Live(s) => (s.params().decoder.rule, s.stopping().copied()),
            AnyPilot::Replay(_) => (replay_rule.unwrap_or(rule), None),
        };
        let paradigm = opts.paradigm();
        writeln!(out, "panel timing: {}", paradigm.describe())?;
        if let Some(e) = &stopping {
            writeln!(out, "{}", stopping_text(e))?;
        }
        // A replayed recording cycles the commands until its decisions are used up.
        let cycle = replay_files.is_some();
        let mut said = Ok(());
        let steps = run_copy(
            &mut prep.pilot,
            commands,
            cycle,
            1.5,
            |_| false,
            |i, s| {
                if said.is_ok() {
                    said = writeln!(out, "{}", row_text(i + 1, s));
                }
            },
        )?
        .steps;
        said?;
        let stopped = oddball_live::stop::reason();
        if let Some(end) = &stopped {
            // Stopped early: what was decided and recorded is kept and written below.
            writeln!(out, "stopped after {} decision(s): {end}", steps.len())?;
            note = Some(match note {
                Some(n) => format!("{n}; stopped early: {end}"),
                None => format!("stopped early: {end}"),
            });
        }
        let rows = &steps;
        if let Some(h) = prep.stream_health() {
            writeln!(out, "stream: {h}")?;
        }
        let simulated_seconds = prep.pilot.time_s();
        let result = scores(rows, &rule);
        let time = time_report(rows, &paradigm);
        let arm = prep.pilot.arm();
        let pen = pen_report(arm, prep.pen_start, rows);
        let over_time = accuracy_over_time(rows, 10);
        let early = headline(rows);
        let posthoc = posthoc(&prep);
        let adaptation = adaptation(&prep);
        let erp_png = report::write_decisions_and_model(&self.out, &prep, &steps)?;
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
        let pen_png = self.out.join("pen_trace.png");
        drawn(
            &pen_png,
            oddball_plot::arm::draw_pen_trace(arm, &paths, &pen_png),
        )?;
        let calibration = CalibrationSummary::from(&prep.calibration);
        let subject_label = prep.subject.clone();
        let fit_seconds = prep.calibration.fit_seconds;
        let session_file = report::save_session(prep, &self.out, "demo over")?;
        let mut files = vec![
            "decisions.csv".to_string(),
            "summary.json".into(),
            "model.json".into(),
            "pen_trace.png".into(),
        ];
        if erp_png.is_some() {
            files.insert(3, "erp.png".into());
        }
        if let Some(f) = session_file.as_ref().and_then(|p| p.file_name()) {
            files.push(f.to_string_lossy().into_owned());
        }
        let summary = Summary {
            facts: SessionFacts {
                command: "demo",
                subject: &subject_label,
                pipeline: opts.pipeline.name(),
                seed: opts.seed,
                paradigm,
                calibration,
            },
            commands: commands.clone(),
            result: &result,
            bits_since_start: early.clone(),
            fixed_rounds_for_comparison: comparison.as_ref(),
            simulated_seconds,
            pen: pen.clone(),
            decisions: numbered(rows),
            accuracy_over_time: over_time.clone(),
            posthoc_correct: posthoc.map(|(r, n)| [r, n]),
            files,
            note,
            time_per_decision: time,
            stopping_chosen: stopping,
        };
        report::write_json(&self.out.join("summary.json"), &summary)?;

        write!(
            out,
            "{}",
            report_text(simulated_seconds, &result, comparison.as_ref(), &pen)
        )?;
        writeln!(out, "{}", accuracy_over_time_text(&over_time))?;
        if let Some(h) = headline_text(&early) {
            writeln!(out, "{h}")?;
        }
        if let Some(a) = adaptation {
            writeln!(
                out,
                "online adaptation: {} decisions taken in, {} undone by the drift guard, {} too unsure (posterior < 0.9)",
                a.accepted, a.rejected, a.unsure
            )?;
        }
        if let Some((right, n)) = posthoc {
            writeln!(
                out,
                "post hoc: the last unsupervised fit re-decides {right}/{n} decisions right"
            )?;
        }
        writeln!(out, "{}", time_text(&time, &paradigm))?;
        writeln!(out, "report in {}", self.out.display())?;
        Ok(DemoOutcome {
            fit_seconds,
            stopped,
        })
    }
}
