//! `oddball inspect FILE…`: what a recording holds, and optionally its target vs non-target ERPs.

use std::path::PathBuf;

use anyhow::Result;
use oddball_eval::erp::ErpParams;

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    #[arg(required = true, help = concat!("Recordings: ", crate::load::formats!(), "."))]
    pub files: Vec<PathBuf>,
    /// Draw target vs non-target averages per channel to this .png or .svg (all files pooled;
    /// they must share channels and sampling rate).
    #[arg(long, value_name = "FILE", value_parser = crate::args::plot_file)]
    pub plot: Option<PathBuf>,
    /// High-pass edge of the band-pass applied before averaging, Hz.
    #[arg(long, default_value_t = 1.0)]
    pub l_freq: f64,
    /// Low-pass edge of the band-pass applied before averaging, Hz.
    #[arg(long, default_value_t = 15.0)]
    pub h_freq: f64,
    /// Start of the plotted epoch relative to the onset, s (the baseline is tmin..0).
    #[arg(long, default_value_t = -0.1, allow_hyphen_values = true)]
    pub tmin: f64,
    /// End of the plotted epoch relative to the onset, s.
    #[arg(long, default_value_t = 0.8)]
    pub tmax: f64,
    #[command(flatten)]
    pub events: crate::load::EventArgs,
}

pub fn run(args: &InspectArgs) -> Result<()> {
    let mapping = args.events.mapping()?;
    let read_options = args.events.read_options()?;
    let mut recordings = Vec::with_capacity(args.files.len());
    for path in &args.files {
        let rec = oddball_eval::dataset::read_mapped(path, mapping.as_ref(), &read_options)
            .map_err(crate::load::with_flags)?;
        print!("{}", oddball_eval::text::recording(&rec));
        recordings.push(rec);
    }
    if let Some(plot) = &args.plot {
        let erp = ErpParams {
            l_freq: args.l_freq,
            h_freq: args.h_freq,
            tmin: args.tmin,
            tmax: args.tmax,
        };
        let (target, nontarget) = erp.epochs(recordings)?;
        oddball_plot::erp::draw_erp(plot, &target, &nontarget, &erp.band())?;
        println!("wrote {}", plot.display());
    }
    Ok(())
}
