//! Target vs non-target averages per channel (`oddball inspect --plot`, and the ERP of the
//! calibration epochs of `demo` and `task`).

use std::path::Path;

use crate::PlotError;
use ndarray::Array2;
use oddball_signal::Epochs;

/// A grid of per-channel averages: targets red, non-targets blue; `band` names the filter.
pub fn draw_erp(
    path: &Path,
    target: &Epochs,
    nontarget: &Epochs,
    band: &str,
) -> Result<(), PlotError> {
    let t_avg: Array2<f64> = target.average().expect("non-empty");
    let n_avg: Array2<f64> = nontarget.average().expect("non-empty");
    let times_ms: Vec<f64> = target.times().iter().map(|t| t * 1000.0).collect();
    let n_channels = target.n_channels();
    let cols = (n_channels as f64).sqrt().ceil() as usize;
    let rows = n_channels.div_ceil(cols);
    let size = ((cols as u32) * 300, (rows as u32) * 220 + 40);
    let lo = t_avg
        .iter()
        .chain(n_avg.iter())
        .fold(f64::INFINITY, |a, &b| a.min(b));
    let hi = t_avg
        .iter()
        .chain(n_avg.iter())
        .fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let pad = 0.05 * (hi - lo).max(1e-6);
    let (y0, y1) = (lo - pad, hi + pad);
    let (x0, x1) = (times_ms[0], *times_ms.last().expect("epoch has samples"));
    crate::with_backend!(path, size, |root| {
        let title = format!(
            "target (n={}, red) vs non-target (n={}, blue), {band}, µV",
            target.n_epochs(),
            nontarget.n_epochs(),
        );
        let root = root
            .titled(&title, (crate::FONT_FAMILY, 20))
            .map_err(|e| PlotError::draw(path, e))?;
        let panels = root.split_evenly((rows, cols));
        for (c, panel) in panels.iter().enumerate().take(n_channels) {
            let mut chart = ChartBuilder::on(panel)
                .caption(&target.ch_names()[c], (crate::FONT_FAMILY, 16))
                .margin(6)
                .x_label_area_size(24)
                .y_label_area_size(40)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| PlotError::draw(path, e))?;
            chart
                .configure_mesh()
                .x_labels(5)
                .y_labels(5)
                .x_desc("ms")
                .label_style((crate::FONT_FAMILY, 11))
                .draw()
                .map_err(|e| PlotError::draw(path, e))?;
            for (avg, color) in [(&n_avg, BLUE), (&t_avg, RED)] {
                chart
                    .draw_series(LineSeries::new(
                        times_ms
                            .iter()
                            .zip(avg.row(c).iter())
                            .map(|(&t, &v)| (t, v)),
                        color.stroke_width(2),
                    ))
                    .map_err(|e| PlotError::draw(path, e))?;
            }
        }
        Ok(())
    })
}
