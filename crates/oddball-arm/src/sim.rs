//! The closed-loop simulation: plant (RK4), controller, actuator saturation, references from
//! direction commands, safety checks, pen trace and per-step reports.

use nalgebra::Vector2;

use crate::config::{ArmConfig, ArmSetup};
use crate::control::TaskSpaceController;
use crate::error::{ArmError, ConfigError};
use crate::integrate::{rk4_step_trig, ArmState};
use crate::model::{ArmModel, Elbow, Trig};
use crate::reference::{Command, ReferenceSample, Transition};
use crate::settings::{ControlUpdate, SimSettings};
use crate::trace::PenTrace;
use crate::workspace::Workspace;

/// One recorded control step: the state at `t_s` and the torque applied over `[t_s, t_s + dt]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time (s).
    pub t_s: f64,
    /// Joint angles (rad).
    pub q: Vector2<f64>,
    /// Joint rates (rad/s).
    pub qd: Vector2<f64>,
    /// Torque applied after saturation (N·m).
    pub u: Vector2<f64>,
    /// Torque the controller asked for (N·m).
    pub u_requested: Vector2<f64>,
    /// Pen position (m).
    pub p: Vector2<f64>,
    /// Desired pen position (m).
    pub p_d: Vector2<f64>,
    /// Which joints were clipped to their torque limit.
    pub saturated: [bool; 2],
    /// Whether damped least squares was active.
    pub dls_active: bool,
}

/// What happened in one control step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// Distance (m) from the pen to the desired position at the start of the step.
    pub tracking_error_m: f64,
    pub u_requested: Vector2<f64>,
    pub u_applied: Vector2<f64>,
    pub saturated: [bool; 2],
    pub dls_active: bool,
}

/// Statistics of a stretch of simulated time, measured against one target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentStats {
    /// Start and end time (s).
    pub t_start_s: f64,
    pub t_end_s: f64,
    /// The target the pen should reach (m).
    pub target: Vector2<f64>,
    /// Time from `t_start_s` after which the pen stayed within the settle tolerance of the
    /// target until `t_end_s`; `None` if it was outside at the end.
    pub settle_time_s: Option<f64>,
    /// Distance from the pen to the target at `t_end_s` (m).
    pub final_error_m: f64,
    /// Largest distance from the pen to the desired position `p_d(t)` (m).
    pub max_tracking_error_m: f64,
    /// Largest |applied torque| per joint (N·m).
    pub max_abs_torque_n_m: [f64; 2],
    /// Number of steps in which at least one joint was clipped to its torque limit.
    pub saturated_steps: usize,
    /// Total time spent saturated (s).
    pub saturated_duration_s: f64,
    /// Number of steps in which damped least squares was active.
    pub dls_steps: usize,
    /// Number of control steps.
    pub steps: usize,
}

/// The report of one executed command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Position of the command in its program (0-based).
    pub index: usize,
    pub command: Command,
    /// Reference position before the command (m).
    pub from: Vector2<f64>,
    /// Target (m).
    pub target: Vector2<f64>,
    pub stats: SegmentStats,
}

/// One command of a program: executed, or refused (the arm then held still for a period).
#[derive(Debug)]
pub enum StepOutcome {
    Executed(StepReport),
    Refused {
        index: usize,
        command: Command,
        /// Why ([`ArmError::CommandRefused`] or a non-finite target).
        error: ArmError,
        /// What the arm did while holding still for one command period.
        hold: SegmentStats,
    },
}

/// The result of [`ArmSim::run_program`].
#[derive(Debug)]
pub struct ProgramReport {
    /// One outcome per command that ran (all of them unless the program was stopped).
    pub outcomes: Vec<StepOutcome>,
    /// The safety stop that ended the program early, if any.
    pub stopped: Option<ArmError>,
}

impl ProgramReport {
    /// The executed steps' reports.
    pub fn executed(&self) -> impl Iterator<Item = &StepReport> {
        self.outcomes.iter().filter_map(|o| match o {
            StepOutcome::Executed(r) => Some(r),
            StepOutcome::Refused { .. } => None,
        })
    }
}

