//! The arm on its board at key instants and the pen trace over the path it should draw
//! (`oddball arm`'s `arm.png`, the reports' `pen_trace.png`): in a session, the intended path
//! and the executed one apart, with the decisions that left the intended path marked.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::{
    Cartesian2d, ChartBuilder, ChartContext, DrawingArea, DrawingBackend, RGBColor,
};

use crate::PlotError;
use oddball_arm::trace::point_segment_distance;
use oddball_arm::{ArmModel, ArmSim, Board, Vector2};
use oddball_session::report::{Miss, MissedDecision};

/// What a session's pen picture draws under and over the trace.
#[derive(Debug, Clone, Copy)]
pub struct SessionPaths<'a> {
    /// What the person meant to draw (the intended commands, a task's plan), metres.
    pub intended: &'a [Vector2<f64>],
    /// Where the executed commands put the reference, metres.
    pub executed: &'a [Vector2<f64>],
    /// The decisions that did not move the pen as intended.
    pub missed: &'a [MissedDecision],
    /// Number the intended path's corners (0 the start, k after the k-th intended move): in a
    /// copy task corner k is where decision k should leave the pen; a task that re-plans after
    /// a wrong move marks them unnumbered.
    pub numbered: bool,
}

/// The arm at the start and at the end of a session over the pen trace, the intended and the
/// executed paths, and the wrong, abstained and refused decisions: a report's `pen_trace.png`.
pub fn draw_pen_trace(
    arm: &ArmSim,
    paths: &SessionPaths<'_>,
    path: &Path,
) -> Result<(), PlotError> {
    let keys = configurations_at(arm, &[0.0, arm.time_s()]);
    draw_with(arm, &keys, Some(paths), paths.intended, None, path)
}

/// The pen panel of [`draw_pen_trace`] alone, square, under `title`: the drawing task's
/// `task.png`.
pub fn draw_pen_paths(
    arm: &ArmSim,
    paths: &SessionPaths<'_>,
    title: &str,
    path: &Path,
) -> Result<(), PlotError> {
    draw_with(arm, &[], Some(paths), paths.intended, Some(title), path)
}

/// The pen's recorded positions (x, z), metres.
pub(crate) fn pen_trace_xz(sim: &ArmSim) -> Vec<(f64, f64)> {
    sim.trace()
        .points()
        .iter()
        .map(|p| (p.p[0], p.p[1]))
        .collect()
}

/// Joint angles at the given simulation times: the recorded samples nearest to them; without
/// recorded samples, the start's at time 0 and the current ones at any other time.
pub fn configurations_at(sim: &ArmSim, times: &[f64]) -> Vec<(f64, Vector2<f64>)> {
    let samples = sim.samples();
    let dt = sim.settings().dt_s;
    times
        .iter()
        .map(|&t| {
            let i = (t / dt).round() as usize;
            let q = match samples.get(i) {
                Some(s) => s.q,
                None if i == 0 => sim.start_q(),
                None => sim.state().q,
            };
            (t, q)
        })
        .collect()
}

/// Axis ranges around `points` with a margin, widened so that one metre is as long on x as on
/// z in a `w`×`h` pixel area.
fn equal_aspect(points: &[Vector2<f64>], margin: f64, w: u32, h: u32) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut z0, mut z1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        z0 = z0.min(p[1]);
        z1 = z1.max(p[1]);
    }
    let (cx, cz) = ((x0 + x1) / 2.0, (z0 + z1) / 2.0);
    let (mut hw, mut hh) = ((x1 - x0) / 2.0 + margin, (z1 - z0) / 2.0 + margin);
    let aspect = f64::from(w) / f64::from(h);
    if hw / hh < aspect {
        hw = hh * aspect;
    } else {
        hh = hw / aspect;
    }
    ((cx - hw, cx + hw), (cz - hh, cz + hh))
}

/// Axis tick text in metres, without a "-0.000".
fn tick(v: f64) -> String {
    let v = if v.abs() < 1e-9 { 0.0 } else { v };
    format!("{v:.3}")
}

