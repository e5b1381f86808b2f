//! Reading recordings and models for the commands: the files, with the path in every error.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use oddball_decode::pipeline::{Model, Preprocess};
use oddball_eval::dataset::{self, DatasetError};
use oddball_eval::evaluate::EpochedRecording;
pub use oddball_eval::layout::Layout;
use oddball_eval::layout::LayoutError;
use oddball_io::{EventMapping, Manifest, ReadOptions};

/// The formats [`oddball_io::read`] takes (by extension; XDF also by its magic bytes), for help
/// texts.
macro_rules! formats {
    () => {
        "BCI2000 .dat (v1.0/v1.1), CSV (e.g. Muse), EDF/EDF+/BDF (annotations as events), NIC \
         .easy (with its .info), XDF, MATLAB .mat v5/v7 (BCI Competition II and III speller \
         layouts), GDF 1.x/2.x (OpenViBE stimulations), BrainVision .vhdr, EEGLAB .set, MNE .fif"
    };
}
pub(crate) use formats;

/// Which events are targets, for recordings that do not flag them (MNE's `event_id`).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct EventArgs {
    /// The target events: stimulus codes or marker/annotation texts, comma-separated (e.g. 2 or
    /// Target). With --nontarget-events; replaces the file's own target flags, and events that
    /// match neither list are left out.
    #[arg(long, value_name = "KEYS", requires = "nontarget_events")]
    pub target_events: Option<String>,
    /// The non-target events, as --target-events (e.g. 1 or NonTarget).
    #[arg(long, value_name = "KEYS", requires = "target_events")]
    pub nontarget_events: Option<String>,
    /// The sampling rate (Hz) of CSV files (instead of the time column's estimate) and MAT files
    /// (instead of their rate variable or 240 Hz).
    #[arg(long, value_name = "HZ")]
    pub sfreq: Option<f64>,
    /// CSV: the EEG columns to read, comma-separated (e.g. TP9,AF7,AF8,TP10); MAT: the names of
    /// the signal's columns; other formats: the channels kept, in this order (e.g. Cz,Pz).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub channels: Option<Vec<String>>,
    /// Names the channels of files that hold no names (or other ones), in order: an EEGLAB .loc
    /// montage, e.g. BCI2000's eeg64.loc for eeg2_1.dat (64 channels). --channels then picks among
    /// those names.
    #[arg(long, value_name = "FILE")]
    pub montage: Option<PathBuf>,
    /// Resample every file to this rate (Hz, polyphase as MNE's resample) before anything else
    /// (e.g. to train a model at an amplifier's rate); files are otherwise resampled only to
    /// meet a model's or the first training file's rate.
    #[arg(long, value_name = "HZ")]
    pub resample: Option<f64>,
    /// CSV: the time column (seconds).
    #[arg(long, value_name = "COLUMN")]
    pub time_column: Option<String>,
    /// CSV: the marker column (0 = no event); MAT: the variable of per-sample stimulus codes
    /// (e.g. --events-from trigger).
    #[arg(long, value_name = "NAME")]
    pub events_from: Option<String>,
    /// MAT: the variable holding the samples, n_times × n_channels (e.g. --data-from eeg).
    #[arg(long, value_name = "VARIABLE")]
    pub data_from: Option<String>,
    /// A data-set manifest (datasets/*.toml) whose [events] mapping (unless --target-events
    /// is given), [read] options (unless given as flags) and [speller] geometry read and label
    /// these files, as `oddball benchmark` labels its runs: e.g. a speller run whose file has
    /// row/column codes but no geometry (export: also each test run's test_text).
    #[arg(long, value_name = "MANIFEST")]
    pub manifest: Option<PathBuf>,
}

impl EventArgs {
    /// The mapping, checked (both lists, no key in both): the flags', else --manifest's
    /// [events], else `None`.
    pub fn mapping(&self) -> Result<Option<EventMapping>> {
        match (&self.target_events, &self.nontarget_events) {
            (Some(t), Some(n)) => Ok(Some(
                EventMapping::parse(t, n).context("--target-events/--nontarget-events")?,
            )),
            _ => Ok(self.manifest()?.and_then(|m| m.events)),
        }
    }

