//! Arguments shared by several commands, typed once (clap parses them into library types):
//! where the EEG comes from ([`SourceArgs`]), who watches the panel and how the session decides
//! ([`SessionOptions`]), the browser panel ([`PanelOptions`]) and NIC's framing ([`NicWire`]);
//! each becomes `oddball_app`'s settings, and [`app_error`] maps a run's errors back to the flags.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use anyhow::{anyhow, bail, Result};
use oddball_app::error::{AppError, SettingError, StartKind};
use oddball_app::panel::PanelSettings;
pub use oddball_app::settings::{join_paths, CalibrationSpec, SubjectSpec};
use oddball_app::settings::{SessionSettings, SourceSettings};
use oddball_arm::Command;
use oddball_decode::preset::Preset;
use oddball_io::nic::{NicFormat, NicMode};
use oddball_live::plan::PlanError;
use oddball_live::source::{SourceSpec, SOURCE_HELP};
use oddball_session::paradigm::{ParadigmPreset, TimingOverrides};
use oddball_session::SessionError;

/// An output file (`-o`, `--json`, `--csv`): checked when the arguments are parsed, before any
/// work, so a mistyped folder fails at once instead of after training. Its folder must exist
/// and the path must not be a folder.
pub fn output_file(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if s.is_empty() {
        return Err("an empty path".into());
    }
    if path.is_dir() {
        return Err(format!("{s} is a folder: give a file name inside it"));
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => return Ok(path),
    };
    if !parent.is_dir() {
        return Err(if parent.exists() {
            format!("{} is not a folder", parent.display())
        } else {
            format!(
                "the folder {} does not exist (create it first, e.g. mkdir -p {})",
                parent.display(),
                parent.display()
            )
        });
    }
    Ok(path)
}

/// A picture to write (`--plot`): an [`output_file`] ending in .png or .svg.
pub fn plot_file(s: &str) -> Result<PathBuf, String> {
    let path = output_file(s)?;
    oddball_plot::PlotFormat::from_path(&path).map_err(|e| e.to_string())?;
    Ok(path)
}

/// A report folder (`--out DIR`): created when the command starts; refused at once when a file
/// of that name is in the way (or in the way of one of its parents).
pub fn output_dir(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if s.is_empty() {
        return Err("an empty path".into());
    }
    for p in path.ancestors().filter(|p| !p.as_os_str().is_empty()) {
        if p.exists() {
            if !p.is_dir() {
                return Err(format!(
                    "{} is a file, not a folder: give another --out",
                    p.display()
                ));
            }
            break;
        }
    }
    Ok(path)
}

/// The letter G of the paper, as `--commands` spells it.
pub const LETTER_G: &str = "up,left,down,right,up,left";

/// `--commands letter-g`: the letter G of the drawing task's stroke font (`task draw --draw G`).
pub const STROKE_G: &str = "letter-g";

/// `--commands paper-g`: the paper's letter G as its six commands (`Command::LETTER_G`).
pub const PAPER_G: &str = "paper-g";

/// What `--commands` takes, for the help texts.
pub const COMMANDS_HELP: &str = "Intended commands, comma-separated (up, down, left, right or u, d, l, r), or a named sequence: `letter-g`, the letter G of `task draw --draw G` (20 one-step moves: up the back and out along the top, then counter-clockwise round the letter as the paper draws it, left along the top, down, right, up and the spur left, then back down to the baseline), or `paper-g`, the paper's six commands up,left,down,right,up,left (the paper's strokes differ in length; on equal steps they trace a square one step wide, one and a half times round)";

/// Intended commands: a comma-separated list (up, down, left, right), or a named sequence
/// ([`STROKE_G`], [`PAPER_G`]).
pub fn commands_arg(s: &str) -> Result<Vec<Command>, String> {
    let c = match s.trim() {
        STROKE_G => oddball_session::tasks::text_commands("G").map_err(|e| e.to_string())?,
        PAPER_G => Command::LETTER_G.to_vec(),
        list => oddball_arm::parse_commands(list).map_err(|e| e.to_string())?,
    };
    if c.is_empty() {
        return Err("empty: give at least one of up, down, left, right".into());
    }
    Ok(c)
}

/// `--subject` of `online`: a simulated preset only (a replayed speller recording is not a live
/// source).
pub fn simulated_subject(s: &str) -> Result<SubjectSpec, String> {
    if s.starts_with("replay:") {
        return Err("online runs a live or simulated subject; to play a recorded session back give --source replay:FILE (a speller recording is replayed by `oddball demo --subject replay:FILE`)".into());
    }
    s.parse()
}

