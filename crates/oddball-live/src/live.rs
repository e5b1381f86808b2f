//! A live session's subject ([`LiveSubject`]: an `EegStream`, `Presenter` and `Observer`): a live EEG source, the panel a person looks at, the marker
//! stream, and the recording, on one clock.
//!
//! The session engine announces each flash [`Presenter::lead`] ahead (half a second) so the page
//! has it before it must draw it. The page stamps the frame that drew it; that stamp, mapped to
//! the EEG's sample clock, becomes the flash's marker (and is sent on the marker stream and
//! recorded). A flash the page never drew within [`UNDRAWN_AFTER_MS`] of its planned onset (no
//! page, a page that disconnected or stalled), by the clock or by the EEG taken, whichever is
//! further on, loses its epoch: a decision never rests on flashes nobody saw, and with none at
//! all the session abstains and the arm holds still.
//! Without a panel ([`Stamping::Schedule`]) flashes count as drawn on schedule.
//!
//! The operator view's requests reach the session here: a pause holds it before its next trial
//! ([`Presenter::hold`], marked `pause` and `resume` in the recording), an abort stops it at the
//! next block of EEG with [`LiveError::Aborted`], which ends a session as cleanly as SIGTERM.
//!
//! A recording played back ([`crate::playback`]) draws each flash where the recording drew it
//! ([`EegSource::recorded_flash`]) and holds where the recorded session held
//! ([`EegSource::recorded_hold`]), so a session set up as the recorded one decides as it did.
//!
//! # Presentation faults
//! What the person is shown is watched as closely as the EEG: flashes undrawn or late (from the
//! stamps), and what the subject page says of itself (hidden, frames stalled or missed, more
//! than one bulb lit) become alarms on the operator view and counts in the session's summary
//! ([`LiveSubject::presentation_faults`]; [`crate::panel::monitor`]).
//!
//! Calibration does not train on garbage, by two rules and nothing more:
//! * an undrawn flash (no stamp within [`UNDRAWN_AFTER_MS`]; or a stamp refused: implausible,
//!   or sent by a page that had said it was hidden) never gives an epoch, in calibration as
//!   online: the engine drops it before its epoch completes. The
//!   page skips a flash it would draw that late rather than draw it, and lights one bulb at a
//!   time, so a page that comes back from the background does not fire a burst of old
//!   flashes;
//! * while a presentation fault that lasts is on (no subject view, the view hidden, or drawing
//!   almost no frames) a calibration holds between trials, as an operator's pause does (the
//!   EEG recorded, `pause` and `resume` marked), and goes on by itself once the view draws
//!   again. The trial under way when the fault began finishes: its flashes drawn before are
//!   sound epochs and kept, the rest are undrawn and dropped. No trial is repeated: a
//!   calibration ends with fewer epochs, never with wrong ones.
//!
//! Online, the same faults raise the same alarms but do not hold: an undrawn flash adds no
//! evidence, and a decision with none abstains, so the arm stays still.
//!
//! # The operator's signal display
//! With a panel, every block of EEG also feeds [`crate::panel::scope::Scope`]: the signal
//! band-passed as the decoder sees it, decimated to bins, each channel's state by the
//! session's epoch rules ([`LiveSubject::set_scope_rules`]; the online default otherwise),
//! and after each trial the average epoch of the cued (or decided) bulb against the others'.

use std::time::Instant;

use ndarray::Array2;
use oddball_arm::ArmSim;
use oddball_io::xdf::session_markers;
use oddball_session::decision::{Phase, TrialOutcome, TrialRecord};
use oddball_session::online::ChannelFaults;
use oddball_session::paradigm::FourBulbParams;
use oddball_session::roles::{Drawn, EegStream, Observer, Presenter};
use oddball_session::SessionError;

use crate::clock::Clock;
use crate::panel::monitor::LATE_AFTER_MS;
pub use crate::panel::protocol::UNDRAWN_AFTER_MS;
use crate::panel::{
    ChannelQuality, DrawnReport, FaultKind, FaultMonitor, PanelServer, PresentationFaults, Scope,
    ScopeRules, ServerMsg,
};
use crate::record::Recorder;
use crate::timing::{plausible_stamp, FlashTiming, Summary};
use crate::LiveError;

