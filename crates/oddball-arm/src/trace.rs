//! The pen's trace on the board: a timestamped polyline.

use nalgebra::Vector2;

/// One vertex of the pen trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracePoint {
    /// Simulation time (s).
    pub t_s: f64,
    /// Pen position (x, z) on the board (m).
    pub p: Vector2<f64>,
}

/// The polyline the pen draws. A new vertex is stored when the pen has moved at least
/// `min_spacing_m` from the last one, so resting does not grow the trace.
#[derive(Debug, Clone, PartialEq)]
pub struct PenTrace {
    points: Vec<TracePoint>,
    min_spacing_m: f64,
}

impl PenTrace {
    /// An empty trace that stores vertices at least `min_spacing_m` (m) apart.
    pub fn new(min_spacing_m: f64) -> Self {
        Self {
            points: Vec::new(),
            min_spacing_m: min_spacing_m.max(0.0),
        }
    }

    /// Offers the pen position at time `t_s`; stored if far enough from the last vertex.
    /// Returns whether it was stored.
    pub fn push(&mut self, t_s: f64, p: Vector2<f64>) -> bool {
        let far = self
            .points
            .last()
            .is_none_or(|last| (p - last.p).norm() >= self.min_spacing_m);
        if far {
            self.points.push(TracePoint { t_s, p });
        }
        far
    }

    /// Stores the pen position unconditionally unless it equals the last vertex exactly
    /// (used to close a segment so the final rest position is on the trace).
    pub fn push_exact(&mut self, t_s: f64, p: Vector2<f64>) {
        if self.points.last().is_none_or(|last| last.p != p) {
            self.points.push(TracePoint { t_s, p });
        }
    }

    /// The vertices, in time order.
    pub fn points(&self) -> &[TracePoint] {
        &self.points
    }

    /// Total drawn length (m).
    pub fn length_m(&self) -> f64 {
        self.points
            .windows(2)
            .map(|w| (w[1].p - w[0].p).norm())
            .sum()
    }

    /// Distance (m) from `q` to the nearest point of the polyline (`None` when empty).
    pub fn distance_to(&self, q: &Vector2<f64>) -> Option<f64> {
        match self.points.len() {
            0 => None,
            1 => Some((self.points[0].p - q).norm()),
            _ => self
                .points
                .windows(2)
                .map(|w| point_segment_distance(q, &w[0].p, &w[1].p))
                .reduce(f64::min),
        }
    }
}

/// Distance (m) from point `q` to the segment `a`–`b`.
pub fn point_segment_distance(q: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((q - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - q).norm()
}
