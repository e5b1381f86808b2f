//! The paper's tasks with a simulated or replayed subject: point-to-point target tracking and
//! drawing letters. Writes a report folder like the demo's ([`crate::report`]) and `task.png`
//! (tracking: targets, the path taken and the minimal path; drawing: the pen panel alone, under
//! the task's result).

use std::io::Write;
use std::path::PathBuf;

use oddball_arm::{ArmSim, Vector2};
use oddball_live::panel::PanelConfig;
use oddball_live::source::AnySource;
use oddball_session::decision::Decision;
use oddball_session::report::{draw_text, headline_text};
use oddball_session::tasks::{
    check_drawing, drawing_path, run_drawing, run_tracking, task_targets, Pilot, TrackParams,
};
use serde::Serialize;

use crate::error::{AppError, Result, SettingError};
use crate::panel::PanelSettings;
use crate::pilot::{prepare, AnyPilot, Prepared};
use crate::replayed::ReplayFiles;
use crate::report::{self, drawn};
use crate::settings::{SessionSettings, SourceSettings};

/// What every task runs with.
#[derive(Debug, Clone)]
pub struct TaskRun {
    pub settings: SessionSettings,
    pub source: SourceSettings,
    pub panel: PanelSettings,
    /// The report folder.
    pub out: PathBuf,
}

/// What a task shows on the panel: its targets and planned path, metres.
struct TaskView {
    targets_m: Vec<[f64; 2]>,
    plan_m: Vec<[f64; 2]>,
}

impl TaskRun {
    /// Tracks targets; `params` are checked against the arm before any EEG work. Returns why the
    /// session stopped early, if it did (a signal, the operator's abort, the source lost).
    pub fn track(&self, params: &TrackParams, out: &mut dyn Write) -> Result<Option<String>> {
        params
            .check(&self.settings.arm()?)
            .map_err(SettingError::Track)?;
        report::create_dir(&self.out)?;
        let mut prep = self.prepare("track", out, |arm| {
            Ok(TaskView {
                targets_m: task_targets(arm, params)
                    .iter()
                    .map(|p| [p[0], p[1]])
                    .collect(),
                plan_m: Vec::new(),
            })
        })?;
        let r = run_tracking(&mut prep.pilot, params)?;
        write!(out, "{r}")?;
        let targets: Vec<Vector2<f64>> = r
            .targets
            .iter()
            .map(|t| Vector2::new(t.target_m[0], t.target_m[1]))
            .collect();
        let step_m = prep.pilot.arm().settings().step_m;
        let intended =
            oddball_session::tasks::intended_track_path(prep.pen_start, &targets, step_m);
        report::write_task_files(&self.out, &prep, &r.steps, &intended, None, out)?;
        let task_png = self.out.join("task.png");
        drawn(
            &task_png,
            oddball_plot::task::draw_track(&task_png, prep.pilot.arm(), &r),
        )?;
        self.finish(prep, "track", &r, &r.steps, out)
    }

    /// Draws `text` in the stroke font; the text must fit the board at this step, checked
    /// before any EEG work. Returns why the session stopped early, if it did.
    pub fn draw(&self, text: &str, out: &mut dyn Write) -> Result<Option<String>> {
        self.settings.rules()?;
        check_drawing(&self.settings.arm()?, text).map_err(|source| SettingError::Drawing {
            text: text.to_string(),
            source,
        })?;
        report::create_dir(&self.out)?;
        let mut prep = self.prepare("draw", out, |arm| {
            Ok(TaskView {
                targets_m: Vec::new(),
                plan_m: drawing_path(arm, text)?
                    .iter()
                    .map(|p| [p[0], p[1]])
                    .collect(),
            })
        })?;
        let r =
            run_drawing(&mut prep.pilot, text, 3, 1.0).map_err(|source| AppError::DrawingTask {
                text: text.to_string(),
                source,
            })?;
        write!(out, "{}", draw_text(&r))?;
        let plan: Vec<Vector2<f64>> = r
            .plan_path_m
            .iter()
            .map(|p| Vector2::new(p[0], p[1]))
            .collect();
        let title = format!(
            "Drawing {:?}: {} in {} decisions (plan {}), pen within {:.3} mm of the plan",
            r.text,
            if r.completed {
                "completed"
            } else {
                "NOT completed"
            },
            r.decisions,
            r.min_decisions,
            r.max_deviation_m * 1e3
        );
        report::write_task_files(&self.out, &prep, &r.steps, &plan, Some(&title), out)?;
        self.finish(prep, "draw", &r, &r.steps, out)
    }

