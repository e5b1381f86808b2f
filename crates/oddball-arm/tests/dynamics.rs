//! Properties of the model: structure of M and C, inverse/forward dynamics consistency,
//! kinematics against finite differences, inverse kinematics, and energy behaviour of the RK4
//! integration.

use oddball_arm::{
    rk4_step_hold, ArmConfig, ArmModel, ArmState, Elbow, LinkParams, Matrix2, Trig, Vector2,
};
use proptest::prelude::*;

fn default_model() -> ArmModel {
    ArmConfig::default()
        .model()
        .expect("default model is valid")
}

/// A random but physically valid arm (COM on the link, positive masses, any inertia ≥ 0).
fn arb_model() -> impl Strategy<Value = ArmModel> {
    let link = (
        0.05f64..1.0,
        0.05f64..5.0,
        0.0f64..=1.0,
        1e-4f64..0.2,
        0.0f64..0.5,
    )
        .prop_map(|(l, m, frac, i, b)| LinkParams {
            length_m: l,
            mass_kg: m,
            com_m: frac * l,
            inertia_kg_m2: i,
            friction_n_m_s_per_rad: b,
            torque_limit_n_m: 100.0,
            joint_min_rad: -10.0,
            joint_max_rad: 10.0,
        });
    (link.clone(), link, 0.0f64..20.0)
        .prop_map(|(a, b, g)| ArmModel::new(a, b, g, Vector2::zeros()).expect("valid"))
}

fn arb_vec(range: f64) -> impl Strategy<Value = Vector2<f64>> {
    (-range..range, -range..range).prop_map(|(a, b)| Vector2::new(a, b))
}

fn cond(m: &Matrix2<f64>) -> f64 {
    let e = m.symmetric_eigenvalues();
    e.max() / e.min()
}

/// dM/dt along θ̇ by central differences of M — independent of the closed-form C.
fn mass_matrix_dot_fd(m: &ArmModel, q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
    let h = 1e-6;
    (m.mass_matrix(&(q + qd * h)) - m.mass_matrix(&(q - qd * h))) / (2.0 * h)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn mass_matrix_is_symmetric_positive_definite(m in arb_model(), q in arb_vec(7.0)) {
        let mm = m.mass_matrix(&q);
        prop_assert_eq!(mm[(0, 1)], mm[(1, 0)]);
        // Positive definite: the Cholesky factorisation exists and both eigenvalues are > 0.
        let eig = mm.symmetric_eigenvalues();
        prop_assert!(eig.min() > 0.0, "eigenvalues {:?} of M at {:?}", eig, q);
        prop_assert!(mm.cholesky().is_some());
    }

    #[test]
    fn mdot_minus_2c_is_skew_symmetric(m in arb_model(), q in arb_vec(7.0), qd in arb_vec(10.0)) {
        let n = mass_matrix_dot_fd(&m, &q, &qd) - 2.0 * m.coriolis_matrix(&q, &qd);
        let sym = n + n.transpose();
        let scale = m.mass_matrix(&q).norm() * qd.norm().max(1.0);
        prop_assert!(sym.norm() <= 1e-7 * scale, "N + Nᵀ = {} (scale {})", sym, scale);
        // Consequence used in passivity arguments: θ̇ᵀ (Ṁ − 2C) θ̇ = 0.
        prop_assert!(qd.dot(&(n * qd)).abs() <= 1e-7 * scale * qd.norm().max(1.0));
    }

    #[test]
    fn inverse_then_forward_dynamics_returns_the_acceleration(
        m in arb_model(), q in arb_vec(7.0), qd in arb_vec(10.0), qdd in arb_vec(50.0)
    ) {
        let u = m.inverse_dynamics(&q, &qd, &qdd);
        let back = m.forward_dynamics(&q, &qd, &u);
        prop_assert!((back - qdd).norm() <= 1e-9 * qdd.norm().max(1.0) * cond(&m.mass_matrix(&q)),
            "commanded {:?}, got {:?}", qdd, back);
    }

    #[test]
    fn forward_then_inverse_dynamics_returns_the_torque(
        m in arb_model(), q in arb_vec(7.0), qd in arb_vec(10.0), u in arb_vec(30.0)
    ) {
        let qdd = m.forward_dynamics(&q, &qd, &u);
        let back = m.inverse_dynamics(&q, &qd, &qdd);
        prop_assert!((back - u).norm() <= 1e-9 * u.norm().max(1.0) * cond(&m.mass_matrix(&q)));
    }

    #[test]
    fn jacobian_matches_finite_differences(q in arb_vec(7.0), qd in arb_vec(5.0)) {
        let m = default_model();
        let h = 1e-6;
        let j = m.jacobian(&q);
        for k in 0..2 {
            let mut e = Vector2::zeros();
            e[k] = h;
            let col = (m.forward_kinematics(&(q + e)) - m.forward_kinematics(&(q - e))) / (2.0 * h);
            prop_assert!((col - j.column(k)).norm() < 1e-8, "column {}: fd {:?} vs {:?}", k, col, j.column(k));
        }
        // J̇ is the derivative of J along θ̇.
        let jd_fd = (m.jacobian(&(q + qd * h)) - m.jacobian(&(q - qd * h))) / (2.0 * h);
        prop_assert!((jd_fd - m.jacobian_dot(&q, &qd)).norm() < 1e-7 * qd.norm().max(1.0));
    }

    #[test]
    fn shifted_trig_matches_direct_evaluation(q in arb_vec(7.0), dq in arb_vec(0.3), tiny in arb_vec(3e-3)) {
        // Covers all three branches of the increment series: tiny, up to 0.1 rad, and beyond.
        for d in [dq, tiny, dq * 1e-3] {
            let shifted = Trig::new(&q).shifted(&d);
            let direct = Trig::new(&(q + d));
            for (a, b) in [
                (shifted.s1, direct.s1), (shifted.c1, direct.c1), (shifted.s12, direct.s12),
                (shifted.c12, direct.c12), (shifted.s2, direct.s2), (shifted.c2, direct.c2),
            ] {
                // Both sides carry the rounding of angles up to 7 rad (ulp ≈ 9e-16) in q + dq.
                prop_assert!((a - b).abs() < 1e-14, "dq {:?}: {} vs {}", d, a, b);
            }
            let exact2 = (q[1] + d[1]).sin_cos();
            prop_assert!((shifted.s2 - exact2.0).abs() < 1e-14 && (shifted.c2 - exact2.1).abs() < 1e-14);
        }
    }

    #[test]
    fn inverse_kinematics_inverts_forward_kinematics(r in 0.06f64..0.54, phi in -3.1f64..3.1, up in any::<bool>()) {
        let m = default_model();
        let p = m.base() + Vector2::new(r * phi.cos(), r * phi.sin());
        let elbow = if up { Elbow::Up } else { Elbow::Down };
        let q = m.inverse_kinematics(&p, elbow).expect("inside the annulus");
        prop_assert!((m.forward_kinematics(&q) - p).norm() < 1e-12);
        prop_assert_eq!(Elbow::of(&q), elbow);
        prop_assert!(q[1].abs() <= std::f64::consts::PI);
    }
}

