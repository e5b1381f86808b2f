//! Error types. Every variant carries the facts needed to act on it: the offending field, value,
//! target point (metres, board coordinates) or simulation time (seconds).

use std::path::PathBuf;

use crate::reference::Command;

/// A problem with an arm configuration (TOML text or programmatic settings).
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The configuration file could not be read.
    #[error("cannot read arm configuration {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The TOML text is malformed, has a value of the wrong type, or names an unknown field.
    /// `message` is the TOML parser's report, which names the key and the line.
    #[error("cannot parse arm configuration{}: {message}", origin.as_ref().map(|p| format!(" {}", p.display())).unwrap_or_default())]
    Parse {
        origin: Option<PathBuf>,
        message: String,
    },
    /// The start position cannot be used (off the board or outside the workspace).
    #[error("invalid arm configuration: start ({:.4}, {:.4}) m is unusable: {reason}", start.0, start.1)]
    Start {
        start: (f64, f64),
        reason: RefusalReason,
    },
    /// A field has a value outside its admissible range.
    #[error("invalid arm configuration: `{field}` = {value}: {reason}")]
    Invalid {
        /// Dotted TOML path of the field, e.g. `link1.mass_kg`.
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
}

/// Why a requested target was refused. The arm keeps its previous target and holds still.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefusalReason {
    /// The target lies outside the drawing board's rectangle.
    #[error("outside the board x ∈ [{x_min_m}, {x_max_m}] m, z ∈ [{z_min_m}, {z_max_m}] m")]
    OffBoard {
        x_min_m: f64,
        x_max_m: f64,
        z_min_m: f64,
        z_max_m: f64,
    },
    /// A point of the straight path to the target is outside the annulus the arm can reach.
    #[error(
        "point ({:.4}, {:.4}) m on the path is {distance_m:.4} m from the shoulder, outside the reachable annulus [{min_m:.4}, {max_m:.4}] m",
        at.0, at.1
    )]
    Unreachable {
        at: (f64, f64),
        distance_m: f64,
        min_m: f64,
        max_m: f64,
    },
    /// Reaching a point of the path would need a joint angle outside the joint's limits
    /// (with the arm's current elbow configuration).
    #[error(
        "point ({:.4}, {:.4}) m on the path needs joint {joint} at {angle_rad:.4} rad, outside its limits [{min_rad:.4}, {max_rad:.4}] rad",
        at.0, at.1
    )]
    JointLimit {
        at: (f64, f64),
        joint: usize,
        angle_rad: f64,
        min_rad: f64,
        max_rad: f64,
    },
    /// A point of the path is too close to the stretched/folded singularity (|sin θ2| too small).
    #[error(
        "point ({:.4}, {:.4}) m on the path is too close to a singularity: |sin θ2| = {sin_elbow:.4} < {min:.4}",
        at.0, at.1
    )]
    NearSingularity {
        at: (f64, f64),
        sin_elbow: f64,
        min: f64,
    },
    /// The previous transition has not finished; a new one would make the reference jump.
    #[error("the previous transition is still running for {remaining_s:.3} s")]
    TransitionInProgress { remaining_s: f64 },
}

/// Errors of the arm simulation and controller.
#[derive(Debug, thiserror::Error)]
pub enum ArmError {
    /// The settings handed to the simulation are invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A direction command was refused; the arm holds its previous target.
    #[error("command `{command}` to ({:.4}, {:.4}) m refused: {reason}", target.0, target.1)]
    CommandRefused {
        command: Command,
        reason: RefusalReason,
        /// The target the command would have set (x, z) in metres.
        target: (f64, f64),
    },
    /// An explicit target point was refused; the arm holds its previous target.
    #[error("target ({:.4}, {:.4}) m refused: {reason}", target.0, target.1)]
    TargetRefused {
        reason: RefusalReason,
        target: (f64, f64),
    },
    /// A reference, target, state or parameter handed to the arm was NaN or infinite.
    #[error("non-finite {what} rejected: {value:?}")]
    NonFinite { what: &'static str, value: Vec<f64> },
    /// The controller produced a non-finite torque (never sent to the actuators).
    #[error("controller produced a non-finite torque {torque_n_m:?} at t = {t_s} s")]
    NonFiniteTorque { t_s: f64, torque_n_m: [f64; 2] },
    /// The integrated state became non-finite; the simulation stopped before using it.
    #[error("simulation state became non-finite at t = {t_s} s")]
    NonFiniteState { t_s: f64 },
    /// The arm left its joint range during the simulation; the simulation stopped.
    #[error("joint {joint} at {angle_rad:.4} rad left its limits [{min_rad:.4}, {max_rad:.4}] rad at t = {t_s} s")]
    JointLimitViolated {
        t_s: f64,
        joint: usize,
        angle_rad: f64,
        min_rad: f64,
        max_rad: f64,
    },
    /// The pen left the board by more than the configured tolerance; the simulation stopped.
    #[error("pen at ({:.4}, {:.4}) m left the board by {excess_m:.4} m at t = {t_s} s", pen.0, pen.1)]
    PenLeftBoard {
        t_s: f64,
        pen: (f64, f64),
        excess_m: f64,
    },
    /// A start position for inverse kinematics cannot be reached.
    #[error("no inverse-kinematics solution for ({:.4}, {:.4}) m: {reason}", target.0, target.1)]
    NoIkSolution {
        target: (f64, f64),
        reason: RefusalReason,
    },
    /// A duration or time step was not positive and finite.
    #[error("invalid {what}: {value} s (must be positive and finite)")]
    InvalidDuration { what: &'static str, value: f64 },
}
