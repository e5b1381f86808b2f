//! Compares the closed-form kinematics and dynamics with golden values from an independent
//! sympy Euler–Lagrange derivation (`tools/golden/arm/make_golden.py`).

use oddball_arm::{ArmModel, LinkParams, Matrix2, Vector2};
use serde_json::Value;

const TOL: f64 = 1e-9;

fn fixture() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/arm_golden.json"
    );
    let text = std::fs::read_to_string(path)
        .expect("golden fixture present (run tools/golden/arm/make_golden.py)");
    serde_json::from_str(&text).expect("golden fixture is valid JSON")
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn vec2(v: &Value) -> Vector2<f64> {
    Vector2::new(num(&v[0]), num(&v[1]))
}

fn mat2(v: &Value) -> Matrix2<f64> {
    Matrix2::new(num(&v[0][0]), num(&v[0][1]), num(&v[1][0]), num(&v[1][1]))
}

fn model(params: &Value) -> ArmModel {
    let p = |k: &str| num(&params[k]);
    let link = |l, m, c, i, b| LinkParams {
        length_m: l,
        mass_kg: m,
        com_m: c,
        inertia_kg_m2: i,
        friction_n_m_s_per_rad: b,
        torque_limit_n_m: 1e3,
        joint_min_rad: -10.0,
        joint_max_rad: 10.0,
    };
    ArmModel::new(
        link(p("l1"), p("m1"), p("lc1"), p("I1"), p("b1")),
        link(p("l2"), p("m2"), p("lc2"), p("I2"), p("b2")),
        p("g"),
        Vector2::new(p("base_x"), p("base_z")),
    )
    .expect("fixture parameters are valid")
}

fn close(what: &str, i: usize, got: &[f64], want: &[f64]) {
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let err = (g - w).abs();
        assert!(
            err <= TOL * w.abs().max(1.0),
            "state {i}: {what}[{k}] = {g:.17e}, golden {w:.17e} (|diff| {err:.3e})"
        );
    }
}

#[test]
fn dynamics_and_kinematics_match_the_sympy_derivation() {
    let fx = fixture();
    let arm = model(&fx["params"]);
    let states = fx["states"].as_array().expect("states");
    assert!(states.len() >= 10, "fixture has {} states", states.len());
    for (i, s) in states.iter().enumerate() {
        let (q, qd, qdd) = (vec2(&s["q"]), vec2(&s["qd"]), vec2(&s["qdd"]));
        close(
            "pen",
            i,
            arm.forward_kinematics(&q).as_slice(),
            vec2(&s["pen"]).as_slice(),
        );
        close(
            "J",
            i,
            arm.jacobian(&q).as_slice(),
            mat2(&s["J"]).as_slice(),
        );
        close(
            "Jdot",
            i,
            arm.jacobian_dot(&q, &qd).as_slice(),
            mat2(&s["Jdot"]).as_slice(),
        );
        close(
            "M",
            i,
            arm.mass_matrix(&q).as_slice(),
            mat2(&s["M"]).as_slice(),
        );
        close(
            "C",
            i,
            arm.coriolis_matrix(&q, &qd).as_slice(),
            mat2(&s["C"]).as_slice(),
        );
        close(
            "g",
            i,
            arm.gravity_torque(&q).as_slice(),
            vec2(&s["g"]).as_slice(),
        );
        close(
            "inverse dynamics",
            i,
            arm.inverse_dynamics(&q, &qd, &qdd).as_slice(),
            vec2(&s["tau"]).as_slice(),
        );
    }
}

#[test]
fn forward_dynamics_recovers_the_golden_accelerations() {
    let fx = fixture();
    let arm = model(&fx["params"]);
    for (i, s) in fx["states"].as_array().expect("states").iter().enumerate() {
        let (q, qd, qdd) = (vec2(&s["q"]), vec2(&s["qd"]), vec2(&s["qdd"]));
        let acc = arm.forward_dynamics(&q, &qd, &vec2(&s["tau"]));
        for k in 0..2 {
            assert!(
                (acc[k] - qdd[k]).abs() <= 1e-8 * qdd[k].abs().max(1.0),
                "state {i}: θ̈[{k}] = {}, golden {}",
                acc[k],
                qdd[k]
            );
        }
    }
}