/// Where the EEG comes from: shared by `demo`, `task` and `online`.
#[derive(Debug, Clone, clap::Args)]
pub struct SourceArgs {
    #[arg(long, default_value = "sim", value_name = "SOURCE", help = SOURCE_HELP)]
    pub source: SourceSpec,
    #[command(flatten)]
    pub nic: NicWire,
    /// Name of the LSL marker outlet (flashes, cues, decisions) with an LSL source.
    #[arg(long, default_value = "oddball-markers")]
    pub markers: String,
    /// Latency of the simulated amplifier, ms: how late its samples arrive (paced `sim`).
    #[arg(long, default_value_t = 250.0)]
    pub sim_latency_ms: f64,
}

impl SourceArgs {
    /// The source's settings (NIC's framing checked).
    pub fn settings(&self) -> Result<SourceSettings> {
        Ok(SourceSettings {
            source: self.source.clone(),
            nic: self.nic.format()?,
            markers: self.markers.clone(),
            sim_latency_ms: self.sim_latency_ms,
        })
    }
}

/// Who watches the panel and how the session decides: shared by `demo`, `task` and `online`.
#[derive(Debug, Clone, clap::Args)]
pub struct SessionOptions {
    /// Who watches the panel: easy, typical or hard (simulated), or replay:FILE[,FILE…]
    /// (P300-speller recordings played back, in order, as four-choice decisions).
    #[arg(long, default_value = "typical")]
    pub subject: SubjectSpec,
    /// How the session starts: `labelled` (calibration-per-bulb labelled decisions per bulb;
    /// for a replayed subject, the replay file's sibling whose name ends in _1 instead of _N,
    /// e.g. eeg3_1.dat for eeg3_2.dat), `none` (no calibration: the first command comes from the
    /// first trial, the decoder is refitted without labels after every decision — EM over "one
    /// bulb per trial" — and abstains while unsure), or FILE (a replayed subject's calibration
    /// recording, or several separated by commas, e.g. BCI Competition II IIb's four training
    /// runs).
    #[arg(long, value_name = "labelled|none|FILE[,FILE…]", default_value = "labelled", value_parser = CalibrationSpec::from_str)]
    pub calibration: CalibrationSpec,
    /// With --calibration none: start from this model (`model.json` of another person's or
    /// another session's `oddball demo`/`train` run, same montage): its scores start the
    /// unsupervised decoder, which then adapts it to this session without labels.
    #[arg(long, value_name = "MODEL")]
    pub transfer: Option<PathBuf>,
    /// Decide with this saved model instead of calibrating: `oddball train`'s (e.g. `oddball
    /// train out/demo/session.dat -o m.json`), or the model.json of a `demo`, `task` or
    /// `online` session. Its channels are matched by name (the EEG may have more, in any order);
    /// a model trained offline runs its band-pass causally.
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// Names the EEG's channels in order (an EEGLAB .loc montage, e.g. BCI2000's eeg64.loc), for
    /// a stream or replayed file whose own names are not the model's; the session's recording
    /// and model carry these names.
    #[arg(long, value_name = "FILE")]
    pub montage: Option<PathBuf>,
    /// After the labelled calibration (`lda` pipeline), adapt the model online: after each
    /// decision its class means take in the decision's epochs, labelled by the decision, through
    /// incremental statistics; decisions with a posterior below 0.9 are left out, and an update
    /// that turns the weights too far from the calibrated ones (cosine below 0.8) is undone.
    #[arg(long)]
    pub adapt: bool,
    /// With --subject replay:…: the text each replayed file spelled, comma-separated (a
    /// speller run recorded without labels, e.g. IIb's test runs: HAM,PIE). It only says which
    /// row or column each decision's attended bulb shows; nothing is fitted on it.
    #[arg(long, value_name = "TEXT,…", value_delimiter = ',')]
    pub test_text: Vec<String>,
    /// Seed of the simulated subject and the flash orders.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Pace the simulated session in real time instead of as fast as possible.
    #[arg(long)]
    pub realtime: bool,
    /// Stop flashing as soon as one bulb is probable enough (and abstain when none is
    /// credible).
    #[arg(long)]
    pub dynamic_stopping: bool,
    /// Posterior at which dynamic stopping decides.
    #[arg(
        long,
        default_value_t = 0.95,
        value_name = "P",
        requires = "dynamic_stopping"
    )]
    pub threshold: f64,
    /// Most rounds per decision with dynamic stopping.
    #[arg(long, default_value_t = 5, requires = "dynamic_stopping")]
    pub max_rounds: usize,
    #[arg(long, default_value = crate::preset_arg::DEFAULT_PIPELINE, value_parser = crate::preset_arg::preset, help = crate::preset_arg::one_help())]
    pub pipeline: Preset,
    /// Calibration decisions per bulb (simulated subjects).
    #[arg(long, default_value_t = 10)]
    pub calibration_per_bulb: usize,
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Choose the dynamic-stopping threshold and round limit from the calibration (its
    /// cross-validated scores) for the most expected bits per minute (Wolpaw) at this timing;
    /// abstains as dynamic stopping does.
    #[arg(long, conflicts_with_all = ["dynamic_stopping", "threshold", "max_rounds"])]
    pub optimise_stopping: bool,
    /// The most rounds --optimise-stopping may choose.
    #[arg(
        long,
        default_value_t = 12,
        value_name = "N",
        requires = "optimise_stopping"
    )]
    pub round_limit: usize,
    /// With --optimise-stopping: only rules expected (from the calibration) to be right at
    /// least this often compete on bits/min; the most accurate wins when none is.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "P",
        requires = "optimise_stopping"
    )]
    pub min_accuracy: f64,
    /// The step h one command moves the pen, metres (e.g. --step 0.01 for text that does not
    /// fit the board at the default) [default: the arm's, 0.02].
    #[arg(long, value_name = "METRES")]
    pub step: Option<f64>,
}

