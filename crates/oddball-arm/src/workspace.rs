//! Where the pen may go: the board's rectangle intersected with the part of the arm's workspace
//! that is reachable within the joint limits, with the current elbow configuration, away from
//! singularities.

use nalgebra::Vector2;

use crate::error::{ConfigError, RefusalReason};
use crate::model::{ArmModel, Elbow};

/// The drawing board: an axis-aligned rectangle in the x–z plane (metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Board {
    pub x_min_m: f64,
    pub x_max_m: f64,
    pub z_min_m: f64,
    pub z_max_m: f64,
}

impl Board {
    /// A board, validated (finite, non-empty).
    pub fn new(
        x_min_m: f64,
        x_max_m: f64,
        z_min_m: f64,
        z_max_m: f64,
    ) -> Result<Self, ConfigError> {
        for (field, v) in [
            ("board.x_min_m", x_min_m),
            ("board.x_max_m", x_max_m),
            ("board.z_min_m", z_min_m),
            ("board.z_max_m", z_max_m),
        ] {
            if !v.is_finite() {
                return Err(ConfigError::Invalid {
                    field,
                    value: v,
                    reason: "must be finite",
                });
            }
        }
        if x_max_m <= x_min_m {
            return Err(ConfigError::Invalid {
                field: "board.x_max_m",
                value: x_max_m,
                reason: "must exceed board.x_min_m",
            });
        }
        if z_max_m <= z_min_m {
            return Err(ConfigError::Invalid {
                field: "board.z_max_m",
                value: z_max_m,
                reason: "must exceed board.z_min_m",
            });
        }
        Ok(Self {
            x_min_m,
            x_max_m,
            z_min_m,
            z_max_m,
        })
    }

    /// Whether `p` (m) lies on the board (edges included).
    pub fn contains(&self, p: &Vector2<f64>) -> bool {
        (self.x_min_m..=self.x_max_m).contains(&p[0])
            && (self.z_min_m..=self.z_max_m).contains(&p[1])
    }

    /// How far (m) `p` lies outside the board; zero on it.
    pub fn excess_m(&self, p: &Vector2<f64>) -> f64 {
        let dx = (self.x_min_m - p[0]).max(p[0] - self.x_max_m).max(0.0);
        let dz = (self.z_min_m - p[1]).max(p[1] - self.z_max_m).max(0.0);
        (dx * dx + dz * dz).sqrt()
    }

    /// The four corners, counter-clockwise from (x_min, z_min).
    pub fn corners(&self) -> [Vector2<f64>; 4] {
        [
            Vector2::new(self.x_min_m, self.z_min_m),
            Vector2::new(self.x_max_m, self.z_min_m),
            Vector2::new(self.x_max_m, self.z_max_m),
            Vector2::new(self.x_min_m, self.z_max_m),
        ]
    }

    fn off_board(&self) -> RefusalReason {
        RefusalReason::OffBoard {
            x_min_m: self.x_min_m,
            x_max_m: self.x_max_m,
            z_min_m: self.z_min_m,
            z_max_m: self.z_max_m,
        }
    }
}

/// The admissible region for the pen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workspace {
    pub board: Board,
    /// Smallest admissible `|sin θ2|` (normalised manipulability) along a path.
    pub min_sin_elbow: f64,
}

/// Spacing (m) of the points checked along a straight path.
const PATH_CHECK_SPACING_M: f64 = 1e-3;

impl Workspace {
    /// Checks one point: on the board, inverse kinematics with `elbow` exists, joints within
    /// limits, away from singularities. Returns the joint angles (rad) on success.
    pub fn check_point(
        &self,
        model: &ArmModel,
        p: &Vector2<f64>,
        elbow: Elbow,
    ) -> Result<Vector2<f64>, RefusalReason> {
        if !self.board.contains(p) {
            return Err(self.board.off_board());
        }
        self.check_reachable(model, p, elbow)
    }

    /// Like [`Workspace::check_point`] without the board test.
    pub fn check_reachable(
        &self,
        model: &ArmModel,
        p: &Vector2<f64>,
        elbow: Elbow,
    ) -> Result<Vector2<f64>, RefusalReason> {
        let at = (p[0], p[1]);
        let (min_m, max_m) = model.reach_m();
        let q = model
            .inverse_kinematics(p, elbow)
            .map_err(|_| RefusalReason::Unreachable {
                at,
                distance_m: (p - model.base()).norm(),
                min_m,
                max_m,
            })?;
        let sin_elbow = q[1].sin().abs();
        if sin_elbow < self.min_sin_elbow {
            return Err(RefusalReason::NearSingularity {
                at,
                sin_elbow,
                min: self.min_sin_elbow,
            });
        }
        if let Some((joint, angle_rad)) = model.check_joint_limits(&q) {
            let l = &model.links()[joint];
            return Err(RefusalReason::JointLimit {
                at,
                joint: joint + 1,
                angle_rad,
                min_rad: l.joint_min_rad,
                max_rad: l.joint_max_rad,
            });
        }
        Ok(q)
    }

    /// Checks the straight path from `from` to `to` (m): the target must be on the board (the
    /// board is convex, so the whole segment then is), and every point of the segment, checked
    /// at 1 mm spacing and at both ends, must be reachable with `elbow`.
    pub fn check_path(
        &self,
        model: &ArmModel,
        from: &Vector2<f64>,
        to: &Vector2<f64>,
        elbow: Elbow,
    ) -> Result<(), RefusalReason> {
        if !self.board.contains(to) {
            return Err(self.board.off_board());
        }
        let len = (to - from).norm();
        let n = ((len / PATH_CHECK_SPACING_M).ceil() as usize).max(1);
        for k in 0..=n {
            let p = from + (to - from) * (k as f64 / n as f64);
            self.check_reachable(model, &p, elbow)?;
        }
        Ok(())
    }
}
