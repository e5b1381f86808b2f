//! Direction commands and the desired pen trajectory `p_d(t)`, `ṗ_d(t)`, `p̈_d(t)` they produce.

use std::fmt;
use std::str::FromStr;

use nalgebra::Vector2;

/// A direction command from the BCI. Each moves the desired pen position by one step `h` (m).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Command {
    /// `z + h`.
    Up,
    /// `z − h`.
    Down,
    /// `x − h`.
    Left,
    /// `x + h`.
    Right,
}

impl Command {
    /// All four commands.
    pub const ALL: [Command; 4] = [Command::Up, Command::Down, Command::Left, Command::Right];

    /// The paper's letter G as its six commands: up, left, down, right, up, left. The paper's
    /// strokes differ in length; on equal steps these trace a square one and a half times
    /// (`oddball_session::tasks::text_commands("G")` draws a G on the step grid).
    pub const LETTER_G: [Command; 6] = [
        Command::Up,
        Command::Left,
        Command::Down,
        Command::Right,
        Command::Up,
        Command::Left,
    ];

    /// Unit direction (x, z) of the command.
    pub fn direction(self) -> Vector2<f64> {
        match self {
            Command::Up => Vector2::new(0.0, 1.0),
            Command::Down => Vector2::new(0.0, -1.0),
            Command::Left => Vector2::new(-1.0, 0.0),
            Command::Right => Vector2::new(1.0, 0.0),
        }
    }

    /// The target reached from `from` (m) with a step of `step_m` (m).
    pub fn apply(self, from: &Vector2<f64>, step_m: f64) -> Vector2<f64> {
        from + self.direction() * step_m
    }

    /// Lower-case name, as parsed by [`FromStr`].
    pub fn name(self) -> &'static str {
        match self {
            Command::Up => "up",
            Command::Down => "down",
            Command::Left => "left",
            Command::Right => "right",
        }
    }
}

/// The planned path of `commands` from `start`: `start`, then the target each command reaches
/// from the previous one, steps of `step_m` (m).
pub fn planned_path(
    start: Vector2<f64>,
    commands: impl IntoIterator<Item = Command>,
    step_m: f64,
) -> Vec<Vector2<f64>> {
    let mut path = vec![start];
    for c in commands {
        let next = c.apply(path.last().expect("non-empty"), step_m);
        path.push(next);
    }
    path
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A word that is not one of `up`, `down`, `left`, `right`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown arm command `{0}` (expected up, down, left or right)")]
pub struct UnknownCommand(pub String);

impl FromStr for Command {
    type Err = UnknownCommand;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "up" | "u" => Ok(Command::Up),
            "down" | "d" => Ok(Command::Down),
            "left" | "l" => Ok(Command::Left),
            "right" | "r" => Ok(Command::Right),
            _ => Err(UnknownCommand(s.to_string())),
        }
    }
}

/// Parses a comma-separated list such as `up,left,down`.
pub fn parse_commands(list: &str) -> Result<Vec<Command>, UnknownCommand> {
    list.split(',')
        .filter(|w| !w.trim().is_empty())
        .map(str::parse)
        .collect()
}

/// How the reference moves from one target to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransitionKind {
    /// A jump of `p_d` to the target, with `ṗ_d = p̈_d = 0`.
    Step,
    /// A fifth-order minimum-jerk polynomial lasting `duration_s` seconds; `p_d`, `ṗ_d`, `p̈_d`
    /// are continuous and start and end at rest.
    MinimumJerk { duration_s: f64 },
}

/// The desired pen position (m), velocity (m/s) and acceleration (m/s²) at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSample {
    pub p: Vector2<f64>,
    pub v: Vector2<f64>,
    pub a: Vector2<f64>,
}

impl ReferenceSample {
    /// Holding still at `p`.
    pub fn hold(p: Vector2<f64>) -> Self {
        Self {
            p,
            v: Vector2::zeros(),
            a: Vector2::zeros(),
        }
    }
}

/// One transition of the reference from `from` to `to`, starting at `t0_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    pub from: Vector2<f64>,
    pub to: Vector2<f64>,
    pub t0_s: f64,
    pub kind: TransitionKind,
}

/// Minimum-jerk profile `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` and its first two derivatives in τ.
#[inline]
pub fn minimum_jerk(tau: f64) -> (f64, f64, f64) {
    let t = tau.clamp(0.0, 1.0);
    let t2 = t * t;
    let t3 = t2 * t;
    (
        t3 * (10.0 - 15.0 * t + 6.0 * t2),
        30.0 * t2 * (1.0 - 2.0 * t + t2),
        60.0 * t * (1.0 - 3.0 * t + 2.0 * t2),
    )
}

impl Transition {
    /// A transition that has already ended at `p` (holding still).
    pub fn hold(p: Vector2<f64>) -> Self {
        Self {
            from: p,
            to: p,
            t0_s: f64::NEG_INFINITY,
            kind: TransitionKind::Step,
        }
    }

    /// Time (s) at which the reference reaches its target.
    pub fn end_time_s(&self) -> f64 {
        match self.kind {
            TransitionKind::Step => self.t0_s,
            TransitionKind::MinimumJerk { duration_s } => self.t0_s + duration_s,
        }
    }

    /// The reference at time `t_s`.
    #[inline]
    pub fn sample(&self, t_s: f64) -> ReferenceSample {
        match self.kind {
            TransitionKind::Step => {
                ReferenceSample::hold(if t_s >= self.t0_s { self.to } else { self.from })
            }
            TransitionKind::MinimumJerk { duration_s } => {
                let tau = (t_s - self.t0_s) / duration_s;
                if tau <= 0.0 {
                    return ReferenceSample::hold(self.from);
                }
                if tau >= 1.0 {
                    return ReferenceSample::hold(self.to);
                }
                let d = self.to - self.from;
                let (s, sd, sdd) = minimum_jerk(tau);
                ReferenceSample {
                    p: self.from + d * s,
                    v: d * (sd / duration_s),
                    a: d * (sdd / (duration_s * duration_s)),
                }
            }
        }
    }
}