/// A chart of the board's x–z plane in metres on `area` over `x` × `z`, captioned `caption` at
/// `caption_size` points, its mesh drawn; `fine`: ticks in millimetres ([`tick`]) and a light
/// grid.
pub(crate) fn xz_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: &str,
    caption_size: u32,
    x: Range<f64>,
    z: Range<f64>,
    fine: bool,
    path: &Path,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, PlotError> {
    let err = |e: &dyn std::fmt::Debug| PlotError::draw(path, format!("{e:?}"));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (crate::FONT_FAMILY, caption_size))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x, z)
        .map_err(|e| err(&e))?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc("x (m)")
        .y_desc("z (m)")
        .label_style((crate::FONT_FAMILY, 13));
    if fine {
        mesh.x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .light_line_style(RGBColor(235, 235, 235));
    }
    mesh.draw().map_err(|e| err(&e))?;
    Ok(chart)
}

/// Ramer–Douglas–Peucker simplification: drops vertices closer than `tolerance` to the segment
/// between the kept neighbours, so every vertex of the data lies within `tolerance` of the drawn
/// line. The distance is to the segment, not to the line through its ends: an out-and-back
/// stroke (the spur of a G, the bar of an I) lies on the line of its own chord, and measured to
/// that line its tip looked redundant and was dropped, leaving the drawn stroke millimetres
/// short of where the pen went.
#[cfg(test)]
fn simplify(points: &[(f64, f64)], tolerance: f64) -> Vec<(f64, f64)> {
    simplify_by(
        points.len(),
        |i| Vector2::new(points[i].0, points[i].1),
        tolerance,
    )
}

/// [`simplify`] of the `n` points `at(0)`, … `at(n − 1)`, read where they are (a session's
/// pen trace is not copied to be drawn).
fn simplify_by(n: usize, at: impl Fn(usize) -> Vector2<f64>, tolerance: f64) -> Vec<(f64, f64)> {
    let xz = |i: usize| {
        let p = at(i);
        (p[0], p[1])
    };
    if n < 3 {
        return (0..n).map(xz).collect();
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0, n - 1)];
    while let Some((a, b)) = stack.pop() {
        let (pa, pb) = (at(a), at(b));
        let mut worst = (0.0, a);
        for i in a + 1..b {
            let d = point_segment_distance(&at(i), &pa, &pb);
            if d > worst.0 {
                worst = (d, i);
            }
        }
        if worst.0 > tolerance {
            keep[worst.1] = true;
            stack.push((a, worst.1));
            stack.push((worst.1, b));
        }
    }
    (0..n).filter(|&i| keep[i]).map(xz).collect()
}

/// The pen trace as a picture draws it: the recorded positions simplified to `tolerance_m`
/// (every recorded position lies within `tolerance_m` of the returned polyline).
pub fn drawn_pen_trace(sim: &ArmSim, tolerance_m: f64) -> Vec<(f64, f64)> {
    let points = sim.trace().points();
    simplify_by(points.len(), |i| points[i].p, tolerance_m)
}

/// Corner labels "0", "1", … with corners visited more than once labelled together ("0, 4").
fn corner_labels(corners: &[Vector2<f64>]) -> Vec<(Vector2<f64>, String)> {
    let mut out: Vec<(Vector2<f64>, String)> = Vec::new();
    for (i, c) in corners.iter().enumerate() {
        match out.iter_mut().find(|(p, _)| (p - c).norm() < 1e-9) {
            Some((_, label)) => {
                let _ = write!(label, ", {i}");
            }
            None => out.push((*c, i.to_string())),
        }
    }
    out
}

fn arm_points(model: &ArmModel, q: &Vector2<f64>) -> [(f64, f64); 3] {
    let b = model.base();
    let e = model.elbow_position(q);
    let p = model.forward_kinematics(q);
    [(b[0], b[1]), (e[0], e[1]), (p[0], p[1])]
}

