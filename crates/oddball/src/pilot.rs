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

use crate::args::{Replayed, SessionOptions, SourceArgs};

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
    if let Some(files) = opts.replay_files()? {
        if source.source != SourceSpec::Sim {
            bail!(
                "--subject replay:{} replays decisions offline: it takes no --source {}",
                files.test_names(),
                source.source
            );
        }
        let r = opts.calibrated_replay(&files, rule)?;
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
