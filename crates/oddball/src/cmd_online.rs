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
use oddball_live::record::Recorder;
use oddball_live::source::{AnySource, SourceSpec};
use oddball_session::engine::{Session, UncalibratedParams};
use oddball_session::roles::EegStream;
use oddball_session::task::run_copy;

use crate::args::{
    commands_arg, CalibrationSpec, PanelOptions, SessionOptions, SourceArgs, LETTER_G,
};

/// Options of `oddball online`.
#[derive(Debug, clap::Args)]
pub struct OnlineArgs {
    #[command(flatten)]
    pub source: SourceArgs,
    /// Calibrate live first (calibration-per-bulb decisions per bulb) instead of loading a model
    /// (`--calibration none`: no calibration at all, the decoder learns from the session).
    #[arg(long, conflicts_with = "model")]
    pub calibrate: bool,
    #[command(flatten)]
    pub panel: PanelOptions,
    /// Comma-separated intended commands (a copy task: the panel cues each); the letter G by
    /// default.
    #[arg(long, default_value = LETTER_G, value_parser = commands_arg)]
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
    let is_replay = matches!(args.source.source, SourceSpec::Replay(_));
    if args.fast && !is_replay {
        bail!("--fast plays back a file: it needs --source replay:FILE");
    }
    // The model read and checked before any EEG work.
    let model = args.session.session_model(rule)?;
    let clock = Clock::new();
    let sim = args.session.simulated()?;
    let (source, markers) = args
        .source
        .source
        .open(args.source.open_options(sim, !args.fast)?, clock)
        .with_context(|| format!("--source {}", args.source.source))?;
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
    // A file at another rate than the model's is resampled to it (polyphase).
    let source = match (source, &model) {
        (AnySource::Playback(p), Some(m)) if (p.sfreq() - m.sfreq).abs() > 1e-9 * m.sfreq => {
            println!(
                "resampling the file from {} Hz to the model's {} Hz (polyphase)",
                p.sfreq(),
                m.sfreq
            );
            AnySource::Playback(
                p.resampled(m.sfreq)
                    .context("resampling the replayed file")?,
            )
        }
        // A live stream is resampled as it streams.
        (s, Some(m)) if (s.sfreq() - m.sfreq).abs() > 1e-9 * m.sfreq => {
            println!(
                "resampling the stream from {} Hz to the model's {} Hz as it streams (polyphase)",
                s.sfreq(),
                m.sfreq
            );
            s.resampled(m.sfreq).context("resampling the stream")?
        }
        (s, _) => s,
    };
    run_with(args, source, markers, clock, (rule, model), &args.commands)
}

fn run_with(
    args: &OnlineArgs,
    source: AnySource,
    markers: Option<Box<dyn oddball_live::live::MarkerSink>>,
    clock: Clock,
    (rule, model): (
        oddball_decode::decision::DecisionRule,
        Option<oddball_decode::pipeline::Model>,
    ),
    commands: &[Command],
) -> Result<()> {
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let paradigm = args.session.paradigm();
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
        model.as_ref().map_or(args.session.pipeline.clone(), |m| m
            .pipeline
            .name()
            .to_string()),
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
    let mut session = Session::new(args.session.params(rule), subject, Some(arm))
        .context("setting up the session")?;
    args.session.name_channels(&mut session)?;
    // The operator view's progress: "calibration decision 3 of 40", "decision 2 of 6".
    let calibrating = model.is_none() && args.session.calibration != CalibrationSpec::None;
    let n_calibration = calibrating.then(|| session.params().calibration_trials());
    session
        .subject_mut()
        .set_plan(n_calibration, Some(commands.len()));
    // A stop request or a source that ends during calibration still closes the recording and
    // writes the summary (with no decisions).
    let mut ended = None;
    match model {
        Some(m) => {
            println!(
                "{}",
                crate::args::model_line(&m, args.session.model.as_deref())
            );
            session.set_model(m).context("using --model")?;
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
            if let Some(m) = session.model() {
                oddball_io::write_atomic(args.out.join("model.json"), m.to_json())?;
            }
        }
        None if args.session.calibration == CalibrationSpec::None => {
            let p = UncalibratedParams::for_sfreq(session.sfreq())
                .context("setting up the uncalibrated decoder")?;
            args.session.start_uncalibrated(&mut session, p)?;
            println!("calibration: none: the decoder learns from the session (EM after every decision, no labels)");
        }
        None => match session.calibrate_with(&mut crate::args::calibration_progress()) {
            Ok(c) => {
                if args.session.adapt {
                    session
                        .start_adaptation(0.8, 0.9)
                        .context("starting online adaptation")?;
                }
                println!(
                    "calibration: {} decisions, {} epochs, cross-validated AUC {:.3}",
                    c.n_trials, c.n_epochs, c.cv_auc
                );
                if let Some(m) = session.model() {
                    oddball_io::write_atomic(args.out.join("model.json"), m.to_json())?;
                }
            }
            Err(e) if is_recording_end(&e) => {
                let end = stop_reason(&e);
                println!("calibration: {end}");
                ended = Some(end);
            }
            Err(e) => return Err(e).context("calibrating"),
        },
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
