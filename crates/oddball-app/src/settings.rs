//! A session's settings as any front end gives them ([`SessionSettings`], [`SourceSettings`]):
//! checked together, turned into the decision rules, the session's parameters, how it starts and
//! a live [`SessionPlan`], and opened with what it did said on the run's output.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use oddball_arm::{ArmSim, Command, Vector2};
use oddball_decode::decision::DecisionRule;
use oddball_decode::pipeline::Model;
use oddball_decode::preset::Preset;
use oddball_decode::stopping::StoppingSearch;
use oddball_io::nic::NicFormat;
use oddball_live::clock::Clock;
use oddball_live::live::LiveSubject;
use oddball_live::plan::{recording_arm, SessionPlan};
use oddball_live::source::{AnySource, OpenOptions, SourceSpec};
use oddball_session::decision::{CalibrationProgress, CalibrationReport};
use oddball_session::decoder::{AdaptParams, Start};
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::{FourBulbParams, ParadigmPreset, TimingOverrides};
use oddball_session::subject::{SubjectParams, SubjectPreset, STARSTIM_SFREQ};

use crate::error::{AppError, Result, SettingError, StartKind};

/// How a session starts: labelled calibration, none, or a replayed subject's calibration files.
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

/// Where the EEG comes from and how the source is opened.
#[derive(Debug, Clone)]
pub struct SourceSettings {
    pub source: SourceSpec,
    /// NIC's framing (checked by the front end that parsed it).
    pub nic: NicFormat,
    /// The LSL marker outlet's name.
    pub markers: String,
    /// How late the simulated amplifier's samples arrive, ms.
    pub sim_latency_ms: f64,
}

impl SourceSettings {
    /// How to open the source for `subject` (the simulated one, which also names a NIC
    /// stream's channels).
    pub fn open_options(
        &self,
        subject: oddball_session::SimulatedSubject,
        paced: bool,
    ) -> Result<OpenOptions, SettingError> {
        let opts = OpenOptions {
            subject,
            paced,
            sim_latency_ms: self.sim_latency_ms,
            nic: self.nic,
            nic_sfreq: STARSTIM_SFREQ,
            markers: self.markers.clone(),
        };
        opts.check().map_err(SettingError::SourceOptions)?;
        Ok(opts)
    }
}

/// Who watches the panel and how the session decides.
#[derive(Debug, Clone)]
pub struct SessionSettings {
    pub subject: SubjectSpec,
    pub calibration: CalibrationSpec,
    /// Without calibration: the model whose scores start the unsupervised decoder.
    pub transfer: Option<PathBuf>,
    /// Decide with this saved model instead of calibrating.
    pub model: Option<PathBuf>,
    /// The EEG's channel names in order (an EEGLAB .loc montage).
    pub montage: Option<PathBuf>,
    /// Adapt the calibrated `lda` model online.
    pub adapt: bool,
    /// The text each replayed speller file spelled.
    pub test_text: Vec<String>,
    pub seed: u64,
    /// Pace a simulated session in real time.
    pub realtime: bool,
    pub dynamic_stopping: bool,
    /// The posterior at which dynamic stopping decides.
    pub threshold: f64,
    /// The most rounds per decision with dynamic stopping.
    pub max_rounds: usize,
    pub pipeline: Preset,
    /// Calibration decisions per bulb (simulated subjects).
    pub calibration_per_bulb: usize,
    /// The panel's timing: a preset and changes to it.
    pub paradigm: ParadigmPreset,
    pub timing: TimingOverrides,
    /// Choose the stopping rule from the calibration for bits/min.
    pub optimise_stopping: bool,
    /// The most rounds the stopping search may choose.
    pub round_limit: usize,
    /// The least expected accuracy of a rule that competes on bits/min.
    pub min_accuracy: f64,
    /// The step one command moves the pen, metres (`None`: the arm's).
    pub step: Option<f64>,
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model, SettingError> {
    oddball_io::check_file(path).map_err(|e| SettingError::ModelFile(Box::new(e)))?;
    let text = std::fs::read_to_string(path).map_err(|source| SettingError::ReadModel {
        path: path.to_path_buf(),
        source,
    })?;
    Model::from_json(&text).map_err(|source| SettingError::LoadModel {
        path: path.to_path_buf(),
        source,
    })
}

impl SessionSettings {
    /// The panel's timing, checked.
    pub fn timed_paradigm(&self) -> Result<FourBulbParams, SettingError> {
        FourBulbParams::timed(self.paradigm, &self.timing).map_err(SettingError::Timing)
    }

