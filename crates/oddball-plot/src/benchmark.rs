//! `oddball benchmark --plot`: the figure a paper shows. Left, each subject's AUC per preset
//! (one dot per subject, the mean as a bar), one protocol; right, the mean character accuracy
//! against repetitions per preset over the speller subjects, chance dashed.

use std::path::Path;

use oddball_eval::benchmark::{BenchmarkReport, Protocol};

use crate::PlotError;

/// Draws the benchmark figure for `protocol` (the first protocol with results when `None`).
pub fn draw_benchmark(
    path: &Path,
    report: &BenchmarkReport,
    protocol: Option<Protocol>,
) -> Result<(), PlotError> {
    let protocol = protocol
        .or_else(|| report.results.first().map(|r| r.protocol))
        .unwrap_or(Protocol::TrainTest);
    let rows: Vec<_> = report
        .results
        .iter()
        .filter(|r| r.protocol == protocol)
        .collect();
    let mut presets: Vec<&str> = Vec::new();
    for r in &rows {
        if !presets.contains(&r.preset.as_str()) {
            presets.push(&r.preset);
        }
    }
    let mut subjects: Vec<(String, Option<String>)> = Vec::new();
    for r in &rows {
        let key = (format!("{}/{}", r.dataset, r.subject), r.session.clone());
        if !subjects.contains(&key) {
            subjects.push(key);
        }
    }
    let curves: Vec<(&str, &[f64])> = report
        .summary
        .iter()
        .filter(|s| s.protocol == protocol)
        .filter_map(|s| Some((s.preset.as_str(), s.char_accuracy_by_reps.as_deref()?)))
        .collect();
    // Chance: of the largest speller matrix among the rows.
    let n_choices = rows.iter().filter_map(|r| r.n_choices).max().unwrap_or(36);
    let lo = rows
        .iter()
        .map(|r| r.auc)
        .fold(1.0f64, f64::min)
        .clamp(0.0, 0.5);
    let n_presets = presets.len().max(1);
    // The subjects' legend sits right of the left panel's plot, outside the dots.
    const LEGEND_W: u32 = 250;
    let left_w = 800 + LEGEND_W;
    let width = if curves.is_empty() {
        left_w
    } else {
        left_w + 700
    };
    crate::with_backend!(path, (width, 620), |root| {
        let (left, right) = if curves.is_empty() {
            (root.clone(), None)
        } else {
            let (l, r) = root.split_horizontally(left_w);
            (l, Some(r))
        };
        let mut chart = ChartBuilder::on(&left)
            .caption(
                format!(
                    "epoch ROC-AUC per subject ({protocol}, {} subject{})",
                    subjects.len(),
                    if subjects.len() == 1 { "" } else { "s" }
                ),
                (crate::FONT_FAMILY, 20),
            )
            .margin(14)
            .margin_right(LEGEND_W)
            .x_label_area_size(70)
            .y_label_area_size(56)
            .build_cartesian_2d(-0.5f64..n_presets as f64 - 0.5, lo..1.0f64)
            .map_err(|e| PlotError::draw(path, e))?;
        let names = presets.clone();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n_presets)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 {
                    names
                        .get(i as usize)
                        .map(|s| s.to_string())
                        .unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_labels(11)
            .y_label_formatter(&|y| format!("{y:.2}"))
            .y_desc("ROC-AUC (0.5 = chance)")
            .label_style((crate::FONT_FAMILY, 14))
            .draw()
            .map_err(|e| PlotError::draw(path, e))?;
        // Chance.
        chart
            .draw_series(DashedLineSeries::new(
                [(-0.5, 0.5), (n_presets as f64 - 0.5, 0.5)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(|e| PlotError::draw(path, e))?;
        for (s, key) in subjects.iter().enumerate() {
            let color = Palette99::pick(s).to_rgba();
            // Subjects spread a little sideways so that equal AUCs stay visible.
            let dx = if subjects.len() > 1 {
                -0.25 + 0.5 * s as f64 / (subjects.len() - 1) as f64
            } else {
                0.0
            };
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| (format!("{}/{}", r.dataset, r.subject), r.session.clone()) == *key)
                .filter_map(|r| {
                    let i = presets.iter().position(|p| *p == r.preset)?;
                    Some((i as f64 + dx, r.auc))
                })
                .collect();
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 5, color.filled())))
                .map_err(|e| PlotError::draw(path, e))?;
        }
        // The mean per preset.
        for (i, preset) in presets.iter().enumerate() {
            let aucs: Vec<f64> = rows
                .iter()
                .filter(|r| r.preset == *preset)
                .map(|r| r.auc)
                .collect();
            let mean = aucs.iter().sum::<f64>() / aucs.len().max(1) as f64;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(i as f64 - 0.35, mean), (i as f64 + 0.35, mean)],
                    BLACK.stroke_width(3),
                )))
                .map_err(|e| PlotError::draw(path, e))?;
        }
        // The legend, drawn on the panel beside the plot (plotters clips series labels to the
        // plotting area).
        let x0 = (left_w - LEGEND_W) as i32;
        let entries = subjects
            .iter()
            .map(|(s, session)| match session {
                Some(session) => format!("{s} ({session})"),
                None => s.clone(),
            })
            .chain(std::iter::once("mean over subjects".to_string()));
        for (i, label) in entries.enumerate() {
            let y = 60 + 22 * i as i32;
            if i < subjects.len() {
                let color = Palette99::pick(i).to_rgba();
                left.draw(&Circle::new((x0 + 8, y), 5, color.filled()))
                    .map_err(|e| PlotError::draw(path, e))?;
            } else {
                left.draw(&PathElement::new(
                    vec![(x0, y), (x0 + 16, y)],
                    BLACK.stroke_width(3),
                ))
                .map_err(|e| PlotError::draw(path, e))?;
            }
            left.draw(&Text::new(
                label,
                (x0 + 22, y - 8),
                (crate::FONT_FAMILY, 14),
            ))
            .map_err(|e| PlotError::draw(path, e))?;
        }

        if let Some(right) = right {
            let n_spellers = rows
                .iter()
                .filter(|r| r.chars_by_reps.is_some())
                .map(|r| (&r.dataset, &r.subject))
                .collect::<std::collections::BTreeSet<_>>()
                .len();
            crate::accuracy::accuracy_chart(
                &right,
                path,
                &format!(
                    "mean character accuracy ({n_spellers} speller subject{})",
                    if n_spellers == 1 { "" } else { "s" }
                ),
                &curves,
                n_choices,
            )?;
        }
        Ok(())
    })
}