fn board_rect(board: &Board) -> [(f64, f64); 2] {
    [
        (board.x_min_m, board.z_min_m),
        (board.x_max_m, board.z_max_m),
    ]
}

/// Draws the arm at the `keys` instants (the start and the end of each command) on its board
/// (left) and the pen trace over the `expected` path of the commands (right, zoomed):
/// `oddball arm`'s picture.
pub fn draw(
    sim: &ArmSim,
    keys: &[(f64, Vector2<f64>)],
    expected: &[Vector2<f64>],
    path: &Path,
) -> Result<(), PlotError> {
    draw_with(sim, keys, None, expected, None, path)
}

/// The colour of a missed decision's mark and the words of its legend entry.
fn miss_style(miss: Miss) -> (plotters::style::RGBColor, &'static str) {
    use plotters::style::RGBColor;
    match miss {
        Miss::Wrong => (RGBColor(210, 30, 30), "wrong"),
        Miss::Abstained => (RGBColor(110, 110, 110), "abstained"),
        Miss::Refused => (RGBColor(140, 50, 170), "refused"),
    }
}

/// The two panels, or with `zoom_only` the pen panel alone under that title. With `session`,
/// the poses are the start and the end, `expected` is the intended path and the executed path
/// and missed decisions are drawn too; without, the poses are those of every command and
/// `expected` is the commanded path.
fn draw_with(
    sim: &ArmSim,
    keys: &[(f64, Vector2<f64>)],
    session: Option<&SessionPaths<'_>>,
    expected: &[Vector2<f64>],
    zoom_only: Option<&str>,
    path: &Path,
) -> Result<(), PlotError> {
    let (w, h, panel_w) = match zoom_only {
        Some(_) => (900u32, 900u32, 900 - 90),
        None => (1500, 720, 1500 / 2 - 90),
    };
    let model = *sim.plant();
    let board = sim.workspace().board;
    let xy = |v: &[Vector2<f64>]| -> Vec<(f64, f64)> { v.iter().map(|p| (p[0], p[1])).collect() };
    let expected_xy = xy(expected);
    let executed_xy = session.map(|s| xy(s.executed));
    let missed: &[MissedDecision] = session.map_or(&[], |s| s.missed);

    let mut overview_pts: Vec<Vector2<f64>> = board.corners().to_vec();
    overview_pts.push(model.base());
    for (_, q) in keys {
        overview_pts.push(model.elbow_position(q));
    }
    let mut zoom_pts: Vec<Vector2<f64>> = expected.to_vec();
    if let Some(s) = session {
        zoom_pts.extend(s.executed);
    }
    zoom_pts.extend(sim.trace().points().iter().map(|p| p.p));
    let zoom_extent = zoom_pts
        .iter()
        .flat_map(|p| {
            (zoom_pts[0] - p)
                .iter()
                .map(|v| v.abs())
                .collect::<Vec<_>>()
        })
        .fold(0.0f64, f64::max);
    let zoom_margin = (0.15 * zoom_extent).max(0.002);
    // Head-room above the drawing for the legend.
    if let Some(top) = zoom_pts.iter().map(|p| p[1]).reduce(f64::max) {
        zoom_pts.push(Vector2::new(
            zoom_pts[0][0],
            top + 0.3 * zoom_extent.max(0.01),
        ));
    }
    let (path_label, left_title, mut zoom_title) = match session {
        None => (
            "commanded path",
            "Arm and board (start and end of each command)".to_string(),
            "Pen trace and commanded path (zoom)".to_string(),
        ),
        Some(_) => {
            let count = |m: Miss| missed.iter().filter(|d| d.miss == m).count();
            let mut t = format!(
                "Pen, intended and executed paths (zoom): {} wrong, {} abstained",
                count(Miss::Wrong),
                count(Miss::Abstained)
            );
            if count(Miss::Refused) > 0 {
                let _ = write!(t, ", {} refused", count(Miss::Refused));
            }
            (
                "intended path",
                "Arm and board (at the start and at the end)".to_string(),
                t,
            )
        }
    };

    if let Some(t) = zoom_only {
        zoom_title = t.to_string();
    }

    crate::with_backend!(path, (w, h), |root| {
        use plotters::prelude::*;
        let err = |e: &dyn std::fmt::Debug| PlotError::draw(path, format!("{e:?}"));
        let (left, right) = root.split_horizontally(w / 2);
        let n_keys = keys.len().max(2);
        let key_colour = |i: usize| {
            let f = i as f64 / (n_keys - 1) as f64;
            HSLColor(0.62 - 0.62 * f, 0.75, 0.42)
        };

        let zoom_panel = (
            if zoom_only.is_some() { &root } else { &right },
            zoom_title.as_str(),
            &zoom_pts,
            zoom_margin,
            true,
        );
        let panels = match zoom_only {
            Some(_) => vec![zoom_panel],
            None => vec![
                (&left, left_title.as_str(), &overview_pts, 0.04, false),
                zoom_panel,
            ],
        };
        for (area, title, pts, margin, zoomed) in panels {
            let (xr, zr) = equal_aspect(pts, margin, panel_w, h - 110);
            let mut chart = xz_chart(area, title, 20, xr.0..xr.1, zr.0..zr.1, true, path)?;
            let [b0, b1] = board_rect(&board);
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [b0, b1],
                    RGBColor(250, 244, 225).filled(),
                )))
                .map_err(|e| err(&e))?
                .label("board")
                .legend(|(x, y)| {
                    Rectangle::new(
                        [(x, y - 5), (x + 14, y + 5)],
                        RGBColor(250, 244, 225).filled(),
                    )
                });
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [b0, b1],
                    RGBColor(150, 130, 90).stroke_width(2),
                )))
                .map_err(|e| err(&e))?;
            // The intended (or commanded) path as a pale band under the pen trace.
            let band = RGBColor(240, 140, 60)
                .mix(0.45)
                .stroke_width(if zoomed { 12 } else { 6 });
            chart
                .draw_series(
                    expected_xy
                        .windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], band)),
                )
                .map_err(|e| err(&e))?
                .label(path_label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], band));
            // The trace, simplified to a quarter of a pixel and drawn segment by segment:
            // plotters' wide-polyline joins break down at nearly collinear vertices and can drop
            // whole stretches of the line.
            let pixel = (xr.1 - xr.0) / f64::from(panel_w + 90);
            let width = if zoomed { 2 } else { 3 };
            let drawn = drawn_pen_trace(sim, 0.25 * pixel);
            chart
                .draw_series(
                    drawn
                        .windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], BLACK.stroke_width(width))),
                )
                .map_err(|e| err(&e))?
                .label("pen trace")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(2)));
            if let (true, Some(executed)) = (zoomed, &executed_xy) {
                // The executed commands' path, dashed over the trace that follows it.
                let blue = RGBColor(40, 110, 230).stroke_width(2);
                for w in executed.windows(2) {
                    chart
                        .draw_series(DashedLineSeries::new(vec![w[0], w[1]], 5, 5, blue))
                        .map_err(|e| err(&e))?;
                }
                chart
                    .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                    .map_err(|e| err(&e))?
                    .label("executed path (the decided commands)")
                    .legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new([(0, 0), (6, 0)], blue)
                            + PathElement::new([(11, 0), (17, 0)], blue)
                    });
            }
            if zoomed {
                let numbered = session.is_none_or(|s| s.numbered);
                chart
                    .draw_series(corner_labels(expected).into_iter().map(|(p, label)| {
                        EmptyElement::at((p[0], p[1]))
                            + Circle::new((0, 0), 5, RGBColor(230, 90, 30).stroke_width(2))
                            + Text::new(
                                if numbered { label } else { String::new() },
                                (7, -18),
                                (crate::FONT_FAMILY, 15),
                            )
                    }))
                    .map_err(|e| err(&e))?;
                // Each missed decision: a wrong move as a red arrow along its segment, an
                // abstention or a refusal as a mark where the arm stood; each with its number.
                for kind in [Miss::Wrong, Miss::Abstained, Miss::Refused] {
                    let (colour, words) = miss_style(kind);
                    let of_kind: Vec<&MissedDecision> =
                        missed.iter().filter(|m| m.miss == kind).collect();
                    if of_kind.is_empty() {
                        continue;
                    }
                    for m in &of_kind {
                        let (a, b) = ((m.from_m[0], m.from_m[1]), (m.to_m[0], m.to_m[1]));
                        if kind == Miss::Wrong {
                            let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
                            chart
                                .draw_series(std::iter::once(PathElement::new(
                                    vec![a, b],
                                    colour.stroke_width(4),
                                )))
                                .map_err(|e| err(&e))?;
                            chart
                                .draw_series(std::iter::once(
                                    EmptyElement::at(b)
                                        + Cross::new((0, 0), 7, colour.stroke_width(3)),
                                ))
                                .map_err(|e| err(&e))?;
                            // Beside the move: below a horizontal one, right of a vertical one.
                            let beside = if (b.0 - a.0).abs() > (b.1 - a.1).abs() {
                                (-28, 8)
                            } else {
                                (8, -8)
                            };
                            chart
                                .draw_series(std::iter::once(
                                    EmptyElement::at(mid)
                                        + Text::new(
                                            format!("{} wrong", m.index),
                                            beside,
                                            (crate::FONT_FAMILY, 15).into_font().color(&colour),
                                        ),
                                ))
                                .map_err(|e| err(&e))?;
                        } else {
                            chart
                                .draw_series(std::iter::once(
                                    EmptyElement::at(a)
                                        + TriangleMarker::new((0, 0), 9, colour.stroke_width(2))
                                        + Text::new(
                                            format!("{} {words}", m.index),
                                            (8, 6),
                                            (crate::FONT_FAMILY, 15).into_font().color(&colour),
                                        ),
                                ))
                                .map_err(|e| err(&e))?;
                        }
                    }
                    let label = match kind {
                        Miss::Wrong => "wrong decision (its number): the move it made",
                        Miss::Abstained => "abstention (its number): the arm stayed",
                        Miss::Refused => "command the arm refused (its number)",
                    };
                    chart
                        .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
                        .map_err(|e| err(&e))?
                        .label(label)
                        .legend(move |(x, y)| {
                            if kind == Miss::Wrong {
                                EmptyElement::at((x, y))
                                    + PathElement::new([(0, 0), (18, 0)], colour.stroke_width(4))
                            } else {
                                EmptyElement::at((x + 9, y))
                                    + PathElement::new(
                                        [(-5, 4), (0, -5), (5, 4), (-5, 4)],
                                        colour.stroke_width(2),
                                    )
                            }
                        });
                }
            }
            // The first and the last pose on top: the legend names them, and a later pose at the
            // same place (the G passes its start again) would hide them.
            let order = (1..keys.len().saturating_sub(1))
                .chain(keys.len().checked_sub(1).filter(|&l| l > 0))
                .chain((!keys.is_empty()).then_some(0));
            for i in order {
                let q = &keys[i].1;
                let c = key_colour(i);
                let pts = arm_points(&model, q);
                if zoomed {
                    // The links reach far outside the zoomed area; mark the pen only.
                    chart
                        .draw_series(std::iter::once(Circle::new(pts[2], 3, c.filled())))
                        .map_err(|e| err(&e))?;
                } else {
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            pts.to_vec(),
                            c.stroke_width(3),
                        )))
                        .map_err(|e| err(&e))?;
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                        .map_err(|e| err(&e))?;
                }
            }
            if !zoomed {
                let b = model.base();
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((b[0], b[1]))
                            + Text::new("shoulder", (8, 6), (crate::FONT_FAMILY, 14)),
                    ))
                    .map_err(|e| err(&e))?;
                let t_last = keys[keys.len() - 1].0;
                let poses = if session.is_some() {
                    format!(
                        "arm at the start (blue, t = 0) and at the end (red, t = {t_last:.1} s)"
                    )
                } else {
                    format!("arm at the start and end of each command: blue (t = 0) → red (t = {t_last:.1} s)")
                };
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![],
                        key_colour(0).stroke_width(3),
                    )))
                    .map_err(|e| err(&e))?
                    .label(poses)
                    .legend(move |(x, y)| {
                        EmptyElement::at((x, y))
                            + PathElement::new([(0, 0), (9, 0)], key_colour(0).stroke_width(3))
                            + PathElement::new(
                                [(9, 0), (18, 0)],
                                key_colour(n_keys - 1).stroke_width(3),
                            )
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .label_font((crate::FONT_FAMILY, 14))
                .draw()
                .map_err(|e| err(&e))?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest distance from a vertex of `points` to the polyline `drawn`.
    fn worst_gap(points: &[(f64, f64)], drawn: &[(f64, f64)]) -> f64 {
        let v = |p: (f64, f64)| Vector2::new(p.0, p.1);
        points
            .iter()
            .map(|&p| {
                drawn
                    .windows(2)
                    .map(|w| point_segment_distance(&v(p), &v(w[0]), &v(w[1])))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn simplifying_keeps_the_tip_of_an_out_and_back_stroke() {
        // Up 20 mm, out 10 mm to the left and back, down again: the spur of a G. Measured to
        // the line through its ends, the spur's tip is on that line and was dropped.
        let mut points = Vec::new();
        for i in 0..=200 {
            points.push((0.0, 1e-4 * f64::from(i)));
        }
        for i in 1..=100 {
            points.push((-1e-4 * f64::from(i), 0.02));
        }
        for i in (0..100).rev() {
            points.push((-1e-4 * f64::from(i), 0.02));
        }
        for i in (0..200).rev() {
            points.push((0.0, 1e-4 * f64::from(i)));
        }
        let drawn = simplify(&points, 1e-5);
        assert!(
            drawn.iter().any(|p| (p.0 + 0.01).abs() < 1e-12),
            "the spur's tip (-0.01, 0.02) is kept: {drawn:?}"
        );
        assert!(worst_gap(&points, &drawn) <= 1e-5);
        // Right 20 mm, then back 10 mm: the chord from the first to the last point lies on the
        // stroke, so the tip (0.02, 0) is 0 from its line and 10 mm from its segment.
        let mut bar: Vec<(f64, f64)> = (0..=200).map(|i| (1e-4 * f64::from(i), 0.0)).collect();
        bar.extend((100..200).rev().map(|i| (1e-4 * f64::from(i), 0.0)));
        let drawn = simplify(&bar, 1e-5);
        assert_eq!(drawn, vec![(0.0, 0.0), (0.02, 0.0), (0.01, 0.0)]);
        assert!(worst_gap(&bar, &drawn) <= 1e-5);
    }

    #[test]
    fn every_vertex_stays_within_the_tolerance_of_the_simplified_line() {
        // Seeded random walks of unit moves with small wobbles, retracing often.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..50 {
            let mut p = (0.0f64, 0.0f64);
            let mut points = vec![p];
            for _ in 0..12 {
                let (dx, dz) =
                    [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)][(next() % 4) as usize];
                for _ in 0..20 {
                    let wobble = ((next() % 1000) as f64 / 1000.0 - 0.5) * 2e-6;
                    p = (p.0 + dx * 1e-3 + wobble, p.1 + dz * 1e-3 - wobble);
                    points.push(p);
                }
            }
            for tolerance in [1e-6, 1e-5, 1e-4] {
                let drawn = simplify(&points, tolerance);
                let gap = worst_gap(&points, &drawn);
                assert!(gap <= tolerance, "{gap} > {tolerance}");
            }
        }
    }
}
