//! Tracking: the pen steered to targets on the board's grid.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use nalgebra::Vector2;
use oddball_arm::{ArmSim, Command};
use serde::{Deserialize, Serialize};

use crate::decision::Decision;
use crate::SessionError;

use super::copy::TaskTotals;
use super::pilot::Pilot;

/// The direction that shrinks the larger remaining error (x first on ties); `None` on target.
pub fn direction_towards(from: &Vector2<f64>, to: &Vector2<f64>, step_m: f64) -> Option<Command> {
    let d = (to - from) / step_m;
    let (dx, dz) = (d[0].round() as i64, d[1].round() as i64);
    if dx == 0 && dz == 0 {
        None
    } else if dx.abs() >= dz.abs() {
        Some(if dx > 0 {
            Command::Right
        } else {
            Command::Left
        })
    } else {
        Some(if dz > 0 { Command::Up } else { Command::Down })
    }
}

/// Settings of a tracking task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackParams {
    /// Seeded targets to place (ignored when `targets` is given).
    pub n_targets: usize,
    pub seed: u64,
    /// Explicit targets (x, z) in metres; snapped to the `h`-grid through the start position.
    pub targets: Option<Vec<[f64; 2]>>,
    /// The pen must settle this close to the target, metres.
    pub tolerance_m: f64,
    /// Give up on a target after `max_factor × minimum + 4` decisions.
    pub max_factor: usize,
    /// Seconds to wait after the last move before measuring the placement.
    pub settle_s: f64,
}

/// The most targets one tracking task places.
pub const MAX_TARGETS: usize = 1000;

impl TrackParams {
    /// The settings' rules, checked before the task starts: a positive tolerance, at most
    /// [`MAX_TARGETS`] targets, and every given target (snapped to the grid) on the board and in
    /// the arm's reach (a target 100 m away kept the task steering for ever).
    pub fn check(&self, arm: &ArmSim) -> Result<(), SessionError> {
        let bad = |name: &'static str, value: String, reason: String| {
            Err(SessionError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(self.tolerance_m.is_finite() && self.tolerance_m > 0.0) {
            return bad(
                "tolerance_m",
                self.tolerance_m.to_string(),
                "a positive distance".into(),
            );
        }
        if self.max_factor == 0 || self.max_factor > 100 {
            return bad("max_factor", self.max_factor.to_string(), "1 to 100".into());
        }
        let n = self.targets.as_ref().map_or(self.n_targets, Vec::len);
        if n > MAX_TARGETS {
            return bad(
                "targets",
                n.to_string(),
                format!("at most {MAX_TARGETS} targets"),
            );
        }
        if let Some(given) = &self.targets {
            for (p, snapped) in given.iter().zip(task_targets(arm, self)) {
                if let Err(why) = arm
                    .workspace()
                    .check_point(arm.plant(), &snapped, arm.elbow())
                {
                    return bad(
                        "target",
                        format!("{},{}", p[0], p[1]),
                        format!("the pen cannot get there: {why}"),
                    );
                }
            }
        }
        Ok(())
    }
}

impl Default for TrackParams {
    fn default() -> Self {
        Self {
            n_targets: 10,
            seed: 1,
            targets: None,
            tolerance_m: 1e-3,
            max_factor: 3,
            settle_s: 1.0,
        }
    }
}

/// How one target went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetResult {
    pub index: usize,
    pub target_m: [f64; 2],
    pub start_m: [f64; 2],
    pub success: bool,
    /// The source ran out of data while steering to this target.
    pub interrupted: bool,
    pub min_commands: usize,
    pub decisions: usize,
    /// Decisions that moved the arm.
    pub moves: usize,
    pub wrong_moves: usize,
    pub abstentions: usize,
    /// `min_commands / decisions` for a reached target (1 = no detour), else 0.
    pub path_efficiency: f64,
    pub time_to_target_s: f64,
    pub decisions_per_minute: f64,
    /// Distance of the settled pen from the target, metres.
    pub final_error_m: f64,
    /// The commanded positions visited, from the start.
    pub path_m: Vec<[f64; 2]>,
}

/// A tracking task's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackReport {
    pub targets: Vec<TargetResult>,
    /// Targets reached, of those tried to the end.
    pub n_reached: usize,
    pub n_attempted: usize,
    pub totals: TaskTotals,
    pub mean_path_efficiency: f64,
    pub mean_final_error_m: f64,
    pub max_final_error_m: f64,
    pub steps: Vec<Decision>,
    /// The source ran out of data before every target was tried.
    pub exhausted: bool,
}

