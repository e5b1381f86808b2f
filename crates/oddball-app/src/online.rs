//! A live session: EEG from a live stream (or the simulated subject paced by the wall clock),
//! flashes drawn by the browser panel, markers stamped by the frames that drew them, decisions
//! driving the arm, everything recorded to XDF as it runs; `decisions.csv` (as demo and task
//! write it) and `summary.json` at the end.
//!
//! When the panel is served its address is said first (the subject view, then the operator
//! view's), then a subject view is waited for before the first countdown.

use std::io::Write;
use std::path::PathBuf;

use oddball_arm::{planned_path, Command};
use oddball_live::clock::Clock;
use oddball_live::live::{EegSource, LiveSubject, MarkerSink};
use oddball_live::online::{
    coincidence, decision_line, free_recording_path, is_recording_end, stop_reason, OnlineRun,
    OnlineSummary,
};
use oddball_live::panel::{PanelConfig, ScopeRules};
use oddball_live::plan::{PlanError, SessionPlan};
use oddball_live::record::Recorder;
use oddball_live::source::{AnySource, SourceSpec};
use oddball_live::timing::Summary;
use oddball_session::decision::CalibrationReport;
use oddball_session::decoder::Start;
use oddball_session::report::{scores, SessionFacts};
use oddball_session::roles::EegStream;
use oddball_session::tasks::run_copy;

use crate::error::{AppError, Result};
use crate::panel::PanelSettings;
use crate::report;
use crate::settings::{model_line, plan_error, CalibrationSpec, SessionSettings, SourceSettings};

/// A live session to run.
#[derive(Debug, Clone)]
pub struct Online {
    pub settings: SessionSettings,
    pub source: SourceSettings,
    pub panel: PanelSettings,
    /// The intended commands (a copy task: the panel cues each).
    pub commands: Vec<Command>,
    /// Calibrate live first (else the settings' model, or no calibration).
    pub calibrate: bool,
    /// Play a recording back, or run the simulated subject, as fast as it is processed.
    pub fast: bool,
    /// The report folder.
    pub out: PathBuf,
}

impl Online {
    /// Runs the session, saying on `out` what it does, decision by decision. Returns why it
    /// stopped before its last command, if it did (a signal, the operator's abort, the source
    /// lost, a replayed recording's end). A session that fails after its recording was created
    /// leaves no empty recording behind.
    pub fn run(&self, out: &mut dyn Write) -> Result<Option<String>> {
        let settings = &self.settings;
        let (_, rule) = settings.rules()?;
        settings.check_commands(&self.commands)?;
        // The model (and montage, transfer model) read and checked before any EEG work.
        let plan = settings.plan(
            &self.source,
            rule,
            !self.fast,
            settings.session_model(rule)?,
        )?;
        let clock = Clock::new();
        let (source, markers) = plan.open_source(clock).map_err(|e| plan_error(e, &plan))?;
        match &source {
            AnySource::Playback(p) => writeln!(
                out,
                "replaying {}: {} channels, {} Hz, {:.1} s, {} events",
                self.source.source.to_string().trim_start_matches("replay:"),
                p.ch_names().len(),
                p.sfreq(),
                p.n_times() as f64 / p.sfreq(),
                p.events().len()
            )?,
            _ if markers.is_some() => writeln!(out, "marker outlet: {}", self.source.markers)?,
            _ => {}
        }
        // A source at another rate than the model's is resampled to it (polyphase).
        let (source, change) = plan
            .at_model_rate(source)
            .map_err(|e| plan_error(e, &plan))?;
        if let Some(c) = change {
            writeln!(out, "{c}")?;
        }
        report::create_dir(&self.out)?;
        let record_path = free_recording_path(&self.out);
        // A session that fails before any EEG leaves no empty recording (the recorder removes it).
        self.run_with(&plan, source, markers, clock, &record_path, out)
    }

