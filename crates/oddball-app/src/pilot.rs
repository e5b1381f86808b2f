//! The calibrated pilot of `demo` and `task`: a replayed subject, or a live session over the
//! settings' source; and what a run reads back from it (the model, what was re-decided, what
//! adaptation did).

use std::io::Write;

use oddball_decode::decision::DecisionRule;
use oddball_live::clock::Clock;
pub use oddball_live::pilot::{AnyPilot, Prepared};
use oddball_live::source::SourceSpec;
use oddball_session::decoder::AdaptationReport;
use oddball_session::replay::ReplaySource;
use oddball_session::tasks::ReplayPilot;

use crate::error::{AppError, Result, SettingError};
use crate::replayed::{calibrated_replay, ReplayFiles, Replayed};
use crate::settings::{SessionSettings, SourceSettings};

/// Calibrates a pilot: a replayed recording (`replayed`, the checked [`ReplayFiles::of`] the
/// settings; offline, so only with the simulated source), or a session over `source`, its calibration paced by the wall clock when `paced`. Says the
/// calibration on `out`; `on_replay` sees a replayed subject's recordings and source before they
/// are used.
pub fn prepare(
    settings: &SessionSettings,
    replayed: Option<&ReplayFiles>,
    source: &SourceSettings,
    rule: DecisionRule,
    paced: bool,
    out: &mut dyn Write,
    on_replay: impl FnOnce(&Replayed, &ReplaySource, &mut dyn Write) -> Result<()>,
) -> Result<Prepared> {
    if let Some(files) = replayed {
        if source.source != SourceSpec::Sim {
            return Err(SettingError::ReplayWithSource {
                files: files.test.clone(),
                spec: source.source.clone(),
            }
            .into());
        }
        let r = calibrated_replay(settings, files, rule, out)?;
        let replay = ReplaySource::new(&r.test, &r.model, &r.params).map_err(|source| {
            AppError::Replaying {
                names: files.test_names(),
                source,
            }
        })?;
        on_replay(&r, &replay, out)?;
        let arm = settings.arm()?;
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
    let preset = settings.preset().ok_or(SettingError::NotLive)?;
    let plan = settings.plan(source, rule, paced, settings.session_model(rule)?)?;
    let (session, calibration, pen_start) = settings.open(&plan, Clock::new(), true, out)?;
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

/// What online adaptation did in a live session.
pub fn adaptation(prep: &Prepared) -> Option<AdaptationReport> {
    match &prep.pilot {
        AnyPilot::Live(s) => s.adaptation(),
        AnyPilot::Replay(_) => None,
    }
}
