//! `oddball demo`: the whole closed loop with no hardware. A subject (simulated, or real EEG
//! replayed) watches the four-bulb panel; the session calibrates, trains a pipeline, then
//! decodes each intended command and the arm draws it.
//!
//! Writes a report folder: `decisions.csv`, `summary.json`, `pen_trace.png`, `erp.png` (the
//! calibration epochs), `model.json`, and for simulated subjects the raw session
//! `session.dat` (BCI2000, float32; `session.easy` when the EEG came over NIC's TCP stream) that
//! `oddball evaluate --model model.json --test session.dat` re-evaluates to the same decisions.
//! In this process, every file depends only on the options (same seed, same bytes); wall-clock
//! times are printed, never written.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use oddball_arm::{parse_commands, ArmConfig, ArmSim, Command, Vector2};
use oddball_decode::decision::DecisionRule;
use oddball_decode::metrics::Itr;
use oddball_session::engine::{CalibrationReport, Session, SessionParams, Subject, TrialOutcome};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::record::{save_session, save_session_easy};
use oddball_session::replay::{self, ReplayParams};
use oddball_session::subject::{SubjectParams, SubjectPreset};
use oddball_signal::Epochs;
use serde::Serialize;

/// Who watches the panel and how the session decides: shared by `oddball demo` and
/// `oddball task`.
#[derive(Debug, clap::Args)]
pub struct SessionOptions {
    /// Who watches the panel: easy, typical or hard (simulated), or replay:FILE (a BCI2000
    /// P300-speller recording played back as four-choice decisions).
    #[arg(long, default_value = "typical")]
    pub subject: String,
    /// Calibration recording for a replayed subject [default: the replay file's sibling whose
    /// name ends in _1 instead of _N, e.g. eeg3_1.dat for eeg3_2.dat].
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
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
    #[arg(long, default_value_t = 0.95, value_name = "P")]
    pub threshold: f64,
    /// Most rounds per decision with dynamic stopping.
    #[arg(long, default_value_t = 5)]
    pub max_rounds: usize,
    /// Pipeline preset: lda, toeplitz-lda, riemann, lda+riemann (score fusion), stack
    /// (toeplitz-lda + riemann + mdm, stacked), mdm, paper, paper-svm, paper-knn.
    #[arg(long, default_value = crate::preset_arg::DEFAULT_PIPELINE, value_parser = crate::preset_arg::parse_preset)]
    pub pipeline: String,
    /// Calibration decisions per bulb (simulated subjects).
    #[arg(long, default_value_t = 10)]
    pub calibration_per_bulb: usize,
}

impl SessionOptions {
    /// The fixed rule (5 rounds) and the rule in effect.
    pub fn rules(&self) -> Result<(DecisionRule, DecisionRule)> {
        let fixed = DecisionRule::Fixed {
            rounds: FourBulbParams::paper().n_rounds,
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
        Ok((
            fixed,
            if self.dynamic_stopping {
                dynamic
            } else {
                fixed
            },
        ))
    }

    /// The simulated preset, or `None` for a replayed subject; an unknown name is an error.
    pub fn preset(&self) -> Result<Option<SubjectPreset>> {
        match self.subject.strip_prefix("replay:") {
            Some(_) => Ok(None),
            None => {
                Ok(Some(self.subject.parse().map_err(|e| {
                    anyhow::anyhow!("--subject {}: {e}", self.subject)
                })?))
            }
        }
    }

    /// The replayed file and its calibration file, for `replay:FILE` subjects.
    pub fn replay_files(&self) -> Result<Option<(PathBuf, PathBuf)>> {
        let Some(file) = self.subject.strip_prefix("replay:") else {
            return Ok(None);
        };
        let file = PathBuf::from(file);
        let cal = match &self.calibration {
            Some(c) => c.clone(),
            None => sibling_calibration(&file)?,
        };
        Ok(Some((file, cal)))
    }
}

/// Options of `oddball demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    #[command(flatten)]
    pub session: SessionOptions,
    /// Comma-separated intended commands (up, down, left, right); the paper's letter G by default.
    #[arg(long, default_value = "up,left,down,right,up,left")]
    pub commands: String,
    /// Where the EEG comes from: `sim` (the simulated subject in this process) or
    /// `nic:HOST:PORT` (a NIC TCP data stream, e.g. from `oddball simulate --nic HOST:PORT`, whose
    /// panel port is PORT + 1). Over NIC the session is saved as `session.easy` (NIC's format)
    /// instead of `session.dat`.
    #[arg(long, default_value = "sim", value_name = "SOURCE")]
    pub source: String,
    #[command(flatten)]
    pub nic: crate::cmd_simulate::NicWire,
    /// Report folder.
    #[arg(long, value_name = "DIR", default_value = "out/demo")]
    pub out: PathBuf,
}

