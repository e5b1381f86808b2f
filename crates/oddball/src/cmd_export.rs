//! `oddball export --bids OUT FILE…`: recordings written as a BIDS-EEG data set. The layout,
//! the sidecars and the checks are `oddball_io::bids`'s; this file maps the flags and prints.

use std::path::PathBuf;

use anyhow::{Context, Result};
use oddball_io::bids::{BidsError, ExportFormat, ExportOptions, ExportPlan};
use oddball_io::IoError;

#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// The BIDS data set's root folder (created; other subjects and runs in it are kept).
    #[arg(long, value_name = "OUT")]
    pub bids: PathBuf,
    #[arg(required = true, help = concat!("Recordings: ", crate::load::formats!(), ". Several files become runs 1..n of one task."))]
    pub files: Vec<PathBuf>,
    /// The subject label (sub-<label>): letters and digits.
    #[arg(long, value_name = "LABEL")]
    pub subject: String,
    /// The session label (ses-<label>), if any: letters and digits.
    #[arg(long, value_name = "LABEL")]
    pub session: Option<String>,
    /// The task label (task-<label>); default: the first file's name, letters and digits only.
    #[arg(long, value_name = "LABEL")]
    pub task: Option<String>,
    /// Replace runs already in OUT.
    #[arg(long)]
    pub overwrite: bool,
    /// The mains frequency, Hz (PowerLineFrequency; default n/a).
    #[arg(long, value_name = "HZ")]
    pub line_freq: Option<f64>,
    /// The EEG reference, as text (EEGReference; default n/a), e.g. "linked mastoids".
    #[arg(long, value_name = "TEXT")]
    pub reference: Option<String>,
    /// The runs' data file format: edf (EDF+, 16-bit) or brainvision (.vhdr/.vmrk/.eeg,
    /// float32 µV).
    #[arg(long, value_enum, default_value_t = DataFormat::Edf)]
    pub format: DataFormat,
    #[command(flatten)]
    pub events: crate::load::EventArgs,
}

/// `--format`'s values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DataFormat {
    Edf,
    Brainvision,
}

impl From<DataFormat> for ExportFormat {
    fn from(f: DataFormat) -> Self {
        match f {
            DataFormat::Edf => ExportFormat::Edf,
            DataFormat::Brainvision => ExportFormat::BrainVision,
        }
    }
}

/// A plan error with the flag that fixes it named.
fn with_flags(e: IoError) -> anyhow::Error {
    let hint = match &e {
        IoError::Bids(b) => match &**b {
            BidsError::Label { entity: "sub", .. } => Some("--subject"),
            BidsError::Label { entity: "ses", .. } => Some("--session"),
            BidsError::Label { .. } => Some("--task (the default is the first file's name)"),
            BidsError::Exists { .. } => Some("--overwrite to replace it"),
            _ => None,
        },
        _ => None,
    };
    match hint {
        Some(h) => anyhow::Error::new(e).context(format!("check the options: {h}")),
        None => e.into(),
    }
}

pub fn run(args: &ExportArgs) -> Result<()> {
    if let Some(f) = args.line_freq.filter(|f| !(f.is_finite() && *f > 0.0)) {
        anyhow::bail!("--line-freq {f}: a frequency in Hz above 0 (50 or 60)");
    }
    let mapping = args.events.mapping()?;
    let read_options = args.events.read_options()?;
    // --manifest: its speller geometry and each test run's spelled text label the runs (as
    // `oddball benchmark` labels them), so the BIDS sidecars carry what the manifest says.
    let manifest = args.events.manifest()?;
    let speller = manifest.as_ref().and_then(|m| m.speller.clone());
    let options = ExportOptions {
        subject: args.subject.clone(),
        session: args.session.clone(),
        task: args.task.clone(),
        overwrite: args.overwrite,
        power_line_frequency: args.line_freq,
        reference: args.reference.clone(),
        format: args.format.into(),
    };
    let plan = ExportPlan::new(&args.bids, &args.files, options).map_err(with_flags)?;
    for (i, run) in plan.runs.iter().enumerate() {
        let text = manifest.as_ref().and_then(|m| m.text_of(&run.source));
        let mut rec = if speller.is_some() || text.is_some() {
            let how = oddball_eval::dataset::Labelling {
                mapping: mapping.as_ref(),
                text,
                speller: speller.as_ref(),
                read: Some(&read_options),
            };
            oddball_eval::dataset::read_labelled(&run.source, how)
        } else {
            oddball_eval::dataset::read_mapped(&run.source, mapping.as_ref(), &read_options)
        }
        .map_err(crate::load::with_flags)?;
        if let Some(to) = args.events.resample {
            rec.raw = oddball_signal::resample::resample_raw(&rec.raw, to).with_context(|| {
                format!("resampling {} to --resample {to} Hz", run.source.display())
            })?;
        }
        let s = plan
            .write_run(i, &rec)
            .with_context(|| format!("exporting {}", run.source.display()))?;
        println!(
            "{} → {}: {} channels, {} samples at {} Hz, {} events{}",
            run.source.display(),
            s.eeg.display(),
            s.n_channels,
            s.n_times,
            rec.raw.sfreq(),
            s.n_events,
            if s.n_annotations > 0 {
                format!(", {} other markers", s.n_annotations)
            } else {
                String::new()
            }
        );
        for p in &s.replaced {
            println!(
                "  removed {} (the run's data in the other format)",
                p.display()
            );
        }
        if let Some(c) = &s.source_copy {
            println!("  original copied to {}", c.display());
        }
    }
    plan.finish()
        .with_context(|| format!("writing the data set's files in {}", args.bids.display()))?;
    println!("wrote BIDS data set {}", args.bids.display());
    Ok(())
}
