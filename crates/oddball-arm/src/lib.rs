//! `oddball-arm`: the robot arm the P300 interface drives — a planar two-link arm in the vertical
//! x–z plane (gravity along −z) whose end-effector carries a pen on a vertical board.
//!
//! * [`config`] — unfitted, TOML-configurable settings ([`ArmConfig`]) with a desk-sized default;
//!   [`ArmConfig::build`] validates them into runtime types.
//! * [`model`] — [`ArmModel`]: forward kinematics, analytical Jacobian `J_A` and `J̇_A`, inverse
//!   kinematics (elbow up/down), `M(θ)`, `C(θ, θ̇)`, `g(θ)`, friction, forward and inverse
//!   dynamics, energy.
//! * [`integrate`] — fixed-step RK4.
//! * [`control`] — [`TaskSpaceController`]: inverse-dynamics linearisation with the task-space
//!   PD law of the paper, damped least squares near singularities.
//! * [`reference`](mod@reference) — direction [`Command`]s and minimum-jerk / step transitions of `p_d`.
//! * [`workspace`] — the [`Board`] and the reachability checks that refuse unsafe commands.
//! * [`trace`] — the pen's timestamped polyline.
//! * [`settings`] — [`SimSettings`]: the validated runtime settings of the simulation.
//! * [`sim`] — [`ArmSim`]: the closed loop with actuator saturation, safety stops and per-step
//!   reports.
//!
//! # What is written from scratch, and why
//! nalgebra supplies the fixed-size vectors and matrices. Everything else — the closed-form
//! 2-link kinematics and dynamics, the RK4 step, the controller and the reference generator —
//! is written here: the closed forms are a few lines each, allocation-free and much faster than a
//! general multibody library (the benchmark runs the closed loop at millions of times real
//! time), the controller must match the paper's law exactly, and keeping the code explicit lets
//! the tests check it against an independent symbolic derivation
//! (`tools/golden/arm/make_golden.py`, sympy Euler–Lagrange) to 1e-9.
//!
//! # Units
//! Lengths in metres, angles in radians, time in seconds, torques in N·m, masses in kg,
//! inertias in kg·m². Field names carry their unit (`length_m`, `dt_s`, `torque_limit_n_m`).
//!
//! # Safety
//! Non-finite references, targets and states are rejected with an error and never reach the
//! actuators; commands that would leave the board or the reachable workspace are refused with a
//! reason and the arm holds its previous target; torque saturation is applied by the actuator
//! model and counted in every [`SegmentStats`]; the simulation stops with an error if the arm
//! ever leaves its joint limits or the pen leaves the board.
//!
//! # Example
//! A command list as the CLI takes it, and where each command moves the pen's target:
//! ```
//! use oddball_arm::{parse_commands, Command, Vector2};
//!
//! let commands = parse_commands("up,right")?;
//! assert_eq!(commands, [Command::Up, Command::Right]);
//! let moved: Vector2<f64> = commands.iter().map(|c| c.direction()).sum();
//! assert_eq!(moved, Vector2::new(1.0, 1.0));
//! # Ok::<(), oddball_arm::UnknownCommand>(())
//! ```

pub mod config;
pub mod control;
pub mod error;
pub mod integrate;
pub mod model;
pub mod reference;
pub mod settings;
pub mod sim;
pub mod trace;
pub mod workspace;

pub use config::{ArmConfig, ArmSetup};
pub use control::{ControlOutput, Gains, TaskSpaceController};
pub use error::{ArmError, ConfigError, RefusalReason};
pub use integrate::{rk4_step, rk4_step_hold, rk4_step_trig, ArmState};
pub use model::{ArmModel, Elbow, LinkParams, Trig};
pub use reference::{
    parse_commands, planned_path, Command, ReferenceSample, Transition, TransitionKind,
    UnknownCommand,
};
pub use settings::{ControlUpdate, SimSettings};
pub use sim::{ArmSim, ProgramReport, Sample, SegmentStats, StepInfo, StepOutcome, StepReport};
pub use trace::{PenTrace, TracePoint};
pub use workspace::{Board, Workspace};

pub use nalgebra::{Matrix2, Vector2};
