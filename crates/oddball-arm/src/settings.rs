//! Validated runtime settings of the simulation ([`SimSettings`]), built from the unfitted
//! [`ArmConfig`](crate::ArmConfig) by [`ArmConfig::build`](crate::ArmConfig::build) and read by
//! [`ArmSim`](crate::ArmSim).

use serde::{Deserialize, Serialize};

use crate::error::ConfigError;
use crate::reference::TransitionKind;

/// When the control law is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControlUpdate {
    /// Once per step; the torque is held over the step (a digital controller at 1/dt Hz).
    ZeroOrderHold,
    /// At every RK4 stage (the continuous-time law, integrated to RK4 accuracy).
    Continuous,
}

/// Validated runtime settings of the simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimSettings {
    /// Integration step and control period (s).
    pub dt_s: f64,
    /// Shape of each commanded transition.
    pub transition: TransitionKind,
    /// Step h per command (m).
    pub step_m: f64,
    /// Time each command runs before the next (s).
    pub command_period_s: f64,
    /// Distance to the target (m) within which a step counts as settled.
    pub settle_tolerance_m: f64,
    /// Distance (m) the pen may stray off the board before the simulation stops as unsafe.
    pub board_tolerance_m: f64,
    pub control_update: ControlUpdate,
    /// Minimum spacing of stored pen-trace vertices (m).
    pub trace_spacing_m: f64,
    /// Whether every step is stored in [`ArmSim::samples`](crate::ArmSim::samples).
    pub record_samples: bool,
}

impl SimSettings {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let bad = |field: &'static str, value: f64, reason: &'static str| {
            Err(ConfigError::Invalid {
                field,
                value,
                reason,
            })
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(pos(self.dt_s) && self.dt_s <= 0.1) {
            return bad("sim.dt_s", self.dt_s, "must be positive and at most 0.1 s");
        }
        if !pos(self.step_m) {
            return bad(
                "reference.step_m",
                self.step_m,
                "must be positive and finite",
            );
        }
        if !pos(self.command_period_s) {
            return bad(
                "reference.command_period_s",
                self.command_period_s,
                "must be positive and finite",
            );
        }
        if let TransitionKind::MinimumJerk { duration_s } = self.transition {
            if !pos(duration_s) {
                return bad(
                    "reference.transition_s",
                    duration_s,
                    "must be positive and finite",
                );
            }
            if duration_s > self.command_period_s {
                return bad(
                    "reference.transition_s",
                    duration_s,
                    "must not exceed reference.command_period_s",
                );
            }
        }
        if !pos(self.settle_tolerance_m) {
            return bad(
                "sim.settle_tolerance_m",
                self.settle_tolerance_m,
                "must be positive and finite",
            );
        }
        if !(self.board_tolerance_m.is_finite() && self.board_tolerance_m >= 0.0) {
            return bad(
                "workspace.board_tolerance_m",
                self.board_tolerance_m,
                "must be non-negative and finite",
            );
        }
        if !(self.trace_spacing_m.is_finite() && self.trace_spacing_m >= 0.0) {
            return bad(
                "sim.trace_spacing_m",
                self.trace_spacing_m,
                "must be non-negative and finite",
            );
        }
        Ok(())
    }
}
