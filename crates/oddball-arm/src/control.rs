//! The paper's controller: inverse-dynamics (computed-torque) linearisation with a task-space PD
//! law,
//!
//! ```text
//! u = M(θ) v + h(θ, θ̇),     h = C(θ, θ̇) θ̇ + g(θ) + B θ̇,
//! v = J_A(θ)⁻¹ (p̈_d + K_D ė + K_P e − J̇_A(θ, θ̇) θ̇),     e = p_d − p,  ė = ṗ_d − ṗ.
//! ```
//!
//! With an exact model and no saturation the closed loop is `ë + K_D ė + K_P e = 0` per axis.
//! Near a singularity `J_A⁻¹` is replaced by the damped least-squares inverse
//! `J_Aᵀ (J_A J_Aᵀ + λ² I)⁻¹` with a damping that grows smoothly from zero as the normalised
//! manipulability `|det J_A| / (l1 l2) = |sin θ2|` falls below a threshold (Nakamura–Hanafusa
//! style variable damping), so the exact inverse is used everywhere else.
//!
//! The controller returns the torque it *asks* for; clipping to the actuator limits is the
//! actuator's job (see [`ArmModel::saturate`]) and is reported by the simulation.

use nalgebra::{Matrix2, Vector2};

use crate::error::{ArmError, ConfigError};
use crate::integrate::ArmState;
use crate::model::{solve_spd2, ArmModel, Trig};
use crate::reference::ReferenceSample;

/// Validated controller settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    /// Diagonal of `K_P` (1/s²), per task axis (x, z).
    pub kp_per_s2: Vector2<f64>,
    /// Diagonal of `K_D` (1/s), per task axis (x, z).
    pub kd_per_s: Vector2<f64>,
    /// Normalised manipulability `|sin θ2|` below which damped least squares is used.
    pub dls_threshold: f64,
    /// Damping λ (m) of the damped least-squares inverse at the singularity itself.
    pub dls_max_damping_m: f64,
}

impl Gains {
    /// Critically damped gains with natural frequency `omega_rad_s` on both axes.
    pub fn critically_damped(omega_rad_s: f64) -> Self {
        Self {
            kp_per_s2: Vector2::repeat(omega_rad_s * omega_rad_s),
            kd_per_s: Vector2::repeat(2.0 * omega_rad_s),
            dls_threshold: 0.05,
            dls_max_damping_m: 0.02,
        }
    }

    /// Checks positivity and finiteness, naming the offending field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ConfigError::Invalid {
                    field,
                    value: v,
                    reason: "must be positive and finite (gains are diagonal positive definite)",
                })
            }
        };
        pos("controller.kp_per_s2[0]", self.kp_per_s2[0])?;
        pos("controller.kp_per_s2[1]", self.kp_per_s2[1])?;
        pos("controller.kd_per_s[0]", self.kd_per_s[0])?;
        pos("controller.kd_per_s[1]", self.kd_per_s[1])?;
        let t = self.dls_threshold;
        if !(t.is_finite() && (0.0..1.0).contains(&t)) {
            return Err(ConfigError::Invalid {
                field: "controller.dls_threshold",
                value: t,
                reason: "must lie in [0, 1)",
            });
        }
        let l = self.dls_max_damping_m;
        if !(l.is_finite() && l >= 0.0) {
            return Err(ConfigError::Invalid {
                field: "controller.dls_max_damping_m",
                value: l,
                reason: "must be non-negative and finite",
            });
        }
        if t > 0.0 && l == 0.0 {
            return Err(ConfigError::Invalid {
                field: "controller.dls_max_damping_m",
                value: l,
                reason: "must be positive when dls_threshold > 0",
            });
        }
        Ok(())
    }
}

/// What the controller computed at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlOutput {
    /// Torque asked of the actuators (N·m), before saturation.
    pub u: Vector2<f64>,
    /// Joint acceleration `v` the linearisation aims for (rad/s²).
    pub v: Vector2<f64>,
    /// Task-space position error `e = p_d − p` (m).
    pub e: Vector2<f64>,
    /// Task-space velocity error `ė = ṗ_d − ṗ` (m/s).
    pub e_dot: Vector2<f64>,
    /// Whether the damped least-squares inverse replaced `J_A⁻¹`.
    pub dls_active: bool,
}