/// The panel's timing: a named preset and changes to it.
#[derive(Debug, Clone, clap::Args)]
pub struct TimingArgs {
    /// Timing of the four-bulb panel: paper (100 ms on, 150 ms gap, rounds of 1 s, 5 s
    /// countdown) or fast (100 ms on, 75 ms off, rounds not padded, 1 s cue).
    #[arg(long, default_value = "paper", value_parser = paradigm_preset)]
    pub paradigm: ParadigmPreset,
    /// Time a bulb stays lit, ms [default: the preset's].
    #[arg(long, value_name = "MS")]
    pub flash_ms: Option<f64>,
    /// Dark time between flashes, ms [default: the preset's].
    #[arg(long, value_name = "MS")]
    pub gap_ms: Option<f64>,
    /// The cue (countdown) before each decision, ms [default: the preset's].
    #[arg(long, value_name = "MS")]
    pub cue_ms: Option<f64>,
    /// Pad each round of four flashes to this length, ms; 0 pads nothing [default: 1000 for
    /// paper, none for fast].
    #[arg(long, value_name = "MS")]
    pub round_ms: Option<f64>,
}

fn paradigm_preset(s: &str) -> Result<ParadigmPreset, String> {
    s.parse()
        .map_err(|e: oddball_session::SessionError| e.to_string())
}

impl SessionOptions {
    /// The session's settings.
    pub fn settings(&self) -> SessionSettings {
        let t = &self.timing;
        SessionSettings {
            subject: self.subject.clone(),
            calibration: self.calibration.clone(),
            transfer: self.transfer.clone(),
            model: self.model.clone(),
            montage: self.montage.clone(),
            adapt: self.adapt,
            test_text: self.test_text.clone(),
            seed: self.seed,
            realtime: self.realtime,
            dynamic_stopping: self.dynamic_stopping,
            threshold: self.threshold,
            max_rounds: self.max_rounds,
            pipeline: self.pipeline,
            calibration_per_bulb: self.calibration_per_bulb,
            paradigm: t.paradigm,
            timing: TimingOverrides {
                flash_ms: t.flash_ms,
                gap_ms: t.gap_ms,
                cue_ms: t.cue_ms,
                round_ms: t.round_ms,
            },
            optimise_stopping: self.optimise_stopping,
            round_limit: self.round_limit,
            min_accuracy: self.min_accuracy,
            step: self.step,
        }
    }
}