/// One line per target and the totals, as printed by `oddball task track`.
impl std::fmt::Display for TrackReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for t in &self.targets {
            writeln!(
                f,
                "target {:>2} at ({:.3}, {:.3}) m: {} in {} decisions (minimum {}, efficiency {:.2}), {} wrong, {} abstained, {:.1} s, {:.1} decisions/min, final error {:.3} mm",
                t.index,
                t.target_m[0],
                t.target_m[1],
                if t.interrupted {
                    "interrupted (recording used up)"
                } else if t.success {
                    "reached"
                } else {
                    "NOT reached"
                },
                t.decisions,
                t.min_commands,
                t.path_efficiency,
                t.wrong_moves,
                t.abstentions,
                t.time_to_target_s,
                t.decisions_per_minute,
                t.final_error_m * 1e3
            )?;
        }
        writeln!(
            f,
            "reached {}/{} targets{}; mean path efficiency {:.2}; final placement error mean {:.4} mm, max {:.4} mm",
            self.n_reached,
            self.n_attempted,
            if self.exhausted {
                " (the replayed recording ran out of decisions before the rest)"
            } else {
                ""
            },
            self.mean_path_efficiency,
            self.mean_final_error_m * 1e3,
            self.max_final_error_m * 1e3,
        )?;
        write!(f, "{}", self.totals)
    }
}

fn grid_point(origin: &Vector2<f64>, step: f64, p: &Vector2<f64>) -> Vector2<f64> {
    let k = (p - origin) / step;
    origin + Vector2::new(k[0].round(), k[1].round()) * step
}

/// Seeded targets: each 2–5 grid steps (Manhattan) from the previous one, on the board with a
/// margin of one step and reachable by the arm.
pub fn seeded_targets(arm: &ArmSim, n: usize, seed: u64) -> Vec<Vector2<f64>> {
    let step = arm.settings().step_m;
    let board = arm.workspace().board;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    let mut from = arm.target();
    let ok = |p: &Vector2<f64>| {
        p[0] >= board.x_min_m + step - 1e-9
            && p[0] <= board.x_max_m - step + 1e-9
            && p[1] >= board.z_min_m + step - 1e-9
            && p[1] <= board.z_max_m - step + 1e-9
            && arm
                .workspace()
                .check_point(arm.plant(), p, arm.elbow())
                .is_ok()
    };
    let mut guard = 0;
    while out.len() < n && guard < 100_000 {
        guard += 1;
        let dist = rng.gen_range(2..=5i64);
        let dx = rng.gen_range(-dist..=dist);
        let dz = (dist - dx.abs()) * if rng.gen_bool(0.5) { 1 } else { -1 };
        let p = from + Vector2::new(dx as f64, dz as f64) * step;
        if ok(&p) {
            out.push(p);
            from = p;
        }
    }
    out
}

/// The path a tracking task intends from `start` through `targets` when every decision is
/// right: at each step the direction [`direction_towards`] chooses, metres.
pub fn intended_track_path(
    start: Vector2<f64>,
    targets: &[Vector2<f64>],
    step_m: f64,
) -> Vec<Vector2<f64>> {
    let mut path = vec![start];
    let mut at = start;
    for target in targets {
        while let Some(c) = direction_towards(&at, target, step_m) {
            at = c.apply(&at, step_m);
            path.push(at);
        }
    }
    path
}

/// The targets a tracking task places for `arm` where it stands: the given ones snapped to its
/// step grid, or seeded ones.
pub fn task_targets(arm: &ArmSim, params: &TrackParams) -> Vec<Vector2<f64>> {
    let step = arm.settings().step_m;
    let origin = arm.target();
    match &params.targets {
        Some(t) => t
            .iter()
            .map(|p| grid_point(&origin, step, &Vector2::new(p[0], p[1])))
            .collect(),
        None => seeded_targets(arm, params.n_targets, params.seed),
    }
}

