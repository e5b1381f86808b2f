//! Unfitted settings: the TOML-configurable description of the arm, board, controller and
//! simulation. [`ArmConfig::build`] validates them into the runtime types ([`ArmModel`],
//! [`Board`], [`TaskSpaceController`], [`SimSettings`]); nothing at run time reads these structs.
//! The links' sections are [`LinkParams`] as the model takes them, checked when it is built.
//!
//! Every section is optional in TOML and missing sections take the defaults below (a desk-sized
//! arm, shoulder at the origin, drawing on a 30 cm × 30 cm board to its right). The physical
//! sections `[base]`, `[link1]`, `[link2]` and `[board]` must be complete when given (half a link
//! is more likely a mistake than a wish for defaults); in the other sections every field is
//! optional. Unknown fields are errors, so a misspelt key never silently falls back to a default.
//! `oddball arm --print-config` writes the full default file.
//!
//! ```toml
//! gravity_m_s2 = 9.81
//! [board]
//! x_min_m = 0.20
//! x_max_m = 0.50
//! z_min_m = -0.10
//! z_max_m = 0.20
//! [controller]
//! kp_per_s2 = [625.0, 625.0]
//! kd_per_s = [50.0, 50.0]
//! [reference]
//! transition = "min-jerk"   # or "step"
//! step_m = 0.02
//! ```

use std::path::Path;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::control::{Gains, TaskSpaceController};
use crate::error::ConfigError;
use crate::model::{ArmModel, Elbow, LinkParams};
use crate::reference::TransitionKind;
use crate::settings::{ControlUpdate, SimSettings};
use crate::workspace::{Board, Workspace};

/// The `[link1]` and `[link2]` sections: a [`LinkParams`] as it is (validated by
/// [`ArmConfig::build`]).
pub type LinkConfig = LinkParams;

impl LinkParams {
    /// Upper arm: 30 cm aluminium-tube-like link of 1.2 kg (motor mass included), slender-rod
    /// inertia `m l²/12`.
    pub fn default_link1() -> Self {
        Self {
            length_m: 0.30,
            mass_kg: 1.2,
            com_m: 0.15,
            inertia_kg_m2: 1.2 * 0.30 * 0.30 / 12.0,
            friction_n_m_s_per_rad: 0.05,
            torque_limit_n_m: 15.0,
            joint_min_rad: -std::f64::consts::FRAC_PI_2,
            joint_max_rad: 3.0 * std::f64::consts::FRAC_PI_4,
        }
    }

    /// Forearm with the pen: 25 cm, 0.8 kg, slender-rod inertia.
    pub fn default_link2() -> Self {
        Self {
            length_m: 0.25,
            mass_kg: 0.8,
            com_m: 0.125,
            inertia_kg_m2: 0.8 * 0.25 * 0.25 / 12.0,
            friction_n_m_s_per_rad: 0.03,
            torque_limit_n_m: 6.0,
            joint_min_rad: -2.8,
            joint_max_rad: 2.8,
        }
    }
}

/// A point (x, z) in metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointConfig {
    pub x_m: f64,
    pub z_m: f64,
}

/// The board rectangle (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoardConfig {
    pub x_min_m: f64,
    pub x_max_m: f64,
    pub z_min_m: f64,
    pub z_max_m: f64,
}

impl Default for BoardConfig {
    fn default() -> Self {
        Self {
            x_min_m: 0.20,
            x_max_m: 0.50,
            z_min_m: -0.10,
            z_max_m: 0.20,
        }
    }
}

/// Where the pen starts (at rest) and with which elbow configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StartConfig {
    pub x_m: f64,
    pub z_m: f64,
    pub elbow: Elbow,
}

impl Default for StartConfig {
    fn default() -> Self {
        Self {
            x_m: 0.35,
            z_m: 0.05,
            elbow: Elbow::Up,
        }
    }
}

/// Task-space PD gains and damped-least-squares settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControllerConfig {
    /// Diagonal of K_P (1/s²) for x and z.
    pub kp_per_s2: [f64; 2],
    /// Diagonal of K_D (1/s) for x and z.
    pub kd_per_s: [f64; 2],
    /// |sin θ2| below which damped least squares replaces J_A⁻¹.
    pub dls_threshold: f64,
    /// Damping λ (m) at the singularity.
    pub dls_max_damping_m: f64,
}

impl Default for ControllerConfig {
    /// Critically damped, natural frequency 25 rad/s: a 2 cm step settles to 0.1 mm in ≈ 0.3 s.
    fn default() -> Self {
        let g = Gains::critically_damped(25.0);
        Self {
            kp_per_s2: [g.kp_per_s2[0], g.kp_per_s2[1]],
            kd_per_s: [g.kd_per_s[0], g.kd_per_s[1]],
            dls_threshold: g.dls_threshold,
            dls_max_damping_m: g.dls_max_damping_m,
        }
    }
}

/// Transition shape between targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TransitionConfig {
    MinJerk,
    Step,
}

/// How commands become a reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReferenceConfig {
    /// Step h per command (m).
    pub step_m: f64,
    pub transition: TransitionConfig,
    /// Duration of a minimum-jerk transition (s).
    pub transition_s: f64,
    /// Time given to each command before the next one (s).
    pub command_period_s: f64,
}

impl Default for ReferenceConfig {
    fn default() -> Self {
        Self {
            step_m: 0.02,
            transition: TransitionConfig::MinJerk,
            transition_s: 0.4,
            command_period_s: 0.8,
        }
    }
}

/// Workspace restrictions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorkspaceConfig {
    /// Smallest admissible |sin θ2| on a commanded path.
    pub min_sin_elbow: f64,
    /// How far (m) the pen may stray off the board before the simulation stops as unsafe.
    pub board_tolerance_m: f64,
}