/// How far ahead flashes are announced to the page, seconds.
pub const ANNOUNCE_AHEAD_S: f64 = 0.5;

/// A live EEG stream.
pub trait EegSource: Send {
    fn sfreq(&self) -> f64;
    fn ch_names(&self) -> &[String];
    /// Blocks until `n` more samples can be taken (errors when the stream is gone or stalls).
    fn wait(&mut self, n: usize) -> Result<(), LiveError>;
    /// The next `n` samples `(n_channels, n)`, µV (after [`EegSource::wait`]).
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError>;
    /// Session-clock time (ms) of sample `i` (extrapolated at the nominal rate beyond the
    /// samples received).
    fn time_of(&self, sample: u64) -> f64;
    /// The person saw a flash of stimulus `code` at sample `onset` (a simulated source renders
    /// the response, a simulated amplifier in another process is told; a real one ignores it).
    fn saw(&mut self, _onset: u64, _code: u32, _attended: bool) -> Result<(), LiveError> {
        Ok(())
    }
    /// The session starts now (after waiting for a page, say): a simulated source starts its
    /// clock here instead of racing to catch up. Live streams keep theirs.
    fn start_now(&mut self) {}
    /// Samples lost, reconnections, stalls; `None` for simulated sources.
    fn health(&self) -> Option<String> {
        None
    }
    /// A recording played back: how it drew the flash of stimulus `code` this session plans at
    /// sample `planned` (its onset the recorded one, `None` when the recording never drew it),
    /// or an error when the recording's flashes are not this session's. `None` for a live
    /// source: the page (or the schedule) says.
    fn recorded_flash(&mut self, _planned: u64, _code: u32) -> Result<Option<Drawn>, LiveError> {
        Ok(None)
    }
    /// A recording played back: whether the recorded session held (paused) before its next
    /// trial at sample `position`. `None` for a live source.
    fn recorded_hold(&self, _position: u64) -> Option<bool> {
        None
    }
}

/// The nearest sample to session-clock time `ms` given `source`'s clock.
pub fn sample_at(source: &dyn EegSource, ms: f64) -> u64 {
    let t0 = source.time_of(0);
    (((ms - t0) * source.sfreq() / 1e3).round()).max(0.0) as u64
}

/// Where the markers of flashes, cues and decisions go besides the recording (an LSL outlet).
pub trait MarkerSink: Send {
    /// `text` happened at session-clock time `ms`.
    fn marker(&mut self, text: &str, ms: f64);
}

/// How flash onsets are known.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stamping {
    /// The page stamps each drawn flash.
    Panel,
    /// No page: flashes count as drawn on schedule.
    Schedule,
}

#[derive(Debug, Clone, Copy)]
struct Announced {
    id: u64,
    planned: u64,
    code: u32,
    attended: bool,
    at_ms: f64,
}

/// The live subject: all three of the engine's roles (`oddball_session::roles`).
pub struct LiveSubject<S: EegSource> {
    source: S,
    panel: Option<PanelServer>,
    stamping: Stamping,
    markers: Option<Box<dyn MarkerSink>>,
    recorder: Option<Recorder>,
    paradigm: FourBulbParams,
    clock: Clock,
    position: u64,
    n_trials: usize,
    /// Trials started in calibration.
    n_calibration: usize,
    n_decisions: usize,
    /// Trials to come per phase when known (calibration, online), for the operator's progress.
    plan: (Option<usize>, Option<usize>),
    /// Held before the next trial (at the operator's request, or for the presentation fault).
    held: (bool, Option<FaultKind>),
    /// Since when (session-clock ms) a calibration holds for a presentation fault.
    fault_hold_since: Option<f64>,
    /// The phase of the trial under way (or of the last one).
    phase: Option<Phase>,
    /// Presentation faults: alarms and counts.
    monitor: FaultMonitor,
    /// The operator's signal display (with a panel), and its rules.
    scope: Option<Scope>,
    scope_rules: ScopeRules,
    /// Held before the next trial where a replayed recording held.
    replay_held: bool,
    /// Epochs rejected per channel when the last trial ended (its own are the difference).
    faults_before: Vec<ChannelFaults>,
    announced: Vec<Announced>,
    /// Flashes on screen: id and on frame (ms).
    lit: Vec<(u64, f64)>,
    next_id: u64,
    drawn: Vec<Drawn>,
    pub timing: FlashTiming,
    /// When the last block of samples was handed to the engine.
    last_block: Instant,
    /// Processing latency per online decision: from the block that completed it to the command
    /// (the trial's end), ms.
    pub decision_latency_ms: Vec<f64>,
    last_arm_ms: f64,
}

