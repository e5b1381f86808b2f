//! The closed loop with the exact model: error dynamics against their analytic solution,
//! settling, saturation reporting, damped least squares.

use oddball_arm::config::TransitionConfig;
use oddball_arm::{
    ArmConfig, ArmError, ArmSim, ArmState, Command, ControlUpdate, Elbow, Gains, ReferenceSample,
    TaskSpaceController, Vector2,
};

/// Solution of `ë + kd ė + kp e = 0` with `e(0) = e0`, `ė(0) = v0`, for all three damping cases.
fn analytic_error(kp: f64, kd: f64, e0: f64, v0: f64, t: f64) -> f64 {
    let disc = kd * kd - 4.0 * kp;
    let scale = kp.max(kd * kd);
    if disc.abs() < 1e-12 * scale {
        let r = -kd / 2.0;
        (e0 + (v0 - r * e0) * t) * (r * t).exp()
    } else if disc > 0.0 {
        let s = disc.sqrt();
        let (r1, r2) = ((-kd + s) / 2.0, (-kd - s) / 2.0);
        let c1 = (v0 - r2 * e0) / (r1 - r2);
        let c2 = e0 - c1;
        c1 * (r1 * t).exp() + c2 * (r2 * t).exp()
    } else {
        let (a, w) = (-kd / 2.0, (-disc).sqrt() / 2.0);
        let b = (v0 - a * e0) / w;
        (a * t).exp() * (e0 * (w * t).cos() + b * (w * t).sin())
    }
}

/// Starts the arm off its reference by `offset` (m) with pen velocity `pen_velocity` (m/s),
/// optionally commands a minimum-jerk move, runs `seconds` and returns the largest deviation (m)
/// of the recorded error `p_d − p` from the analytic solution, and the initial error size.
fn error_dynamics_deviation(
    gains: ([f64; 2], [f64; 2]),
    update: ControlUpdate,
    offset: Vector2<f64>,
    pen_velocity: Vector2<f64>,
    moving_reference: bool,
    seconds: f64,
) -> (f64, f64) {
    let mut cfg = ArmConfig::default();
    cfg.controller.kp_per_s2 = gains.0;
    cfg.controller.kd_per_s = gains.1;
    cfg.sim.control_update = update;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let plant = *sim.plant();
    let p_ref = sim.target();
    let q = plant
        .inverse_kinematics(&(p_ref + offset), Elbow::Up)
        .unwrap();
    let j = plant.jacobian(&q);
    let qd = j.try_inverse().unwrap() * pen_velocity;
    sim.set_state(ArmState { q, qd }).unwrap();
    if moving_reference {
        sim.issue(Command::Left).unwrap();
    }
    let stats = sim.run_for(seconds).unwrap();
    assert_eq!(
        stats.saturated_steps, 0,
        "precondition: no torque saturation"
    );
    assert_eq!(stats.dls_steps, 0, "precondition: exact Jacobian inverse");
    let e0 = -offset;
    let v0 = -pen_velocity;
    let mut worst: f64 = 0.0;
    for s in sim.samples() {
        let e = s.p_d - s.p;
        for k in 0..2 {
            let want = analytic_error(gains.0[k], gains.1[k], e0[k], v0[k], s.t_s);
            worst = worst.max((e[k] - want).abs());
        }
    }
    (worst, e0.norm().max(v0.norm() / gains.1[0]))
}

const GAIN_SETS: [([f64; 2], [f64; 2]); 3] = [
    // Default: critically damped, ωn = 25 rad/s.
    ([625.0, 625.0], [50.0, 50.0]),
    // Under-damped, different per axis (ζ = 0.4 and 0.6).
    ([400.0, 900.0], [16.0, 36.0]),
    // Over-damped (ζ = 1.5 and 1.25).
    ([100.0, 144.0], [30.0, 30.0]),
];