impl Default for WorkspaceConfig {
    fn default() -> Self {
        Self {
            min_sin_elbow: 0.1,
            board_tolerance_m: 1e-3,
        }
    }
}

/// Integration and reporting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    /// RK4 step and control period (s).
    pub dt_s: f64,
    /// Error (m) within which a step counts as settled.
    pub settle_tolerance_m: f64,
    pub control_update: ControlUpdate,
    /// Minimum spacing (m) of stored pen-trace vertices.
    pub trace_spacing_m: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            dt_s: 1e-3,
            settle_tolerance_m: 1e-4,
            control_update: ControlUpdate::ZeroOrderHold,
            trace_spacing_m: 1e-5,
        }
    }
}

/// The whole configuration (unfitted settings).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ArmConfig {
    /// Magnitude of gravity along −z (m/s²).
    pub gravity_m_s2: f64,
    /// Shoulder position (m).
    pub base: PointConfig,
    pub link1: LinkParams,
    pub link2: LinkParams,
    pub board: BoardConfig,
    pub start: StartConfig,
    pub controller: ControllerConfig,
    pub reference: ReferenceConfig,
    pub workspace: WorkspaceConfig,
    pub sim: SimConfig,
}

impl Default for ArmConfig {
    fn default() -> Self {
        Self {
            gravity_m_s2: 9.81,
            base: PointConfig { x_m: 0.0, z_m: 0.0 },
            link1: LinkParams::default_link1(),
            link2: LinkParams::default_link2(),
            board: BoardConfig::default(),
            start: StartConfig::default(),
            controller: ControllerConfig::default(),
            reference: ReferenceConfig::default(),
            workspace: WorkspaceConfig::default(),
            sim: SimConfig::default(),
        }
    }
}

/// Validated runtime parts built from an [`ArmConfig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmSetup {
    /// The simulated (true) arm.
    pub plant: ArmModel,
    /// The controller, with its own nominal model (equal to the plant when built from a config).
    pub controller: TaskSpaceController,
    pub workspace: Workspace,
    /// Start pen position (m).
    pub start: Vector2<f64>,
    pub elbow: Elbow,
    pub settings: SimSettings,
}

impl ArmConfig {
    /// Parses TOML text; errors name the offending key and line.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        toml::from_str(text).map_err(|e| ConfigError::Parse {
            origin: None,
            message: e.to_string(),
        })
    }

    /// Reads and parses a TOML file.
    pub fn from_toml_path(path: &Path) -> Result<Self, ConfigError> {
        // A device, pipe or socket (or a link to one) has no end to bound what reading costs.
        if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
            return Err(ConfigError::Read {
                path: path.to_path_buf(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "not a regular file (a device, pipe or socket): refused",
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        toml::from_str(&text).map_err(|e| ConfigError::Parse {
            origin: Some(path.to_path_buf()),
            message: e.to_string(),
        })
    }

    /// Serialises to TOML (every field written out).
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).expect("ArmConfig contains only TOML-representable values")
    }

    /// The physical model described by this configuration.
    pub fn model(&self) -> Result<ArmModel, ConfigError> {
        ArmModel::new(
            self.link1,
            self.link2,
            self.gravity_m_s2,
            Vector2::new(self.base.x_m, self.base.z_m),
        )
    }

    /// Validates everything and builds the runtime parts.
    pub fn build(&self) -> Result<ArmSetup, ConfigError> {
        let plant = self.model()?;
        let c = &self.controller;
        let gains = Gains {
            kp_per_s2: Vector2::from(c.kp_per_s2),
            kd_per_s: Vector2::from(c.kd_per_s),
            dls_threshold: c.dls_threshold,
            dls_max_damping_m: c.dls_max_damping_m,
        };
        let controller = TaskSpaceController::new(plant, gains)?;
        let b = &self.board;
        let board = Board::new(b.x_min_m, b.x_max_m, b.z_min_m, b.z_max_m)?;
        let w = &self.workspace;
        if !(w.min_sin_elbow.is_finite() && (0.0..1.0).contains(&w.min_sin_elbow)) {
            return Err(ConfigError::Invalid {
                field: "workspace.min_sin_elbow",
                value: w.min_sin_elbow,
                reason: "must lie in [0, 1)",
            });
        }
        let r = &self.reference;
        let transition = match r.transition {
            TransitionConfig::Step => TransitionKind::Step,
            TransitionConfig::MinJerk => TransitionKind::MinimumJerk {
                duration_s: r.transition_s,
            },
        };
        let settings = SimSettings {
            dt_s: self.sim.dt_s,
            transition,
            step_m: r.step_m,
            command_period_s: r.command_period_s,
            settle_tolerance_m: self.sim.settle_tolerance_m,
            board_tolerance_m: w.board_tolerance_m,
            control_update: self.sim.control_update,
            trace_spacing_m: self.sim.trace_spacing_m,
            record_samples: true,
        };
        settings.validate()?;
        let workspace = Workspace {
            board,
            min_sin_elbow: w.min_sin_elbow,
        };
        let start = Vector2::new(self.start.x_m, self.start.z_m);
        for (field, v) in [("start.x_m", start[0]), ("start.z_m", start[1])] {
            if !v.is_finite() {
                return Err(ConfigError::Invalid {
                    field,
                    value: v,
                    reason: "must be finite",
                });
            }
        }
        workspace
            .check_point(&plant, &start, self.start.elbow)
            .map_err(|reason| ConfigError::Start {
                start: (start[0], start[1]),
                reason,
            })?;
        Ok(ArmSetup {
            plant,
            controller,
            workspace,
            start,
            elbow: self.start.elbow,
            settings,
        })
    }
}
