//! Arguments shared by several commands, typed once (clap parses them into library types):
//! where the EEG comes from ([`SourceArgs`]), who watches the panel and how the session decides
//! ([`SessionOptions`]), the browser panel ([`PanelOptions`]) and NIC's framing ([`NicWire`]).

use std::net::{SocketAddr, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use oddball_arm::{ArmSim, Command, Vector2};
use oddball_decode::decision::DecisionRule;
use oddball_decode::pipeline::Model;
use oddball_decode::preset::Preset;
use oddball_io::nic::{NicFormat, NicMode};
use oddball_live::clock::Clock;
use oddball_live::live::LiveSubject;
use oddball_live::panel::{PanelConfig, PanelServer};
use oddball_live::plan::{recording_arm, PlanError, SessionPlan};
use oddball_live::source::AnySource;
use oddball_live::source::{OpenOptions, SourceSpec, SOURCE_HELP};
use oddball_session::decision::{CalibrationProgress, CalibrationReport};
use oddball_session::decoder::{AdaptParams, Start, UncalibratedParams};
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::{FourBulbParams, ParadigmPreset, TimingOverrides};
use oddball_session::subject::{SubjectParams, SubjectPreset, STARSTIM_SFREQ};
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

/// How a session starts: `--calibration labelled|none|FILE`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum CalibrationSpec {
    /// Labelled calibration decisions (a replayed subject: its sibling recording).
    #[default]
    Labelled,
    /// No calibration: the unsupervised decoder learns from the session itself.
    None,
    /// The calibration recordings of a replayed subject (comma-separated).
    Files(Vec<PathBuf>),
}

impl FromStr for CalibrationSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "labelled" | "labeled" => Self::Labelled,
            "none" => Self::None,
            "" => return Err("give labelled, none or a calibration recording".into()),
            files => Self::Files(files.split(',').map(PathBuf::from).collect()),
        })
    }
}

/// Who watches the panel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SubjectSpec {
    /// A simulated subject: easy, typical or hard.
    Preset(SubjectPreset),
    /// P300-speller recordings played back, in order, as four-choice decisions.
    Replay(Vec<PathBuf>),
}