/// A run's error in the command line's terms: the flags at fault named, the library's facts as
/// the cause (`opts`: the session's options, for the files they name).
pub fn app_error(e: AppError, opts: &SessionOptions) -> anyhow::Error {
    let path = |p: &Option<PathBuf>| p.as_deref().unwrap_or(Path::new("")).display().to_string();
    match e {
        AppError::Setting(s) => setting_error(s),
        AppError::Plan {
            error,
            source_spec,
            start,
        } => match error {
            PlanError::Invalid(why) => anyhow!("{why}"),
            PlanError::Arm(e) => anyhow::Error::new(e).context("checking --step"),
            PlanError::Open(e) => anyhow::Error::new(e).context(format!("--source {source_spec}")),
            PlanError::Rate(e) => {
                anyhow::Error::new(e).context("resampling the EEG to the model's rate")
            }
            PlanError::Session(e) => anyhow::Error::new(e).context("setting up the session"),
            PlanError::Montage(e) => anyhow::Error::new(e).context(format!(
                "naming the channels with --montage {}",
                path(&opts.montage)
            )),
            PlanError::Start(e) => {
                let channels = matches!(e, SessionError::ModelChannels { .. });
                let e = anyhow::Error::new(e);
                match start {
                    StartKind::Calibrate => e.context("calibrating"),
                    StartKind::Model if channels => e.context(
                        "using --model: name the EEG's channels in order with --montage FILE",
                    ),
                    StartKind::Model => e.context("using --model"),
                    StartKind::Uncalibrated { transfer: true } => {
                        e.context(format!("starting from --transfer {}", path(&opts.transfer)))
                    }
                    StartKind::Uncalibrated { transfer: false } => {
                        e.context("setting up the uncalibrated decoder")
                    }
                }
            }
        },
        e => anyhow::Error::new(e),
    }
}

/// Settings at fault, as the flags that gave them.
fn setting_error(e: SettingError) -> anyhow::Error {
    use SettingError as S;
    let within =
        |e: SessionError, flags: &str| anyhow::Error::new(e).context(format!("checking {flags}"));
    match e {
        S::ModelWithoutCalibration => anyhow!("--calibration none starts without a model: not with --model"),
        S::AdaptWithModel => anyhow!("--adapt adapts a calibration made in this session (--calibrate), not --model"),
        S::OptimiseWithModel => anyhow!("--optimise-stopping chooses the rule from this session's calibration: use it with --calibrate, not --model"),
        S::ReplayWithModel { files } => anyhow!(
            "--subject replay:{} calibrates on the recording's calibration file, not --model; to replay a recording with a model: oddball online --source replay:{} --model MODEL --fast",
            join_paths(&files),
            files.first().map(|f| f.display().to_string()).unwrap_or_default()
        ),
        S::TransferNeedsUncalibrated => anyhow!("--transfer starts an uncalibrated session: it needs --calibration none"),
        S::AdaptUncalibrated => anyhow!("--adapt adapts a labelled calibration; --calibration none adapts by itself"),
        S::TestTextWithoutReplay => anyhow!("--test-text labels replayed files: it needs --subject replay:FILE"),
        S::AdaptNeedsLda { pipeline } => anyhow!("--adapt needs --pipeline lda (got {pipeline})"),
        S::Timing(e) => within(e, "--paradigm/--flash-ms/--gap-ms/--cue-ms/--round-ms"),
        S::DynamicRule(e) => anyhow::Error::new(e).context("checking --threshold/--max-rounds"),
        S::StoppingSearch(e) => anyhow::Error::new(e).context("checking --round-limit/--min-accuracy"),
        S::Arm(e) => anyhow::Error::new(e).context("checking --step"),
        S::Commands(e) => off_board(e, "--commands", "fewer commands"),
        S::Drawing { text, source } => off_board(source, &format!("--draw {text:?}"), "shorter text"),
        S::Track(e) => within(e, "--target/--targets/--tolerance-mm"),
        S::NotLive => anyhow!("--subject replay:… is not a live source"),
        S::Subject(e) => anyhow::Error::new(e).context("building the simulated subject"),
        S::SourceOptions(e) => anyhow::Error::new(e).context("checking --sim-latency-ms"),
        S::NoDecisionModel { path } => anyhow!(
            "--model {}: {}",
            path.display(),
            oddball_decode::model::NO_DECISION_MODEL
        ),
        S::Montage { source, .. } => anyhow::Error::new(source),
        S::ReplayUncalibrated => anyhow!(
            "--calibration none runs a live or simulated session; a replayed subject \
             (--subject replay:…) is calibrated on its recording (use `oddball evaluate \
             --unsupervised` to replay a recording without labels)"
        ),
        S::ReplayedFile(e) => anyhow::Error::new(e).context("--subject replay:FILE"),
        S::TestTextCount { texts, files } => anyhow!(
            "--test-text gives {texts} texts for {files} replayed files (one per file)"
        ),
        S::CalibrationFile(e) => anyhow::Error::new(e).context("the calibration recording"),
        S::NoSibling { path } => anyhow!(
            "no calibration recording for {}: give one with --calibration FILE",
            path.display()
        ),
        S::Unlabelled {
            path,
            n_events,
            events,
            calibration,
        } => anyhow!(
            "{} has {n_events} events but none is labelled target or non-target (its events: {events}); {}",
            path.display(),
            if calibration {
                "calibrate on a labelled recording (--calibration FILE)"
            } else {
                "give the text each replayed speller run spelled with --test-text"
            }
        ),
        S::ReplayWithSource { files, spec } => anyhow!(
            "--subject replay:{} replays decisions offline: it takes no --source {spec}",
            join_paths(&files)
        ),
        S::ServeReplay => anyhow!("--serve: the panel runs with simulated subjects; a replayed recording's flashes are already fixed"),
        S::WaitPage { seconds, max } => anyhow!("--wait-page {seconds}: expected 0 to {max} seconds"),
        S::Address { addr, source: Some(e) } => {
            anyhow::Error::new(e).context(format!("{addr}: expected HOST:PORT"))
        }
        S::Address { addr, source: None } => anyhow!("{addr}: no address"),
        e @ (S::ModelFile(_)
        | S::ReadModel { .. }
        | S::LoadModel { .. }
        | S::ReplayedAndCalibrated { .. }) => {
            anyhow::Error::new(e)
        }
    }
}

