//! Building the calibrated pilot of `demo` and `task` from the command line's options (the pilot
//! itself and what a run leaves behind are `oddball_live::pilot`'s).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use oddball_decode::decision::DecisionRule;
use oddball_live::clock::Clock;
use oddball_live::pilot::decisions_csv;
pub use oddball_live::pilot::{AnyPilot, Prepared};
use oddball_live::source::SourceSpec;
use oddball_session::decision::Decision;
use oddball_session::replay::ReplaySource;
use oddball_session::tasks::ReplayPilot;

use crate::args::{join_paths, CalibrationSpec, SessionOptions, SourceArgs, SubjectSpec};
use oddball_session::decision::CalibrationReport;
use oddball_session::replay::{self, ReplayParams};

/// Calibrates a pilot: a replayed recording (`--subject replay:FILE`, offline, so only with
/// `--source sim`), or a session over `--source`, its calibration paced by the wall clock when
/// `paced`. Prints the calibration; `on_replay` sees a replayed subject's recordings and source
/// before they are used.
pub fn prepare(
    opts: &SessionOptions,
    source: &SourceArgs,
    rule: DecisionRule,
    paced: bool,
    on_replay: impl FnOnce(&Replayed, &ReplaySource) -> Result<()>,
) -> Result<Prepared> {
    if let Some(files) = replay_files(opts)? {
        if source.source != SourceSpec::Sim {
            bail!(
                "--subject replay:{} replays decisions offline: it takes no --source {}",
                files.test_names(),
                source.source
            );
        }
        let r = calibrated_replay(opts, &files, rule)?;
        let replay = ReplaySource::new(&r.test, &r.model, &r.params)
            .with_context(|| format!("replaying {}", files.test_names()))?;
        on_replay(&r, &replay)?;
        let arm = opts.arm()?;
        let pen_start = arm.pen();
        return Ok(Prepared {
            pilot: AnyPilot::Replay(ReplayPilot::new(replay, arm)),
            calibration: r.calibration,
            erp: r.calibration_epochs,
            model_json: r.model.to_json(),
            subject: format!("replay:{}", files.test_names()),
            pen_start,
        });
    }
    let preset = opts
        .preset()
        .expect("a simulated preset when not replaying");
    let plan = opts.plan(source, rule, paced, opts.session_model(rule)?)?;
    let (session, calibration, pen_start) = opts.open(&plan, Clock::new(), true)?;
    let erp = session.calibration_epochs()?;
    // An uncalibrated session has no model yet (see `model_json`).
    let model_json = session.model().map(|m| m.to_json()).unwrap_or_default();
    Ok(Prepared {
        pilot: AnyPilot::Live(session),
        calibration,
        erp,
        model_json,
        subject: match &source.source {
            SourceSpec::Sim => preset.to_string(),
            other => format!("{preset} over {other}"),
        },
        pen_start,
    })
}

/// Ends a live pilot's session and saves its raw EEG in `out` (`session.easy` for a NIC stream,
/// `session.dat` otherwise); `None` for a replayed recording.
pub fn save_session(prep: Prepared, out: &Path, end: &str) -> Result<Option<PathBuf>> {
    let Some(path) = prep.session_file(out) else {
        return Ok(None);
    };
    prep.save_session(&path, end)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(Some(path))
}

/// model.json of a run: the calibrated model, or for an uncalibrated session the latest
/// unsupervised fit.
pub fn model_json(prep: &Prepared) -> Result<String> {
    if let AnyPilot::Live(s) = &prep.pilot {
        if let Some(m) = s.unsupervised() {
            return Ok(serde_json::to_string_pretty(m)? + "\n");
        }
    }
    Ok(prep.model_json.clone())
}

/// An uncalibrated session's decisions re-decided by its last fit ("post hoc"): (right, decisions
/// it re-decided); `None` after a labelled calibration.
pub fn posthoc(prep: &Prepared) -> Option<(usize, usize)> {
    let AnyPilot::Live(s) = &prep.pilot else {
        return None;
    };
    let re = s.redecided();
    if re.is_empty() {
        return None;
    }
    let right = re
        .iter()
        .filter(|(trial, code, _)| s.trials()[*trial].intended == Some(*code))
        .count();
    Some((right, re.len()))
}

/// What online adaptation did in a live session (`--adapt`).
pub fn adaptation(prep: &Prepared) -> Option<oddball_session::engine::AdaptationReport> {
    match &prep.pilot {
        AnyPilot::Live(s) => s.adaptation(),
        AnyPilot::Replay(_) => None,
    }
}

/// decisions.csv: one row per step.
pub fn write_decisions_csv(path: &Path, steps: &[Decision]) -> Result<()> {
    oddball_io::write_atomic(path, decisions_csv(steps))
        .with_context(|| format!("writing {}", path.display()))
}

