//! The physical arm: parameters, kinematics and rigid-body dynamics of a planar two-link arm in
//! the vertical x–z plane, gravity along −z.
//!
//! Conventions:
//! * `x` is horizontal (to the right on the board), `z` is vertical (up), both in metres, in the
//!   board's frame; the shoulder sits at [`ArmModel::base`].
//! * `θ1` (rad) is the angle of link 1 from the +x axis towards +z; `θ2` (rad) is the angle of
//!   link 2 relative to link 1 (so link 2's absolute angle is `θ1 + θ2`).
//! * Joint torques `u` are in N·m, joint rates in rad/s, accelerations in rad/s².
//! * Each link's centre of mass lies on the link at `com_m` from its proximal joint; its inertia
//!   `inertia_kg_m2` is about an axis through the centre of mass normal to the plane.
//!
//! The equations of motion are `M(θ) θ̈ + C(θ, θ̇) θ̇ + g(θ) + B θ̇ = u` with `B` the diagonal
//! viscous-friction matrix and `C` built from the Christoffel symbols of `M` (so `Ṁ − 2C` is
//! skew-symmetric).

use nalgebra::{Matrix2, Vector2};

use crate::error::{ArmError, ConfigError, RefusalReason};

/// Physical parameters of one link and its (proximal) joint, as a configuration's `[link1]` and
/// `[link2]` sections give them (every field required, no unknown ones); [`ArmModel::new`]
/// validates them.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkParams {
    /// Joint-to-joint length (m).
    pub length_m: f64,
    /// Mass (kg).
    pub mass_kg: f64,
    /// Distance of the centre of mass from the proximal joint, along the link (m).
    pub com_m: f64,
    /// Moment of inertia about the centre of mass, normal to the plane (kg·m²).
    pub inertia_kg_m2: f64,
    /// Viscous friction coefficient of the proximal joint (N·m·s/rad).
    pub friction_n_m_s_per_rad: f64,
    /// Symmetric torque limit of the joint's actuator (N·m).
    pub torque_limit_n_m: f64,
    /// Lower joint limit (rad).
    pub joint_min_rad: f64,
    /// Upper joint limit (rad).
    pub joint_max_rad: f64,
}

/// Elbow configuration of an inverse-kinematics solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Elbow {
    /// Elbow above the shoulder–pen line when the pen is to the right of the shoulder (θ2 < 0).
    Up,
    /// Elbow below the shoulder–pen line when the pen is to the right of the shoulder (θ2 > 0).
    Down,
}

impl Elbow {
    /// The elbow configuration of a joint configuration (θ2 ≤ 0 counts as up).
    pub fn of(q: &Vector2<f64>) -> Self {
        if q[1] <= 0.0 {
            Elbow::Up
        } else {
            Elbow::Down
        }
    }
}

impl std::fmt::Display for Elbow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Elbow::Up => "up",
            Elbow::Down => "down",
        })
    }
}

/// Sines and cosines of one configuration: of θ1, of θ1 + θ2 and (derived from those) of θ2.
///
/// Every kinematic and dynamic quantity of the arm depends on θ only through these, so the
/// controller and the integrator compute them once per configuration (`_t` methods of
/// [`ArmModel`]). [`Trig::shifted`] moves them by a small angle increment with the addition
/// theorems, which is how the RK4 stages avoid calling `sin`/`cos` at all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trig {
    pub s1: f64,
    pub c1: f64,
    pub s12: f64,
    pub c12: f64,
    pub s2: f64,
    pub c2: f64,
}