#[test]
fn continuous_control_error_follows_the_analytic_solution() {
    for gains in GAIN_SETS {
        for moving in [false, true] {
            let (dev, size) = error_dynamics_deviation(
                gains,
                ControlUpdate::Continuous,
                Vector2::new(0.004, -0.003),
                Vector2::new(-0.02, 0.05),
                moving,
                1.0,
            );
            // RK4 with the law evaluated at every stage: deviation is integration error only
            // (about 1e-11 m here).
            assert!(
                dev < 1e-9,
                "gains {gains:?}, moving reference {moving}: deviation {dev:.3e} m for an error of {size:.3e} m"
            );
        }
    }
}

#[test]
fn digital_control_error_follows_the_analytic_solution_to_first_order_in_dt() {
    // Holding the torque over dt = 1 ms acts like a delay of about dt/2, so the deviation from the
    // continuous-time solution is of order ωn·dt relative to the initial error (about a tenth of
    // that here); a quarter is allowed.
    for gains in GAIN_SETS {
        let omega = gains.0[0].max(gains.0[1]).sqrt();
        let (dev, size) = error_dynamics_deviation(
            gains,
            ControlUpdate::ZeroOrderHold,
            Vector2::new(0.004, -0.003),
            Vector2::new(-0.02, 0.05),
            true,
            1.0,
        );
        let bound = 0.25 * omega * 1e-3 * size;
        assert!(
            dev < bound,
            "gains {gains:?}: deviation {dev:.3e} m, bound {bound:.3e} m"
        );
    }
}

fn settle_2cm(transition: TransitionConfig, command: Command) -> oddball_arm::StepReport {
    let mut cfg = ArmConfig::default();
    cfg.reference.transition = transition;
    cfg.reference.step_m = 0.02;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    sim.execute(0, command).unwrap()
}

#[test]
fn a_2cm_step_settles_within_a_tenth_of_a_millimetre_in_under_half_a_second() {
    for transition in [TransitionConfig::Step, TransitionConfig::MinJerk] {
        for command in Command::ALL {
            let r = settle_2cm(transition, command);
            let settle = r
                .stats
                .settle_time_s
                .expect("settled within the command period");
            assert!(
                settle < 0.5,
                "{transition:?} {command}: settle time {settle} s"
            );
            assert!(
                r.stats.final_error_m < 1e-4,
                "{transition:?} {command}: final error {}",
                r.stats.final_error_m
            );
            assert_eq!(
                r.stats.saturated_steps, 0,
                "{transition:?} {command}: default moves respect the torque limits"
            );
            assert!((r.target - r.from).norm() > 0.0199 && (r.target - r.from).norm() < 0.0201);
        }
    }
}

#[test]
fn plain_step_settle_time_matches_critically_damped_theory() {
    // e(t) = e0 (1 + ωn t) e^{−ωn t} drops below 0.1 mm from 20 mm at ωn t ≈ 7.43, i.e. 0.297 s.
    let r = settle_2cm(TransitionConfig::Step, Command::Up);
    let omega = 25.0f64;
    let mut t = 0.0;
    while 0.02 * (1.0 + omega * t) * (-omega * t).exp() > 1e-4 {
        t += 1e-5;
    }
    let settle = r.stats.settle_time_s.unwrap();
    assert!((settle - t).abs() < 0.01, "settle {settle} s, theory {t} s");
}

#[test]
fn saturation_is_applied_and_reported() {
    let mut cfg = ArmConfig::default();
    cfg.reference.transition = TransitionConfig::Step;
    cfg.link1.torque_limit_n_m = 4.5;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let r = sim.execute(0, Command::Up).unwrap();
    assert!(
        r.stats.saturated_steps > 0,
        "a plain 2 cm step needs more than 4.5 N·m at the shoulder"
    );
    assert!((r.stats.saturated_duration_s - r.stats.saturated_steps as f64 * 1e-3).abs() < 1e-12);
    assert!(r.stats.max_abs_torque_n_m[0] <= 4.5);
    let flagged = sim
        .samples()
        .iter()
        .filter(|s| s.saturated[0] || s.saturated[1])
        .count();
    assert_eq!(flagged, r.stats.saturated_steps);
    for s in sim.samples() {
        assert!(s.u[0].abs() <= 4.5 && s.u[1].abs() <= cfg.link2.torque_limit_n_m);
        if s.saturated[0] {
            assert!(s.u_requested[0].abs() > 4.5 && s.u[0].abs() == 4.5);
        } else {
            assert_eq!(s.u[0], s.u_requested[0]);
        }
    }
    // Saturation slows the move but the loop still settles.
    assert!(
        r.stats.final_error_m < 1e-4,
        "final error {}",
        r.stats.final_error_m
    );
}

