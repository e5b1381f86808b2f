//! `oddball online`: a live session. EEG from a live stream (or the simulated subject paced by
//! the wall clock), flashes drawn by the browser panel the binary serves, markers stamped by
//! the frames that drew them, decisions driving the arm, everything recorded to XDF as it runs.
//!
//! Prints the panel's address on its first line when serving (`panel: http://ADDR/`), then
//! waits for a page before the first countdown.

use std::fs;
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use oddball_arm::{parse_commands, ArmConfig, ArmSim};
use oddball_decode::pipeline::Model;
use oddball_live::live::{EegSource, LiveSubject, SimSource, Summary};
use oddball_live::panel::{Clock, PanelConfig, PanelServer};
use oddball_live::playback::PlaybackSource;
use oddball_live::record::Recorder;
use oddball_live::LiveError;
use oddball_session::engine::{Session, SessionParams, ShownFlash, Subject};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::subject::SubjectParams;
use serde::Serialize;

use crate::cmd_demo::SessionOptions;

/// Options of `oddball online`.
#[derive(Debug, clap::Args)]
pub struct OnlineArgs {
    /// Where the EEG comes from: `sim` (the simulated subject, paced by the wall clock),
    /// `lsl:NAME` / `lsl:type=EEG` (a Lab Streaming Layer EEG stream by name or type; needs the
    /// `lsl` feature) or `replay:FILE` (a recording played back at its own rate from its first
    /// sample; a session.xdf of `oddball online` replays to the same flashes with the same
    /// --seed and --commands; the session stops at the end of the file).
    #[arg(long, default_value = "sim", value_name = "SOURCE")]
    pub source: String,
    /// A model trained in a session (`oddball demo` writes one: out/demo/model.json).
    #[arg(long, value_name = "FILE", required_unless_present = "calibrate")]
    pub model: Option<PathBuf>,
    /// Calibrate live first (calibration-per-bulb decisions per bulb) instead of loading a model.
    #[arg(long, conflicts_with = "model")]
    pub calibrate: bool,
    #[command(flatten)]
    pub panel: PanelOptions,
    /// Comma-separated intended commands (a copy task: the panel cues each); the letter G by
    /// default.
    #[arg(long, default_value = "up,left,down,right,up,left")]
    pub commands: String,
    /// Name of the LSL marker outlet (flashes, cues, decisions) with an LSL source.
    #[arg(long, default_value = "oddball-markers")]
    pub markers: String,
    /// With --source replay:FILE, play the file back as fast as it is processed instead of in
    /// real time (re-running a recorded session with another model, say); not with --serve.
    #[arg(long, conflicts_with = "serve")]
    pub fast: bool,
    /// Latency of the simulated amplifier, ms: how late its samples arrive.
    #[arg(long, default_value_t = 250.0)]
    pub sim_latency_ms: f64,
    #[command(flatten)]
    pub session: SessionOptions,
    /// Report folder: session.xdf (written as the session runs; an existing one is kept and the
    /// new one numbered) and summary.json.
    #[arg(long, value_name = "DIR", default_value = "out/online")]
    pub out: PathBuf,
}

/// The stimulus panel in a browser: shared by `oddball online` and `oddball task`.
#[derive(Debug, Clone, clap::Args)]
pub struct PanelOptions {
    /// Serve the stimulus panel here (loopback unless --allow-remote; port 0 picks one) and
    /// wait for a page to open it; its first stdout line is `panel: http://ADDR/`.
    #[arg(long, value_name = "HOST:PORT")]
    pub serve: Option<String>,
    /// Let --serve bind a non-loopback address.
    #[arg(long)]
    pub allow_remote: bool,
    /// Seconds to wait for a page to open the panel before the session starts.
    #[arg(long, default_value_t = 120.0)]
    pub wait_page: f64,
}

impl PanelOptions {
    /// Starts the panel (when --serve) and waits for a page; prints its address first.
    pub fn start(&self, config: PanelConfig, clock: Clock) -> Result<Option<PanelServer>> {
        let Some(addr) = &self.serve else {
            return Ok(None);
        };
        let panel = PanelServer::start(resolve(addr)?, self.allow_remote, config, clock)
            .context("starting the panel")?;
        println!("panel: http://{}/", panel.local_addr());
        if !panel.wait_for_page(Duration::from_secs_f64(self.wait_page)) {
            bail!(
                "no page opened the panel at http://{}/ within {} s",
                panel.local_addr(),
                self.wait_page
            );
        }
        let stats = panel.stats();
        println!(
            "panel page connected: frame {:.2} ms, {}",
            stats.frame_ms.unwrap_or(f64::NAN),
            stats.agent.as_deref().unwrap_or("?")
        );
        Ok(Some(panel))
    }
}