#[test]
fn inverse_kinematics_rejects_points_out_of_reach_and_nan() {
    let m = default_model();
    assert!(m
        .inverse_kinematics(&Vector2::new(0.56, 0.0), Elbow::Up)
        .is_err());
    assert!(m
        .inverse_kinematics(&Vector2::new(0.04, 0.0), Elbow::Down)
        .is_err());
    assert!(m
        .inverse_kinematics(&Vector2::new(f64::NAN, 0.1), Elbow::Up)
        .is_err());
}

#[test]
fn elbow_up_puts_the_elbow_above_the_shoulder_pen_line() {
    let m = default_model();
    let p = Vector2::new(0.35, 0.05);
    for (elbow, sign) in [(Elbow::Up, 1.0), (Elbow::Down, -1.0)] {
        let q = m.inverse_kinematics(&p, elbow).unwrap();
        let e = m.elbow_position(&q) - m.base();
        let d = p - m.base();
        let cross = d[0] * e[1] - d[1] * e[0];
        assert!(sign * cross > 0.0, "{elbow}: elbow {e:?} for pen {d:?}");
    }
}

/// Mechanical energy measured above its lowest possible value, so "relative" means relative to
/// the energy the arm actually has to exchange.
fn relative_energy_drift(model: &ArmModel, start: ArmState, dt: f64, seconds: f64) -> f64 {
    let e0 = model.total_energy(&start.q, &start.qd);
    let scale = e0 - model.min_potential_energy();
    let mut s = start;
    let mut worst: f64 = 0.0;
    for _ in 0..(seconds / dt).round() as usize {
        s = rk4_step_hold(model, &s, dt, &Vector2::zeros());
        worst = worst.max((model.total_energy(&s.q, &s.qd) - e0).abs());
    }
    worst / scale
}

