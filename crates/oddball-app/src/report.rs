//! The report folder a run leaves: `decisions.csv`, `model.json`, `erp.png`, `pen_trace.png`,
//! `summary.json` and the session's raw EEG; every file depends only on the settings (same seed,
//! same bytes).

use std::io::Write;
use std::path::{Path, PathBuf};

use oddball_arm::Vector2;
use oddball_live::pilot::{decisions_csv, Prepared};
use oddball_plot::arm::SessionPaths;
use oddball_session::decision::Decision;
use oddball_session::report::{
    accuracy_over_time, accuracy_over_time_text, executed_path, missed_decisions, MissedDecision,
};
use oddball_session::tasks::Pilot;
use serde::Serialize;

use crate::error::{AppError, Result};
use crate::pilot::model_json;

/// Creates the report folder.
pub fn create_dir(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|source| AppError::CreateDir {
        path: out.to_path_buf(),
        source,
    })
}

/// Writes `text` to `path` atomically.
pub fn write(path: &Path, text: impl AsRef<[u8]>) -> Result<()> {
    oddball_io::write_atomic(path, text).map_err(|source| AppError::Write {
        path: path.to_path_buf(),
        source: Box::new(source),
    })
}

/// Writes `value` to `path` as pretty JSON (a final newline).
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    write(path, serde_json::to_string_pretty(value)? + "\n")
}

/// A picture drawn to `path`, its error naming the file.
pub fn drawn(path: &Path, r: Result<(), oddball_plot::PlotError>) -> Result<()> {
    r.map_err(|source| AppError::Draw {
        path: path.to_path_buf(),
        source,
    })
}

/// decisions.csv (one row per step), model.json, and erp.png after a labelled calibration (an
/// uncalibrated session has no labelled epochs to draw). Returns erp.png's path when drawn.
pub fn write_decisions_and_model(
    out: &Path,
    prep: &Prepared,
    steps: &[Decision],
) -> Result<Option<PathBuf>> {
    write(&out.join("decisions.csv"), decisions_csv(steps))?;
    write(&out.join("model.json"), model_json(prep)?)?;
    write_erp(out, &prep.erp)
}

/// erp.png of labelled calibration epochs (`None` and nothing drawn without any: an
/// uncalibrated session, or one started from a model).
pub fn write_erp(out: &Path, erp: &oddball_signal::Epochs) -> Result<Option<PathBuf>> {
    if erp.n_epochs() == 0 {
        return Ok(None);
    }
    let erp_png = out.join("erp.png");
    drawn(
        &erp_png,
        oddball_plot::task::draw_calibration_erp(&erp_png, erp),
    )?;
    Ok(Some(erp_png))
}

/// Where the executed commands put the reference (from `pen_start`, by `steps`) and the
/// decisions that did not move the pen as intended.
pub fn executed_and_missed(
    arm: &oddball_arm::ArmSim,
    pen_start: Vector2<f64>,
    steps: &[Decision],
) -> (Vec<Vector2<f64>>, Vec<MissedDecision>) {
    let step_m = arm.settings().step_m;
    (
        executed_path(pen_start, steps, step_m),
        missed_decisions(pen_start, steps, step_m),
    )
}

/// pen_trace.png: the arm at the start and the end, the pen trace over `paths`.
pub fn write_pen_trace(
    out: &Path,
    arm: &oddball_arm::ArmSim,
    paths: &SessionPaths<'_>,
) -> Result<PathBuf> {
    let pen_png = out.join("pen_trace.png");
    drawn(
        &pen_png,
        oddball_plot::arm::draw_pen_trace(arm, paths, &pen_png),
    )?;
    Ok(pen_png)
}

/// Ends a live pilot's session and saves its raw EEG in `out` (`session.easy` for a NIC stream,
/// `session.dat` otherwise); `None` for a replayed recording.
pub fn save_session(prep: Prepared, out: &Path, end: &str) -> Result<Option<PathBuf>> {
    let Some(path) = prep.session_file(out) else {
        return Ok(None);
    };
    prep.save_session(&path, end)
        .map_err(|source| AppError::SaveSession {
            path: path.clone(),
            source,
        })?;
    Ok(Some(path))
}

/// A task's files: decisions.csv, model.json, erp.png (after a labelled calibration) and
/// pen_trace.png (the `intended` path, the executed one and the missed decisions), and with
/// `task_title` the pen panel alone as task.png; says the accuracy over time on `say`.
pub fn write_task_files(
    out: &Path,
    prep: &Prepared,
    steps: &[Decision],
    intended: &[Vector2<f64>],
    task_title: Option<&str>,
    say: &mut dyn Write,
) -> Result<()> {
    write_decisions_and_model(out, prep, steps)?;
    writeln!(
        say,
        "{}",
        accuracy_over_time_text(&accuracy_over_time(steps, 10))
    )?;
    let arm = prep.pilot.arm();
    let (executed, missed) = executed_and_missed(arm, prep.pen_start, steps);
    let paths = SessionPaths {
        intended,
        executed: &executed,
        missed: &missed,
        numbered: false,
    };
    write_pen_trace(out, arm, &paths)?;
    if let Some(title) = task_title {
        let task_png = out.join("task.png");
        drawn(
            &task_png,
            oddball_plot::arm::draw_pen_paths(arm, &paths, title, &task_png),
        )?;
    }
    Ok(())
}