/// `(sin δ, cos δ)` of an angle increment: Taylor series to machine precision for |δ| ≤ 0.1 rad
/// (the RK4 stage increments are about θ̇·dt/2, i.e. milliradians), libm beyond.
#[inline]
fn sin_cos_increment(d: f64) -> (f64, f64) {
    // Taylor coefficients ±1/n!, multiplied rather than divided (divisions are slow).
    const S3: f64 = -1.0 / 6.0;
    const S5: f64 = 1.0 / 120.0;
    const S7: f64 = -1.0 / 5040.0;
    const S9: f64 = 1.0 / 362_880.0;
    const S11: f64 = -1.0 / 39_916_800.0;
    const C2: f64 = -0.5;
    const C4: f64 = 1.0 / 24.0;
    const C6: f64 = -1.0 / 720.0;
    const C8: f64 = 1.0 / 40_320.0;
    const C10: f64 = -1.0 / 3_628_800.0;
    const C12: f64 = 1.0 / 479_001_600.0;
    let a = d.abs();
    let d2 = d * d;
    if a <= 1e-3 {
        // The common case (θ̇ up to 1 rad/s at dt = 1 ms), kept short because it lies on the
        // integrator's critical path. First omitted terms: |δ|⁵/5! < 9e-18, δ⁶/6! < 2e-21.
        let s = d + S3 * d * d2;
        let c = 1.0 + d2 * (C2 + d2 * C4);
        (s, c)
    } else if a <= 0.1 {
        // First omitted terms: |δ|¹³/13! < 2e-23, δ¹⁴/14! < 2e-25.
        let s = d + d * d2 * (S3 + d2 * (S5 + d2 * (S7 + d2 * (S9 + d2 * S11))));
        let c = 1.0 + d2 * (C2 + d2 * (C4 + d2 * (C6 + d2 * (C8 + d2 * (C10 + d2 * C12)))));
        (s, c)
    } else {
        d.sin_cos()
    }
}

impl Trig {
    /// Evaluates the sines and cosines of `q` (rad).
    #[inline]
    pub fn new(q: &Vector2<f64>) -> Self {
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        Self::from_link_angles(s1, c1, s12, c12)
    }

    /// Completes the set with θ2 = (θ1 + θ2) − θ1 (absolute error about 1e-16).
    #[inline]
    fn from_link_angles(s1: f64, c1: f64, s12: f64, c12: f64) -> Self {
        Self {
            s1,
            c1,
            s12,
            c12,
            s2: s12 * c1 - c12 * s1,
            c2: c12 * c1 + s12 * s1,
        }
    }

    /// The sines and cosines of `q + dq`, given those of `q` (addition theorems).
    #[inline]
    pub fn shifted(&self, dq: &Vector2<f64>) -> Self {
        // θ2's own increment keeps cos θ2 (which M⁻¹ needs first) off the longer derived path.
        let (sa, ca) = sin_cos_increment(dq[0]);
        let (sb, cb) = sin_cos_increment(dq[0] + dq[1]);
        let (sc, cc) = sin_cos_increment(dq[1]);
        Self {
            s1: self.s1 * ca + self.c1 * sa,
            c1: self.c1 * ca - self.s1 * sa,
            s12: self.s12 * cb + self.c12 * sb,
            c12: self.c12 * cb - self.s12 * sb,
            s2: self.s2 * cc + self.c2 * sc,
            c2: self.c2 * cc - self.s2 * sc,
        }
    }
}

/// A validated planar two-link arm. Cheap to copy; all methods are pure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmModel {
    links: [LinkParams; 2],
    gravity_m_s2: f64,
    base: Vector2<f64>,
    // Constant coefficients of M, C and g (see `new`).
    m11_const: f64,
    m12_const: f64,
    m22: f64,
    coupling: f64,
    det_const: f64,
    g1_coef: f64,
    g12_coef: f64,
}

fn check(
    field: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), ConfigError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ConfigError::Invalid {
            field,
            value,
            reason,
        })
    }
}