impl StepOutcome {
    /// Position of the command in its program (0-based).
    pub fn index(&self) -> usize {
        match self {
            StepOutcome::Executed(r) => r.index,
            StepOutcome::Refused { index, .. } => *index,
        }
    }

    pub fn command(&self) -> Command {
        match self {
            StepOutcome::Executed(r) => r.command,
            StepOutcome::Refused { command, .. } => *command,
        }
    }

    /// The statistics of the command's period (the hold, for a refused command).
    pub fn stats(&self) -> &SegmentStats {
        match self {
            StepOutcome::Executed(r) => &r.stats,
            StepOutcome::Refused { hold, .. } => hold,
        }
    }
}

/// A simulated arm under inverse-dynamics task-space control.
#[derive(Debug, Clone)]
pub struct ArmSim {
    plant: ArmModel,
    controller: TaskSpaceController,
    workspace: Workspace,
    settings: SimSettings,
    elbow: Elbow,
    state: ArmState,
    /// Sines and cosines of `state.q`, and the pen position, kept with the state.
    trig: Trig,
    pen: Vector2<f64>,
    /// Steps since `trig` was last evaluated with libm rather than by the addition theorems.
    steps_since_trig_anchor: u32,
    steps_done: u64,
    transition: Transition,
    trace: PenTrace,
    samples: Vec<Sample>,
    /// The joint angles at time 0.
    start_q: Vector2<f64>,
}

/// Steps after which the cached sines and cosines are evaluated afresh with libm.
const TRIG_ANCHOR_STEPS: u32 = 32;

fn finite2(what: &'static str, v: &Vector2<f64>) -> Result<(), ArmError> {
    if v[0].is_finite() && v[1].is_finite() {
        Ok(())
    } else {
        Err(ArmError::NonFinite {
            what,
            value: vec![v[0], v[1]],
        })
    }
}

impl ArmSim {
    /// Builds a simulation from a configuration.
    pub fn from_config(config: &ArmConfig) -> Result<Self, ArmError> {
        Self::new(config.build()?)
    }

    /// Builds a simulation with the pen at rest at `setup.start`.
    pub fn new(setup: ArmSetup) -> Result<Self, ArmError> {
        setup.settings.validate()?;
        finite2("start position", &setup.start)?;
        let q = setup
            .workspace
            .check_point(&setup.plant, &setup.start, setup.elbow)
            .map_err(|reason| ConfigError::Start {
                start: (setup.start[0], setup.start[1]),
                reason,
            })?;
        let mut trace = PenTrace::new(setup.settings.trace_spacing_m);
        trace.push(0.0, setup.start);
        let trig = Trig::new(&q);
        Ok(Self {
            trig,
            pen: setup.plant.forward_kinematics_t(&trig),
            steps_since_trig_anchor: 0,
            plant: setup.plant,
            controller: setup.controller,
            workspace: setup.workspace,
            settings: setup.settings,
            elbow: setup.elbow,
            state: ArmState::at_rest(q),
            steps_done: 0,
            transition: Transition::hold(setup.start),
            trace,
            samples: Vec::new(),
            start_q: q,
        })
    }

    /// The joint angles at time 0 (kept whether or not steps are recorded).
    pub fn start_q(&self) -> Vector2<f64> {
        self.start_q
    }

    /// Replaces the mechanical state (e.g. to start off the reference). Rejects non-finite
    /// states and states outside the joint limits.
    pub fn set_state(&mut self, state: ArmState) -> Result<(), ArmError> {
        if !state.is_finite() {
            return Err(ArmError::NonFinite {
                what: "arm state",
                value: state.q.iter().chain(state.qd.iter()).copied().collect(),
            });
        }
        let trig = Trig::new(&state.q);
        let pen = self.plant.forward_kinematics_t(&trig);
        self.check_safety(&state, &pen)?;
        if self.steps_done == 0 {
            self.start_q = state.q;
        }
        self.state = state;
        self.trig = trig;
        self.pen = pen;
        self.steps_since_trig_anchor = 0;
        Ok(())
    }