/// What a replayed subject's report says about its decisions.
pub const REPLAY_NOTE: &str = "replayed speller flashes: the four bulbs of each decision are the target and three non-target rows (or columns) of one spelled character; seconds and ITR use the four-bulb panel's timing; the raw EEG is the source file itself, so no session.dat is written";

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

/// What one run (simulated or replayed) produced.
struct Run {
    rows: Vec<Row>,
    calibration: CalibrationReport,
    arm: ArmSim,
    pen_start: Vector2<f64>,
    erp: Epochs,
    simulated_seconds: f64,
    model_json: String,
    session_file: Option<PathBuf>,
}

pub fn run(args: &DemoArgs) -> Result<()> {
    let wall = Instant::now();
    let commands = parse_commands(&args.commands).context("parsing --commands")?;
    if commands.is_empty() {
        bail!("--commands is empty: give at least one of up, down, left, right");
    }
    let (fixed, rule) = args.session.rules()?;
    let preset = args.session.preset()?;
    let replay_files = args.session.replay_files()?;
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;

    let (run, comparison, subject_label, note) = match (replay_files, preset) {
        (Some((file, cal)), _) => {
            println!(
                "oddball demo: replaying {} (calibration {}), pipeline {}, {}",
                file.display(),
                cal.display(),
                args.session.pipeline,
                rule_name(&rule)
            );
            let (run, comparison) = run_replay(args, &file, &cal, &commands, rule, fixed)?;
            (
                run,
                comparison,
                format!("replay:{}", file.display()),
                Some(REPLAY_NOTE),
            )
        }
        (None, preset) => {
            let preset = preset.expect("a simulated preset when not replaying");
            println!(
                "oddball demo: {} simulated subject (seed {}), pipeline {}, {}; calibration: {} decisions per bulb",
                preset,
                args.session.seed,
                args.session.pipeline,
                rule_name(&rule),
                args.session.calibration_per_bulb
            );
            if let Some(addr) = args.source.strip_prefix("nic:") {
                let subject = crate::cmd_simulate::connect_nic(addr, &args.nic, preset)?;
                println!(
                    "reading EEG from the NIC stream at {addr} ({}, {} channels)",
                    args.nic.nic_mode, args.nic.nic_channels
                );
                let run = run_subject(
                    args,
                    subject,
                    rule,
                    &commands,
                    Some(&args.out.join("session.easy")),
                    true,
                )?;
                (run, None, format!("{preset} over nic:{addr}"), None)
            } else {
                if args.source != "sim" {
                    bail!("--source {}: expected sim or nic:HOST:PORT", args.source);
                }
                let comparison = if args.session.dynamic_stopping {
                    // The same subject and calibration (same seed), online with fixed rounds.
                    let quiet = run_simulated(args, preset, fixed, &commands, None, false)?;
                    Some(scores(&quiet.rows, &fixed))
                } else {
                    None
                };
                let run = run_simulated(
                    args,
                    preset,
                    rule,
                    &commands,
                    Some(&args.out.join("session.dat")),
                    true,
                )?;
                (run, comparison, preset.to_string(), None)
            }
        }
    };

    let result = scores(&run.rows, &rule);
    let pen = pen_report(&run);
    let mut files = vec![
        "decisions.csv".to_string(),
        "summary.json".into(),
        "model.json".into(),
        "erp.png".into(),
        "pen_trace.png".into(),
    ];
    if let Some(f) = run.session_file.as_ref().and_then(|p| p.file_name()) {
        files.push(f.to_string_lossy().into_owned());
    }
    write_decisions_csv(&args.out.join("decisions.csv"), &run.rows)?;
    fs::write(args.out.join("model.json"), &run.model_json)
        .with_context(|| format!("writing {}", args.out.join("model.json").display()))?;
    let (target, nontarget) = split_targets(&run.erp);
    crate::plot_erp::draw_erp(
        &args.out.join("erp.png"),
        &target,
        &nontarget,
        "calibration epochs, causal 1–15 Hz",
    )
    .context("drawing erp.png")?;
    let expected: Vec<Vector2<f64>> = pen
        .expected_m
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    let key_times: Vec<f64> = std::iter::once(0.0)
        .chain(std::iter::once(run.arm.time_s()))
        .collect();
    let keys = crate::cmd_arm::configurations_at(&run.arm, &key_times);
    crate::cmd_arm::draw(&run.arm, &keys, &expected, &args.out.join("pen_trace.png"))
        .context("drawing pen_trace.png")?;
    let summary = Summary {
        subject: &subject_label,
        pipeline: &args.session.pipeline,
        seed: args.session.seed,
        commands: commands.clone(),
        calibration: (&run.calibration).into(),
        result: &result,
        fixed_rounds_for_comparison: comparison.as_ref(),
        simulated_seconds: run.simulated_seconds,
        pen: pen.clone(),
        decisions: &run.rows,
        files,
        note,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    fs::write(args.out.join("summary.json"), json + "\n")
        .with_context(|| format!("writing {}", args.out.join("summary.json").display()))?;

    print!("{}", report_text(&run, &result, comparison.as_ref(), &pen));
    println!("report in {}", args.out.display());
    // Wall-clock time goes to stderr: stdout, like every file, depends only on the options.
    eprintln!(
        "wall time {:.2} s (calibration fit {:.2} s)",
        wall.elapsed().as_secs_f64(),
        run.calibration.fit_seconds,
    );
    Ok(())
}

/// A session with any subject (simulated, or a live stream), calibrated.
pub fn calibrated<S: Subject>(
    opts: &SessionOptions,
    subject: S,
    rule: DecisionRule,
    verbose: bool,
) -> Result<(Session<S>, CalibrationReport, Vector2<f64>)> {
    let mut params = SessionParams::paper(&opts.pipeline);
    params.seed = opts.seed;
    params.rule = rule;
    params.calibration_per_bulb = opts.calibration_per_bulb;
    let mut arm = ArmSim::from_config(&ArmConfig::default()).context("setting up the arm")?;
    arm.set_recording(true);
    let pen_start = arm.pen();
    let mut session = Session::new(params, subject, Some(arm)).context("setting up the session")?;
    session.set_realtime(opts.realtime && verbose);
    let calibration = session.calibrate().context("calibrating")?;
    if verbose {
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
    }
    Ok((session, calibration, pen_start))
}

/// A replayed subject: the calibration recording read and trained on, the test recording read.
pub struct Replayed {
    pub calibration_recording: oddball_io::Recording,
    pub test: oddball_io::Recording,
    pub model: oddball_decode::pipeline::Model,
    pub calibration: CalibrationReport,
    pub params: ReplayParams,
}

/// Reads both files and calibrates on the first; prints the calibration.
pub fn calibrated_replay(
    opts: &SessionOptions,
    file: &Path,
    cal_file: &Path,
    rule: DecisionRule,
) -> Result<Replayed> {
    let cal =
        oddball_io::read(cal_file).with_context(|| format!("reading {}", cal_file.display()))?;
    let test = oddball_io::read(file).with_context(|| format!("reading {}", file.display()))?;
    let mut params = ReplayParams::paper(&opts.pipeline);
    params.seed = opts.seed;
    params.rule = rule;
    params.rounds_per_decision = rule.max_rounds().max(FourBulbParams::paper().n_rounds);
    let (model, calibration) = replay::calibrate(&cal, &params)
        .with_context(|| format!("calibrating on {}", cal_file.display()))?;
    println!(
        "calibration: {} characters, {} epochs ({} targets, {} rejected) of {}; cross-validated AUC {:.3}, d' {:.2}",
        calibration.n_trials,
        calibration.n_epochs,
        calibration.n_targets,
        calibration.n_rejected,
        cal_file.display(),
        calibration.cv_auc,
        calibration.d_prime
    );
    Ok(Replayed {
        calibration_recording: cal,
        test,
        model,
        calibration,
        params,
    })
}

fn run_simulated(
    args: &DemoArgs,
    preset: SubjectPreset,
    rule: DecisionRule,
    commands: &[Command],
    save: Option<&Path>,
    verbose: bool,
) -> Result<Run> {
    let subject = SubjectParams::preset(preset)
        .with_seed(args.session.seed)
        .build()
        .context("building the simulated subject")?;
    run_subject(args, subject, rule, commands, save, verbose)
}

/// Calibration, the commands and the saved session for any subject. A `.easy` save path
/// writes NIC's format, anything else BCI2000.
fn run_subject<S: Subject>(
    args: &DemoArgs,
    subject: S,
    rule: DecisionRule,
    commands: &[Command],
    save: Option<&Path>,
    verbose: bool,
) -> Result<Run> {
    let (mut session, calibration, pen_start) = calibrated(&args.session, subject, rule, verbose)?;
    let mut rows = Vec::new();
    for (index, &command) in commands.iter().enumerate() {
        let t = session
            .decide(Some(command))
            .with_context(|| format!("decision {}", index + 1))?;
        let p = session.params().paradigm;
        let row = Row {
            index: index + 1,
            intended: Some(command),
            decided: t.decided().and_then(|c| p.command_of(c)),
            abstained: t.outcome == TrialOutcome::Abstained,
            rounds: t.rounds,
            confidence: t.confidence(),
            seconds: (t.end - t.start) as f64 / session.sfreq(),
            arm_refusal: t.arm_refusal.clone(),
            pen_m: t.pen_m,
        };
        if verbose {
            println!("{}", row_text(&row));
        }
        rows.push(row);
    }
    // Let the last movement finish.
    session.idle(1.5)?;
    if let (Some(health), true) = (session.subject().stream_health(), verbose) {
        println!("stream: {health}");
    }
    let erp = session.calibration_epochs()?;
    let model_json = session
        .model()
        .map(|m| m.to_json())
        .context("the session has no model")?;
    let simulated_seconds = session.time_s();
    let paradigm = session.params().paradigm;
    let (log, _, arm) = session.finish();
    let session_file = match save {
        Some(path) => {
            if path.extension().is_some_and(|e| e == "easy") {
                save_session_easy(path, &log, &paradigm, 0)
                    .map(|_| ())
                    .with_context(|| format!("writing {}", path.display()))?;
            } else {
                save_session(path, &log, &paradigm)
                    .map(|_| ())
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            Some(path.to_path_buf())
        }
        None => None,
    };
    Ok(Run {
        rows,
        calibration,
        arm: arm.expect("the session has an arm"),
        pen_start,
        erp,
        simulated_seconds,
        model_json,
        session_file,
    })
}

fn run_replay(
    args: &DemoArgs,
    file: &Path,
    cal_file: &Path,
    commands: &[Command],
    rule: DecisionRule,
    fixed: DecisionRule,
) -> Result<(Run, Option<Scores>)> {
    let Replayed {
        calibration_recording: cal,
        test,
        model,
        calibration,
        params,
    } = calibrated_replay(&args.session, file, cal_file, rule)?;
    let to_rows = |decisions: &[replay::ReplayDecision]| -> Vec<Row> {
        decisions
            .iter()
            .enumerate()
            .map(|(i, d)| Row {
                index: i + 1,
                intended: Some(d.intended),
                decided: d.decided(&params.paradigm),
                abstained: d.outcome == TrialOutcome::Abstained,
                rounds: d.rounds,
                confidence: match d.outcome {
                    TrialOutcome::Chosen { code } => d.posterior[code as usize - 1],
                    _ => d.posterior.iter().copied().fold(0.0, f64::max),
                },
                seconds: d.seconds,
                arm_refusal: None,
                pen_m: None,
            })
            .collect()
    };
    let decisions = replay::replay(&test, &model, commands, &params)
        .with_context(|| format!("replaying {}", file.display()))?;
    let mut rows = to_rows(&decisions);
    let comparison = if rule != fixed {
        let mut p = params.clone();
        p.rule = fixed;
        let d = replay::replay(&test, &model, commands, &p)?;
        Some(scores(&to_rows(&d), &fixed))
    } else {
        None
    };
    // Drive the arm with the decisions, each taking its panel time.
    let mut arm = ArmSim::from_config(&ArmConfig::default()).context("setting up the arm")?;
    arm.set_recording(true);
    let pen_start = arm.pen();
    for row in &mut rows {
        arm.run_for(row.seconds)?;
        row.pen_m = Some([arm.pen()[0], arm.pen()[1]]);
        if let Some(c) = row.decided {
            if let Err(e) = arm.issue(c) {
                row.arm_refusal = Some(e.to_string());
            }
        }
        println!("{}", row_text(row));
    }
    arm.run_for(1.5)?;
    let epochs = replay::stream_epochs(&cal, &params.preprocess, params.chunk)?;
    let erp = epochs_of(&cal, &epochs)?;
    let simulated_seconds = arm.time_s();
    let run = Run {
        rows,
        calibration,
        arm,
        pen_start,
        erp,
        simulated_seconds,
        model_json: model.to_json(),
        session_file: None,
    };
    Ok((run, comparison))
}

/// Calibration epochs of a replayed recording as `Epochs` (accepted ones), for the ERP plot.
pub fn epochs_of(
    rec: &oddball_io::Recording,
    epochs: &[Option<oddball_session::online::ReadyEpoch>],
) -> Result<Epochs> {
    let kept: Vec<usize> = (0..epochs.len())
        .filter(|&i| epochs[i].as_ref().is_some_and(|e| e.accepted))
        .collect();
    let first = epochs[kept[0]].as_ref().expect("kept");
    let (n_ch, n_t) = first.data.dim();
    let mut x = ndarray::Array3::zeros((kept.len(), n_ch, n_t));
    for (j, &i) in kept.iter().enumerate() {
        x.index_axis_mut(ndarray::Axis(0), j)
            .assign(&epochs[i].as_ref().expect("kept").data);
    }
    let events = kept
        .iter()
        .map(|&i| rec.raw.events().as_slice()[i].clone())
        .collect();
    Ok(Epochs::new(
        x,
        rec.raw.sfreq(),
        0.0,
        rec.raw.ch_names().to_vec(),
        events,
    )?)
}

pub fn split_targets(epochs: &Epochs) -> (Epochs, Epochs) {
    let idx = |want: bool| -> Vec<usize> {
        (0..epochs.n_epochs())
            .filter(|&i| epochs.events()[i].target == Some(want))
            .collect()
    };
    (epochs.select(&idx(true)), epochs.select(&idx(false)))
}

/// `eeg3_2.dat` → `eeg3_1.dat` in the same folder, if it exists and differs.
fn sibling_calibration(file: &Path) -> Result<PathBuf> {
    let stem = file
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or_default();
    let ext = file.extension().and_then(|s| s.to_str()).unwrap_or("dat");
    if let Some((base, n)) = stem.rsplit_once('_') {
        if n.chars().all(|c| c.is_ascii_digit()) && n != "1" {
            let cand = file.with_file_name(format!("{base}_1.{ext}"));
            if cand.exists() {
                return Ok(cand);
            }
        }
    }
    bail!(
        "no calibration recording for {}: give one with --calibration FILE",
        file.display()
    )
}

/// Corners: the pen after each executed command (at the next decision, or at the end)
/// against where the executed commands put the reference.
fn pen_report(run: &Run) -> PenReport {
    let h = run.arm.settings().step_m;
    let mut expected = vec![run.pen_start];
    let mut measured = Vec::new();
    let mut errors = Vec::new();
    let mut intended_ok = true;
    let end_pen = [run.arm.pen()[0], run.arm.pen()[1]];
    for (k, row) in run.rows.iter().enumerate() {
        let executed = row.decided.filter(|_| row.arm_refusal.is_none());
        intended_ok &= executed.is_some() && row.decided == row.intended;
        if let Some(c) = executed {
            let target = c.apply(expected.last().expect("non-empty"), h);
            expected.push(target);
            // The pen when the next decision comes (or at the end) shows where this one left it.
            let pen = run.rows.get(k + 1).and_then(|r| r.pen_m).unwrap_or(end_pen);
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

fn report_text(run: &Run, result: &Scores, comparison: Option<&Scores>, pen: &PenReport) -> String {
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
    let _ = writeln!(s, "simulated time {:.1} s", run.simulated_seconds);
    s
}

fn write_decisions_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let mut s =
        String::from("decision,intended,decided,abstained,rounds,confidence,seconds,arm_refusal\n");
    for r in rows {
        let name = |c: Option<Command>| c.map_or(String::new(), |c| c.to_string());
        let _ = writeln!(
            s,
            "{},{},{},{},{},{:.6},{:.4},{}",
            r.index,
            name(r.intended),
            name(r.decided),
            r.abstained,
            r.rounds,
            r.confidence,
            r.seconds,
            r.arm_refusal.as_deref().unwrap_or("").replace(',', ";")
        );
    }
    fs::write(path, s).with_context(|| format!("writing {}", path.display()))
}
