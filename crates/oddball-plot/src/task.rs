//! The pictures of a task's report: the calibration ERP (`erp.png`) and the tracking task's
//! targets and paths (`task.png`).

use std::path::Path;

use crate::PlotError;
use oddball_arm::ArmSim;
use oddball_session::tasks::TrackReport;
use oddball_signal::Epochs;

/// Target and non-target averages of the accepted calibration epochs: a report's `erp.png`.
pub fn draw_calibration_erp(path: &Path, erp: &Epochs) -> Result<(), PlotError> {
    let idx = |want: bool| -> Vec<usize> {
        (0..erp.n_epochs())
            .filter(|&i| erp.events()[i].target == Some(want))
            .collect()
    };
    let (target, nontarget) = (erp.select(&idx(true)), erp.select(&idx(false)));
    crate::erp::draw_erp(
        path,
        &target,
        &nontarget,
        "calibration epochs, causal 1–15 Hz",
    )
}

/// Targets (numbered), the pen's path and each target's minimal path (x first, then z).
pub fn draw_track(path: &Path, arm: &ArmSim, r: &TrackReport) -> Result<(), PlotError> {
    let trace = crate::arm::pen_trace_xz(arm);
    let mut xs: Vec<f64> = trace.iter().map(|p| p.0).collect();
    let mut zs: Vec<f64> = trace.iter().map(|p| p.1).collect();
    for t in &r.targets {
        xs.push(t.target_m[0]);
        zs.push(t.target_m[1]);
    }
    let (x0, x1) = bounds(&xs);
    let (z0, z1) = bounds(&zs);
    let span = (x1 - x0).max(z1 - z0) * 0.5 + 0.01;
    let (cx, cz) = ((x0 + x1) / 2.0, (z0 + z1) / 2.0);
    crate::with_backend!(path, (900, 900), |root| {
        use plotters::prelude::*;
        let err = |e: &dyn std::fmt::Debug| PlotError::draw(path, format!("{e:?}"));
        let caption = format!(
            "Tracking: {}/{} targets reached (black: pen, dashed: minimal path)",
            r.n_reached, r.n_attempted
        );
        let mut chart = crate::arm::xz_chart(
            &root,
            &caption,
            18,
            cx - span..cx + span,
            cz - span..cz + span,
            false,
            path,
        )?;
        for t in &r.targets {
            let (a, b) = (t.start_m, t.target_m);
            let corner = (b[0], a[1]);
            for seg in [((a[0], a[1]), corner), (corner, (b[0], b[1]))] {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![seg.0, seg.1],
                        6,
                        4,
                        RGBColor(240, 140, 60).stroke_width(3),
                    ))
                    .map_err(|e| err(&e))?;
            }
        }
        chart
            .draw_series(
                trace
                    .windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], BLACK.stroke_width(2))),
            )
            .map_err(|e| err(&e))?;
        chart
            .draw_series(r.targets.iter().map(|t| {
                let colour = if t.success {
                    RGBColor(30, 140, 60)
                } else {
                    RGBColor(200, 30, 30)
                };
                EmptyElement::at((t.target_m[0], t.target_m[1]))
                    + Circle::new((0, 0), 8, colour.stroke_width(3))
                    + Text::new(t.index.to_string(), (10, -20), (crate::FONT_FAMILY, 16))
            }))
            .map_err(|e| err(&e))?;
        Ok(())
    })
}

fn bounds(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}
