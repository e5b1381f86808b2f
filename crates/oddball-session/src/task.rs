//! Tasks people do with the BCI: point-to-point target tracking, and drawing text.
//!
//! A [`Pilot`] turns an intended direction into a decided command that moves the arm: a live or
//! simulated [`Session`], or a [`ReplayPilot`] of real speller EEG. The tasks choose the
//! intention the way a person would and measure what a BCI study reports.
//!
//! * **Tracking** ([`run_tracking`]): targets on the board's `h`-grid, seeded (each 2–5 steps
//!   from the previous one) or given. The person intends the direction that shrinks the larger
//!   remaining error of the pen's commanded position, so a wrong decision costs a real detour.
//!   A target is reached when the commanded position is on it and the pen has settled within
//!   `tolerance_m`. Metrics per target: success, commands used against the minimum (path
//!   efficiency), wrong moves, abstentions, time to target, decisions per minute, ITR, final
//!   placement error of the pen.
//! * **Drawing** ([`stroke_plan`], [`run_drawing`]): letters and digits from a built-in stroke
//!   font on a grid 2 steps wide and 4 high, starting at the glyph's bottom-left corner. The
//!   board model has no pen-up state, so every glyph is one continuous path that retraces its
//!   own strokes where it must, ends on the baseline at its right edge where it can, and the
//!   travel to the next glyph (down to the baseline, then right to one step past the glyph) is
//!   part of the plan and drawn. The person intends the next planned move; after a wrong
//!   move they intend the way back to the plan. The trace is scored against the planned path
//!   (mean and max distance of the pen from it).

use std::collections::BTreeMap;

use nalgebra::Vector2;
use oddball_arm::{ArmSim, Command};
use oddball_decode::metrics::Itr;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::engine::{Session, Subject, TrialOutcome};
use crate::paradigm::FourBulbParams;
use crate::replay::ReplaySource;
use crate::SessionError;

/// One decision of a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Step {
    pub intended: Command,
    pub decided: Option<Command>,
    pub abstained: bool,
    pub rounds: usize,
    pub confidence: f64,
    /// Seconds the decision took (countdown included).
    pub seconds: f64,
    /// The arm refused the decided command (it would leave the board).
    pub arm_refusal: Option<String>,
    /// Pen (x, z) in metres when the decision was made, before its command (not in reports).
    #[serde(skip)]
    pub pen_m: Option<[f64; 2]>,
}

impl Step {
    pub fn correct(&self) -> bool {
        self.decided == Some(self.intended)
    }
}

/// Something that turns intentions into arm moves.
pub trait Pilot {
    /// One decision while the person intends `intended`; `None` when the source has no more
    /// data (a replayed recording used up).
    fn decide(&mut self, intended: Command) -> Result<Option<Step>, SessionError>;
    fn arm(&self) -> &ArmSim;
    /// Lets time pass (the arm settles).
    fn wait(&mut self, seconds: f64) -> Result<(), SessionError>;
    /// Seconds since the start of the task clock.
    fn time_s(&self) -> f64;
}

impl<S: Subject> Pilot for Session<S> {
    fn decide(&mut self, intended: Command) -> Result<Option<Step>, SessionError> {
        let t = Session::decide(self, Some(intended))?;
        let p = self.params().paradigm;
        Ok(Some(Step {
            intended,
            decided: t.decided().and_then(|c| p.command_of(c)),
            abstained: t.outcome == TrialOutcome::Abstained,
            rounds: t.rounds,
            confidence: t.confidence(),
            seconds: (t.end - t.start) as f64 / self.sfreq(),
            arm_refusal: t.arm_refusal.clone(),
            pen_m: t.pen_m,
        }))
    }

    fn arm(&self) -> &ArmSim {
        Session::arm(self).expect("a task session drives an arm")
    }

    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        self.idle(seconds)
    }

    fn time_s(&self) -> f64 {
        Session::time_s(self)
    }
}

/// Replayed speller EEG driving an arm: each decision lasts its four-bulb panel time.
#[derive(Debug)]
pub struct ReplayPilot {
    source: ReplaySource,
    arm: ArmSim,
    paradigm: FourBulbParams,
}