/// Inverse-dynamics task-space controller with its own (nominal) model of the arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskSpaceController {
    model: ArmModel,
    gains: Gains,
    /// l1·l2 (m²): det J_A = l1 l2 sin θ2.
    l1l2: f64,
}

impl TaskSpaceController {
    /// A controller that linearises with `model` (which may differ from the plant) and `gains`.
    pub fn new(model: ArmModel, gains: Gains) -> Result<Self, ConfigError> {
        gains.validate()?;
        let l1l2 = model.links()[0].length_m * model.links()[1].length_m;
        Ok(Self { model, gains, l1l2 })
    }

    /// The controller's nominal model.
    pub fn model(&self) -> &ArmModel {
        &self.model
    }

    /// The controller's gains.
    pub fn gains(&self) -> &Gains {
        &self.gains
    }

    /// Solves `J v = a` with the exact inverse, or damped least squares when the normalised
    /// manipulability `w = |sin θ2|` is below the threshold.
    #[inline]
    fn solve_task(&self, s2: f64, j: &Matrix2<f64>, a: &Vector2<f64>) -> (Vector2<f64>, bool) {
        let w = s2.abs();
        let thr = self.gains.dls_threshold;
        if w >= thr {
            // det J_A = l1 l2 sin θ2, known before J_A itself is assembled.
            let inv_det = 1.0 / (self.l1l2 * s2);
            (
                Vector2::new(
                    (j[(1, 1)] * a[0] - j[(0, 1)] * a[1]) * inv_det,
                    (j[(0, 0)] * a[1] - j[(1, 0)] * a[0]) * inv_det,
                ),
                false,
            )
        } else {
            let r = w / thr;
            let lambda2 = self.gains.dls_max_damping_m.powi(2) * (1.0 - r * r);
            let jjt = j * j.transpose() + Matrix2::identity() * lambda2;
            (j.transpose() * solve_spd2(&jjt, a), true)
        }
    }

    /// The control law at state `s` for reference `r`, at time `t_s` (used in error reports).
    ///
    /// Fails with [`ArmError::NonFinite`] if the reference is not finite and with
    /// [`ArmError::NonFiniteTorque`] if the result is not, so no NaN can reach the actuators.
    pub fn compute(
        &self,
        t_s: f64,
        s: &ArmState,
        r: &ReferenceSample,
    ) -> Result<ControlOutput, ArmError> {
        self.compute_t(t_s, s, &Trig::new(&s.q), r)
    }

    /// [`TaskSpaceController::compute`] given the sines and cosines of `s.q`.
    #[inline]
    pub fn compute_t(
        &self,
        t_s: f64,
        s: &ArmState,
        trig: &Trig,
        r: &ReferenceSample,
    ) -> Result<ControlOutput, ArmError> {
        let values = [r.p[0], r.p[1], r.v[0], r.v[1], r.a[0], r.a[1]];
        if !values.iter().all(|x| x.is_finite()) {
            return Err(ArmError::NonFinite {
                what: "reference (p_d, ṗ_d, p̈_d)",
                value: values.to_vec(),
            });
        }
        let m = &self.model;
        let j = m.jacobian_t(trig);
        let p = m.forward_kinematics_t(trig);
        let pd = j * s.qd;
        let e = r.p - p;
        let e_dot = r.v - pd;
        let a = r.a
            + self.gains.kd_per_s.component_mul(&e_dot)
            + self.gains.kp_per_s2.component_mul(&e)
            - m.jacobian_dot_t(trig, &s.qd) * s.qd;
        let (v, dls_active) = self.solve_task(trig.s2, &j, &a);
        let u = m.mass_matrix_t(trig) * v + m.bias_torque_t(trig, &s.qd);
        if !(u[0].is_finite() && u[1].is_finite()) {
            return Err(ArmError::NonFiniteTorque {
                t_s,
                torque_n_m: [u[0], u[1]],
            });
        }
        Ok(ControlOutput {
            u,
            v,
            e,
            e_dot,
            dls_active,
        })
    }
}