impl<S: EegSource> std::fmt::Debug for LiveSubject<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveSubject")
            .field("position", &self.position)
            .field("stamping", &self.stamping)
            .field("panel", &self.panel)
            .finish_non_exhaustive()
    }
}

impl<S: EegSource> LiveSubject<S> {
    pub fn new(source: S, paradigm: FourBulbParams, clock: Clock) -> Self {
        Self {
            source,
            panel: None,
            stamping: Stamping::Schedule,
            markers: None,
            recorder: None,
            paradigm,
            clock,
            position: 0,
            n_trials: 0,
            n_calibration: 0,
            n_decisions: 0,
            plan: (None, None),
            held: (false, None),
            fault_hold_since: None,
            phase: None,
            monitor: FaultMonitor::new(),
            scope: None,
            scope_rules: ScopeRules::default(),
            replay_held: false,
            faults_before: Vec::new(),
            announced: Vec::new(),
            lit: Vec::new(),
            next_id: 1,
            drawn: Vec::new(),
            timing: FlashTiming::default(),
            last_block: Instant::now(),
            decision_latency_ms: Vec::new(),
            last_arm_ms: f64::NEG_INFINITY,
        }
    }

    /// Flashes are drawn (and stamped) by this panel's page.
    pub fn with_panel(mut self, panel: PanelServer) -> Self {
        self.attach_panel(panel);
        self
    }

    /// Hands flashes to this panel's page from now on.
    pub fn attach_panel(&mut self, panel: PanelServer) {
        self.panel = Some(panel);
        self.stamping = Stamping::Panel;
        self.start_scope();
    }

    /// The operator's signal display follows these rules (the session's band-pass, epoch
    /// window and rejection thresholds: `ScopeRules::of(&params.decoder.preprocess)`); by
    /// default those of [`oddball_decode::preprocess::Preprocess::online`].
    pub fn set_scope_rules(&mut self, rules: ScopeRules) {
        self.scope_rules = rules;
        if self.panel.is_some() {
            self.start_scope();
        }
    }

    fn start_scope(&mut self) {
        let Some(p) = &self.panel else {
            return;
        };
        let scope = Scope::new(
            self.scope_rules,
            self.source.sfreq(),
            self.source.ch_names(),
            self.position,
        );
        let (erp_tmin_ms, erp_dt_ms) = scope.erp_axis_ms();
        p.send(&ServerMsg::Scope {
            names: scope.names().to_vec(),
            bin_ms: scope.bin_ms(),
            flat_uv: scope.rules().flat_uv,
            noisy_uv: scope.rules().noisy_uv,
            band: scope.band_text(),
            erp_tmin_ms,
            erp_dt_ms,
        });
        self.scope = Some(scope);
    }

    /// The presentation faults so far: what the session's summary reports of them.
    pub fn presentation_faults(&self) -> PresentationFaults {
        let now = self.clock.now_ms();
        let mut c = self.monitor.counts(now);
        if let Some(t0) = self.fault_hold_since {
            c.calibration_held_s += (now - t0).max(0.0) / 1e3;
        }
        c
    }

    /// Whether the next trial is a calibration's (what a presentation fault holds).
    fn calibrating(&self) -> bool {
        match self.plan.0 {
            Some(n) => self.n_calibration < n && self.n_decisions == 0,
            None => self.phase == Some(Phase::Calibration),
        }
    }

    /// How many calibration trials and online decisions the session will run, when known:
    /// the operator view shows "decision 3 of 40".
    pub fn set_plan(&mut self, calibration: Option<usize>, decisions: Option<usize>) {
        self.plan = (calibration, decisions);
    }

    pub fn source_mut(&mut self) -> &mut S {
        &mut self.source
    }

    pub fn with_markers(mut self, sink: Box<dyn MarkerSink>) -> Self {
        self.markers = Some(sink);
        self
    }