    /// The --manifest, read and checked.
    pub fn manifest(&self) -> Result<Option<Manifest>> {
        self.manifest
            .as_ref()
            .map(|p| Manifest::load(p).with_context(|| format!("--manifest {}", p.display())))
            .transpose()
    }

    /// The reading options, checked: each flag's, else --manifest's `[read]` value (as
    /// `oddball benchmark` reads the manifest's runs).
    pub fn read_options(&self) -> Result<ReadOptions> {
        let m = self.manifest()?.and_then(|m| m.read).unwrap_or_default();
        let o = ReadOptions {
            sfreq: self.sfreq.or(m.sfreq),
            channels: self.channels.clone().or(m.channels),
            montage: self.montage.clone().or(m.montage),
            time_column: self.time_column.clone().or(m.time_column),
            events: self.events_from.clone().or(m.events),
            data: self.data_from.clone().or(m.data),
        };
        o.check().map_err(anyhow::Error::msg)?;
        Ok(o)
    }
}

/// A library error with the flags that would fix it named, as the message says them.
pub(crate) fn with_flags(e: DatasetError) -> anyhow::Error {
    match e {
        DatasetError::Resample { path, to, source } => anyhow::Error::new(source).context(format!(
            "resampling {} to --resample {to} Hz",
            path.display()
        )),
        DatasetError::Layout(l) => match *l {
            LayoutError::Channels {
                recording,
                of,
                source,
            } => anyhow::Error::new(source).context(format!(
                "matching the channels of {recording} to those of {of}; name the file's \
                 channels with --montage FILE (an EEGLAB .loc, e.g. eeg64.loc) or --channels"
            )),
            l => l.into(),
        },
        // A reader that could not find the rate (no time column, too few rows): the option
        // that gives it.
        DatasetError::Read { path, source } if source.to_string().contains("sampling rate") => {
            anyhow::Error::new(*source).context(format!(
                "reading {}; give its sampling rate with --sfreq HZ (in a manifest: [read] sfreq)",
                path.display()
            ))
        }
        e => e.into(),
    }
}

/// Reads, labels (see [`EventArgs`]; `texts`: the spelled text of each file, for speller runs
/// recorded without labels) and epochs each recording ([`dataset::load_epochs`]); a recording
/// whose events carry no labels is an error saying how to label them. Every file's channels
/// are matched by name to `layout`'s (else to the first file's, returned).
pub fn load_epochs(
    paths: &[PathBuf],
    pre: &Preprocess,
    events: &EventArgs,
    texts: &[String],
    layout: Option<&Layout>,
) -> Result<(Vec<EpochedRecording>, Option<Layout>)> {
    if !texts.is_empty() && texts.len() != paths.len() {
        anyhow::bail!(
            "--test-text gives {} texts for {} test files (one per file)",
            texts.len(),
            paths.len()
        );
    }
    let mapping = events.mapping()?;
    let speller = events.manifest()?.and_then(|m| m.speller);
    let read = events.read_options()?;
    let runs = paths.iter().enumerate().map(|(i, p)| {
        let how = dataset::Labelling {
            mapping: mapping.as_ref(),
            text: texts.get(i).map(String::as_str),
            speller: speller.as_ref(),
            read: Some(&read),
        };
        (p.as_path(), how)
    });
    dataset::load_epochs(runs, pre, events.resample, layout, &mut |p, r, of| {
        eprint!("{}", oddball_eval::text::resampled(p, r, of))
    })
    .map_err(with_flags)
}

/// Writes `text` to `path` (atomically) and says so.
pub fn write_out(path: &Path, text: String) -> Result<()> {
    oddball_io::write_atomic(path, text).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Reads a saved model.
pub fn load_model(path: &Path) -> Result<Model> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Model::from_json(&text).with_context(|| format!("loading model {}", path.display()))
}

/// `--transfer none|pooled|FILE`: no pooled start, the shipped one, or one read (and checked)
/// from a file.
pub fn pooled_start(arg: &str) -> Result<Option<oddball_decode::unsupervised::PooledStart>> {
    use oddball_decode::unsupervised::{pooled_start, PooledStart};
    Ok(match arg {
        "none" => None,
        "pooled" => Some(pooled_start()),
        path => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("--transfer: reading {path}"))?;
            Some(PooledStart::from_json(&text).with_context(|| format!("--transfer {path}"))?)
        }
    })
}
