//! `oddball online`: a live session. EEG from a live stream (or the simulated subject paced by
//! the wall clock), flashes drawn by the browser panel the binary serves, markers stamped by
//! the frames that drew them, decisions driving the arm, everything recorded to XDF as it runs.
//!
//! Prints the panel's address on its first line when serving (`panel: http://ADDR/`, the
//! subject view; the operator view's on the next), then waits for a subject view before the
//! first countdown.

use std::path::PathBuf;

use anyhow::{bail, Result};
use oddball_app::online::Online;
use oddball_arm::Command;
use oddball_live::source::SourceSpec;

use crate::args::{
    app_error, commands_arg, CalibrationSpec, PanelOptions, SessionOptions, SourceArgs,
    COMMANDS_HELP, STROKE_G,
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
    /// With --source replay:FILE or sim, run as fast as the EEG is processed instead of in real
    /// time (re-running a recorded session with another model, say, or hours of a simulated
    /// session in minutes); not with --serve.
    #[arg(long, conflicts_with = "serve")]
    pub fast: bool,
    #[command(flatten)]
    pub session: SessionOptions,
    /// Report folder: session.xdf (written as the session runs; an existing one is kept and the
    /// new one numbered) and summary.json.
    #[arg(long, value_name = "DIR", default_value = "out/online", value_parser = crate::args::output_dir)]
    pub out: PathBuf,
}

/// Runs the session; `Some(reason)` when it stopped before its last command.
pub fn run(args: &OnlineArgs) -> Result<Option<String>> {
    let settings = args.session.settings();
    let error = |e| app_error(e, &args.session);
    settings.rules().map_err(|e| error(e.into()))?;
    settings
        .check_commands(&args.commands)
        .map_err(|e| error(e.into()))?;
    let uncalibrated = args.session.calibration == CalibrationSpec::None;
    if (args.session.model.is_none(), args.calibrate, uncalibrated) == (true, false, false) {
        bail!("give --model FILE, --calibrate (labelled calibration first) or --calibration none");
    }
    if args.session.realtime {
        bail!("--realtime paces a simulated demo or task: online runs in real time already (--fast plays a file back as fast as it goes)");
    }
    if args.fast && !matches!(args.source.source, SourceSpec::Replay(_) | SourceSpec::Sim) {
        bail!("--fast plays back a file or runs the simulated subject: it needs --source replay:FILE or sim");
    }
    let online = Online {
        settings,
        source: args.source.settings()?,
        panel: args.panel.settings(),
        commands: args.commands.clone(),
        calibrate: args.calibrate,
        fast: args.fast,
        out: args.out.clone(),
    };
    online.run(&mut std::io::stdout()).map_err(error)
}