    /// Turns per-step recording on or off (off for benchmarks and long runs).
    pub fn set_recording(&mut self, on: bool) {
        self.settings.record_samples = on;
    }

    /// The simulated (true) arm.
    pub fn plant(&self) -> &ArmModel {
        &self.plant
    }
    /// The controller, with its own nominal model.
    pub fn controller(&self) -> &TaskSpaceController {
        &self.controller
    }
    /// The board and reachability limits commands are checked against.
    pub fn workspace(&self) -> &Workspace {
        &self.workspace
    }
    /// The simulation settings.
    pub fn settings(&self) -> &SimSettings {
        &self.settings
    }
    /// The elbow configuration targets are checked with.
    pub fn elbow(&self) -> Elbow {
        self.elbow
    }
    /// The current joint angles (rad) and rates (rad/s).
    pub fn state(&self) -> &ArmState {
        &self.state
    }
    /// Simulation time (s).
    pub fn time_s(&self) -> f64 {
        self.steps_done as f64 * self.settings.dt_s
    }
    /// Current pen position (m).
    pub fn pen(&self) -> Vector2<f64> {
        self.pen
    }
    /// The current transition of the reference.
    pub fn transition(&self) -> &Transition {
        &self.transition
    }
    /// The reference target the arm is heading for or holding (m).
    pub fn target(&self) -> Vector2<f64> {
        self.transition.to
    }
    /// The reference at the current time.
    pub fn reference(&self) -> ReferenceSample {
        self.transition.sample(self.time_s())
    }
    /// The pen's trace so far.
    pub fn trace(&self) -> &PenTrace {
        &self.trace
    }
    /// Every recorded control step (empty when recording is off).
    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }

    /// The target a command would set, after all checks, without changing anything.
    pub fn plan(&self, command: Command) -> Result<Vector2<f64>, ArmError> {
        let from = self.transition.to;
        let target = command.apply(&from, self.settings.step_m);
        let refuse = |reason| ArmError::CommandRefused {
            command,
            reason,
            target: (target[0], target[1]),
        };
        finite2("command target", &target)?;
        let remaining = self.transition.end_time_s() - self.time_s();
        if remaining > 1e-9 {
            return Err(refuse(crate::error::RefusalReason::TransitionInProgress {
                remaining_s: remaining,
            }));
        }
        self.workspace
            .check_path(&self.plant, &from, &target, self.elbow)
            .map_err(refuse)?;
        Ok(target)
    }

    /// Starts the transition for `command` now. If refused, nothing changes: the reference
    /// keeps its previous target, so the arm holds still.
    pub fn issue(&mut self, command: Command) -> Result<Vector2<f64>, ArmError> {
        let target = self.plan(command)?;
        self.start_transition(target);
        Ok(target)
    }

    /// Starts a transition to an explicit target (m), with the same checks as a command.
    pub fn issue_target(&mut self, target: Vector2<f64>) -> Result<(), ArmError> {
        finite2("target", &target)?;
        let refuse = |reason| ArmError::TargetRefused {
            reason,
            target: (target[0], target[1]),
        };
        let remaining = self.transition.end_time_s() - self.time_s();
        if remaining > 1e-9 {
            return Err(refuse(crate::error::RefusalReason::TransitionInProgress {
                remaining_s: remaining,
            }));
        }
        self.workspace
            .check_path(&self.plant, &self.transition.to, &target, self.elbow)
            .map_err(refuse)?;
        self.start_transition(target);
        Ok(())
    }

    fn start_transition(&mut self, target: Vector2<f64>) {
        self.transition = Transition {
            from: self.transition.to,
            to: target,
            t0_s: self.time_s(),
            kind: self.settings.transition,
        };
    }

    fn check_safety(&self, s: &ArmState, pen: &Vector2<f64>) -> Result<(), ArmError> {
        let t_s = self.time_s();
        if let Some((joint, angle_rad)) = self.plant.check_joint_limits(&s.q) {
            let l = &self.plant.links()[joint];
            return Err(ArmError::JointLimitViolated {
                t_s,
                joint: joint + 1,
                angle_rad,
                min_rad: l.joint_min_rad,
                max_rad: l.joint_max_rad,
            });
        }
        let excess_m = self.workspace.board.excess_m(pen);
        if excess_m > self.settings.board_tolerance_m {
            return Err(ArmError::PenLeftBoard {
                t_s,
                pen: (pen[0], pen[1]),
                excess_m,
            });
        }
        Ok(())
    }

    /// Advances one control period `dt`. On any error the state is left as it was.
    pub fn step(&mut self) -> Result<StepInfo, ArmError> {
        let t = self.time_s();
        let dt = self.settings.dt_s;
        let r = self.transition.sample(t);
        let (next, info) = match self.settings.control_update {
            ControlUpdate::ZeroOrderHold => {
                let out = self.controller.compute_t(t, &self.state, &self.trig, &r)?;
                let (u, saturated) = self.plant.saturate(&out.u);
                let next = rk4_step_trig(&self.plant, &self.state, &self.trig, t, dt, |_, _, _| u);
                (
                    next,
                    StepInfo {
                        tracking_error_m: out.e.norm(),
                        u_requested: out.u,
                        u_applied: u,
                        saturated,
                        dls_active: out.dls_active,
                    },
                )
            }
            ControlUpdate::Continuous => {
                let (plant, controller, transition) =
                    (&self.plant, &self.controller, &self.transition);
                let mut error = None;
                let mut first: Option<StepInfo> = None;
                let mut saturated = [false; 2];
                let mut dls_active = false;
                let next = rk4_step_trig(plant, &self.state, &self.trig, t, dt, |ts, s, trig| {
                    match controller.compute_t(ts, s, trig, &transition.sample(ts)) {
                        Ok(out) => {
                            let (u, sat) = plant.saturate(&out.u);
                            saturated[0] |= sat[0];
                            saturated[1] |= sat[1];
                            dls_active |= out.dls_active;
                            first.get_or_insert(StepInfo {
                                tracking_error_m: out.e.norm(),
                                u_requested: out.u,
                                u_applied: u,
                                saturated: sat,
                                dls_active: out.dls_active,
                            });
                            u
                        }
                        Err(e) => {
                            error.get_or_insert(e);
                            Vector2::zeros()
                        }
                    }
                });
                if let Some(e) = error {
                    return Err(e);
                }
                let mut info = first.expect("RK4 evaluates the torque at least once");
                info.saturated = saturated;
                info.dls_active = dls_active;
                (next, info)
            }
        };
        if !next.is_finite() {
            return Err(ArmError::NonFiniteState { t_s: t + dt });
        }
        // The next configuration's sines and cosines follow from the current ones by the addition
        // theorems; every TRIG_ANCHOR_STEPS steps they are evaluated afresh so that rounding
        // (about 1e-16 per step) cannot accumulate.
        let anchor = self.steps_since_trig_anchor + 1 >= TRIG_ANCHOR_STEPS;
        let next_trig = if anchor {
            Trig::new(&next.q)
        } else {
            self.trig.shifted(&(next.q - self.state.q))
        };
        let next_pen = self.plant.forward_kinematics_t(&next_trig);
        self.check_safety(&next, &next_pen)?;
        if self.settings.record_samples {
            self.samples.push(Sample {
                t_s: t,
                q: self.state.q,
                qd: self.state.qd,
                u: info.u_applied,
                u_requested: info.u_requested,
                p: self.pen,
                p_d: r.p,
                saturated: info.saturated,
                dls_active: info.dls_active,
            });
        }
        self.state = next;
        self.trig = next_trig;
        self.pen = next_pen;
        self.steps_since_trig_anchor = if anchor {
            0
        } else {
            self.steps_since_trig_anchor + 1
        };
        self.steps_done += 1;
        self.trace.push(self.time_s(), next_pen);
        Ok(info)
    }

    /// Runs for `duration_s` (rounded to whole steps) and measures against the current target.
    pub fn run_for(&mut self, duration_s: f64) -> Result<SegmentStats, ArmError> {
        if !(duration_s.is_finite() && duration_s >= 0.0) {
            return Err(ArmError::InvalidDuration {
                what: "run duration",
                value: duration_s,
            });
        }
        let dt = self.settings.dt_s;
        let n = (duration_s / dt).round() as usize;
        let t_start_s = self.time_s();
        let target = self.transition.to;
        let tol2 = self.settings.settle_tolerance_m.powi(2);
        let mut last_violation: Option<f64> = None;
        if (self.pen - target).norm_squared() > tol2 {
            last_violation = Some(t_start_s);
        }
        let mut stats = SegmentStats {
            t_start_s,
            t_end_s: t_start_s,
            target,
            settle_time_s: None,
            final_error_m: 0.0,
            max_tracking_error_m: 0.0,
            max_abs_torque_n_m: [0.0; 2],
            saturated_steps: 0,
            saturated_duration_s: 0.0,
            dls_steps: 0,
            steps: n,
        };
        for _ in 0..n {
            let info = self.step()?;
            stats.max_tracking_error_m = stats.max_tracking_error_m.max(info.tracking_error_m);
            for i in 0..2 {
                stats.max_abs_torque_n_m[i] =
                    stats.max_abs_torque_n_m[i].max(info.u_applied[i].abs());
            }
            if info.saturated[0] || info.saturated[1] {
                stats.saturated_steps += 1;
            }
            stats.dls_steps += usize::from(info.dls_active);
            if (self.pen - target).norm_squared() > tol2 {
                last_violation = Some(self.time_s());
            }
        }
        let t_end_s = self.time_s();
        let pen = self.pen();
        self.trace.push_exact(t_end_s, pen);
        stats.t_end_s = t_end_s;
        stats.final_error_m = (pen - target).norm();
        stats.saturated_duration_s = stats.saturated_steps as f64 * dt;
        stats.settle_time_s = match last_violation {
            None => Some(0.0),
            Some(t) if n > 0 && t < t_end_s => Some(t + dt - t_start_s),
            Some(_) => None,
        };
        Ok(stats)
    }

    /// Holds the current target for `duration_s`.
    pub fn hold(&mut self, duration_s: f64) -> Result<SegmentStats, ArmError> {
        self.run_for(duration_s)
    }

    /// Issues `command` and runs one command period. A refused command returns the refusal
    /// and leaves time, state and reference untouched.
    pub fn execute(&mut self, index: usize, command: Command) -> Result<StepReport, ArmError> {
        let from = self.transition.to;
        let target = self.issue(command)?;
        let stats = self.run_for(self.settings.command_period_s)?;
        Ok(StepReport {
            index,
            command,
            from,
            target,
            stats,
        })
    }

    /// Runs a sequence of commands, one command period each. Refused commands are reported and
    /// the arm holds still for their period. A safety stop (non-finite values, joint limits, pen
    /// off the board) ends the program early; it is returned in [`ProgramReport::stopped`] along
    /// with the outcomes up to that point, and the simulation keeps its last safe state.
    pub fn run_program(&mut self, commands: &[Command]) -> ProgramReport {
        let mut outcomes = Vec::with_capacity(commands.len());
        for (index, &command) in commands.iter().enumerate() {
            let from = self.transition.to;
            let outcome = match self.issue(command) {
                Ok(target) => self.run_for(self.settings.command_period_s).map(|stats| {
                    StepOutcome::Executed(StepReport {
                        index,
                        command,
                        from,
                        target,
                        stats,
                    })
                }),
                Err(error) => {
                    self.hold(self.settings.command_period_s)
                        .map(|hold| StepOutcome::Refused {
                            index,
                            command,
                            error,
                            hold,
                        })
                }
            };
            match outcome {
                Ok(o) => outcomes.push(o),
                Err(stop) => {
                    return ProgramReport {
                        outcomes,
                        stopped: Some(stop),
                    }
                }
            }
        }
        ProgramReport {
            outcomes,
            stopped: None,
        }
    }
}
