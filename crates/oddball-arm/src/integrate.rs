//! Fixed-step classical Runge–Kutta (RK4) integration of the arm's equations of motion.

use nalgebra::Vector2;

use crate::model::{ArmModel, Trig};

/// The arm's mechanical state: joint angles (rad) and joint rates (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    /// Joint angles θ (rad).
    pub q: Vector2<f64>,
    /// Joint rates θ̇ (rad/s).
    pub qd: Vector2<f64>,
}

impl ArmState {
    /// A state at rest at joint angles `q` (rad).
    pub fn at_rest(q: Vector2<f64>) -> Self {
        Self {
            q,
            qd: Vector2::zeros(),
        }
    }

    /// True when all four components are finite.
    pub fn is_finite(&self) -> bool {
        [self.q[0], self.q[1], self.qd[0], self.qd[1]]
            .iter()
            .all(|v| v.is_finite())
    }
}

/// One RK4 step of length `dt_s` from `state` at time `t_s`.
///
/// `torque(t, state)` gives the joint torque (N·m) at each of the four stages. A digital
/// controller that holds its output over the step (zero-order hold) returns the same torque for
/// every stage; a continuous-time control law is re-evaluated at each stage.
#[inline]
pub fn rk4_step<F>(
    model: &ArmModel,
    state: &ArmState,
    t_s: f64,
    dt_s: f64,
    mut torque: F,
) -> ArmState
where
    F: FnMut(f64, &ArmState) -> Vector2<f64>,
{
    rk4_step_trig(model, state, &Trig::new(&state.q), t_s, dt_s, |t, s, _| {
        torque(t, s)
    })
}

/// [`rk4_step`] given the sines and cosines `trig` of `state.q`; the torque callback also
/// receives those of each stage. The stages' sines and cosines are obtained from `trig` by the
/// addition theorems ([`Trig::shifted`]), so a step makes no `sin`/`cos` calls for increments
/// below 0.1 rad.
#[inline]
pub fn rk4_step_trig<F>(
    model: &ArmModel,
    state: &ArmState,
    trig: &Trig,
    t_s: f64,
    dt_s: f64,
    mut torque: F,
) -> ArmState
where
    F: FnMut(f64, &ArmState, &Trig) -> Vector2<f64>,
{
    let h = dt_s;
    let half = 0.5 * h;
    // The stage positions q + k·(h/2) are formed as q̇·(h/2) + k̇·(h/2)² rather than
    // (q̇ + k̇·h/2)·h/2: the same value up to rounding, one operation shorter on the critical path.
    let qd_half = state.qd * half;
    // Stage 1 at the start.
    let u1 = torque(t_s, state, trig);
    let k1q = state.qd;
    let k1v = model.forward_dynamics_t(trig, &state.qd, &u1);
    // A stage at time `t`, its position `d` and its rates `dv` away from `state`: its rates and
    // accelerations.
    let mut stage = |t: f64, d: Vector2<f64>, dv: Vector2<f64>| {
        let s = ArmState {
            q: state.q + d,
            qd: state.qd + dv,
        };
        let ts = trig.shifted(&d);
        let u = torque(t, &s, &ts);
        (s.qd, model.forward_dynamics_t(&ts, &s.qd, &u))
    };
    // Stage 2 at the midpoint along k1.
    let (k2q, k2v) = stage(t_s + half, qd_half, k1v * half);
    // Stage 3 at the midpoint along k2.
    let (k3q, k3v) = stage(t_s + half, qd_half + k1v * (half * half), k2v * half);
    // Stage 4 at the end along k3.
    let (k4q, k4v) = stage(t_s + h, state.qd * h + k2v * (half * h), k3v * h);
    ArmState {
        q: state.q + (k1q + 2.0 * k2q + 2.0 * k3q + k4q) * (h / 6.0),
        qd: state.qd + (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * (h / 6.0),
    }
}

/// One RK4 step with the torque `u` (N·m) held constant over the step.
#[inline]
pub fn rk4_step_hold(model: &ArmModel, state: &ArmState, dt_s: f64, u: &Vector2<f64>) -> ArmState {
    rk4_step(model, state, 0.0, dt_s, |_, _| *u)
}