impl ReplayPilot {
    pub fn new(source: ReplaySource, arm: ArmSim, paradigm: FourBulbParams) -> Self {
        Self {
            source,
            arm,
            paradigm,
        }
    }

    pub fn into_arm(self) -> ArmSim {
        self.arm
    }
}

impl Pilot for ReplayPilot {
    fn decide(&mut self, intended: Command) -> Result<Option<Step>, SessionError> {
        let Some(d) = self.source.decide(intended) else {
            return Ok(None);
        };
        self.arm.run_for(d.seconds)?;
        let pen_m = Some([self.arm.pen()[0], self.arm.pen()[1]]);
        let decided = d.decided(&self.paradigm);
        let arm_refusal = match decided {
            Some(c) => self.arm.issue(c).err().map(|e| e.to_string()),
            None => None,
        };
        Ok(Some(Step {
            intended,
            decided,
            abstained: d.outcome == TrialOutcome::Abstained,
            rounds: d.rounds,
            confidence: d.confidence(),
            seconds: d.seconds,
            arm_refusal,
            pen_m,
        }))
    }

    fn arm(&self) -> &ArmSim {
        &self.arm
    }

    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        self.arm.run_for(seconds)?;
        Ok(())
    }

    fn time_s(&self) -> f64 {
        self.arm.time_s()
    }
}

/// What a copy task did.
#[derive(Debug)]
pub struct CopyRun {
    pub steps: Vec<Step>,
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
    mut each: impl FnMut(usize, &Step),
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
    pub fn from_steps(steps: &[Step]) -> Self {
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
    pub steps: Vec<Step>,
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

/// The stroke font: each glyph a continuous path of unit moves from its bottom-left corner on
/// a grid 2 wide and 4 high (`u`, `d`, `l`, `r`).
fn glyph(c: char) -> Option<&'static str> {
    Some(match c.to_ascii_uppercase() {
        'A' => "uuuurrddllrrdd",
        'B' => "uuuurddrddllrr",
        'C' => "uuuurrlldddd rr",
        'D' => "uuuurdrddldlrr",
        'E' => "uuuurrllddrrllddrr",
        'F' => "uuuurrllddrrlldd",
        'G' => "uuuurrllddddrruulrdd",
        'H' => "uuuuddrruudddd",
        'I' => "rrluuuulrrlddddr",
        'J' => "rruuuuddddllud",
        'K' => "uuuuddruuddrdd",
        'L' => "uuuudddd rr",
        'M' => "uuuurdduurdddd",
        'N' => "uuuurdddruuudddd",
        'O' => "uuuurrddddll rr",
        'P' => "uuuurrddlldd",
        'Q' => "uuuurrddddllrrlurd",
        'R' => "uuuurrddllrdrd",
        'S' => "rruulluurrllddrrdd",
        'T' => "ruuuulrrldddd",
        'U' => "uuuudddd rruuuudddd",
        'V' => "uuuudddrdruuuudddd",
        'W' => "uuuuddddruuddruuuudddd",
        'X' => "ruuuuddlrrlddr",
        'Y' => "ruuluuddrruuddlddr",
        'Z' => "rrlluurruullrrddllddrr",
        '0' => "uuuurrddddll rr",
        '1' => "ruuuudddd r",
        '2' => "uurruullrrddllddrr",
        '3' => "rruulruullrrdddd",
        '4' => "rruuuuddlluuddrrdd",
        '5' => "rruulluurrllddrrdd",
        '6' => "uuuurrllddrrddllrr",
        '7' => "rruuuullrrdddd",
        '8' => "uuuurrddllrrddllrr",
        '9' => "rruuuullddrrdd",
        ' ' => "rr",
        _ => return None,
    })
}

/// A planned move: the command and whether it is travel between glyphs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlannedMove {
    pub command: Command,
    pub travel: bool,
}