/// What the page needs to draw the panel and the arm for `arm` (targets and planned path in
/// metres).
pub fn panel_config(
    arm: &ArmSim,
    paradigm: &FourBulbParams,
    targets_m: Vec<[f64; 2]>,
    plan_m: Vec<[f64; 2]>,
    title: String,
) -> PanelConfig {
    let board = arm.workspace().board;
    PanelConfig {
        bulbs: paradigm
            .bulbs
            .iter()
            .map(|c| (paradigm.code_of(*c), c.name().to_string()))
            .collect(),
        flash_ms: paradigm.flash_s * 1e3,
        countdown_s: paradigm.countdown_s,
        board_m: [board.x_min_m, board.x_max_m, board.z_min_m, board.z_max_m],
        base_m: [arm.plant().base()[0], arm.plant().base()[1]],
        targets_m,
        plan_m,
        title,
    }
}

#[derive(Debug, Serialize)]
struct DecisionRow {
    index: usize,
    intended: String,
    decided: Option<String>,
    rounds: usize,
    confidence: f64,
    seconds: f64,
}

#[derive(Debug, Serialize)]
struct TimingRow {
    n: usize,
    mean_ms: f64,
    sd_ms: f64,
    min_ms: f64,
    max_ms: f64,
}

impl From<Summary> for TimingRow {
    fn from(s: Summary) -> Self {
        Self {
            n: s.n,
            mean_ms: s.mean,
            sd_ms: s.sd,
            min_ms: s.min,
            max_ms: s.max,
        }
    }
}

#[derive(Debug, Serialize)]
struct OnlineSummary {
    source: String,
    decisions: Vec<DecisionRow>,
    correct: usize,
    abstained: usize,
    flash_on_time: Option<TimingRow>,
    flash_onset_error: Option<TimingRow>,
    stamp_delay: Option<TimingRow>,
    undrawn_flashes: usize,
    decision_latency: Option<TimingRow>,
    recording: String,
    /// `--source replay:…`: how many flashes fell on the file's flashes.
    replay: Option<String>,
    /// What stopped the session early (the replayed file's end).
    ended: Option<String>,
}

fn resolve(addr: &str) -> Result<SocketAddr> {
    addr.to_socket_addrs()
        .with_context(|| format!("{addr}: expected HOST:PORT"))?
        .next()
        .with_context(|| format!("{addr}: no address"))
}

pub fn run(args: &OnlineArgs) -> Result<()> {
    let commands = parse_commands(&args.commands).context("parsing --commands")?;
    if commands.is_empty() {
        bail!("--commands is empty: give at least one of up, down, left, right");
    }
    let (_, rule) = args.session.rules()?;
    if args.fast && !args.source.starts_with("replay:") {
        bail!("--fast plays back a file: it needs --source replay:FILE");
    }
    let clock = Clock::new();
    if let Some(name) = args.source.strip_prefix("lsl:") {
        #[cfg(feature = "lsl")]
        {
            use oddball_live::lsl::StreamQuery;
            use oddball_live::lsl_live::{LslMarkers, LslSource};
            let markers = LslMarkers::new(&args.markers, clock)
                .with_context(|| format!("opening the marker outlet {}", args.markers))?;
            println!("marker outlet: {}", args.markers);
            let query: StreamQuery = name.parse()?;
            let source = LslSource::resolve(&query, 30.0, clock)
                .with_context(|| format!("--source lsl:{name}"))?;
            // Markers pushed before anyone listens are lost (the first cue, say).
            if !markers.wait_for_consumers(10.0) {
                println!("note: nobody reads the marker stream {} yet", args.markers);
            }
            return run_with(
                args,
                source,
                Some(Box::new(markers)),
                clock,
                rule,
                &commands,
                |_, _| None,
            );
        }
        #[cfg(not(feature = "lsl"))]
        bail!(
            "--source lsl:{name}: built without the lsl feature: cargo build --release --features lsl"
        );
    }
    if let Some(file) = args.source.strip_prefix("replay:") {
        let mut source =
            PlaybackSource::open(file, clock).with_context(|| format!("--source replay:{file}"))?;
        if args.fast {
            source = source.unpaced();
        }
        println!(
            "replaying {file}: {} channels, {} Hz, {:.1} s, {} events",
            source.ch_names().len(),
            source.sfreq(),
            source.n_times() as f64 / source.sfreq(),
            source.events().len()
        );
        return run_with(args, source, None, clock, rule, &commands, coincidence);
    }
    if args.source != "sim" {
        bail!(
            "--source {}: expected sim, lsl:NAME or replay:FILE",
            args.source
        );
    }
    let preset = args
        .session
        .preset()?
        .context("--subject replay:… is not a live source")?;
    let sim = SubjectParams::preset(preset)
        .with_seed(args.session.seed)
        .build()
        .context("building the simulated subject")?;
    let source = SimSource::new(sim, clock, args.sim_latency_ms);
    run_with(args, source, None, clock, rule, &commands, |_, _| None)
}

