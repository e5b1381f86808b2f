//! Arm safety under any command sequence: the pen never leaves the board, torques never pass
//! their limits, and a refused command (off the board, or during a move) or an abstention
//! leaves the arm holding still.

use oddball_arm::{ArmConfig, ArmSim, Command};
use proptest::prelude::*;

fn arb_command() -> impl Strategy<Value = Option<Command>> {
    prop_oneof![
        Just(Some(Command::Up)),
        Just(Some(Command::Down)),
        Just(Some(Command::Left)),
        Just(Some(Command::Right)),
        // An abstention: no command.
        Just(None),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn no_command_sequence_leaves_the_board_or_exceeds_a_torque_limit(
        program in proptest::collection::vec((arb_command(), 0.05f64..1.2), 1..40),
        big_steps in any::<bool>(),
    ) {
        let mut config = ArmConfig::default();
        if big_steps {
            // Steps of 8 cm reach the board's edges within a few commands.
            config.reference.step_m = 0.08;
        }
        let mut sim = ArmSim::from_config(&config).unwrap();
        sim.set_recording(true);
        let board = sim.workspace().board;
        let limits = [
            sim.plant().links()[0].torque_limit_n_m,
            sim.plant().links()[1].torque_limit_n_m,
        ];
        for (command, wait_s) in program {
            let before = sim.target();
            match command {
                Some(c) => {
                    if sim.issue(c).is_err() {
                        // Refused: the reference did not move.
                        prop_assert_eq!(sim.target(), before);
                    }
                }
                None => prop_assert_eq!(sim.target(), before),
            }
            // A safety stop would be an error here: the invariant is that it never happens.
            sim.run_for(wait_s).unwrap();
        }
        sim.run_for(1.0).unwrap();
        let tol = sim.settings().board_tolerance_m;
        for s in sim.samples() {
            prop_assert!(board.excess_m(&s.p) <= tol, "pen {:?} off the board", s.p);
            for (j, limit) in limits.iter().enumerate() {
                prop_assert!(s.u[j].abs() <= limit + 1e-12, "joint {} torque {}", j + 1, s.u[j]);
            }
            prop_assert!(s.q.iter().chain(s.qd.iter()).all(|v| v.is_finite()));
        }
        // At rest after the last wait: the pen sits on the reference.
        prop_assert!((sim.pen() - sim.target()).norm() < 1e-3);
        prop_assert!(board.contains(&sim.target()));
    }
}