    /// The calibrated pilot of a task; when the panel is served, it shows the task and the
    /// session runs in real time in front of it (calibration ran unpaced).
    fn prepare(
        &self,
        what: &str,
        out: &mut dyn Write,
        view: impl Fn(&ArmSim) -> Result<TaskView>,
    ) -> Result<Prepared> {
        let opts = &self.settings;
        let (_, rule) = opts.rules()?;
        let replayed = ReplayFiles::of(opts)?;
        match (&replayed, opts.preset()) {
            (Some(files), _) => {
                if self.panel.serve.is_some() {
                    return Err(SettingError::ServeReplay.into());
                }
                writeln!(
                    out,
                    "oddball task {what}: replaying {} (calibration {}), pipeline {}",
                    files.test_names(),
                    files.calibration_names(),
                    opts.pipeline
                )?;
            }
            (None, preset) => writeln!(
                out,
                "oddball task {what}: {} simulated subject (seed {}), pipeline {}",
                preset.expect("a simulated preset when not replaying"),
                opts.seed,
                opts.pipeline
            )?,
        }
        let mut prep = prepare(
            opts,
            replayed.as_ref(),
            &self.source,
            rule,
            opts.realtime,
            out,
            |_, replay, out| {
                writeln!(
                    out,
                    "{} decisions available in the recording",
                    replay.remaining()
                )?;
                Ok(())
            },
        )?;
        if let AnyPilot::Live(session) = &mut prep.pilot {
            let arm = Pilot::arm(session).clone();
            let v = view(&arm)?;
            let config = PanelConfig::for_arm(
                &arm,
                &session.params().paradigm,
                v.targets_m,
                v.plan_m,
                format!("task {what} · {} subject · {}", prep.subject, opts.pipeline),
            );
            let clock = session.subject().clock();
            if let Some(p) = self.panel.start(config, clock, out)? {
                // The task runs in real time in front of the page; calibration ran unpaced.
                let subject = session.subject_mut();
                if let AnySource::Sim(sim) = subject.source_mut() {
                    sim.pace_from_now(self.source.sim_latency_ms);
                }
                subject.attach_panel(p);
            }
            let pre = session.params().decoder.preprocess;
            session
                .subject_mut()
                .set_scope_rules(oddball_live::panel::ScopeRules::of(&pre));
        }
        Ok(prep)
    }

    /// summary.json (what ran, the calibration, the bits delivered since the start and the
    /// task's report), then the live session's raw EEG saved.
    fn finish<T: Serialize>(
        &self,
        prep: Prepared,
        task: &'static str,
        r: &T,
        steps: &[Decision],
        out: &mut dyn Write,
    ) -> Result<Option<String>> {
        let summary = prep.task_summary(
            task,
            self.settings.pipeline.name(),
            self.settings.seed,
            self.settings.paradigm(),
            steps,
            r,
        );
        if let Some(h) = headline_text(&summary.bits_since_start) {
            writeln!(out, "{h}")?;
        }
        report::write_json(&self.out.join("summary.json"), &summary)?;
        report::save_session(
            prep,
            &self.out,
            &format!("task over: report in {}", self.out.display()),
        )?;
        writeln!(out, "report in {}", self.out.display())?;
        Ok(oddball_live::stop::reason())
    }
}