#[test]
fn zero_torque_zero_friction_conserves_energy_over_ten_seconds() {
    let m = default_model().without_friction();
    // A swinging double pendulum (chaotic) started from several states, including a fast one.
    for (q, qd) in [
        ((0.3, -1.2), (1.0, -2.0)),
        ((1.5, 0.0), (0.0, 0.0)),
        ((-0.5, 2.0), (4.0, -6.0)),
    ] {
        let start = ArmState {
            q: Vector2::new(q.0, q.1),
            qd: Vector2::new(qd.0, qd.1),
        };
        let drift = relative_energy_drift(&m, start, 1e-3, 10.0);
        assert!(
            drift < 1e-6,
            "relative energy drift {drift:.3e} from {start:?}"
        );
    }
}

#[test]
fn energy_drift_shrinks_like_dt_to_the_fourth() {
    // Guards against an integrator that conserves energy by accident (e.g. a wrong but
    // symplectic-looking scheme): halving dt must cut the RK4 drift by roughly 2⁴.
    let m = default_model().without_friction();
    let start = ArmState {
        q: Vector2::new(-0.5, 2.0),
        qd: Vector2::new(6.0, -9.0),
    };
    let coarse = relative_energy_drift(&m, start, 8e-3, 2.0);
    let fine = relative_energy_drift(&m, start, 4e-3, 2.0);
    let ratio = coarse / fine;
    assert!(
        (8.0..40.0).contains(&ratio),
        "drift {coarse:.3e} → {fine:.3e}, ratio {ratio:.1}"
    );
}

#[test]
fn friction_dissipates_energy_at_the_rate_qdot_b_qdot() {
    let m = default_model();
    let mut s = ArmState {
        q: Vector2::new(0.3, -1.2),
        qd: Vector2::new(1.0, -2.0),
    };
    let dt = 1e-3;
    for _ in 0..2000 {
        let e0 = m.total_energy(&s.q, &s.qd);
        let p0 = m.friction_torque(&s.qd).dot(&s.qd);
        let next = rk4_step_hold(&m, &s, dt, &Vector2::zeros());
        let e1 = m.total_energy(&next.q, &next.qd);
        let p1 = m.friction_torque(&next.qd).dot(&next.qd);
        assert!(e1 <= e0 + 1e-12, "energy rose from {e0} to {e1}");
        // dE/dt = −θ̇ᵀ B θ̇ (trapezoidal estimate over one step).
        let expected = -0.5 * (p0 + p1) * dt;
        assert!(((e1 - e0) - expected).abs() < 1e-3 * expected.abs() + 1e-10);
        s = next;
    }
}

#[test]
fn torque_does_work_equal_to_the_energy_change() {
    // With a constant torque u and no friction, d/dt (E − uᵀθ) = 0.
    let m = default_model().without_friction();
    let u = Vector2::new(1.5, -0.4);
    let mut s = ArmState::at_rest(Vector2::new(0.2, -0.9));
    let inv0 = m.total_energy(&s.q, &s.qd) - u.dot(&s.q);
    // One second: the constant torque spins the arm up (θ̇2 ≈ −28 rad/s by then).
    for _ in 0..1000 {
        s = rk4_step_hold(&m, &s, 1e-3, &u);
    }
    assert!(
        s.qd.norm() > 10.0,
        "the arm should have been spun up: θ̇ = {:?}",
        s.qd
    );
    let inv1 = m.total_energy(&s.q, &s.qd) - u.dot(&s.q);
    assert!(
        (inv1 - inv0).abs() < 1e-6,
        "E − uᵀθ changed by {}",
        inv1 - inv0
    );
}

#[test]
fn gravity_pulls_a_resting_arm_down() {
    let m = default_model();
    let acc = m.forward_dynamics(
        &Vector2::new(0.0, 0.0),
        &Vector2::zeros(),
        &Vector2::zeros(),
    );
    // Horizontal, stretched arm: the shoulder must accelerate downwards (θ1 decreasing).
    assert!(acc[0] < 0.0, "θ̈ = {acc:?}");
    // Holding it takes exactly g(θ).
    let hold = m.gravity_torque(&Vector2::new(0.0, 0.0));
    let acc = m.forward_dynamics(&Vector2::new(0.0, 0.0), &Vector2::zeros(), &hold);
    assert!(acc.norm() < 1e-12);
}

#[test]
fn config_parameters_reach_the_model() {
    let cfg = ArmConfig::default();
    let m = cfg.model().unwrap();
    assert_eq!(m.links()[0].length_m, cfg.link1.length_m);
    assert_eq!(m.links()[1].torque_limit_n_m, cfg.link2.torque_limit_n_m);
    assert_eq!(m.gravity_m_s2(), cfg.gravity_m_s2);
}