/// A path that leaves the board as one line naming the option at fault (`option`) and what
/// fixes it: `--step` with the largest step that fits, or `less` (shorter text, fewer
/// commands); the library's facts follow as the cause.
fn off_board(e: SessionError, option: &str, less: &str) -> anyhow::Error {
    let hint = match &e {
        SessionError::PathOffBoard {
            max_step_m: Some(m),
            ..
        } => format!("use --step {m} (metres) or less, or {less}"),
        SessionError::PathOffBoard { .. } => format!("no step fits from the pen's start: {less}"),
        _ => return anyhow::Error::new(e).context(format!("checking {option}")),
    };
    anyhow::Error::new(e).context(format!("checking {option}: it leaves the board; {hint}"))
}

/// The stimulus panel in a browser: shared by `online` and `task`.
#[derive(Debug, Clone, clap::Args)]
pub struct PanelOptions {
    /// Serve the stimulus panel here (loopback unless --allow-remote; port 0 picks one) and
    /// wait for a page to open it; its first stdout line is `panel: http://ADDR/` (the subject
    /// view), its second the operator view's address (progress, timing, pause and abort).
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
    /// The panel's settings.
    pub fn settings(&self) -> PanelSettings {
        PanelSettings {
            serve: self.serve.clone(),
            allow_remote: self.allow_remote,
            wait_page: self.wait_page,
        }
    }
}

/// How NIC's stream is framed: shared by the simulator and the sessions reading it.
#[derive(Debug, Clone, clap::Args)]
pub struct NicWire {
    /// binary or ascii framing.
    #[arg(long, default_value = "binary", value_parser = nic_mode)]
    pub nic_mode: NicMode,
    /// EEG channels per sample (the simulated Starstim has 8).
    #[arg(long, default_value_t = 8)]
    pub nic_channels: usize,
    /// The stream carries no trigger column.
    #[arg(long)]
    pub nic_no_trigger: bool,
    /// The stream carries no timestamp (lost samples cannot be counted).
    #[arg(long)]
    pub nic_no_timestamp: bool,
}

fn nic_mode(name: &str) -> Result<NicMode, String> {
    match name {
        "binary" => Ok(NicMode::Binary),
        "ascii" => Ok(NicMode::Ascii),
        other => Err(format!("NIC mode {other:?}: expected binary or ascii")),
    }
}

impl NicWire {
    pub fn format(&self) -> Result<NicFormat> {
        if !(1..=64).contains(&self.nic_channels) {
            bail!("--nic-channels {}: expected 1..=64", self.nic_channels);
        }
        Ok(NicFormat {
            mode: self.nic_mode,
            n_channels: self.nic_channels,
            trigger: !self.nic_no_trigger,
            timestamp: !self.nic_no_timestamp,
        })
    }
}

/// `HOST:PORT` → its first address.
pub fn resolve(addr: &str) -> Result<SocketAddr> {
    oddball_app::panel::resolve(addr).map_err(setting_error)
}