/// Steers the pen to each target in turn.
pub fn run_tracking<P: Pilot>(
    pilot: &mut P,
    params: &TrackParams,
) -> Result<TrackReport, SessionError> {
    params.check(pilot.arm())?;
    let step = pilot.arm().settings().step_m;
    let targets = task_targets(pilot.arm(), params);
    let mut results = Vec::new();
    let mut steps = Vec::new();
    let mut exhausted = false;
    for (index, target) in targets.iter().enumerate() {
        let start = pilot.arm().target();
        let d = (target - start) / step;
        let min_commands = (d[0].round().abs() + d[1].round().abs()) as usize;
        let max_decisions = params.max_factor * min_commands + 4;
        let t0 = pilot.time_s();
        let mut path = vec![[start[0], start[1]]];
        let (mut decisions, mut moves, mut wrong, mut abstentions) = (0, 0, 0, 0);
        let mut decision_seconds = 0.0;
        while decisions < max_decisions {
            let here = pilot.arm().target();
            let Some(intended) = direction_towards(&here, target, step) else {
                break;
            };
            let Some(s) = pilot.decide(intended)? else {
                exhausted = true;
                break;
            };
            decisions += 1;
            decision_seconds += s.seconds;
            if s.decided.is_some() && s.arm_refusal.is_none() {
                moves += 1;
                let now = pilot.arm().target();
                path.push([now[0], now[1]]);
            }
            wrong += usize::from(s.decided.is_some() && !s.correct());
            abstentions += usize::from(s.abstained);
            steps.push(s);
        }
        pilot.wait(params.settle_s)?;
        let on_target = (pilot.arm().target() - target).norm() < 1e-9;
        let final_error_m = (pilot.arm().pen() - target).norm();
        let elapsed = pilot.time_s() - t0;
        results.push(TargetResult {
            index: index + 1,
            target_m: [target[0], target[1]],
            start_m: [start[0], start[1]],
            success: on_target && final_error_m <= params.tolerance_m,
            interrupted: exhausted,
            min_commands,
            decisions,
            moves,
            wrong_moves: wrong,
            abstentions,
            path_efficiency: if !(on_target && final_error_m <= params.tolerance_m) {
                0.0
            } else if decisions > 0 {
                min_commands as f64 / decisions as f64
            } else {
                1.0
            },
            time_to_target_s: elapsed,
            decisions_per_minute: if decision_seconds > 0.0 {
                60.0 * decisions as f64 / decision_seconds
            } else {
                0.0
            },
            final_error_m,
            path_m: path,
        });
        if exhausted {
            break;
        }
    }
    // Metrics over the targets tried to the end (not the one a used-up recording cut short).
    let done: Vec<&TargetResult> = results.iter().filter(|r| !r.interrupted).collect();
    let n = done.len().max(1) as f64;
    Ok(TrackReport {
        n_reached: done.iter().filter(|r| r.success).count(),
        n_attempted: done.len(),
        mean_path_efficiency: done.iter().map(|r| r.path_efficiency).sum::<f64>() / n,
        mean_final_error_m: done.iter().map(|r| r.final_error_m).sum::<f64>() / n,
        max_final_error_m: done.iter().map(|r| r.final_error_m).fold(0.0, f64::max),
        totals: TaskTotals::from_steps(&steps),
        targets: results,
        steps,
        exhausted,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks::font::text_commands;

    #[test]
    fn the_intended_track_path_takes_the_larger_error_first() {
        let h = 0.02;
        let o = Vector2::new(0.0, 0.0);
        let targets = [Vector2::new(2.0 * h, h), Vector2::new(2.0 * h, -h)];
        let path = intended_track_path(o, &targets, h);
        let steps: Vec<[i64; 2]> = path
            .iter()
            .map(|p| [(p[0] / h).round() as i64, (p[1] / h).round() as i64])
            .collect();
        // Right, right (x first on the tie), up; then down twice.
        assert_eq!(steps, [[0, 0], [1, 0], [2, 0], [2, 1], [2, 0], [2, -1]]);
        assert_eq!(text_commands("G").unwrap().len(), 20);
    }

    #[test]
    fn direction_shrinks_the_larger_error() {
        let o = Vector2::new(0.0, 0.0);
        let h = 0.02;
        assert_eq!(
            direction_towards(&o, &Vector2::new(0.06, 0.02), h),
            Some(Command::Right)
        );
        assert_eq!(
            direction_towards(&o, &Vector2::new(0.0, -0.04), h),
            Some(Command::Down)
        );
        assert_eq!(direction_towards(&o, &Vector2::new(0.001, 0.0), h), None);
    }
}