fn check_link(prefix: usize, link: &LinkParams) -> Result<(), ConfigError> {
    // Field names are static strings so that errors can name them exactly.
    let names: [&'static str; 8] = if prefix == 1 {
        [
            "link1.length_m",
            "link1.mass_kg",
            "link1.com_m",
            "link1.inertia_kg_m2",
            "link1.friction_n_m_s_per_rad",
            "link1.torque_limit_n_m",
            "link1.joint_min_rad",
            "link1.joint_max_rad",
        ]
    } else {
        [
            "link2.length_m",
            "link2.mass_kg",
            "link2.com_m",
            "link2.inertia_kg_m2",
            "link2.friction_n_m_s_per_rad",
            "link2.torque_limit_n_m",
            "link2.joint_min_rad",
            "link2.joint_max_rad",
        ]
    };
    check(
        names[0],
        link.length_m,
        link.length_m > 0.0,
        "must be positive",
    )?;
    check(
        names[1],
        link.mass_kg,
        link.mass_kg > 0.0,
        "must be positive",
    )?;
    check(
        names[2],
        link.com_m,
        link.com_m >= 0.0 && link.com_m <= link.length_m,
        "must lie on the link: 0 ≤ com_m ≤ length_m",
    )?;
    check(
        names[3],
        link.inertia_kg_m2,
        link.inertia_kg_m2 >= 0.0,
        "must be non-negative",
    )?;
    // Keeps M(θ) positive definite for every θ: det M ≥ (m2 lc2² + I2)(m1 lc1² + I1) + m2 l1² I2.
    check(
        names[3],
        link.inertia_kg_m2,
        link.mass_kg * link.com_m * link.com_m + link.inertia_kg_m2 > 0.0,
        "the link needs a positive inertia about its joint (mass_kg·com_m² + inertia_kg_m2 > 0)",
    )?;
    check(
        names[4],
        link.friction_n_m_s_per_rad,
        link.friction_n_m_s_per_rad >= 0.0,
        "must be non-negative",
    )?;
    check(
        names[5],
        link.torque_limit_n_m,
        link.torque_limit_n_m > 0.0,
        "must be positive",
    )?;
    check(names[6], link.joint_min_rad, true, "must be finite")?;
    check(
        names[7],
        link.joint_max_rad,
        link.joint_max_rad > link.joint_min_rad,
        "must exceed joint_min_rad",
    )?;
    Ok(())
}

impl ArmModel {
    /// Builds a model, validating every parameter. `gravity_m_s2` is the magnitude of gravity
    /// (acting along −z); `base` is the shoulder position (x, z) in metres.
    pub fn new(
        link1: LinkParams,
        link2: LinkParams,
        gravity_m_s2: f64,
        base: Vector2<f64>,
    ) -> Result<Self, ConfigError> {
        check_link(1, &link1)?;
        check_link(2, &link2)?;
        check(
            "gravity_m_s2",
            gravity_m_s2,
            gravity_m_s2 >= 0.0,
            "must be non-negative",
        )?;
        check("base.x_m", base[0], true, "must be finite")?;
        check("base.z_m", base[1], true, "must be finite")?;
        let (l1, m1, c1, i1) = (
            link1.length_m,
            link1.mass_kg,
            link1.com_m,
            link1.inertia_kg_m2,
        );
        let (m2, c2, i2) = (link2.mass_kg, link2.com_m, link2.inertia_kg_m2);
        let m11_const = m1 * c1 * c1 + i1 + m2 * (l1 * l1 + c2 * c2) + i2;
        let m22 = m2 * c2 * c2 + i2;
        Ok(Self {
            det_const: m22 * (m11_const - m22),
            links: [link1, link2],
            gravity_m_s2,
            base,
            m11_const,
            m12_const: m22,
            m22,
            coupling: m2 * l1 * c2,
            g1_coef: (m1 * c1 + m2 * l1) * gravity_m_s2,
            g12_coef: m2 * c2 * gravity_m_s2,
        })
    }

    /// Link parameters, index 0 for link 1 (shoulder) and 1 for link 2 (elbow).
    pub fn links(&self) -> &[LinkParams; 2] {
        &self.links
    }