#[test]
fn damped_least_squares_takes_over_only_near_the_singularity() {
    let cfg = ArmConfig::default();
    let model = cfg.model().unwrap();
    let gains = Gains::critically_damped(25.0);
    let ctl = TaskSpaceController::new(model, gains).unwrap();
    let r = ReferenceSample::hold(Vector2::new(0.5, 0.1));
    let at = |q2: f64| {
        let s = ArmState {
            q: Vector2::new(0.2, q2),
            qd: Vector2::new(0.3, -0.2),
        };
        (s, ctl.compute(0.0, &s, &r).unwrap())
    };
    // Away from the singularity: exact inverse, so J v = task acceleration exactly.
    let (s, out) = at(-0.8);
    assert!(!out.dls_active);
    let a = gains.kd_per_s.component_mul(&out.e_dot) + gains.kp_per_s2.component_mul(&out.e)
        - model.jacobian_dot(&s.q, &s.qd) * s.qd;
    assert!((model.jacobian(&s.q) * out.v - a).norm() < 1e-9 * a.norm());
    assert!((out.u - model.inverse_dynamics(&s.q, &s.qd, &out.v)).norm() < 1e-12 * out.u.norm());
    // At and near the singularity: damped, finite, bounded.
    for q2 in [0.0, 1e-6, -1e-3, 0.01] {
        let (_, out) = at(q2);
        assert!(out.dls_active, "θ2 = {q2}");
        assert!(out.u.iter().all(|u| u.is_finite()));
        assert!(out.v.norm() < 1e5, "θ2 = {q2}: v = {:?}", out.v);
    }
    // The damping fades to zero at the threshold, so v is continuous there.
    let thr = gains.dls_threshold.asin();
    let (_, inside) = at(-(thr * (1.0 - 1e-9)));
    let (_, outside) = at(-(thr * (1.0 + 1e-9)));
    assert!(inside.dls_active && !outside.dls_active);
    assert!((inside.v - outside.v).norm() < 1e-5 * outside.v.norm());
}

#[test]
fn the_controller_rejects_non_finite_references() {
    let cfg = ArmConfig::default();
    let ctl =
        TaskSpaceController::new(cfg.model().unwrap(), Gains::critically_damped(25.0)).unwrap();
    let s = ArmState::at_rest(Vector2::new(0.9, -1.7));
    for bad in [
        ReferenceSample::hold(Vector2::new(f64::NAN, 0.0)),
        ReferenceSample {
            p: Vector2::new(0.3, 0.0),
            v: Vector2::new(0.0, f64::INFINITY),
            a: Vector2::zeros(),
        },
        ReferenceSample {
            p: Vector2::new(0.3, 0.0),
            v: Vector2::zeros(),
            a: Vector2::new(f64::NAN, f64::NAN),
        },
    ] {
        assert!(matches!(
            ctl.compute(0.0, &s, &bad),
            Err(ArmError::NonFinite { .. })
        ));
    }
}

#[test]
fn gains_must_be_positive() {
    let cfg = ArmConfig::default();
    let mut g = Gains::critically_damped(25.0);
    g.kd_per_s[1] = 0.0;
    let err = TaskSpaceController::new(cfg.model().unwrap(), g).unwrap_err();
    assert!(err.to_string().contains("controller.kd_per_s[1]"), "{err}");
}