/// How many of this session's flashes fall on a flash of the same bulb in the replayed file.
fn coincidence(source: &PlaybackSource, flashes: &[ShownFlash]) -> Option<String> {
    // A P300 spans hundreds of ms: a page's few ms of onset jitter do not matter.
    let tolerance = (REPLAY_TOLERANCE_S * source.sfreq()).round().max(1.0) as u64;
    let shown: Vec<(u64, u32)> = flashes.iter().map(|f| (f.onset, f.code)).collect();
    let k = source.coincidence(&shown, tolerance);
    let mut line = format!(
        "replay: {k} of {} flashes of this session fall on a flash of the same bulb in the file (±{tolerance} samples)",
        shown.len()
    );
    if k < shown.len() {
        line.push_str(
            "; the others met EEG with no response to them (replay with the recording's --seed and --commands)",
        );
    }
    Some(line)
}

/// Flashes of a replayed session within this of a flash in the file coincide with it, s.
const REPLAY_TOLERANCE_S: f64 = 0.010;

fn run_with<S: EegSource>(
    args: &OnlineArgs,
    source: S,
    markers: Option<Box<dyn oddball_live::live::MarkerSink>>,
    clock: Clock,
    rule: oddball_decode::decision::DecisionRule,
    commands: &[oddball_arm::Command],
    review: impl FnOnce(&S, &[ShownFlash]) -> Option<String>,
) -> Result<()> {
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let paradigm = FourBulbParams::paper();
    let mut arm = ArmSim::from_config(&ArmConfig::default()).context("setting up the arm")?;
    arm.set_recording(true);
    let model = match &args.model {
        Some(path) => {
            let text =
                fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            let mut m =
                Model::from_json(&text).with_context(|| format!("loading {}", path.display()))?;
            // The stopping rule is this session's choice, not the training session's.
            if let Some(d) = &mut m.decision {
                d.rule = rule;
            }
            Some(m)
        }
        None => None,
    };
    // Never overwrite an earlier recording: session.xdf, else session-1.xdf, session-2.xdf, …
    let record_path = (0..)
        .map(|i| match i {
            0 => args.out.join("session.xdf"),
            i => args.out.join(format!("session-{i}.xdf")),
        })
        .find(|p| !p.exists())
        .expect("a free name");
    let recorder = Recorder::create(
        &record_path,
        source.ch_names(),
        source.sfreq(),
        &args.source,
    )
    .with_context(|| format!("creating {}", record_path.display()))?;
    let title = format!(
        "{} · {} · {}",
        args.source,
        model.as_ref().map_or(args.session.pipeline.clone(), |m| m
            .pipeline
            .name()
            .to_string()),
        if args.calibrate {
            "calibrating first"
        } else {
            "model loaded"
        }
    );
    let mut subject = LiveSubject::new(source, paradigm, clock).with_recorder(recorder);
    if let Some(m) = markers {
        subject = subject.with_markers(m);
    }
    let config = panel_config(&arm, &paradigm, Vec::new(), plan(&arm, commands), title);
    if let Some(panel) = args.panel.start(config, clock)? {
        subject = subject.with_panel(panel);
    }
    println!(
        "oddball online: source {}, {} commands, recording {}",
        args.source,
        commands.len(),
        record_path.display()
    );
    subject.source_mut().start_now();
    let mut params = SessionParams::paper(&args.session.pipeline);
    params.seed = args.session.seed;
    params.rule = rule;
    params.calibration_per_bulb = args.session.calibration_per_bulb;
    let mut session = Session::new(params, subject, Some(arm)).context("setting up the session")?;
    match model {
        Some(m) => session.set_model(m).context("using the model")?,
        None => {
            let c = session.calibrate().context("calibrating")?;
            println!(
                "calibration: {} decisions, {} epochs, cross-validated AUC {:.3}",
                c.n_trials, c.n_epochs, c.cv_auc
            );
            if let Some(m) = session.model() {
                fs::write(args.out.join("model.json"), m.to_json())?;
            }
        }
    }
    let mut rows = Vec::new();
    let p = session.params().paradigm;
    let mut ended = None;
    for (i, &command) in commands.iter().enumerate() {
        let t = match session.decide(Some(command)) {
            Ok(t) => t,
            Err(e) => match recording_ended(&mut session) {
                Some(end) => {
                    println!("decision {}: {end}", i + 1);
                    ended = Some(end);
                    break;
                }
                None => return Err(e).with_context(|| format!("decision {}", i + 1)),
            },
        };
        let decided = t.decided().and_then(|c| p.command_of(c));
        let row = DecisionRow {
            index: i + 1,
            intended: command.name().to_string(),
            decided: decided.map(|c| c.name().to_string()),
            rounds: t.rounds,
            confidence: t.confidence(),
            seconds: (t.end - t.start) as f64 / session.sfreq(),
        };
        println!(
            "decision {}: {} → {}{} (p {:.3}, {} rounds, {:.2} s)",
            row.index,
            row.intended,
            row.decided.as_deref().unwrap_or("abstain"),
            match decided {
                Some(d) if d == command => " ✓",
                Some(_) => " ✗",
                None => "",
            },
            row.confidence,
            row.rounds,
            row.seconds
        );
        if let Some(r) = &t.arm_refusal {
            println!("  the arm refused: {r}");
        }
        rows.push(row);
    }
    if ended.is_none() {
        if let Err(e) = session.idle(1.5) {
            ended = Some(recording_ended(&mut session).ok_or(e)?);
        }
    }
    let correct = rows
        .iter()
        .filter(|r| r.decided.as_deref() == Some(r.intended.as_str()))
        .count();
    let abstained = rows.iter().filter(|r| r.decided.is_none()).count();
    if let Some(r) = session.channel_report() {
        println!("{r}");
    }
    let replay = review(session.subject().source(), session.flashes());
    if let Some(r) = &replay {
        println!("{r}");
    }
    let subject = session.subject_mut();
    let timing = subject.timing.clone();
    let latency = subject.decision_latency_ms.clone();
    let health = subject.stream_health();
    let mut summary_line = format!(
        "{correct}/{} decisions right, {abstained} abstained",
        rows.len()
    );
    if ended.is_some() {
        summary_line.push_str(&format!(
            " ({} of {} made before the recording ended)",
            rows.len(),
            commands.len()
        ));
    }
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
    let (log, _, _) = session.finish();
    let summary = OnlineSummary {
        source: args.source.clone(),
        decisions: rows,
        correct,
        abstained,
        flash_on_time: Summary::of(&timing.on_ms).map(Into::into),
        flash_onset_error: Summary::of(&timing.onset_error_ms).map(Into::into),
        stamp_delay: Summary::of(&timing.report_delay_ms).map(Into::into),
        undrawn_flashes: timing.undrawn,
        decision_latency: Summary::of(&latency).map(Into::into),
        recording: record_path.display().to_string(),
        replay,
        ended: ended.map(|e| e.to_string()),
    };
    let _ = log;
    let path = args.out.join("summary.json");
    fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "recording: {} ({} samples)",
        record_path.display(),
        summary_samples(&record_path)
    );
    Ok(())
}

/// The replayed file's end, when that is what stopped the session.
fn recording_ended<S: EegSource>(session: &mut Session<LiveSubject<S>>) -> Option<LiveError> {
    match session.subject_mut().take_error() {
        Some(e @ LiveError::RecordingEnded { .. }) => Some(e),
        _ => None,
    }
}

fn summary_samples(path: &std::path::Path) -> String {
    match oddball_io::read(path) {
        Ok(r) => r.raw.n_times().to_string(),
        Err(e) => format!("unreadable: {e}"),
    }
}

/// The pen's planned path for `commands` from where it starts.
fn plan(arm: &ArmSim, commands: &[oddball_arm::Command]) -> Vec<[f64; 2]> {
    let mut p = arm.target();
    let mut out = vec![[p[0], p[1]]];
    for &c in commands {
        p = c.apply(&p, arm.settings().step_m);
        out.push([p[0], p[1]]);
    }
    out
}
