//! `oddball online`: a live session. EEG from a live stream (or the simulated subject paced by
//! the wall clock), flashes drawn by the browser panel the binary serves, markers stamped by
//! the frames that drew them, decisions driving the arm, everything recorded to XDF as it runs.
//!
//! Prints the panel's address on its first line when serving (`panel: http://ADDR/`, the
//! subject view; the operator view's on the next), then waits for a subject view before the
//! first countdown.

use std::fs;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use oddball_arm::{planned_path, Command};
use oddball_live::clock::Clock;
use oddball_live::live::{EegSource, LiveSubject, Summary};
use oddball_live::online::{
    coincidence, decision_line, free_recording_path, is_recording_end, recording_samples,
    stop_reason, OnlineSummary,
};
use oddball_live::panel::PanelConfig;
use oddball_live::plan::{PlanError, SessionPlan};
use oddball_live::record::Recorder;
use oddball_live::source::{AnySource, SourceSpec};
use oddball_session::decoder::Start;
use oddball_session::roles::EegStream;
use oddball_session::tasks::run_copy;

use crate::args::{
    commands_arg, CalibrationSpec, PanelOptions, SessionOptions, SourceArgs, COMMANDS_HELP,
    STROKE_G,
};

/// Options of `oddball online`: a live session's subject is simulated or real, never a replayed
/// speller recording (`--source replay:FILE` plays a recorded session back), so `--subject`
/// takes a preset only and `--test-text` is not offered.
#[derive(Debug, clap::Args)]
#[command(
    mut_arg("subject", |a| a
        .help("The simulated subject of --source sim (and the montage of a NIC stream): easy, typical or hard")
        .value_parser(crate::args::simulated_subject)),
    mut_arg("test_text", |a| a.hide(true)),
    mut_arg("realtime", |a| a.hide(true))
)]
pub struct OnlineArgs {
    #[command(flatten)]
    pub source: SourceArgs,
    /// Calibrate live first (calibration-per-bulb decisions per bulb) instead of loading a model
    /// (`--calibration none`: no calibration at all, the decoder learns from the session).
    #[arg(long, conflicts_with = "model")]
    pub calibrate: bool,
    #[command(flatten)]
    pub panel: PanelOptions,
    /// Intended commands (a copy task: the panel cues each).
    #[arg(long, default_value = STROKE_G, value_parser = commands_arg, help = COMMANDS_HELP)]
    pub commands: std::vec::Vec<Command>,
    /// With --source replay:FILE, play the file back as fast as it is processed instead of in
    /// real time (re-running a recorded session with another model, say); not with --serve.
    #[arg(long, conflicts_with = "serve")]
    pub fast: bool,
    #[command(flatten)]
    pub session: SessionOptions,
    /// Report folder: session.xdf (written as the session runs; an existing one is kept and the
    /// new one numbered) and summary.json.
    #[arg(long, value_name = "DIR", default_value = "out/online", value_parser = crate::args::output_dir)]
    pub out: PathBuf,
}

pub fn run(args: &OnlineArgs) -> Result<()> {
    let (_, rule) = args.session.rules()?;
    args.session.check_commands(&args.commands)?;
    let uncalibrated = args.session.calibration == CalibrationSpec::None;
    if (args.session.model.is_none(), args.calibrate, uncalibrated) == (true, false, false) {
        bail!("give --model FILE, --calibrate (labelled calibration first) or --calibration none");
    }
    if args.session.realtime {
        bail!("--realtime paces a simulated demo or task: online runs in real time already (--fast plays a file back as fast as it goes)");
    }
    let is_replay = matches!(args.source.source, SourceSpec::Replay(_));
    if args.fast && !is_replay {
        bail!("--fast plays back a file: it needs --source replay:FILE");
    }
    // The model (and montage, transfer model) read and checked before any EEG work.
    let plan = args.session.plan(
        &args.source,
        rule,
        !args.fast,
        args.session.session_model(rule)?,
    )?;
    let clock = Clock::new();
    let (source, markers) = plan
        .open_source(clock)
        .map_err(|e| args.session.plan_error(e, &plan))?;
    match &source {
        AnySource::Playback(p) => println!(
            "replaying {}: {} channels, {} Hz, {:.1} s, {} events",
            args.source.source.to_string().trim_start_matches("replay:"),
            p.ch_names().len(),
            p.sfreq(),
            p.n_times() as f64 / p.sfreq(),
            p.events().len()
        ),
        _ if markers.is_some() => println!("marker outlet: {}", args.source.markers),
        _ => {}
    }
    // A source at another rate than the model's is resampled to it (polyphase).
    let (source, change) = plan
        .at_model_rate(source)
        .map_err(|e| args.session.plan_error(e, &plan))?;
    if let Some(c) = change {
        println!("{c}");
    }
    run_with(args, &plan, source, markers, clock, &args.commands)
}