    fn run_with(
        &self,
        plan: &SessionPlan,
        source: AnySource,
        markers: Option<Box<dyn MarkerSink>>,
        clock: Clock,
        record_path: &std::path::Path,
        out: &mut dyn Write,
    ) -> Result<Option<String>> {
        let settings = &self.settings;
        let commands = &self.commands;
        let paradigm = plan.params.paradigm;
        let arm = settings.arm()?;
        let recorder = Recorder::create(
            record_path,
            source.ch_names(),
            source.sfreq(),
            &self.source.source.to_string(),
        )
        .map_err(|source| AppError::CreateRecording {
            path: record_path.to_path_buf(),
            source,
        })?;
        let uncalibrated = settings.calibration == CalibrationSpec::None;
        let title = format!(
            "{} · {} · {}",
            self.source.source,
            match &plan.start {
                Start::Model(m) => m.pipeline.name(),
                _ => plan.params.decoder.pipeline.name(),
            },
            if uncalibrated {
                "no calibration"
            } else if self.calibrate {
                "labelled calibration"
            } else {
                "model loaded"
            }
        );
        let mut subject = LiveSubject::new(source, paradigm, clock).with_recorder(recorder);
        if let Some(m) = markers {
            subject = subject.with_markers(m);
        }
        let plan_m = planned_path(
            arm.target(),
            commands.iter().copied(),
            arm.settings().step_m,
        )
        .iter()
        .map(|p| [p[0], p[1]])
        .collect();
        let config = PanelConfig::for_arm(&arm, &paradigm, Vec::new(), plan_m, title);
        if let Some(panel) = self.panel.start(config, clock, out)? {
            subject = subject.with_panel(panel);
        }
        writeln!(
            out,
            "oddball online: source {}, {} commands, recording {}",
            self.source.source,
            commands.len(),
            record_path.display()
        )?;
        subject.source_mut().start_now();
        if let AnySource::Playback(p) = subject.source() {
            if !p.holds_flashes() {
                writeln!(
                    out,
                    "warning: {} is not an XDF recording: it holds no flash as drawn, so this session's own flashes fall on EEG with no response to them and its decisions mean nothing (a panel demonstration); replay a session's session.xdf to re-decide it",
                    p.path().display()
                )?;
            }
        }
        let mut session = plan.session(subject).map_err(|e| plan_error(e, plan))?;
        // The recorder writes every sample as it comes: the session keeps none (flat memory).
        session.discard_samples();
        // The operator view's progress: "calibration decision 3 of 40", "decision 2 of 6".
        let calibrating = matches!(plan.start, Start::Calibrate { .. });
        let n_calibration = calibrating.then(|| session.params().calibration_trials());
        session
            .subject_mut()
            .set_plan(n_calibration, Some(commands.len()));
        // A stop request or a source that ends during calibration still closes the recording and
        // writes the summary (with no decisions).
        let mut ended = None;
        if let Start::Model(m) = &plan.start {
            writeln!(out, "{}", model_line(m, settings.model.as_deref()))?;
        }
        let started = plan.start(
            &mut session,
            &mut crate::settings::calibration_progress(&mut *out),
        );
        let mut calibration = None;
        match started {
            Ok(Some(c)) => {
                writeln!(
                    out,
                    "calibration: {} decisions, {} epochs, cross-validated AUC {:.3}",
                    c.n_trials, c.n_epochs, c.cv_auc
                )?;
                calibration = Some(c);
            }
            Ok(None) if uncalibrated => {
                settings.say_transfer(out)?;
                writeln!(out, "calibration: none: the decoder learns from the session (EM after every decision, no labels)")?;
            }
            Ok(None) => {
                // A replayed recording's calibration is passed over, not played as commands.
                let recorded = match session.subject().source() {
                    AnySource::Playback(p) => p.calibration(),
                    _ => None,
                };
                if let Some(c) = recorded {
                    writeln!(
                        out,
                        "passing over the recording's calibration: {} trials, {:.1} s (filtered, nothing decided)",
                        c.n_trials,
                        c.end as f64 / session.sfreq()
                    )?;
                    session
                        .pass_calibration(c.n_trials, c.end)
                        .map_err(AppError::PassCalibration)?;
                }
            }
            Err(PlanError::Start(e)) if calibrating && is_recording_end(&e) => {
                let end = stop_reason(&e);
                writeln!(out, "calibration: {end}")?;
                ended = Some(end);
            }
            Err(e) => return Err(plan_error(e, plan)),
        }
        // The operator's signal display judges channels by the session's own band and rules
        // (a loaded model's, once started).
        let pre = session.params().decoder.preprocess;
        session.subject_mut().set_scope_rules(ScopeRules::of(&pre));
        if let Some(m) = session.model() {
            report::write(&self.out.join("model.json"), m.to_json())?;
        }
        let mut steps = Vec::new();
        if ended.is_none() {
            let mut said = Ok(());
            let run = run_copy(
                &mut session,
                commands,
                false,
                1.5,
                is_recording_end,
                |i, s| {
                    if said.is_ok() {
                        said = writeln!(out, "{}", decision_line(i, s));
                    }
                    if let (Ok(()), Some(r)) = (&said, &s.arm_refusal) {
                        said = writeln!(out, "  the arm refused: {r}");
                    }
                },
            )
            .map_err(AppError::Running)?;
            said?;
            ended = match run.stopped {
                Some((e, deciding)) => {
                    let end = stop_reason(&e);
                    if deciding {
                        writeln!(out, "decision {}: {end}", run.steps.len() + 1)?;
                    }
                    Some(end)
                }
                None => None,
            };
            steps = run.steps;
        }
        // decisions.csv, erp.png and pen_trace.png as demo writes them.
        report::write(
            &self.out.join("decisions.csv"),
            oddball_live::pilot::decisions_csv(&steps),
        )?;
        if calibration.is_some() {
            report::write_erp(&self.out, &session.calibration_epochs()?)?;
        }
        if let Some(session_arm) = session.arm() {
            let pen_start = arm.pen();
            let intended: Vec<_> = planned_path(
                pen_start,
                steps.iter().map(|s| s.intended),
                session_arm.settings().step_m,
            );
            let (executed, missed) = report::executed_and_missed(session_arm, pen_start, &steps);
            let paths = oddball_plot::arm::SessionPaths {
                intended: &intended,
                executed: &executed,
                missed: &missed,
                numbered: true,
            };
            report::write_pen_trace(&self.out, session_arm, &paths)?;
        }
        if let Some(r) = session.channel_report() {
            writeln!(out, "{r}")?;
        }
        let replay = coincidence(session.subject().source(), session.flashes());
        if let Some(r) = &replay {
            writeln!(out, "{r}")?;
        }
        let subject = session.subject_mut();
        let source_name = self.source.source.to_string();
        let subject_name = match (&self.source.source, settings.preset()) {
            (SourceSpec::Sim, Some(preset)) => preset.to_string(),
            _ => source_name.clone(),
        };
        let summary = OnlineSummary::new(
            OnlineRun {
                facts: SessionFacts {
                    command: "online",
                    subject: &subject_name,
                    pipeline: settings.pipeline.name(),
                    seed: settings.seed,
                    paradigm,
                    calibration: calibration
                        .as_ref()
                        .map_or_else(|| (&CalibrationReport::none()).into(), Into::into),
                },
                source: source_name.clone(),
                result: scores(&steps, &plan.params.decoder.rule),
                presentation: subject.presentation_faults(),
            },
            &steps,
            &subject.timing,
            &subject.decision_latency_ms,
            record_path,
            replay,
            ended.clone(),
        );
        let timing = subject.timing.clone();
        let latency = subject.decision_latency_ms.clone();
        let health = subject.stream_health();
        let summary_line = summary.line(commands.len());
        subject.end(&summary_line);
        if let Some(panel) = subject.panel() {
            let s = panel.stats();
            writeln!(
                out,
                "panel: {} connection(s), {} message(s) rejected, {} request(s) refused at the door, {} other subject view(s) refused",
                s.connections, s.rejected, s.refused, s.refused_subjects
            )?;
        }
        writeln!(out, "{summary_line}")?;
        if let Some(h) = oddball_session::report::headline_text(&summary.bits_since_start) {
            writeln!(out, "{h}")?;
        }
        writeln!(out, "{}", timing.report())?;
        if let Some(l) = Summary::of(&latency) {
            writeln!(
                out,
                "processing latency, last block of the deciding epoch → arm command: {l}"
            )?;
        }
        if let Some(h) = health {
            writeln!(out, "stream: {h}")?;
        }
        let recorded = session.subject().recorded_samples().unwrap_or(0);
        // The recording's stream footers written and the file synced.
        session
            .into_subject()
            .finish()
            .map_err(|source| AppError::CloseRecording {
                path: record_path.to_path_buf(),
                source,
            })?;
        report::write_json(&self.out.join("summary.json"), &summary)?;
        writeln!(
            out,
            "recording: {} ({recorded} samples)",
            record_path.display(),
        )?;
        Ok(ended)
    }
}