    pub fn with_recorder(mut self, recorder: Recorder) -> Self {
        self.recorder = Some(recorder);
        self
    }

    /// EEG samples recorded so far (`None` without a recorder).
    pub fn recorded_samples(&self) -> Option<u64> {
        self.recorder.as_ref().map(Recorder::n_times)
    }

    pub fn source(&self) -> &S {
        &self.source
    }
    pub fn panel(&self) -> Option<&PanelServer> {
        self.panel.as_ref()
    }
    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// Tells the page the session is over (`summary` shown).
    pub fn end(&mut self, summary: &str) {
        let now = self.clock.now_ms();
        if let Some(m) = &mut self.markers {
            m.marker("end", now);
        }
        if let Some(p) = &self.panel {
            // The operator's figures as they stand at the end, then the end itself.
            p.send(&ServerMsg::Diag {
                text: self.status(),
            });
            p.send(&ServerMsg::End {
                summary: summary.to_string(),
            });
        }
    }

    /// Closes the recording (footers written) and returns the panel, if any.
    pub fn finish(mut self) -> Result<Option<PanelServer>, LiveError> {
        if let Some(r) = self.recorder.take() {
            r.finish()?;
        }
        Ok(self.panel.take())
    }

    fn marker(&mut self, text: &str, ms: f64) -> Result<(), LiveError> {
        self.marker_recorded(text, text, ms)
    }

    /// A marker whose recorded text says more than the live stream's (see
    /// [`oddball_io::xdf::session_markers`]).
    fn marker_recorded(&mut self, text: &str, recorded: &str, ms: f64) -> Result<(), LiveError> {
        if let Some(m) = &mut self.markers {
            m.marker(text, ms);
        }
        if let Some(r) = &mut self.recorder {
            r.marker(recorded, ms)?;
        }
        Ok(())
    }

    /// A flash seen at sample `onset`: the simulated brain, the marker stream, the recording.
    fn seen(&mut self, a: Announced, onset: u64, on_ms: f64) -> Result<(), LiveError> {
        self.source.saw(onset, a.code, a.attended)?;
        self.marker_recorded(
            &format!("flash {}", a.code),
            &session_markers::flash_marker(a.code, a.attended),
            on_ms,
        )?;
        self.drawn.push(Drawn {
            planned: a.planned,
            code: a.code,
            onset: Some(onset),
        });
        if let Some(s) = &mut self.scope {
            s.flash(onset, a.code);
        }
        Ok(())
    }

    /// A flash lost: never drawn in time, or its stamp refused. Its epoch is dropped.
    fn undrawn(&mut self, a: Announced) {
        self.timing.undrawn += 1;
        self.monitor
            .event(FaultKind::Undrawn, self.clock.now_ms(), 1, 0.0);
        if self.phase == Some(Phase::Calibration) {
            self.monitor.calibration_undrawn(1);
        }
        self.drawn.push(Drawn {
            planned: a.planned,
            code: a.code,
            onset: None,
        });
    }

    /// Takes the page's stamps; declares flashes past their deadline undrawn: more than
    /// [`UNDRAWN_AFTER_MS`] ago by the clock, or by the EEG about to be taken (`upcoming`
    /// samples more: a source faster than real time, a file played back `--fast`, must not
    /// complete an epoch whose flash no page stamped yet).
    fn collect_stamps(&mut self, upcoming: u64) -> Result<(), LiveError> {
        let Some(panel) = &self.panel else {
            return Ok(());
        };
        let reports = panel.take_drawn();
        for r in reports {
            match r {
                DrawnReport::On {
                    id,
                    on_ms,
                    received_ms,
                    hidden,
                    ..
                } => {
                    let Some(k) = self.announced.iter().position(|a| a.id == id) else {
                        self.timing.late_stamps += 1;
                        continue;
                    };
                    let a = self.announced.remove(k);
                    // A page that said it was hidden drew nothing anyone saw.
                    if hidden || !plausible_stamp(a.at_ms, on_ms) {
                        self.timing.refused_stamps += 1;
                        self.undrawn(a);
                        continue;
                    }
                    if on_ms - a.at_ms > LATE_AFTER_MS {
                        let now = self.clock.now_ms();
                        self.monitor.event(FaultKind::Late, now, 1, on_ms - a.at_ms);
                    }
                    self.lit.push((id, on_ms));
                    self.timing.onset_error_ms.push(on_ms - a.at_ms);
                    self.timing.report_delay_ms.push(received_ms - on_ms);
                    let onset = sample_at(&self.source, on_ms);
                    self.seen(a, onset, on_ms)?;
                }
                DrawnReport::Off { id, off_ms } => {
                    if let Some(k) = self.lit.iter().position(|&(i, _)| i == id) {
                        let (_, on_ms) = self.lit.swap_remove(k);
                        self.timing.on_ms.push(off_ms - on_ms);
                    }
                }
            }
        }
        // Flashes on screen whose off frame never came (a page that went away) are forgotten.
        if self.lit.len() > 64 {
            self.lit.drain(..32);
        }
        let now = self
            .clock
            .now_ms()
            .max(self.source.time_of(self.position + upcoming));
        let (gone, kept): (Vec<Announced>, Vec<Announced>) = self
            .announced
            .iter()
            .partition(|a| now > a.at_ms + UNDRAWN_AFTER_MS);
        self.announced = kept;
        for a in gone {
            self.undrawn(a);
        }
        self.watch_presentation();
        Ok(())
    }

