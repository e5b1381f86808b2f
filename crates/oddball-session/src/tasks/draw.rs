//! Drawing text with the stroke font; the trace scored against the plan.

use nalgebra::Vector2;
use oddball_arm::{ArmSim, Command};
use serde::{Deserialize, Serialize};

use crate::decision::Decision;
use crate::SessionError;

use super::copy::{check_path, TaskTotals};
use super::font::{stroke_plan, PlannedMove};
use super::pilot::Pilot;
use super::track::direction_towards;

/// The vertices of the path that draws `text` from `arm`'s current target, metres.
pub fn drawing_path(arm: &ArmSim, text: &str) -> Result<Vec<Vector2<f64>>, SessionError> {
    let moves = stroke_plan(text)?;
    Ok(oddball_arm::planned_path(
        arm.target(),
        moves.iter().map(|m| m.command),
        arm.settings().step_m,
    ))
}

/// Checks, before any EEG work, that `text` drawn from `arm`'s current target stays on the board
/// and in the arm's reach; returns its path (as [`drawing_path`]).
pub fn check_drawing(arm: &ArmSim, text: &str) -> Result<Vec<Vector2<f64>>, SessionError> {
    let moves: Vec<Command> = stroke_plan(text)?.iter().map(|m| m.command).collect();
    check_path(arm, &moves, &format!("the text {text:?}"))
}

/// A drawing task's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DrawReport {
    pub text: String,
    pub plan: Vec<PlannedMove>,
    /// The planned path's vertices, metres (from the start position).
    pub plan_path_m: Vec<[f64; 2]>,
    /// Decisions spent, and how many were needed.
    pub decisions: usize,
    pub min_decisions: usize,
    pub completed: bool,
    pub steps: Vec<Decision>,
    pub totals: TaskTotals,
    /// Distance of the pen trace from the planned path: mean and max over trace points, m.
    pub mean_deviation_m: f64,
    pub max_deviation_m: f64,
}

/// Draws `text` at the arm's current position. The plan must fit on the board.
pub fn run_drawing<P: Pilot>(
    pilot: &mut P,
    text: &str,
    max_factor: usize,
    settle_s: f64,
) -> Result<DrawReport, SessionError> {
    let plan = stroke_plan(text)?;
    let step = pilot.arm().settings().step_m;
    let path = check_drawing(pilot.arm(), text)?;
    let max_decisions = max_factor * plan.len() + 4;
    let mut steps = Vec::new();
    let mut k = 0; // next planned vertex to reach
    let mut completed = plan.is_empty();
    while !completed && steps.len() < max_decisions {
        let here = pilot.arm().target();
        // On the plan at vertex k: intend the next planned move; else head back to vertex k.
        let intended = if (here - path[k]).norm() < 1e-9 {
            plan[k].command
        } else {
            direction_towards(&here, &path[k], step).expect("off the plan")
        };
        let Some(s) = pilot.decide(intended)? else {
            break;
        };
        steps.push(s);
        if (pilot.arm().target() - path[k + 1]).norm() < 1e-9 {
            k += 1;
            completed = k == plan.len();
        }
    }
    pilot.wait(settle_s)?;
    let trace = pilot.arm().trace().points();
    let mut dists = Vec::new();
    for p in trace {
        let d = path
            .windows(2)
            .map(|w| oddball_arm::trace::point_segment_distance(&p.p, &w[0], &w[1]))
            .fold(f64::INFINITY, f64::min);
        let d = if path.len() == 1 {
            (p.p - path[0]).norm()
        } else {
            d
        };
        dists.push(d);
    }
    let n = dists.len().max(1) as f64;
    Ok(DrawReport {
        text: text.to_string(),
        plan_path_m: path.iter().map(|p| [p[0], p[1]]).collect(),
        decisions: steps.len(),
        min_decisions: plan.len(),
        completed,
        totals: TaskTotals::from_steps(&steps),
        steps,
        plan,
        mean_deviation_m: dists.iter().sum::<f64>() / n,
        max_deviation_m: dists.iter().copied().fold(0.0, f64::max),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm_with_step(step_m: f64) -> ArmSim {
        let mut config = oddball_arm::ArmConfig::default();
        config.reference.step_m = step_m;
        ArmSim::from_config(&config).unwrap()
    }

    #[test]
    fn a_drawing_off_the_board_names_the_largest_step_that_fits() {
        let arm = arm_with_step(0.02);
        let Err(SessionError::PathOffBoard {
            at_m, max_step_m, ..
        }) = check_drawing(&arm, "HELLO")
        else {
            panic!("HELLO at 20 mm fits the board?");
        };
        assert!(!arm
            .workspace()
            .board
            .contains(&Vector2::new(at_m[0], at_m[1])));
        let m = max_step_m.expect("a smaller step fits");
        assert!(
            m < 0.02 && (m / 5e-4 - (m / 5e-4).round()).abs() < 1e-9,
            "{m}"
        );
        // At that step every vertex is on the board; half a millimetre more, one is not.
        let path = check_drawing(&arm_with_step(m), "HELLO").expect("fits at the step named");
        let board = arm.workspace().board;
        assert!(path.iter().all(|p| board.contains(p)));
        assert!(check_drawing(&arm_with_step(m + 5e-4), "HELLO").is_err());
        // What fits is returned as drawing_path plans it.
        assert_eq!(
            check_drawing(&arm, "HI").unwrap(),
            drawing_path(&arm, "HI").unwrap()
        );
    }
}