/// The replayed files and their calibration files, for `replay:FILE` subjects.
pub fn replay_files(opts: &SessionOptions) -> Result<Option<ReplayFiles>> {
    let SubjectSpec::Replay(test) = &opts.subject else {
        return Ok(None);
    };
    // Options before files.
    if opts.calibration == CalibrationSpec::None {
        bail!(
            "--calibration none runs a live or simulated session; a replayed subject \
             (--subject replay:…) is calibrated on its recording (use `oddball evaluate \
             --unsupervised` to replay a recording without labels)"
        );
    }
    // The replayed files first: a missing one is not its calibration file's fault.
    for file in test {
        oddball_io::check_file(file).context("--subject replay:FILE")?;
    }
    if !opts.test_text.is_empty() && opts.test_text.len() != test.len() {
        bail!(
            "--test-text gives {} texts for {} replayed files (one per file)",
            opts.test_text.len(),
            test.len()
        );
    }
    // Labelled (None is refused above): the replayed file's sibling.
    let calibration = match &opts.calibration {
        CalibrationSpec::Files(c) => c.clone(),
        _ => vec![sibling_calibration(&test[0])?],
    };
    for c in &calibration {
        oddball_io::check_file(c).context("the calibration recording")?;
        if test.contains(c) {
            bail!(
                "{} is both replayed and calibrated on: calibrate on other recordings",
                c.display()
            );
        }
    }
    Ok(Some(ReplayFiles {
        test: test.clone(),
        calibration,
    }))
}

/// Reads a replayed subject's files (the replayed ones labelled by --test-text when given)
/// and calibrates on the calibration files; prints the calibration.
pub fn calibrated_replay(
    opts: &SessionOptions,
    files: &ReplayFiles,
    rule: DecisionRule,
) -> Result<Replayed> {
    // A recording without target labels: the library's advice names `evaluate`'s options;
    // these are the session's.
    let read = |p: &PathBuf, text: Option<&String>, calibration: bool| {
        let how = oddball_eval::dataset::Labelling {
            text: text.map(String::as_str),
            ..Default::default()
        };
        oddball_eval::dataset::read_labelled(p, how).map_err(|e| match e {
            oddball_eval::dataset::DatasetError::Unlabelled {
                path,
                n_events,
                events,
            } => anyhow::anyhow!(
                "{} has {n_events} events but none is labelled target or non-target (its events: {events}); {}",
                path.display(),
                if calibration {
                    "calibrate on a labelled recording (--calibration FILE)"
                } else {
                    "give the text each replayed speller run spelled with --test-text"
                }
            ),
            e => e.into(),
        })
    };
    let cal = files
        .calibration
        .iter()
        .map(|p| read(p, None, true))
        .collect::<Result<Vec<_>>>()?;
    let test = files
        .test
        .iter()
        .enumerate()
        .map(|(i, p)| read(p, opts.test_text.get(i), false))
        .collect::<Result<Vec<_>>>()?;
    let cal_names = files.calibration_names();
    let mut params = ReplayParams::paper(opts.pipeline);
    params.paradigm = opts.paradigm();
    params.decoder.seed = opts.seed;
    params.decoder.rule = rule;
    params.rounds_per_decision = rule.max_rounds().max(params.paradigm.n_rounds);
    params.decoder.stopping = opts.optimise_stopping.then(|| opts.stopping_search());
    let replay::Calibrated {
        model,
        report: calibration,
        expected: chosen,
        epochs: calibration_epochs,
    } = replay::calibrate_for_bit_rate(&cal, &params)
        .with_context(|| format!("calibrating on {cal_names}"))?;
    println!(
        "calibration: {} characters, {} epochs ({} targets, {} rejected) of {}; cross-validated AUC {:.3}, d' {:.2}",
        calibration.n_trials,
        calibration.n_epochs,
        calibration.n_targets,
        calibration.n_rejected,
        cal_names,
        calibration.cv_auc,
        calibration.d_prime
    );
    if let Some(e) = &chosen {
        params.decoder.rule = e.rule;
        println!("{}", oddball_session::timing::stopping_text(e));
    }
    Ok(Replayed {
        calibration_epochs,
        test,
        model,
        calibration,
        params,
    })
}

/// A replayed subject's files: those played back and those calibrated on, each in order.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayFiles {
    pub test: Vec<PathBuf>,
    pub calibration: Vec<PathBuf>,
}

impl ReplayFiles {
    /// The replayed files, comma-separated, as --subject replay: names them.
    pub fn test_names(&self) -> String {
        join_paths(&self.test)
    }

    /// The calibration files, comma-separated.
    pub fn calibration_names(&self) -> String {
        join_paths(&self.calibration)
    }
}

/// A replayed subject: the calibration's accepted epochs (what it was trained on), the test
/// recordings read.
#[derive(Debug)]
pub struct Replayed {
    pub calibration_epochs: oddball_signal::Epochs,
    pub test: Vec<oddball_io::Recording>,
    pub model: oddball_decode::pipeline::Model,
    pub calibration: CalibrationReport,
    pub params: ReplayParams,
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
