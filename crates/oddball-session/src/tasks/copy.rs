//! The copy task (the person intends given commands in turn), the totals of any task's
//! decisions, and the check that commands keep the pen on the board.

use nalgebra::Vector2;
use oddball_arm::{ArmSim, Command};
use serde::{Deserialize, Serialize};

use crate::decision::Decision;
use crate::SessionError;
use oddball_decode::metrics::Itr;

use super::pilot::Pilot;

/// What a copy task did.
#[derive(Debug)]
pub struct CopyRun {
    pub steps: Vec<Decision>,
    /// The error that ended the task early (one `stop` accepted: a played-back recording
    /// that ran out, say), and whether it came during a decision (else while the arm settled).
    pub stopped: Option<(SessionError, bool)>,
}

/// The copy task (`oddball demo`, `oddball online`): the person intends `commands` in turn,
/// then the arm settles for `settle_s`. With `cycle`, the commands repeat until the pilot has
/// no more data (a replayed recording used up); otherwise each is intended once (and a pilot out
/// of data stops the task early). An error for which `stop` says yes ends the task early with
/// what was done; any other is returned. `each` sees every step as it is made.
pub fn run_copy<P: Pilot>(
    pilot: &mut P,
    commands: &[Command],
    cycle: bool,
    settle_s: f64,
    stop: impl Fn(&SessionError) -> bool,
    mut each: impl FnMut(usize, &Decision),
) -> Result<CopyRun, SessionError> {
    if commands.is_empty() {
        return Err(SessionError::InvalidParameter {
            name: "commands",
            value: "[]".into(),
            reason: "at least one command".into(),
        });
    }
    let mut steps = Vec::new();
    while cycle || steps.len() < commands.len() {
        let step = match pilot.decide(commands[steps.len() % commands.len()]) {
            Ok(Some(step)) => step,
            Ok(None) => break,
            Err(e) if stop(&e) => {
                return Ok(CopyRun {
                    steps,
                    stopped: Some((e, true)),
                })
            }
            Err(e) => return Err(e),
        };
        each(steps.len(), &step);
        steps.push(step);
    }
    let stopped = match pilot.wait(settle_s) {
        Ok(()) => None,
        Err(e) if stop(&e) => Some((e, false)),
        Err(e) => return Err(e),
    };
    Ok(CopyRun { steps, stopped })
}

/// Checks that the commands, each moving the target one step from `arm`'s current target, keep
/// it on the board and in reach; returns the path's vertices. The error names the first vertex
/// at fault and the largest step (a multiple of 0.5 mm, at most the arm's) that fits.
pub fn check_path(
    arm: &ArmSim,
    commands: &[Command],
    what: &str,
) -> Result<Vec<Vector2<f64>>, SessionError> {
    let start = arm.target();
    let step = arm.settings().step_m;
    let off = |step_m: f64| {
        oddball_arm::planned_path(start, commands.iter().copied(), step_m)
            .into_iter()
            .find(|p| {
                arm.workspace()
                    .check_point(arm.plant(), p, arm.elbow())
                    .is_err()
            })
    };
    let Some(at) = off(step) else {
        return Ok(oddball_arm::planned_path(
            start,
            commands.iter().copied(),
            step,
        ));
    };
    const GRAIN_M: f64 = 5e-4;
    let max_step_m = (1..=(step / GRAIN_M).floor() as usize)
        .rev()
        .map(|k| k as f64 * GRAIN_M)
        .find(|&s| s < step && off(s).is_none());
    Err(SessionError::PathOffBoard {
        what: what.to_string(),
        step_m: step,
        start_m: [start[0], start[1]],
        at_m: [at[0], at[1]],
        max_step_m,
    })
}

/// Totals of a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskTotals {
    pub decisions: usize,
    pub correct: usize,
    pub wrong_moves: usize,
    pub abstentions: usize,
    pub accuracy: f64,
    pub wrong_move_rate: f64,
    pub decisions_per_minute: f64,
    pub mean_rounds: f64,
    pub itr: Itr,
}

impl TaskTotals {
    pub fn from_steps(steps: &[Decision]) -> Self {
        let n = steps.len();
        let nf = n.max(1) as f64;
        let correct = steps.iter().filter(|s| s.correct()).count();
        let wrong = steps
            .iter()
            .filter(|s| s.decided.is_some() && !s.correct())
            .count();
        let seconds: f64 = steps.iter().map(|s| s.seconds).sum();
        let accuracy = correct as f64 / nf;
        Self {
            decisions: n,
            correct,
            wrong_moves: wrong,
            abstentions: steps.iter().filter(|s| s.abstained).count(),
            accuracy,
            wrong_move_rate: wrong as f64 / nf,
            decisions_per_minute: if seconds > 0.0 {
                60.0 * n as f64 / seconds
            } else {
                0.0
            },
            mean_rounds: steps.iter().map(|s| s.rounds as f64).sum::<f64>() / nf,
            itr: Itr::new(4, accuracy, seconds / nf),
        }
    }
}

impl std::fmt::Display for TaskTotals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "decisions {}: accuracy {:.1} %, wrong moves {} ({:.1} %), abstentions {}, mean rounds {:.2}, {:.2} decisions/min, ITR {:.2} bits/decision, {:.2} bits/min",
            self.decisions,
            100.0 * self.accuracy,
            self.wrong_moves,
            100.0 * self.wrong_move_rate,
            self.abstentions,
            self.mean_rounds,
            self.decisions_per_minute,
            self.itr.bits_per_selection,
            self.itr.bits_per_minute
        )
    }
}