    /// The subject view's state and reports into alarms for the operator view.
    fn watch_presentation(&mut self) {
        let Some(panel) = &self.panel else {
            return;
        };
        let now = self.clock.now_ms();
        self.monitor.set_holds(self.calibrating());
        self.monitor.view(&panel.subject_view(), now);
        let alarms = self.monitor.alarms(now);
        if alarms.is_empty() {
            return;
        }
        for a in alarms {
            panel.send(&ServerMsg::Alarm(a));
        }
        panel.send(&ServerMsg::Faults {
            counts: self.presentation_faults(),
        });
    }

    fn status(&self) -> String {
        let mut s = self.timing.report();
        if let Some(h) = self.source.health() {
            s.push('\n');
            s.push_str(&h);
        }
        if let Some(l) = Summary::of(&self.decision_latency_ms) {
            s.push_str(&format!("\ndecision latency {l}"));
        }
        if let Some(p) = &self.panel {
            let st = p.stats();
            s.push_str(&format!(
                "\nsubject page: {} connected ({} in all), frame {}, {} message(s) rejected",
                st.connected,
                st.connections,
                st.frame_ms.map_or("–".into(), |f| format!("{f:.2} ms")),
                st.rejected
            ));
            if let (Some(offset), Some(rtt)) = (st.clock_offset_ms, st.clock_rtt_ms) {
                s.push_str(&format!(
                    "\npage clock offset {offset:.2} ms (round trip {rtt:.2} ms)"
                ));
            }
        }
        s
    }
}

impl<S: EegSource> EegStream for LiveSubject<S> {
    fn sfreq(&self) -> f64 {
        self.source.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.source.ch_names()
    }
    fn position(&self) -> u64 {
        self.position
    }
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        if crate::stop::requested() {
            return Err(LiveError::Stopped.into());
        }
        if self
            .panel
            .as_ref()
            .is_some_and(PanelServer::abort_requested)
        {
            return Err(LiveError::Aborted.into());
        }
        self.source.wait(n)?;
        self.collect_stamps(n as u64)?;
        let data = self.source.take(n)?;
        if let Some(rec) = &mut self.recorder {
            let t0 = self.source.time_of(self.position);
            rec.eeg(t0, self.source.sfreq(), data.view())?;
        }
        if let (Some(scope), Some(p)) = (&mut self.scope, &self.panel) {
            if let Some(b) = scope.push(data.view()) {
                p.send(&ServerMsg::Signal {
                    t_ms: self.source.time_of(b.first_sample),
                    lo: b.lo,
                    hi: b.hi,
                    state: b.state,
                });
            }
        }
        self.position += n as u64;
        self.last_block = Instant::now();
        Ok(data)
    }
    fn stream_health(&self) -> Option<String> {
        self.source.health()
    }
}