    /// The fixed rule (the paradigm's rounds) and the rule in effect (the settings checked
    /// first).
    pub fn rules(&self) -> Result<(DecisionRule, DecisionRule), SettingError> {
        self.check()?;
        let fixed = DecisionRule::Fixed {
            rounds: self.timed_paradigm()?.n_rounds,
        };
        let dynamic = DecisionRule::dynamic_at(self.threshold, self.max_rounds);
        dynamic.validate().map_err(SettingError::DynamicRule)?;
        if self.optimise_stopping {
            let search = self.stopping_search();
            search.validate().map_err(SettingError::StoppingSearch)?;
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

    /// The panel's timing (checked by [`Self::rules`], which every run calls first; the
    /// paper's should it be invalid).
    pub fn paradigm(&self) -> FourBulbParams {
        self.timed_paradigm().unwrap_or_default()
    }

    /// The simulated preset (the subject of a `sim` source, and the montage of a NIC stream).
    pub fn preset(&self) -> Option<SubjectPreset> {
        match self.subject {
            SubjectSpec::Preset(p) => Some(p),
            SubjectSpec::Replay(_) => None,
        }
    }

    /// The simulated subject of this seed.
    pub fn simulated(&self) -> Result<oddball_session::SimulatedSubject, SettingError> {
        let preset = self.preset().ok_or(SettingError::NotLive)?;
        SubjectParams::preset(preset)
            .with_seed(self.seed)
            .build()
            .map_err(SettingError::Subject)
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

    /// What the stopping search searches.
    pub fn stopping_search(&self) -> StoppingSearch {
        StoppingSearch {
            max_rounds: self.round_limit,
            min_accuracy: self.min_accuracy,
            seed: self.seed,
            ..Default::default()
        }
    }

    /// The session's plan over `source` under `rule` (paced by the wall clock when `paced`),
    /// starting with `model` (read by [`Self::session_model`]) when given.
    pub fn plan(
        &self,
        source: &SourceSettings,
        rule: DecisionRule,
        paced: bool,
        model: Option<Model>,
    ) -> Result<SessionPlan, SettingError> {
        let montage = match &self.montage {
            Some(path) => Some(oddball_io::montage::read_montage(path).map_err(|source| {
                SettingError::Montage {
                    path: path.clone(),
                    source: Box::new(source),
                }
            })?),
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

    /// How the session starts: without calibration (from the transfer model if given), with
    /// `model` (read by [`Self::session_model`]), or calibrating (adapting when asked).
    pub fn start(&self, model: Option<Model>) -> Result<Start, SettingError> {
        if self.calibration == CalibrationSpec::None {
            let transfer = match &self.transfer {
                Some(path) => Some(load_model(path)?),
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

    /// The model to decide with instead of calibrating (read and checked), its decision rule
    /// replaced by this session's `rule`.
    pub fn session_model(&self, rule: DecisionRule) -> Result<Option<Model>, SettingError> {
        let Some(path) = &self.model else {
            return Ok(None);
        };
        let mut model = load_model(path)?;
        match &mut model.decision {
            // The stopping rule is this session's choice, not the training's.
            Some(d) => d.rule = rule,
            None => return Err(SettingError::NoDecisionModel { path: path.clone() }),
        }
        Ok(Some(model))
    }

    /// The arm the session drives (recording its trace), at this step.
    pub fn arm(&self) -> Result<ArmSim, SettingError> {
        recording_arm(self.step).map_err(SettingError::Arm)
    }

    /// Checks, before any EEG work, that the intended commands keep the pen on the board.
    pub fn check_commands(&self, commands: &[Command]) -> Result<(), SettingError> {
        oddball_session::tasks::check_path(&self.arm()?, commands, "the commands")
            .map(|_| ())
            .map_err(SettingError::Commands)
    }

    /// Checks the settings together before any session starts.
    pub fn check(&self) -> Result<(), SettingError> {
        if self.model.is_some() {
            if self.calibration == CalibrationSpec::None {
                return Err(SettingError::ModelWithoutCalibration);
            }
            if self.adapt {
                return Err(SettingError::AdaptWithModel);
            }
            if self.optimise_stopping {
                return Err(SettingError::OptimiseWithModel);
            }
            if let SubjectSpec::Replay(files) = &self.subject {
                return Err(SettingError::ReplayWithModel {
                    files: files.clone(),
                });
            }
        }
        self.arm()?;
        if self.transfer.is_some() && self.calibration != CalibrationSpec::None {
            return Err(SettingError::TransferNeedsUncalibrated);
        }
        if self.adapt && self.calibration == CalibrationSpec::None {
            return Err(SettingError::AdaptUncalibrated);
        }
        if !self.test_text.is_empty() && self.preset().is_some() {
            return Err(SettingError::TestTextWithoutReplay);
        }
        if self.adapt && self.pipeline != Preset::Lda {
            return Err(SettingError::AdaptNeedsLda {
                pipeline: self.pipeline,
            });
        }
        Ok(())
    }

    /// Opens `plan`'s live session and starts it; when `verbose`, says on `out` what it did
    /// (the calibration's progress when slow, what calibration measured or the model used).
    /// Returns the session, its calibration and the pen's start.
    pub fn open(
        &self,
        plan: &SessionPlan,
        clock: Clock,
        verbose: bool,
        out: &mut dyn Write,
    ) -> Result<(
        Session<LiveSubject<AnySource>>,
        CalibrationReport,
        Vector2<f64>,
    )> {
        let pen_start = self.arm()?.pen();
        let opened = if verbose {
            plan.open(clock, &mut calibration_progress(&mut *out))
        } else {
            plan.open(clock, &mut |_| {})
        }
        .map_err(|error| plan_error(error, plan))?;
        let session = opened.session;
        if let Some(c) = opened.rate_change {
            writeln!(out, "{c}")?;
        }
        if matches!(plan.start, Start::Uncalibrated { .. }) {
            self.say_transfer(out)?;
        }
        if !verbose {
            let calibration = opened.calibration.unwrap_or_else(CalibrationReport::none);
            return Ok((session, calibration, pen_start));
        }
        match (&plan.start, opened.calibration) {
            (Start::Model(model), _) => {
                writeln!(out, "{}", model_line(model, self.model.as_deref()))?
            }
            (Start::Uncalibrated { .. }, _) => {
                // What the started session runs with.
                let abstain = session.uncalibrated_params().map_or(String::new(), |p| {
                    format!("; abstains below posterior {}", p.abstain_below)
                });
                let pre = &session.params().decoder.preprocess;
                let band = format!(
                    "; EEG band-passed {}{}",
                    pre.band.band,
                    if pre.causal { " causally" } else { "" }
                );
                let learning = session.learning_rounds().map_or(String::new(), |l| {
                    format!(
                        "; the first trials run {}× the rounds until it holds {} epochs per feature",
                        l.factor, l.epochs_per_feature
                    )
                });
                writeln!(
                    out,
                    "calibration: none: the decoder learns from the session itself (EM over one bulb per trial after every decision, no labels{abstain}{band}{learning})"
                )?;
            }
            (Start::Calibrate { .. }, Some(calibration)) => {
                writeln!(
                    out,
                    "calibration: {} decisions, {} epochs ({} targets, {} rejected) in {:.1} s of EEG; cross-validated AUC {:.3}, d' {:.2}",
                    calibration.n_trials,
                    calibration.n_epochs,
                    calibration.n_targets,
                    calibration.n_rejected,
                    session.time_s(),
                    calibration.cv_auc,
                    calibration.d_prime
                )?;
                return Ok((session, calibration, pen_start));
            }
            (Start::Calibrate { .. }, None) => {}
        }
        Ok((session, CalibrationReport::none(), pen_start))
    }

    /// `transfer: starting from FILE` for a session started from a transfer model.
    pub fn say_transfer(&self, out: &mut dyn Write) -> std::io::Result<()> {
        if let (CalibrationSpec::None, Some(path)) = (&self.calibration, &self.transfer) {
            writeln!(out, "transfer: starting from {}", path.display())?;
        }
        Ok(())
    }
}

/// A plan's error with what the plan was: where the EEG came from and how it was to start.
pub fn plan_error(error: oddball_live::plan::PlanError, plan: &SessionPlan) -> AppError {
    AppError::Plan {
        error,
        source_spec: plan.source.clone(),
        start: StartKind::from(&plan.start),
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

/// Says a calibration's progress ("calibration decision 3 of 40 …") on `out` when it is slow
/// enough to need it: a line after each trial once two seconds of wall time have passed since
/// the start or the last line (a live or real-time calibration says every trial; an unpaced
/// simulation, over in a second, says nothing). A failed write is left for the run's next
/// line to find.
pub fn calibration_progress(out: &mut dyn Write) -> impl FnMut(CalibrationProgress) + '_ {
    let mut last = std::time::Instant::now();
    let mut printed = false;
    move |p| {
        let end = p.done == p.total;
        if last.elapsed().as_secs_f64() >= 2.0 || (printed && end) {
            let _ = writeln!(
                out,
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

/// Paths comma-separated, as a replayed subject names them.
pub fn join_paths(p: &[PathBuf]) -> String {
    p.iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(",")
}
