//! A replayed subject: P300-speller recordings played back as four-choice decisions, calibrated
//! on other recordings of the same person (by default the replayed file's sibling `…_1`).

use std::io::Write;
use std::path::{Path, PathBuf};

use oddball_decode::decision::DecisionRule;
use oddball_decode::pipeline::Model;
use oddball_eval::dataset::{self, DatasetError, Labelling};
use oddball_io::Recording;
use oddball_session::decision::CalibrationReport;
use oddball_session::replay::{self, ReplayParams};
use oddball_signal::Epochs;

use crate::error::{AppError, Result, SettingError};
use crate::settings::{join_paths, CalibrationSpec, SessionSettings, SubjectSpec};

/// A replayed subject's files: those played back and those calibrated on, each in order.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayFiles {
    pub test: Vec<PathBuf>,
    pub calibration: Vec<PathBuf>,
}

impl ReplayFiles {
    /// The replayed subject's files, checked (`None` for a simulated subject): the replayed
    /// ones exist, one text per file when texts are given, the calibration files (given, or the
    /// first replayed file's sibling) exist and are not replayed too.
    pub fn of(settings: &SessionSettings) -> Result<Option<Self>, SettingError> {
        let SubjectSpec::Replay(test) = &settings.subject else {
            return Ok(None);
        };
        // Settings before files.
        if settings.calibration == CalibrationSpec::None {
            return Err(SettingError::ReplayUncalibrated);
        }
        // The replayed files first: a missing one is not its calibration file's fault.
        for file in test {
            oddball_io::check_file(file).map_err(|e| SettingError::ReplayedFile(Box::new(e)))?;
        }
        if !settings.test_text.is_empty() && settings.test_text.len() != test.len() {
            return Err(SettingError::TestTextCount {
                texts: settings.test_text.len(),
                files: test.len(),
            });
        }
        // Labelled (None is refused above): the replayed file's sibling.
        let calibration = match &settings.calibration {
            CalibrationSpec::Files(c) => c.clone(),
            _ => vec![sibling_calibration(&test[0])?],
        };
        for c in &calibration {
            oddball_io::check_file(c).map_err(|e| SettingError::CalibrationFile(Box::new(e)))?;
            if test.contains(c) {
                return Err(SettingError::ReplayedAndCalibrated { path: c.clone() });
            }
        }
        Ok(Some(ReplayFiles {
            test: test.clone(),
            calibration,
        }))
    }

    /// The replayed files, comma-separated, as a replayed subject names them.
    pub fn test_names(&self) -> String {
        join_paths(&self.test)
    }

    /// The calibration files, comma-separated.
    pub fn calibration_names(&self) -> String {
        join_paths(&self.calibration)
    }
}

/// A replayed subject: the calibration's accepted epochs (what it was trained on), the test
/// recordings read, the model and the replay's settings.
#[derive(Debug)]
pub struct Replayed {
    pub calibration_epochs: Epochs,
    pub test: Vec<Recording>,
    pub model: Model,
    pub calibration: CalibrationReport,
    pub params: ReplayParams,
}

/// Reads a replayed subject's files (the replayed ones labelled by the settings' texts when
/// given) and calibrates on the calibration files; says the calibration on `out`.
pub fn calibrated_replay(
    settings: &SessionSettings,
    files: &ReplayFiles,
    rule: DecisionRule,
    out: &mut dyn Write,
) -> Result<Replayed> {
    let read = |p: &PathBuf, text: Option<&String>, calibration: bool| {
        let how = Labelling {
            text: text.map(String::as_str),
            ..Default::default()
        };
        dataset::read_labelled(p, how).map_err(|e| match e {
            DatasetError::Unlabelled {
                path,
                n_events,
                events,
            } => AppError::Setting(SettingError::Unlabelled {
                path,
                n_events,
                events,
                calibration,
            }),
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
        .map(|(i, p)| read(p, settings.test_text.get(i), false))
        .collect::<Result<Vec<_>>>()?;
    let cal_names = files.calibration_names();
    let mut params = ReplayParams::paper(settings.pipeline);
    params.paradigm = settings.paradigm();
    params.decoder.seed = settings.seed;
    params.decoder.rule = rule;
    params.rounds_per_decision = rule.max_rounds().max(params.paradigm.n_rounds);
    params.decoder.stopping = settings
        .optimise_stopping
        .then(|| settings.stopping_search());
    let replay::Calibrated {
        model,
        report: calibration,
        expected: chosen,
        epochs: calibration_epochs,
    } = replay::calibrate_for_bit_rate(&cal, &params).map_err(|source| AppError::Calibrating {
        names: cal_names.clone(),
        source,
    })?;
    writeln!(
        out,
        "calibration: {} characters, {} epochs ({} targets, {} rejected) of {}; cross-validated AUC {:.3}, d' {:.2}",
        calibration.n_trials,
        calibration.n_epochs,
        calibration.n_targets,
        calibration.n_rejected,
        cal_names,
        calibration.cv_auc,
        calibration.d_prime
    )?;
    if let Some(e) = &chosen {
        params.decoder.rule = e.rule;
        writeln!(out, "{}", oddball_session::timing::stopping_text(e))?;
    }
    Ok(Replayed {
        calibration_epochs,
        test,
        model,
        calibration,
        params,
    })
}

/// `eeg3_2.dat` → `eeg3_1.dat` in the same folder, if it exists and differs.
fn sibling_calibration(file: &Path) -> Result<PathBuf, SettingError> {
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
    Err(SettingError::NoSibling {
        path: file.to_path_buf(),
    })
}