impl<S: EegSource> Presenter for LiveSubject<S> {
    fn lead(&self) -> u64 {
        // A page, or a marker stream's consumer (a remote simulated subject), needs flashes
        // ahead of time; on schedule in this process they need none.
        if self.stamping == Stamping::Panel || self.markers.is_some() {
            (ANNOUNCE_AHEAD_S * self.source.sfreq()).round() as u64
        } else {
            0
        }
    }
    fn show(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), SessionError> {
        let a = Announced {
            id: self.next_id,
            planned: onset,
            code,
            attended,
            at_ms: self.source.time_of(onset),
        };
        self.next_id += 1;
        if let Some(d) = self.source.recorded_flash(onset, code)? {
            return Ok(self.replayed(a, d)?);
        }
        match (&self.panel, self.stamping) {
            (Some(panel), Stamping::Panel) => {
                panel.send(&ServerMsg::Flash {
                    id: a.id,
                    code,
                    at_ms: a.at_ms,
                    dur_ms: self.paradigm.flash_s * 1e3,
                });
                self.announced.push(a);
                Ok(())
            }
            _ => Ok(self.seen(a, onset, a.at_ms)?),
        }
    }
    fn drawn(&mut self) -> Vec<Drawn> {
        std::mem::take(&mut self.drawn)
    }
    /// Holds at the operator's request, and in calibration while a presentation fault that
    /// lasts is on (see the module doc).
    fn hold(&mut self) -> Result<bool, SessionError> {
        if self.replay_hold()? {
            return Ok(true);
        }
        let Some(panel) = &self.panel else {
            return Ok(false);
        };
        let operator = panel.pause_requested();
        self.monitor.set_holds(self.calibrating());
        let fault = if operator {
            None
        } else {
            self.monitor.holding()
        };
        let held = (operator || fault.is_some(), fault);
        let now = self.clock.now_ms();
        if held != self.held {
            panel.send(&ServerMsg::Paused {
                paused: held.0,
                at_ms: now,
                fault,
            });
            if held.0 != self.held.0 {
                self.marker(if held.0 { "pause" } else { "resume" }, now)?;
            }
        }
        match (fault.is_some(), self.fault_hold_since) {
            (true, None) => {
                self.fault_hold_since = Some(now);
                self.monitor.held(0.0, true);
            }
            (false, Some(t0)) => {
                self.fault_hold_since = None;
                self.monitor.held((now - t0).max(0.0) / 1e3, false);
            }
            _ => {}
        }
        self.held = held;
        Ok(held.0)
    }
    fn trial_started(
        &mut self,
        start: u64,
        phase: Phase,
        intended: Option<u32>,
    ) -> Result<(), SessionError> {
        let at_ms = self.source.time_of(start);
        let trial = self.n_trials;
        self.n_trials += 1;
        self.phase = Some(phase);
        let (number, of) = match phase {
            Phase::Calibration => {
                self.n_calibration += 1;
                (self.n_calibration, self.plan.0)
            }
            Phase::Online => (self.n_decisions + 1, self.plan.1),
        };
        if let Some(p) = &self.panel {
            p.send(&ServerMsg::Trial {
                trial,
                phase: match phase {
                    Phase::Calibration => "calibration".into(),
                    Phase::Online => "online".into(),
                },
                number,
                of,
                cue: intended,
                at_ms,
                countdown_s: self.paradigm.countdown_s,
            });
        }
        let code = intended.unwrap_or(0);
        Ok(self.marker_recorded(
            &format!("cue {code}"),
            &session_markers::cue_marker(code, phase == Phase::Calibration),
            at_ms,
        )?)
    }
}