impl FromStr for SubjectSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.strip_prefix("replay:") {
            Some(f) if !f.split(',').any(str::is_empty) => {
                Ok(Self::Replay(f.split(',').map(PathBuf::from).collect()))
            }
            Some(_) => Err("replay: needs a file, or files separated by commas".into()),
            None => s.parse().map(Self::Preset).map_err(|e| e.to_string()),
        }
    }
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
    /// How to open the source for `subject` (the simulated one, which also names a NIC
    /// stream's channels).
    pub fn open_options(
        &self,
        subject: oddball_session::SimulatedSubject,
        paced: bool,
    ) -> Result<OpenOptions> {
        let opts = OpenOptions {
            subject,
            paced,
            sim_latency_ms: self.sim_latency_ms,
            nic: self.nic.format()?,
            nic_sfreq: STARSTIM_SFREQ,
            markers: self.markers.clone(),
        };
        opts.check().context("checking --sim-latency-ms")?;
        Ok(opts)
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

impl TimingArgs {
    /// The panel's timing, checked.
    pub fn paradigm(&self) -> Result<FourBulbParams> {
        let o = TimingOverrides {
            flash_ms: self.flash_ms,
            gap_ms: self.gap_ms,
            cue_ms: self.cue_ms,
            round_ms: self.round_ms,
        };
        FourBulbParams::timed(self.paradigm, &o)
            .context("checking --paradigm/--flash-ms/--gap-ms/--cue-ms/--round-ms")
    }
}

impl SessionOptions {
    /// The fixed rule (5 rounds) and the rule in effect (the options checked first).
    pub fn rules(&self) -> Result<(DecisionRule, DecisionRule)> {
        self.check()?;
        let fixed = DecisionRule::Fixed {
            rounds: self.timing.paradigm()?.n_rounds,
        };
        let dynamic = DecisionRule::Dynamic {
            threshold: self.threshold,
            min_rounds: 1,
            max_rounds: self.max_rounds,
            credible: 0.5,
            p_no_control: 0.2,
        };
        dynamic
            .validate()
            .context("checking --threshold/--max-rounds")?;
        if self.optimise_stopping {
            let search = self.stopping_search();
            search
                .validate()
                .context("checking --round-limit/--min-accuracy")?;
            // Replaced by the rule calibration chooses.
            return Ok((fixed, DecisionRule::dynamic(search.max_rounds)));
        }
        Ok((
            fixed,
            if self.dynamic_stopping {
                dynamic
            } else {
                fixed
            },
        ))
    }

    /// The panel's timing (checked by [`Self::rules`], which every command calls first; the
    /// paper's should it be invalid).
    pub fn paradigm(&self) -> FourBulbParams {
        self.timing.paradigm().unwrap_or_default()
    }

    /// The simulated preset (the subject of a `sim` source, and the montage of a NIC stream).
    pub fn preset(&self) -> Option<SubjectPreset> {
        match self.subject {
            SubjectSpec::Preset(p) => Some(p),
            SubjectSpec::Replay(_) => None,
        }
    }

    /// The simulated subject of this seed.
    pub fn simulated(&self) -> Result<oddball_session::SimulatedSubject> {
        let preset = self
            .preset()
            .context("--subject replay:… is not a live source")?;
        SubjectParams::preset(preset)
            .with_seed(self.seed)
            .build()
            .context("building the simulated subject")
    }

    /// The session's settings under `rule`.
    pub fn params(&self, rule: DecisionRule) -> SessionParams {
        let mut params = SessionParams::paper(self.pipeline);
        params.paradigm = self.paradigm();
        params.decoder.seed = self.seed;
        params.decoder.rule = rule;
        params.calibration_per_bulb = self.calibration_per_bulb;
        // Only for the rule in effect (a fixed-rounds comparison keeps its rounds).
        params.decoder.stopping = (self.optimise_stopping
            && !matches!(rule, DecisionRule::Fixed { .. }))
        .then(|| self.stopping_search());
        params
    }

    /// What --optimise-stopping searches.
    pub fn stopping_search(&self) -> oddball_decode::stopping::StoppingSearch {
        oddball_decode::stopping::StoppingSearch {
            max_rounds: self.round_limit,
            min_accuracy: self.min_accuracy,
            seed: self.seed,
            ..Default::default()
        }
    }

    /// The session's plan over `source` under `rule` (paced by the wall clock when `paced`),
    /// starting with `model` (`--model`, read by [`Self::session_model`]) when given.
    pub fn plan(
        &self,
        source: &SourceArgs,
        rule: DecisionRule,
        paced: bool,
        model: Option<Model>,
    ) -> Result<SessionPlan> {
        let montage = match &self.montage {
            Some(path) => Some(oddball_io::montage::read_montage(path)?),
            None => None,
        };
        Ok(SessionPlan {
            source: source.source.clone(),
            open: source.open_options(self.simulated()?, paced)?,
            params: self.params(rule),
            start: self.start(model)?,
            montage,
            step_m: self.step,
        })
    }

    /// Opens `plan`'s live session and starts it, printing what it did when `verbose`: the
    /// session, what calibration measured, the pen's start.
    pub fn open(
        &self,
        plan: &SessionPlan,
        clock: Clock,
        verbose: bool,
    ) -> Result<(
        Session<LiveSubject<AnySource>>,
        CalibrationReport,
        Vector2<f64>,
    )> {
        let pen_start = self.arm()?.pen();
        let opened = if verbose {
            plan.open(clock, &mut calibration_progress())
        } else {
            plan.open(clock, &mut |_| {})
        }
        .map_err(|e| self.plan_error(e, plan))?;
        let session = opened.session;
        if let Some(c) = opened.rate_change {
            println!("{c}");
        }
        if matches!(plan.start, Start::Uncalibrated { .. }) {
            self.print_transfer();
        }
        if !verbose {
            let calibration = opened.calibration.unwrap_or_else(CalibrationReport::none);
            return Ok((session, calibration, pen_start));
        }
        match (&plan.start, opened.calibration) {
            (Start::Model(model), _) => println!("{}", model_line(model, self.model.as_deref())),
            (Start::Uncalibrated { .. }, _) => {
                println!(
                    "calibration: none: the decoder learns from the session itself (EM over one bulb per trial after every decision, no labels; abstains below posterior {})",
                    UncalibratedParams::for_sfreq(session.sfreq())?.abstain_below
                );
            }
            (Start::Calibrate { .. }, Some(calibration)) => {
                println!(
                    "calibration: {} decisions, {} epochs ({} targets, {} rejected) in {:.1} s of EEG; cross-validated AUC {:.3}, d' {:.2}",
                    calibration.n_trials,
                    calibration.n_epochs,
                    calibration.n_targets,
                    calibration.n_rejected,
                    session.time_s(),
                    calibration.cv_auc,
                    calibration.d_prime
                );
                return Ok((session, calibration, pen_start));
            }
            (Start::Calibrate { .. }, None) => {}
        }
        Ok((session, CalibrationReport::none(), pen_start))
    }

    /// `transfer: starting from FILE` for a session started from `--transfer`.
    pub fn print_transfer(&self) {
        if let (CalibrationSpec::None, Some(path)) = (&self.calibration, &self.transfer) {
            println!("transfer: starting from {}", path.display());
        }
    }

    /// A plan's error as the option at fault.
    pub fn plan_error(&self, e: PlanError, plan: &SessionPlan) -> anyhow::Error {
        let path =
            |p: &Option<PathBuf>| p.as_deref().unwrap_or(Path::new("")).display().to_string();
        match e {
            PlanError::Invalid(why) => anyhow::anyhow!("{why}"),
            PlanError::Arm(e) => anyhow::Error::new(e).context("checking --step"),
            PlanError::Open(e) => {
                anyhow::Error::new(e).context(format!("--source {}", plan.source))
            }
            PlanError::Rate(e) => {
                anyhow::Error::new(e).context("resampling the EEG to the model's rate")
            }
            PlanError::Session(e) => anyhow::Error::new(e).context("setting up the session"),
            PlanError::Montage(e) => anyhow::Error::new(e).context(format!(
                "naming the channels with --montage {}",
                path(&self.montage)
            )),
            PlanError::Start(e) => {
                let channels = matches!(e, SessionError::ModelChannels { .. });
                let e = anyhow::Error::new(e);
                match &plan.start {
                    Start::Calibrate { .. } => e.context("calibrating"),
                    Start::Model(_) if channels => e.context(
                        "using --model: name the EEG's channels in order with --montage FILE",
                    ),
                    Start::Model(_) => e.context("using --model"),
                    Start::Uncalibrated {
                        transfer: Some(_), ..
                    } => e.context(format!("starting from --transfer {}", path(&self.transfer))),
                    Start::Uncalibrated { .. } => e.context("setting up the uncalibrated decoder"),
                }
            }
        }
    }

    /// How the session starts: without calibration (`--calibration none`, from the
    /// `--transfer` model if given), with `model` (`--model`, read by [`Self::session_model`]),
    /// or calibrating (and with `--adapt` adapting).
    pub fn start(&self, model: Option<Model>) -> Result<Start> {
        if self.calibration == CalibrationSpec::None {
            let transfer = match &self.transfer {
                Some(path) => Some(crate::load::load_model(path)?),
                None => None,
            };
            return Ok(Start::Uncalibrated {
                params: None,
                transfer,
            });
        }
        Ok(match model {
            Some(model) => Start::Model(model),
            None => Start::Calibrate {
                adapt: self.adapt.then(AdaptParams::default),
            },
        })
    }

    /// The `--model` to decide with instead of calibrating (read and checked), its decision
    /// rule replaced by this session's `rule`.
    pub fn session_model(&self, rule: DecisionRule) -> Result<Option<Model>> {
        let Some(path) = &self.model else {
            return Ok(None);
        };
        let mut model = crate::load::load_model(path)?;
        match &mut model.decision {
            // The stopping rule is this session's choice, not the training's.
            Some(d) => d.rule = rule,
            None => bail!(
                "--model {}: {}",
                path.display(),
                oddball_decode::model::NO_DECISION_MODEL
            ),
        }
        Ok(Some(model))
    }

    /// The arm the session drives (recording its trace), with `--step`.
    pub fn arm(&self) -> Result<ArmSim> {
        recording_arm(self.step).context("checking --step")
    }

    /// Checks, before any EEG work, that the intended commands keep the pen on the board.
    pub fn check_commands(&self, commands: &[Command]) -> Result<()> {
        oddball_session::tasks::check_path(&self.arm()?, commands, "the commands")
            .map(|_| ())
            .map_err(|e| off_board(e, "--commands", "fewer commands"))
    }

    /// Checks option combinations before any session starts.
    pub fn check(&self) -> Result<()> {
        if self.model.is_some() {
            if self.calibration == CalibrationSpec::None {
                bail!("--calibration none starts without a model: not with --model");
            }
            if self.adapt {
                bail!(
                    "--adapt adapts a calibration made in this session (--calibrate), not --model"
                );
            }
            if self.optimise_stopping {
                bail!("--optimise-stopping chooses the rule from this session's calibration: use it with --calibrate, not --model");
            }
            if let SubjectSpec::Replay(files) = &self.subject {
                bail!(
                    "--subject replay:{} calibrates on the recording's calibration file, not --model; to replay a recording with a model: oddball online --source replay:{} --model MODEL --fast",
                    join_paths(files),
                    files.first().map(|f| f.display().to_string()).unwrap_or_default()
                );
            }
        }
        self.arm()?;
        if self.transfer.is_some() && self.calibration != CalibrationSpec::None {
            bail!("--transfer starts an uncalibrated session: it needs --calibration none");
        }
        if self.adapt && self.calibration == CalibrationSpec::None {
            bail!("--adapt adapts a labelled calibration; --calibration none adapts by itself");
        }
        if !self.test_text.is_empty() && self.preset().is_some() {
            bail!("--test-text labels replayed files: it needs --subject replay:FILE");
        }
        if self.adapt && self.pipeline != Preset::Lda {
            bail!("--adapt needs --pipeline lda (got {})", self.pipeline);
        }
        Ok(())
    }
}

/// What a session says of the model it decides with instead of calibrating.
pub fn model_line(model: &Model, path: Option<&Path>) -> String {
    format!(
        "model: {}{}, {} channels at {} Hz, epochs {}–{} s{}: no calibration",
        model.pipeline.name(),
        path.map(|p| format!(" from {}", p.display()))
            .unwrap_or_default(),
        model.ch_names.len(),
        model.sfreq,
        model.preprocess.tmin,
        model.preprocess.tmax,
        match (model.preprocess.causal, &model.live) {
            (true, _) => "",
            (false, Some(_)) => " (its causal fit, as a session filters)",
            (false, None) => " (trained zero-phase, run causally: expect lower accuracy)",
        }
    )
}

/// Prints a calibration's progress ("calibration decision 3 of 40 …") when it is slow enough
/// to need it: a line after each trial once two seconds of wall time have passed since the
/// start or the last line (a live or real-time calibration prints every trial; an unpaced
/// simulation, over in a second, prints nothing).
pub fn calibration_progress() -> impl FnMut(CalibrationProgress) {
    let mut last = std::time::Instant::now();
    let mut printed = false;
    move |p| {
        let end = p.done == p.total;
        if last.elapsed().as_secs_f64() >= 2.0 || (printed && end) {
            println!(
                "calibration decision {} of {} · {} of EEG{}",
                p.done,
                p.total,
                minutes_seconds(p.eeg_seconds),
                if end {
                    " · training".to_string()
                } else {
                    format!(" · about {} left", minutes_seconds(p.seconds_left))
                }
            );
            last = std::time::Instant::now();
            printed = true;
        }
    }
}

/// "7 s", "2 min 05 s".
fn minutes_seconds(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    if s < 60 {
        format!("{s} s")
    } else {
        format!("{} min {:02} s", s / 60, s % 60)
    }
}

/// A path that leaves the board as one line naming the option at fault (`option`) and what
/// fixes it: `--step` with the largest step that fits, or `less` (shorter text, fewer
/// commands); the library's facts follow as the cause.
pub fn off_board(e: oddball_session::SessionError, option: &str, less: &str) -> anyhow::Error {
    let hint = match &e {
        oddball_session::SessionError::PathOffBoard {
            max_step_m: Some(m),
            ..
        } => format!("use --step {m} (metres) or less, or {less}"),
        oddball_session::SessionError::PathOffBoard { .. } => {
            format!("no step fits from the pen's start: {less}")
        }
        _ => return anyhow::Error::new(e).context(format!("checking {option}")),
    };
    anyhow::Error::new(e).context(format!("checking {option}: it leaves the board; {hint}"))
}

pub fn join_paths(p: &[PathBuf]) -> String {
    p.iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The longest --wait-page, seconds (a day).
const MAX_WAIT_PAGE_S: f64 = 86_400.0;

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
    /// Starts the panel (when --serve) and waits for a page; prints its address first.
    pub fn start(&self, config: PanelConfig, clock: Clock) -> Result<Option<PanelServer>> {
        let Some(addr) = &self.serve else {
            return Ok(None);
        };
        if !(self.wait_page.is_finite() && (0.0..=MAX_WAIT_PAGE_S).contains(&self.wait_page)) {
            bail!(
                "--wait-page {}: expected 0 to {MAX_WAIT_PAGE_S} seconds",
                self.wait_page
            );
        }
        let panel = PanelServer::start(resolve(addr)?, self.allow_remote, config, clock)
            .context("starting the panel")?;
        println!("panel: http://{}/", panel.local_addr());
        println!(
            "operator view: http://{}{}",
            panel.local_addr(),
            oddball_live::panel::protocol::OPERATOR_PAGE
        );
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
    addr.to_socket_addrs()
        .with_context(|| format!("{addr}: expected HOST:PORT"))?
        .next()
        .with_context(|| format!("{addr}: no address"))
}