    /// Magnitude of gravity (m/s²), acting along −z.
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }

    /// Shoulder position (x, z) in metres.
    pub fn base(&self) -> Vector2<f64> {
        self.base
    }

    /// A copy with every joint's viscous friction set to zero (for conservation checks).
    pub fn without_friction(&self) -> Self {
        let mut m = *self;
        m.links[0].friction_n_m_s_per_rad = 0.0;
        m.links[1].friction_n_m_s_per_rad = 0.0;
        m
    }

    /// Torque limits (N·m) of the two actuators.
    pub fn torque_limits(&self) -> Vector2<f64> {
        Vector2::new(
            self.links[0].torque_limit_n_m,
            self.links[1].torque_limit_n_m,
        )
    }

    /// Clips a torque to the actuator limits; the flags tell which joints were clipped.
    pub fn saturate(&self, u: &Vector2<f64>) -> (Vector2<f64>, [bool; 2]) {
        let lim = self.torque_limits();
        let mut out = *u;
        let mut flags = [false; 2];
        for i in 0..2 {
            if out[i] > lim[i] {
                out[i] = lim[i];
                flags[i] = true;
            } else if out[i] < -lim[i] {
                out[i] = -lim[i];
                flags[i] = true;
            }
        }
        (out, flags)
    }

    // ---------------------------------------------------------------- kinematics

    /// Elbow position (x, z) in metres.
    pub fn elbow_position(&self, q: &Vector2<f64>) -> Vector2<f64> {
        let l1 = self.links[0].length_m;
        self.base + Vector2::new(l1 * q[0].cos(), l1 * q[0].sin())
    }

    /// Forward kinematics: the pen (end-effector) position (x, z) in metres.
    pub fn forward_kinematics(&self, q: &Vector2<f64>) -> Vector2<f64> {
        self.forward_kinematics_t(&Trig::new(q))
    }

    /// [`ArmModel::forward_kinematics`] from precomputed sines and cosines.
    #[inline]
    pub fn forward_kinematics_t(&self, t: &Trig) -> Vector2<f64> {
        let (l1, l2) = (self.links[0].length_m, self.links[1].length_m);
        self.base + Vector2::new(l1 * t.c1 + l2 * t.c12, l1 * t.s1 + l2 * t.s12)
    }

    /// Analytical Jacobian `J_A(θ) = ∂p/∂θ` (m/rad); rows are x and z.
    pub fn jacobian(&self, q: &Vector2<f64>) -> Matrix2<f64> {
        self.jacobian_t(&Trig::new(q))
    }

    /// [`ArmModel::jacobian`] from precomputed sines and cosines.
    #[inline]
    pub fn jacobian_t(&self, t: &Trig) -> Matrix2<f64> {
        let (l1, l2) = (self.links[0].length_m, self.links[1].length_m);
        Matrix2::new(
            -l1 * t.s1 - l2 * t.s12,
            -l2 * t.s12,
            l1 * t.c1 + l2 * t.c12,
            l2 * t.c12,
        )
    }

    /// Time derivative `J̇_A(θ, θ̇)` of the analytical Jacobian (m/(rad·s)).
    pub fn jacobian_dot(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
        self.jacobian_dot_t(&Trig::new(q), qd)
    }

    /// [`ArmModel::jacobian_dot`] from precomputed sines and cosines.
    #[inline]
    pub fn jacobian_dot_t(&self, t: &Trig, qd: &Vector2<f64>) -> Matrix2<f64> {
        let (l1, l2) = (self.links[0].length_m, self.links[1].length_m);
        let w12 = qd[0] + qd[1];
        Matrix2::new(
            -l1 * t.c1 * qd[0] - l2 * t.c12 * w12,
            -l2 * t.c12 * w12,
            -l1 * t.s1 * qd[0] - l2 * t.s12 * w12,
            -l2 * t.s12 * w12,
        )
    }

    /// Pen velocity `ṗ = J_A θ̇` (m/s).
    pub fn pen_velocity(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> Vector2<f64> {
        self.jacobian(q) * qd
    }

    /// Reachable distances from the shoulder: `[|l1 − l2|, l1 + l2]` (m).
    pub fn reach_m(&self) -> (f64, f64) {
        let (l1, l2) = (self.links[0].length_m, self.links[1].length_m);
        ((l1 - l2).abs(), l1 + l2)
    }

    /// Inverse kinematics for the pen at `p` (m) with the given elbow configuration.
    ///
    /// θ1 is returned in (−π, π], shifted by ±2π when that brings it inside joint 1's limits.
    /// Joint limits are *not* enforced here; see [`ArmModel::check_joint_limits`].
    pub fn inverse_kinematics(
        &self,
        p: &Vector2<f64>,
        elbow: Elbow,
    ) -> Result<Vector2<f64>, ArmError> {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(ArmError::NonFinite {
                what: "inverse-kinematics target",
                value: vec![p[0], p[1]],
            });
        }
        let (l1, l2) = (self.links[0].length_m, self.links[1].length_m);
        let d = p - self.base;
        let r2 = d.norm_squared();
        let (rmin, rmax) = self.reach_m();
        let c2 = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
        if !(-1.0..=1.0).contains(&c2) {
            return Err(ArmError::NoIkSolution {
                target: (p[0], p[1]),
                reason: RefusalReason::Unreachable {
                    at: (p[0], p[1]),
                    distance_m: r2.sqrt(),
                    min_m: rmin,
                    max_m: rmax,
                },
            });
        }
        let s2_abs = (1.0 - c2 * c2).sqrt();
        let s2 = match elbow {
            Elbow::Up => -s2_abs,
            Elbow::Down => s2_abs,
        };
        let q2 = s2.atan2(c2);
        let mut q1 = d[1].atan2(d[0]) - (l2 * s2).atan2(l1 + l2 * c2);
        let tau = std::f64::consts::TAU;
        if q1 > std::f64::consts::PI {
            q1 -= tau;
        } else if q1 <= -std::f64::consts::PI {
            q1 += tau;
        }
        let (lo, hi) = (self.links[0].joint_min_rad, self.links[0].joint_max_rad);
        if q1 < lo && q1 + tau <= hi {
            q1 += tau;
        } else if q1 > hi && q1 - tau >= lo {
            q1 -= tau;
        }
        Ok(Vector2::new(q1, q2))
    }

    /// The first joint (0-based) outside its limits, with its angle, or `None`.
    pub fn check_joint_limits(&self, q: &Vector2<f64>) -> Option<(usize, f64)> {
        (0..2).find_map(|i| {
            let l = &self.links[i];
            (!(l.joint_min_rad..=l.joint_max_rad).contains(&q[i])).then_some((i, q[i]))
        })
    }

    // ---------------------------------------------------------------- dynamics

    /// Inertia (mass) matrix `M(θ)` (kg·m²).
    pub fn mass_matrix(&self, q: &Vector2<f64>) -> Matrix2<f64> {
        self.mass_matrix_t(&Trig::new(q))
    }

    /// [`ArmModel::mass_matrix`] from precomputed sines and cosines.
    #[inline]
    pub fn mass_matrix_t(&self, t: &Trig) -> Matrix2<f64> {
        let m12 = self.m12_const + self.coupling * t.c2;
        Matrix2::new(
            self.m11_const + 2.0 * self.coupling * t.c2,
            m12,
            m12,
            self.m22,
        )
    }

    /// Coriolis/centrifugal matrix `C(θ, θ̇)` from the Christoffel symbols of `M` (kg·m²/s).
    pub fn coriolis_matrix(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
        self.coriolis_matrix_t(&Trig::new(q), qd)
    }

    /// [`ArmModel::coriolis_matrix`] from precomputed sines and cosines.
    #[inline]
    pub fn coriolis_matrix_t(&self, t: &Trig, qd: &Vector2<f64>) -> Matrix2<f64> {
        let h = -self.coupling * t.s2;
        Matrix2::new(h * qd[1], h * (qd[0] + qd[1]), -h * qd[0], 0.0)
    }

    /// Gravity torques `g(θ) = ∂V/∂θ` (N·m).
    pub fn gravity_torque(&self, q: &Vector2<f64>) -> Vector2<f64> {
        self.gravity_torque_t(&Trig::new(q))
    }

    /// [`ArmModel::gravity_torque`] from precomputed sines and cosines.
    #[inline]
    pub fn gravity_torque_t(&self, t: &Trig) -> Vector2<f64> {
        let g2 = self.g12_coef * t.c12;
        Vector2::new(self.g1_coef * t.c1 + g2, g2)
    }

    /// Viscous friction torques `B θ̇` (N·m) that oppose the motion.
    #[inline]
    pub fn friction_torque(&self, qd: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            self.links[0].friction_n_m_s_per_rad * qd[0],
            self.links[1].friction_n_m_s_per_rad * qd[1],
        )
    }

    /// `h(θ, θ̇) = C(θ, θ̇) θ̇ + g(θ) + B θ̇` (N·m): everything but the inertial term.
    pub fn bias_torque(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> Vector2<f64> {
        self.bias_torque_t(&Trig::new(q), qd)
    }

    /// [`ArmModel::bias_torque`] from precomputed sines and cosines.
    #[inline]
    pub fn bias_torque_t(&self, t: &Trig, qd: &Vector2<f64>) -> Vector2<f64> {
        // C θ̇ written out: h = −m2 l1 lc2 sin θ2, C θ̇ = (h θ̇2 (2θ̇1 + θ̇2), −h θ̇1²).
        let h = -self.coupling * t.s2;
        let g2 = self.g12_coef * t.c12;
        Vector2::new(
            h * qd[1] * (2.0 * qd[0] + qd[1])
                + self.g1_coef * t.c1
                + g2
                + self.links[0].friction_n_m_s_per_rad * qd[0],
            -h * qd[0] * qd[0] + g2 + self.links[1].friction_n_m_s_per_rad * qd[1],
        )
    }

    /// Inverse dynamics: the torque `u = M θ̈ + C θ̇ + g + B θ̇` (N·m) that produces `qdd`.
    pub fn inverse_dynamics(
        &self,
        q: &Vector2<f64>,
        qd: &Vector2<f64>,
        qdd: &Vector2<f64>,
    ) -> Vector2<f64> {
        let t = Trig::new(q);
        self.mass_matrix_t(&t) * qdd + self.bias_torque_t(&t, qd)
    }

    /// Forward dynamics: `θ̈ = M⁻¹ (u − C θ̇ − g − B θ̇)` (rad/s²).
    pub fn forward_dynamics(
        &self,
        q: &Vector2<f64>,
        qd: &Vector2<f64>,
        u: &Vector2<f64>,
    ) -> Vector2<f64> {
        self.forward_dynamics_t(&Trig::new(q), qd, u)
    }

    /// [`ArmModel::forward_dynamics`] from precomputed sines and cosines.
    #[inline]
    pub fn forward_dynamics_t(
        &self,
        t: &Trig,
        qd: &Vector2<f64>,
        u: &Vector2<f64>,
    ) -> Vector2<f64> {
        // M⁻¹ written out; with M12 const = M22 = γ, det M = γ (M11 const − γ) − (m2 l1 lc2 cos θ2)²
        // is positive for every θ (see `check_link`) and needs only cos θ2.
        let bc = self.coupling * t.c2;
        let inv_det = 1.0 / (self.det_const - bc * bc);
        let m11 = self.m11_const + 2.0 * bc;
        let m12 = self.m12_const + bc;
        let r = u - self.bias_torque_t(t, qd);
        Vector2::new(
            (self.m22 * r[0] - m12 * r[1]) * inv_det,
            (m11 * r[1] - m12 * r[0]) * inv_det,
        )
    }

    /// Kinetic energy `½ θ̇ᵀ M θ̇` (J).
    pub fn kinetic_energy(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> f64 {
        0.5 * qd.dot(&(self.mass_matrix(q) * qd))
    }

    /// Gravitational potential energy (J), zero with both links horizontal at the shoulder height.
    pub fn potential_energy(&self, q: &Vector2<f64>) -> f64 {
        (self.g1_coef * q[0].sin()) + self.g12_coef * (q[0] + q[1]).sin()
    }

    /// The lowest possible potential energy (both links hanging straight down), J.
    pub fn min_potential_energy(&self) -> f64 {
        -(self.g1_coef + self.g12_coef)
    }

    /// Total mechanical energy (J).
    pub fn total_energy(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> f64 {
        self.kinetic_energy(q, qd) + self.potential_energy(q)
    }
}

/// Solves `A x = b` for a 2×2 symmetric positive-definite `A` by the closed-form inverse.
#[inline]
pub(crate) fn solve_spd2(a: &Matrix2<f64>, b: &Vector2<f64>) -> Vector2<f64> {
    let inv_det = 1.0 / (a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)]);
    Vector2::new(
        (a[(1, 1)] * b[0] - a[(0, 1)] * b[1]) * inv_det,
        (a[(0, 0)] * b[1] - a[(1, 0)] * b[0]) * inv_det,
    )
}