impl<S: EegSource> Observer for LiveSubject<S> {
    fn trial_ended(&mut self, t: &TrialRecord) -> Result<(), SessionError> {
        let now = self.clock.now_ms();
        // Flashes announced for this trial and not drawn yet are void.
        for a in std::mem::take(&mut self.announced) {
            self.drawn.push(Drawn {
                planned: a.planned,
                code: a.code,
                onset: None,
            });
        }
        if let Some(p) = &self.panel {
            p.send(&ServerMsg::Cancel { after_ms: now });
        }
        if t.phase == Phase::Online {
            self.decision_latency_ms
                .push(self.last_block.elapsed().as_secs_f64() * 1e3);
            let code = t.decided();
            self.n_decisions += 1;
            if let Some(p) = &self.panel {
                p.send(&ServerMsg::Decision {
                    trial: self.n_decisions,
                    code,
                    intended: t.intended,
                    posterior: t.posterior.clone(),
                    confidence: t.confidence(),
                    rounds: t.rounds,
                    refused: t.arm_refusal.clone(),
                });
            }
            let text = match t.outcome {
                TrialOutcome::Chosen { code } => format!("decision {code}"),
                _ => "abstain".to_string(),
            };
            let at = self.source.time_of(t.end);
            self.marker(&text, at)?;
            if let Some(rec) = &mut self.recorder {
                let json = serde_json::to_string(t).expect("trial records serialise");
                rec.decision(&json, at)?;
            }
        }
        if let Some(p) = &self.panel {
            p.send(&ServerMsg::Diag {
                text: self.status(),
            });
            p.send(&ServerMsg::Faults {
                counts: self.presentation_faults(),
            });
            let target = t.intended.or(t.decided());
            if let Some(a) = self.scope.as_mut().and_then(|s| s.trial_done(target)) {
                p.send(&ServerMsg::Average {
                    trial: match t.phase {
                        Phase::Calibration => self.n_calibration,
                        Phase::Online => self.n_decisions,
                    },
                    phase: match t.phase {
                        Phase::Calibration => "calibration".into(),
                        Phase::Online => "online".into(),
                    },
                    target: a.target,
                    n_target: a.n_target,
                    n_other: a.n_other,
                    target_uv: a.target_uv,
                    other_uv: a.other_uv,
                });
            }
        }
        Ok(())
    }
    fn channel_faults(&mut self, faults: &[ChannelFaults]) -> Result<(), SessionError> {
        let before = std::mem::replace(&mut self.faults_before, faults.to_vec());
        let Some(p) = &self.panel else {
            return Ok(());
        };
        let since = |now: &ChannelFaults, then: Option<&ChannelFaults>| {
            let then = then.copied().unwrap_or_default();
            ChannelFaults {
                non_finite: now.non_finite - then.non_finite,
                flat: now.flat - then.flat,
                over_threshold: now.over_threshold - then.over_threshold,
            }
        };
        let channels = faults
            .iter()
            .zip(self.source.ch_names())
            .enumerate()
            .map(|(c, (f, name))| ChannelQuality {
                name: name.clone(),
                last: since(f, before.get(c)),
                total: *f,
            })
            .collect();
        p.send(&ServerMsg::Quality { channels });
        Ok(())
    }
    fn arm_state(&mut self, position: u64, arm: &ArmSim) -> Result<(), SessionError> {
        let t_ms = self.source.time_of(position);
        let q = arm.state().q;
        let elbow = arm.plant().elbow_position(&q);
        let pen = arm.pen();
        if let Some(rec) = &mut self.recorder {
            rec.arm(t_ms, [pen[0], pen[1], q[0], q[1]])?;
        }
        // The page needs no more than ~30 frames a second of arm.
        if t_ms - self.last_arm_ms >= 33.0 {
            self.last_arm_ms = t_ms;
            if let Some(p) = &self.panel {
                p.send(&ServerMsg::Arm {
                    t_ms,
                    elbow_m: [elbow[0], elbow[1]],
                    pen_m: [pen[0], pen[1]],
                });
            }
        }
        Ok(())
    }
}

/// A recording played back ([`crate::playback`]): its flashes and pauses are the recording's.
impl<S: EegSource> LiveSubject<S> {
    /// A flash as the replayed recording drew it: seen at its recorded onset, or never drawn
    /// (its epoch lost, as it was when recorded). A page is not asked to draw or stamp it.
    fn replayed(&mut self, a: Announced, d: Drawn) -> Result<(), LiveError> {
        match d.onset {
            Some(onset) => self.seen(a, onset, self.source.time_of(onset)),
            None => {
                self.timing.undrawn += 1;
                self.drawn.push(d);
                Ok(())
            }
        }
    }

    /// Holds where the replayed recording held, marking `pause` and `resume` at the sample.
    fn replay_hold(&mut self) -> Result<bool, LiveError> {
        let held = self.source.recorded_hold(self.position).unwrap_or(false);
        if held != self.replay_held {
            self.replay_held = held;
            let text = if held {
                session_markers::PAUSE
            } else {
                session_markers::RESUME
            };
            self.marker(text, self.source.time_of(self.position))?;
        }
        Ok(held)
    }
}