fn run_with(
    args: &OnlineArgs,
    plan: &SessionPlan,
    source: AnySource,
    markers: Option<Box<dyn oddball_live::live::MarkerSink>>,
    clock: Clock,
    commands: &[Command],
) -> Result<()> {
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let paradigm = plan.params.paradigm;
    let arm = args.session.arm()?;
    let record_path = free_recording_path(&args.out);
    let recorder = Recorder::create(
        &record_path,
        source.ch_names(),
        source.sfreq(),
        &args.source.source.to_string(),
    )
    .with_context(|| format!("creating {}", record_path.display()))?;
    let title = format!(
        "{} · {} · {}",
        args.source.source,
        match &plan.start {
            Start::Model(m) => m.pipeline.name(),
            _ => plan.params.decoder.pipeline.name(),
        },
        if args.session.calibration == CalibrationSpec::None {
            "no calibration"
        } else if args.calibrate {
            "labelled calibration"
        } else {
            "model loaded"
        }
    );
    let mut subject = LiveSubject::new(source, paradigm, clock).with_recorder(recorder);
    if let Some(m) = markers {
        subject = subject.with_markers(m);
    }
    let plan_m = planned_path(
        arm.target(),
        commands.iter().copied(),
        arm.settings().step_m,
    )
    .iter()
    .map(|p| [p[0], p[1]])
    .collect();
    let config = PanelConfig::for_arm(&arm, &paradigm, Vec::new(), plan_m, title);
    if let Some(panel) = args.panel.start(config, clock)? {
        subject = subject.with_panel(panel);
    }
    println!(
        "oddball online: source {}, {} commands, recording {}",
        args.source.source,
        commands.len(),
        record_path.display()
    );
    subject.source_mut().start_now();
    let mut session = plan
        .session(subject)
        .map_err(|e| args.session.plan_error(e, plan))?;
    // The operator view's progress: "calibration decision 3 of 40", "decision 2 of 6".
    let calibrating = matches!(plan.start, Start::Calibrate { .. });
    let n_calibration = calibrating.then(|| session.params().calibration_trials());
    session
        .subject_mut()
        .set_plan(n_calibration, Some(commands.len()));
    // A stop request or a source that ends during calibration still closes the recording and
    // writes the summary (with no decisions).
    let mut ended = None;
    if let Start::Model(m) = &plan.start {
        println!(
            "{}",
            crate::args::model_line(m, args.session.model.as_deref())
        );
    }
    match plan.start(&mut session, &mut crate::args::calibration_progress()) {
        Ok(Some(c)) => println!(
            "calibration: {} decisions, {} epochs, cross-validated AUC {:.3}",
            c.n_trials, c.n_epochs, c.cv_auc
        ),
        Ok(None) if args.session.calibration == CalibrationSpec::None => {
            args.session.print_transfer();
            println!("calibration: none: the decoder learns from the session (EM after every decision, no labels)");
        }
        Ok(None) => {
            // A replayed recording's calibration is passed over, not played as commands.
            let recorded = match session.subject().source() {
                AnySource::Playback(p) => p.calibration(),
                _ => None,
            };
            if let Some(c) = recorded {
                println!(
                    "passing over the recording's calibration: {} trials, {:.1} s (filtered, nothing decided)",
                    c.n_trials,
                    c.end as f64 / session.sfreq()
                );
                session
                    .pass_calibration(c.n_trials, c.end)
                    .context("passing over the recorded calibration")?;
            }
        }
        Err(PlanError::Start(e)) if calibrating && is_recording_end(&e) => {
            let end = stop_reason(&e);
            println!("calibration: {end}");
            ended = Some(end);
        }
        Err(e) => return Err(args.session.plan_error(e, plan)),
    }
    if let Some(m) = session.model() {
        oddball_io::write_atomic(args.out.join("model.json"), m.to_json())?;
    }
    let mut steps = Vec::new();
    if ended.is_none() {
        let run = run_copy(
            &mut session,
            commands,
            false,
            1.5,
            is_recording_end,
            |i, s| {
                println!("{}", decision_line(i, s));
                if let Some(r) = &s.arm_refusal {
                    println!("  the arm refused: {r}");
                }
            },
        )
        .context("running the commands")?;
        ended = run.stopped.map(|(e, deciding)| {
            let end = stop_reason(&e);
            if deciding {
                println!("decision {}: {end}", run.steps.len() + 1);
            }
            end
        });
        steps = run.steps;
    }
    if let Some(r) = session.channel_report() {
        println!("{r}");
    }
    let replay = coincidence(session.subject().source(), session.flashes());
    if let Some(r) = &replay {
        println!("{r}");
    }
    let subject = session.subject_mut();
    let summary = OnlineSummary::new(
        args.source.source.to_string(),
        &steps,
        &subject.timing,
        &subject.decision_latency_ms,
        &record_path,
        replay,
        ended,
    );
    let timing = subject.timing.clone();
    let latency = subject.decision_latency_ms.clone();
    let health = subject.stream_health();
    let summary_line = summary.line(commands.len());
    subject.end(&summary_line);
    if let Some(panel) = subject.panel() {
        let s = panel.stats();
        println!(
            "panel: {} connection(s), {} message(s) rejected",
            s.connections, s.rejected
        );
    }
    println!("{summary_line}");
    println!("{}", timing.report());
    if let Some(l) = Summary::of(&latency) {
        println!("processing latency, last block of the deciding epoch → arm command: {l}");
    }
    if let Some(h) = health {
        println!("stream: {h}");
    }
    // The recording's stream footers written and the file synced.
    session
        .into_subject()
        .finish()
        .with_context(|| format!("closing {}", record_path.display()))?;
    let path = args.out.join("summary.json");
    oddball_io::write_atomic(&path, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "recording: {} ({} samples)",
        record_path.display(),
        recording_samples(&record_path)
    );
    Ok(())
}
