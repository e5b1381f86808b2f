//! The speller's character accuracy against repetitions, one line per preset (`oddball evaluate
//! --plot`).

use std::path::Path;

use crate::PlotError;
use oddball_eval::evaluate::PipelineResult;

/// Character accuracy (%) vs repetitions, one line per preset, chance level dashed.
pub fn draw_accuracy(path: &Path, results: &[PipelineResult]) -> Result<(), PlotError> {
    let curves: Vec<(&str, &[f64])> = results
        .iter()
        .filter_map(|r| Some((r.pipeline.as_str(), r.speller_accuracy.as_deref()?)))
        .collect();
    let n_choices = results.iter().find_map(|r| r.speller_choices).unwrap_or(36);
    let n_chars = results
        .iter()
        .find_map(|r| r.speller_text.as_ref().map(|t| t.chars().count()))
        .unwrap_or(0);
    crate::with_backend!(path, (900, 600), |root| {
        accuracy_chart(
            &root,
            path,
            &format!("character accuracy vs repetitions ({n_chars} characters)"),
            &curves,
            n_choices,
        )
    })
}

/// The chart of [`draw_accuracy`] on `area`: `curves` of accuracy (0–1) by repetitions, one per
/// name, and chance (one over `n_choices`) dashed. `path` names the file in errors.
pub(crate) fn accuracy_chart<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    path: &Path,
    caption: &str,
    curves: &[(&str, &[f64])],
    n_choices: usize,
) -> Result<(), PlotError> {
    use plotters::prelude::*;
    let n_reps = curves
        .iter()
        .map(|(_, a)| a.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let chance = 100.0 / n_choices.max(1) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (crate::FONT_FAMILY, 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(0.5f64..n_reps as f64 + 0.5, 0f64..105.0)
        .map_err(|e| PlotError::draw(path, e))?;
    chart
        .configure_mesh()
        .x_labels(n_reps.min(20))
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_labels(11)
        .y_label_formatter(&|y| format!("{y:.0}"))
        .x_desc("repetitions (flashes of every row and column)")
        .y_desc("characters right, %")
        .label_style((crate::FONT_FAMILY, 14))
        .draw()
        .map_err(|e| PlotError::draw(path, e))?;
    // Earlier curves drawn wider, so curves that coincide stay visible under later ones.
    for (i, (name, acc)) in curves.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let width = 2 + (curves.len() - 1 - i) as u32;
        let points: Vec<(f64, f64)> = acc
            .iter()
            .enumerate()
            .map(|(r, a)| ((r + 1) as f64, 100.0 * a))
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(width)))
            .map_err(|e| PlotError::draw(path, e))?
            .label(*name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
            });
        chart
            .draw_series(
                points
                    .iter()
                    .map(|&p| Circle::new(p, 2 + width / 2, color.filled())),
            )
            .map_err(|e| PlotError::draw(path, e))?;
    }
    chart
        .draw_series(DashedLineSeries::new(
            [(0.5, chance), (n_reps as f64 + 0.5, chance)],
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(|e| PlotError::draw(path, e))?
        .label(format!("chance (1/{n_choices} = {chance:.1} %)"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::MiddleRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((crate::FONT_FAMILY, 14))
        .draw()
        .map_err(|e| PlotError::draw(path, e))?;
    Ok(())
}