/// The moves that draw `text`, glyph after glyph, each glyph starting one step right of the
/// previous glyph's box on the baseline.
pub fn stroke_plan(text: &str) -> Result<Vec<PlannedMove>, SessionError> {
    let mut plan = Vec::new();
    let mut x_box = 0i64; // left edge of the current glyph box, in steps
    let (mut x, mut z) = (0i64, 0i64);
    for (k, c) in text.chars().enumerate() {
        let g = glyph(c).ok_or_else(|| SessionError::InvalidParameter {
            name: "text",
            value: text.to_string(),
            reason: format!("no glyph for {c:?}: the font has A–Z, 0–9 and space"),
        })?;
        if k > 0 {
            // Travel: down to the baseline, right (or left) to the glyph's start.
            for _ in 0..z {
                plan.push(PlannedMove {
                    command: Command::Down,
                    travel: true,
                });
            }
            z = 0;
            let dx = x_box - x;
            let cmd = if dx >= 0 {
                Command::Right
            } else {
                Command::Left
            };
            for _ in 0..dx.abs() {
                plan.push(PlannedMove {
                    command: cmd,
                    travel: true,
                });
            }
            x = x_box;
        }
        for ch in g.chars().filter(|c| !c.is_whitespace()) {
            let command = match ch {
                'u' => Command::Up,
                'd' => Command::Down,
                'l' => Command::Left,
                'r' => Command::Right,
                _ => unreachable!("glyph strings hold u, d, l, r"),
            };
            let v = command.direction();
            x += v[0] as i64;
            z += v[1] as i64;
            plan.push(PlannedMove {
                command,
                travel: false,
            });
        }
        x_box += 3;
    }
    Ok(plan)
}

/// The commands that draw `text` from its first glyph's bottom-left corner: [`stroke_plan`]'s
/// moves, travel between glyphs included (`text_commands("G")` is `oddball demo`'s letter G).
pub fn text_commands(text: &str) -> Result<Vec<Command>, SessionError> {
    Ok(stroke_plan(text)?.iter().map(|m| m.command).collect())
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
    pub steps: Vec<Step>,
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

/// A glyph's box `(x_min, x_max, z_min, z_max)` and end point `(x, z)`, in steps.
pub type GlyphExtent = ((i64, i64, i64, i64), (i64, i64));

/// Extent and end point of every glyph's path.
pub fn glyph_extents() -> BTreeMap<char, GlyphExtent> {
    let chars = ('A'..='Z').chain('0'..='9').chain(std::iter::once(' '));
    chars
        .map(|c| {
            let (mut x, mut z, mut x0, mut x1, mut z0, mut z1) = (0i64, 0i64, 0, 0, 0, 0);
            for ch in glyph(c).expect("in the font").chars() {
                match ch {
                    'u' => z += 1,
                    'd' => z -= 1,
                    'l' => x -= 1,
                    'r' => x += 1,
                    _ => {}
                }
                x0 = x0.min(x);
                x1 = x1.max(x);
                z0 = z0.min(z);
                z1 = z1.max(z);
            }
            (c, ((x0, x1, z0, z1), (x, z)))
        })
        .collect()
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

    #[test]
    fn every_glyph_stays_in_its_box() {
        for (c, ((x0, x1, z0, z1), (x, z))) in glyph_extents() {
            assert!(
                x0 >= 0 && x1 <= 2 && z0 >= 0 && z1 <= 4,
                "{c:?}: x {x0}..{x1} z {z0}..{z1}"
            );
            assert_eq!(z, 0, "{c:?} ends on the baseline");
            if !"FJPT".contains(c) {
                assert_eq!(x, 2, "{c:?} ends at its right edge");
            }
        }
    }

    #[test]
    fn hi_plans_h_travel_and_i() {
        let plan = stroke_plan("HI").unwrap();
        let h = glyph('H').unwrap().len();
        let i = glyph('I').unwrap().len();
        // H ends at (2, 0); I starts at (3, 0): one travel step right.
        assert_eq!(plan.len(), h + 1 + i);
        assert!(plan[h].travel && plan[h].command == Command::Right);
        assert!(plan.iter().filter(|m| m.travel).count() == 1);
        assert!(stroke_plan("H!").is_err());
    }

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
