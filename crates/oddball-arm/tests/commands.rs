//! Commands, refusals, safety, the letter G, and the configuration file.

use oddball_arm::config::TransitionConfig;
use oddball_arm::trace::point_segment_distance;
use oddball_arm::{
    parse_commands, ArmConfig, ArmError, ArmSim, ArmState, Command, ConfigError, RefusalReason,
    StepOutcome, Vector2,
};

fn expected_corners(start: Vector2<f64>, commands: &[Command], h: f64) -> Vec<Vector2<f64>> {
    let mut pts = vec![start];
    for c in commands {
        let last = *pts.last().unwrap();
        pts.push(c.apply(&last, h));
    }
    pts
}

fn run_g(transition: TransitionConfig) -> (ArmSim, Vec<StepOutcome>) {
    let mut cfg = ArmConfig::default();
    cfg.reference.transition = transition;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let report = sim.run_program(&Command::LETTER_G);
    assert!(
        report.stopped.is_none(),
        "safety stop: {:?}",
        report.stopped
    );
    (sim, report.outcomes)
}

#[test]
fn the_letter_g_passes_every_corner_within_half_a_millimetre() {
    for transition in [TransitionConfig::MinJerk, TransitionConfig::Step] {
        let (sim, out) = run_g(transition);
        let cfg = ArmConfig::default();
        let start = Vector2::new(cfg.start.x_m, cfg.start.z_m);
        let corners = expected_corners(start, &Command::LETTER_G, cfg.reference.step_m);
        assert_eq!(corners.len(), 7);
        for o in &out {
            let StepOutcome::Executed(r) = o else {
                panic!("{transition:?}: a command of the G was refused: {o:?}");
            };
            assert!(
                r.stats.settle_time_s.is_some(),
                "{transition:?}: step {} did not settle",
                r.index
            );
            assert_eq!(r.stats.saturated_steps, 0);
            assert!((r.target - corners[r.index + 1]).norm() < 1e-12);
        }
        let trace = sim.trace();
        for (i, c) in corners.iter().enumerate() {
            let d = trace.distance_to(c).unwrap();
            assert!(
                d < 5e-4,
                "{transition:?}: corner {i} {c:?} missed by {d:.3e} m"
            );
        }
        // The trace is time-ordered and stays on the six-segment path.
        let pts = trace.points();
        assert!(pts.windows(2).all(|w| w[1].t_s > w[0].t_s));
        let worst = pts
            .iter()
            .map(|tp| {
                corners
                    .windows(2)
                    .map(|s| point_segment_distance(&tp.p, &s[0], &s[1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(
            worst < 5e-4,
            "{transition:?}: pen strayed {worst:.3e} m from the path"
        );
        // The simulation's cached pen position (kept with sines and cosines updated by the
        // addition theorems) agrees with forward kinematics of the final state.
        let fk = sim.plant().forward_kinematics(&sim.state().q);
        assert!(
            (sim.pen() - fk).norm() < 1e-14,
            "cached pen {:?} vs {:?}",
            sim.pen(),
            fk
        );
        // Drawn length: six 2 cm segments.
        assert!(
            (trace.length_m() - 0.12).abs() < 2e-3,
            "{transition:?}: length {}",
            trace.length_m()
        );
    }
}

#[test]
fn the_trace_reaches_each_corner_at_the_end_of_its_step() {
    let (sim, out) = run_g(TransitionConfig::MinJerk);
    for o in &out {
        let StepOutcome::Executed(r) = o else {
            unreachable!()
        };
        let last = sim
            .trace()
            .points()
            .iter()
            .rfind(|p| p.t_s <= r.stats.t_end_s + 1e-12)
            .unwrap();
        assert!(
            (last.p - r.target).norm() < 1e-4,
            "step {}: pen at {:?}",
            r.index,
            last.p
        );
    }
}

fn sim_near_right_edge() -> ArmSim {
    let mut cfg = ArmConfig::default();
    cfg.start.x_m = cfg.board.x_max_m - 0.01;
    ArmSim::from_config(&cfg).unwrap()
}

#[test]
fn a_command_off_the_board_is_refused_and_the_arm_holds_still() {
    let mut sim = sim_near_right_edge();
    sim.hold(0.2).unwrap();
    let pen_before = sim.pen();
    let target_before = sim.target();
    let t_before = sim.time_s();
    let err = sim.issue(Command::Right).unwrap_err();
    match &err {
        ArmError::CommandRefused {
            command,
            reason: RefusalReason::OffBoard { x_max_m, .. },
            target,
        } => {
            assert_eq!(*command, Command::Right);
            assert!(target.0 > *x_max_m);
        }
        other => panic!("unexpected {other:?}"),
    }
    assert!(
        err.to_string().contains("right") && err.to_string().contains("board"),
        "{err}"
    );
    assert_eq!(sim.time_s(), t_before);
    assert_eq!(sim.target(), target_before);
    let stats = sim.hold(0.8).unwrap();
    assert!(
        (sim.pen() - pen_before).norm() < 1e-6,
        "the arm moved while holding"
    );
    assert!(stats.final_error_m < 1e-6);
    // The program runner reports the refusal and keeps going.
    let report = sim.run_program(&[Command::Right, Command::Left]);
    assert!(report.stopped.is_none());
    assert!(matches!(
        report.outcomes[0],
        StepOutcome::Refused {
            command: Command::Right,
            ..
        }
    ));
    assert!(matches!(report.outcomes[1], StepOutcome::Executed(_)));
    assert_eq!(report.executed().count(), 1);
    let held = report.outcomes[0].stats();
    assert!(held.final_error_m < 1e-6 && held.t_end_s - held.t_start_s > 0.79);
}

#[test]
fn unreachable_and_singular_targets_are_refused() {
    let mut cfg = ArmConfig::default();
    cfg.board.x_max_m = 0.8;
    cfg.start.x_m = 0.52;
    cfg.start.z_m = 0.0;
    cfg.reference.step_m = 0.04;
    cfg.workspace.min_sin_elbow = 0.0;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let err = sim.issue(Command::Right).unwrap_err();
    assert!(
        matches!(err, ArmError::CommandRefused { reason: RefusalReason::Unreachable { max_m, .. }, .. } if (max_m - 0.55).abs() < 1e-12),
        "{err:?}"
    );
    // From x = 0.47 m (|sin θ2| ≈ 0.89) to 0.51 m (|sin θ2| ≈ 0.70).
    cfg.workspace.min_sin_elbow = 0.75;
    cfg.start.x_m = 0.47;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let err = sim.issue(Command::Right).unwrap_err();
    assert!(
        matches!(
            err,
            ArmError::CommandRefused {
                reason: RefusalReason::NearSingularity { .. },
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn a_path_through_a_joint_limit_is_refused() {
    let mut cfg = ArmConfig::default();
    let sim = ArmSim::from_config(&cfg).unwrap();
    // Put joint 1's upper limit just above the start configuration: going up needs more θ1.
    cfg.link1.joint_max_rad = sim.state().q[0] + 0.01;
    let mut sim = ArmSim::from_config(&cfg).unwrap();
    let err = sim.issue(Command::Up).unwrap_err();
    assert!(
        matches!(
            err,
            ArmError::CommandRefused {
                reason: RefusalReason::JointLimit { joint: 1, .. },
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn a_new_command_during_a_transition_is_refused() {
    let mut sim = ArmSim::from_config(&ArmConfig::default()).unwrap();
    sim.issue(Command::Up).unwrap();
    sim.run_for(0.1).unwrap();
    let err = sim.issue(Command::Left).unwrap_err();
    assert!(matches!(
        err,
        ArmError::CommandRefused { reason: RefusalReason::TransitionInProgress { remaining_s }, .. } if (remaining_s - 0.3).abs() < 1e-9
    ));
    sim.run_for(0.3).unwrap();
    sim.issue(Command::Left).unwrap();
}

#[test]
fn non_finite_inputs_never_reach_the_arm() {
    let mut sim = ArmSim::from_config(&ArmConfig::default()).unwrap();
    let before = *sim.state();
    assert!(matches!(
        sim.issue_target(Vector2::new(f64::NAN, 0.0)),
        Err(ArmError::NonFinite { .. })
    ));
    assert!(matches!(
        sim.issue_target(Vector2::new(0.3, f64::INFINITY)),
        Err(ArmError::NonFinite { .. })
    ));
    assert!(matches!(
        sim.set_state(ArmState {
            q: Vector2::new(f64::NAN, 0.0),
            qd: Vector2::zeros()
        }),
        Err(ArmError::NonFinite { .. })
    ));
    assert_eq!(*sim.state(), before);
    sim.hold(0.1).unwrap();
    assert!(sim
        .samples()
        .iter()
        .all(|s| s.u.iter().all(|u| u.is_finite())));
    // A non-finite step size is a configuration error naming the field.
    let mut cfg = ArmConfig::default();
    cfg.reference.step_m = f64::NAN;
    let err = ArmSim::from_config(&cfg).unwrap_err();
    assert!(err.to_string().contains("reference.step_m"), "{err}");
}

#[test]
fn an_explicit_target_on_the_board_is_reached() {
    let mut sim = ArmSim::from_config(&ArmConfig::default()).unwrap();
    let target = Vector2::new(0.30, 0.12);
    sim.issue_target(target).unwrap();
    let stats = sim.run_for(0.8).unwrap();
    assert!(stats.final_error_m < 1e-4);
    assert!(matches!(
        sim.issue_target(Vector2::new(0.1, 0.0)),
        Err(ArmError::TargetRefused {
            reason: RefusalReason::OffBoard { .. },
            ..
        })
    ));
}

#[test]
fn safety_stop_when_the_plant_is_driven_off_the_board() {
    // A plant much heavier than the controller's model, with a weak shoulder, cannot hold the
    // pen up: the simulation must stop with an error rather than draw off the board.
    let cfg = ArmConfig::default();
    let mut setup = cfg.build().unwrap();
    let mut heavy = cfg;
    heavy.link2.mass_kg = 6.0;
    heavy.link1.torque_limit_n_m = 3.0;
    setup.plant = heavy.model().unwrap();
    let mut sim = ArmSim::new(setup).unwrap();
    let err = sim.hold(5.0).unwrap_err();
    assert!(
        matches!(
            err,
            ArmError::PenLeftBoard { .. } | ArmError::JointLimitViolated { .. }
        ),
        "{err:?}"
    );
    assert!(sim.workspace().board.excess_m(&sim.pen()) <= sim.settings().board_tolerance_m);
    // In a program the stop ends the run and is reported with the outcomes so far.
    let mut sim = ArmSim::new(setup).unwrap();
    let report = sim.run_program(&Command::LETTER_G);
    assert!(report.stopped.is_some());
    assert!(report.outcomes.len() < Command::LETTER_G.len());
}

#[test]
fn commands_parse() {
    assert_eq!(
        parse_commands("up,left, down ,RIGHT,up,left").unwrap(),
        Command::LETTER_G.to_vec()
    );
    assert_eq!(parse_commands("u,l,d,r").unwrap().len(), 4);
    let err = parse_commands("up,sideways").unwrap_err();
    assert!(err.to_string().contains("sideways"));
    for c in Command::ALL {
        assert_eq!(c.name().parse::<Command>().unwrap(), c);
        let moved = c.apply(&Vector2::new(1.0, 2.0), 0.5);
        let expected = match c {
            Command::Up => Vector2::new(1.0, 2.5),
            Command::Down => Vector2::new(1.0, 1.5),
            Command::Left => Vector2::new(0.5, 2.0),
            Command::Right => Vector2::new(1.5, 2.0),
        };
        assert_eq!(moved, expected);
    }
}

#[test]
fn config_round_trips_through_toml() {
    let cfg = ArmConfig::default();
    let text = cfg.to_toml_string();
    let back = ArmConfig::from_toml_str(&text).unwrap();
    assert_eq!(back, cfg);
    // Partial files keep the defaults elsewhere.
    let partial = ArmConfig::from_toml_str(
        "[controller]\nkp_per_s2 = [400.0, 400.0]\n[reference]\ntransition = \"step\"\n",
    )
    .unwrap();
    assert_eq!(partial.controller.kp_per_s2, [400.0, 400.0]);
    assert_eq!(partial.controller.kd_per_s, cfg.controller.kd_per_s);
    assert_eq!(partial.reference.transition, TransitionConfig::Step);
    assert_eq!(partial.link1, cfg.link1);
}

#[test]
fn config_errors_name_the_field() {
    let err = ArmConfig::from_toml_str("[reference]\nstep_mm = 20\n").unwrap_err();
    assert!(matches!(err, ConfigError::Parse { .. }));
    assert!(err.to_string().contains("step_mm"), "{err}");
    let err = ArmConfig::from_toml_str("[sim]\ndt_s = \"fast\"\n").unwrap_err();
    assert!(err.to_string().contains("dt_s"), "{err}");

    let mut cfg = ArmConfig::default();
    cfg.link1.mass_kg = -1.0;
    let err = cfg.build().unwrap_err();
    assert!(
        matches!(err, ConfigError::Invalid { field: "link1.mass_kg", value, .. } if value == -1.0),
        "{err:?}"
    );
    let mut cfg = ArmConfig::default();
    cfg.link2.com_m = 0.3;
    assert!(matches!(
        cfg.build().unwrap_err(),
        ConfigError::Invalid {
            field: "link2.com_m",
            ..
        }
    ));
    let mut cfg = ArmConfig::default();
    cfg.reference.transition_s = 2.0;
    assert!(matches!(
        cfg.build().unwrap_err(),
        ConfigError::Invalid {
            field: "reference.transition_s",
            ..
        }
    ));
    let mut cfg = ArmConfig::default();
    cfg.start.x_m = 0.0;
    assert!(matches!(
        cfg.build().unwrap_err(),
        ConfigError::Start {
            reason: RefusalReason::OffBoard { .. },
            ..
        }
    ));
}

#[test]
fn config_file_errors_name_the_file() {
    let dir = oddball_testkit::TempDir::new("arm-test");
    let path = dir.join("arm.toml");
    std::fs::write(&path, "gravity_m_s2 = 9.81\n[board]\nx_min_m = 0.2\n").unwrap();
    let err = ArmConfig::from_toml_path(&path).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("arm.toml") && msg.contains("x_max_m"), "{msg}");
    let missing = ArmConfig::from_toml_path(&dir.join("nope.toml")).unwrap_err();
    assert!(matches!(missing, ConfigError::Read { .. }));
    // Issue #30: a device (here /dev/zero, whose content never ends) is refused, not read.
    #[cfg(unix)]
    {
        let err = ArmConfig::from_toml_path(std::path::Path::new("/dev/zero")).unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An arm that records no steps (a session's, for hours) still knows where it started: the
/// start's joint angles are the first recorded sample's when steps are recorded.
#[test]
fn the_start_configuration_is_kept_without_recorded_steps() {
    let mut recorded = ArmSim::from_config(&ArmConfig::default()).unwrap();
    recorded.set_recording(true);
    let mut bare = ArmSim::from_config(&ArmConfig::default()).unwrap();
    bare.set_recording(false);
    for sim in [&mut recorded, &mut bare] {
        sim.execute(0, Command::Up).unwrap();
    }
    assert!(bare.samples().is_empty());
    assert_eq!(recorded.samples()[0].q, recorded.start_q());
    assert_eq!(bare.start_q(), recorded.start_q());
    assert!((bare.state().q - bare.start_q()).norm() > 1e-3);
}
