//! `oddball inspect FILE…`: what a recording holds, and optionally its target vs non-target ERPs.

use std::path::PathBuf;

use anyhow::{bail, Result};
use oddball_io::Recording;
use oddball_signal::detrend::DetrendKind;
use oddball_signal::epochs::EpochsParams;
use oddball_signal::filter::{Band, ButterworthParams};
use oddball_signal::preprocess::{Filtering, PreprocessParams};
use oddball_signal::Epochs;

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
        let rec = crate::load::read_mapped(path, mapping.as_ref(), &read_options)?;
        print!("{}", oddball_eval::text::recording(&rec));
        recordings.push(rec);
    }
    if let Some(plot) = &args.plot {
        let (target, nontarget) = erp_epochs(recordings, args)?;
        let band = format!("{}–{} Hz", args.l_freq, args.h_freq);
        oddball_plot::erp::draw_erp(plot, &target, &nontarget, &band)?;
        println!("wrote {}", plot.display());
    }
    Ok(())
}

/// Band-passed, baseline-corrected epochs of all recordings, split into targets and non-targets:
/// windows into the recordings, each filtered in its own memory (no copy of the samples).
fn erp_epochs(recordings: Vec<Recording>, args: &InspectArgs) -> Result<(Epochs, Epochs)> {
    let (first_path, first_names, first_sfreq) = (
        recordings[0].path.clone(),
        recordings[0].raw.ch_names().to_vec(),
        recordings[0].raw.sfreq(),
    );
    let params = PreprocessParams {
        band: ButterworthParams {
            order: 4,
            band: Band::Bandpass {
                l_freq: args.l_freq,
                h_freq: args.h_freq,
            },
        },
        filtering: Filtering::ZeroPhase {
            detrend: Some(DetrendKind::Linear),
        },
        epochs: EpochsParams::new(args.tmin, args.tmax).with_baseline(args.tmin.min(0.0), 0.0),
    };
    let mut target = Vec::new();
    let mut nontarget = Vec::new();
    for rec in recordings {
        let raw = rec.raw;
        if raw.ch_names() != first_names || raw.sfreq() != first_sfreq {
            bail!(
                "{} has other channels or another sampling rate than {}: plot them one at a time",
                rec.path.display(),
                first_path.display()
            );
        }
        let (epochs, _) = params.epochs_owned(raw)?;
        let idx = |want: bool| -> Vec<usize> {
            (0..epochs.n_epochs())
                .filter(|&i| epochs.events()[i].target == Some(want))
                .collect()
        };
        target.push(epochs.select(&idx(true)));
        nontarget.push(epochs.select(&idx(false)));
    }
    let target = Epochs::concatenate(&target)?;
    let nontarget = Epochs::concatenate(&nontarget)?;
    if target.is_empty() || nontarget.is_empty() {
        bail!(
            "no ERP to plot: {} target and {} non-target epochs (the files must flag targets)",
            target.n_epochs(),
            nontarget.n_epochs()
        );
    }
    Ok((target, nontarget))
}
