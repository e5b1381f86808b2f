//! `oddball decode`: the flags mapped to an `oddball_live::decode::DecodePlan`, its JSON lines
//! written, its summary printed.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use oddball_decode::preset::Preset;
use oddball_io::nic::{NicFormat, NicMode};
use oddball_io::Paradigm;
use oddball_live::decode::{self, DecodePlan, MarkerSpec};
use oddball_live::source::SourceSpec;
use oddball_session::listener::{ListenerParams, ListenerStart};

use crate::load::load_model;
use crate::preset_arg::{one_help, preset};

/// How decoding starts (`--calibration`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationArg {
    /// The first N trials' flags or cues are the calibration.
    Trials(usize),
    /// No calibration: the unsupervised decoder.
    None,
}

fn calibration_arg(s: &str) -> Result<CalibrationArg, String> {
    if s == "none" {
        return Ok(CalibrationArg::None);
    }
    match s.parse::<usize>() {
        Ok(n) if (1..=1000).contains(&n) => Ok(CalibrationArg::Trials(n)),
        _ => Err("expected `none` or a number of calibration trials (1 to 1000)".into()),
    }
}

#[derive(Debug, clap::Args)]
pub struct DecodeArgs {
    /// Where the EEG comes from: lsl:NAME or lsl:type=EEG (an LSL stream), nic:HOST:PORT, or
    /// replay:FILE (a recording played back at its own rate, for testing).
    #[arg(long)]
    pub source: SourceSpec,
    /// The stimulus program's marker stream: lsl:NAME or lsl:type=Markers (string or numeric
    /// markers); `recording` takes a played-back recording's own events instead (no LSL).
    #[arg(long, default_value = "lsl:type=Markers")]
    pub markers: String,
    /// The paradigm file: the choices, which marker flashes which, how trials start and end
    /// (see paradigms/).
    #[arg(long, value_name = "FILE")]
    pub paradigm: PathBuf,
    /// Decide with a model from `oddball train` or an earlier session.
    #[arg(long, value_name = "FILE", conflicts_with = "calibration")]
    pub model: Option<PathBuf>,
    /// Calibrate in-stream on the first N trials (their target flags or cues), or `none` (the
    /// unsupervised decoder, no labels: one attended choice per trial).
    #[arg(long, value_name = "N|none", value_parser = calibration_arg, required_unless_present = "model")]
    pub calibration: Option<CalibrationArg>,
    /// With --calibration N: the pipeline fitted.
    #[arg(long, default_value = "lda", value_parser = preset, help = one_help())]
    pub pipeline: Preset,
    /// Stop a trial as soon as one choice is probable enough (a `stop` message goes out first),
    /// abstain when none is credible.
    #[arg(long)]
    pub dynamic_stopping: bool,
    /// With --dynamic-stopping: the posterior that stops a trial.
    #[arg(long, default_value_t = 0.95, requires = "dynamic_stopping")]
    pub threshold: f64,
    /// JSON lines of the decisions: a file, or - for standard output.
    #[arg(long, short, value_name = "FILE", default_value = "-")]
    pub out: String,
    /// Name of the LSL outlet the decisions go out on (type oddball-decisions); `none` for no
    /// outlet.
    #[arg(long, default_value = "oddball-decisions")]
    pub outlet: String,
    /// With replay:FILE, decode as fast as possible instead of in real time.
    #[arg(long)]
    pub fast: bool,
    /// Write the run's summary (decisions, marker counts, latency) as JSON.
    #[arg(long, value_name = "FILE")]
    pub summary: Option<PathBuf>,
    /// Seconds to wait for the LSL streams to appear.
    #[arg(long, default_value_t = 30.0)]
    pub resolve_timeout: f64,
}

pub fn run(args: &DecodeArgs) -> Result<Option<String>> {
    let paradigm = Paradigm::load(&args.paradigm)?;
    let start = match (&args.model, args.calibration) {
        (Some(path), _) => ListenerStart::Model(Box::new(load_model(path)?)),
        (None, Some(CalibrationArg::Trials(trials))) => ListenerStart::Calibrate { trials },
        (None, Some(CalibrationArg::None)) => ListenerStart::Uncalibrated { params: None },
        (None, None) => anyhow::bail!("give --model FILE or --calibration N|none"),
    };
    if !(args.threshold > 0.0 && args.threshold <= 1.0) {
        anyhow::bail!("--threshold {}: a probability in (0, 1]", args.threshold);
    }
    if !(args.resolve_timeout > 0.0 && args.resolve_timeout <= 3600.0) {
        anyhow::bail!("--resolve-timeout {}: 0 to 3600 s", args.resolve_timeout);
    }
    let markers = if args.markers == "recording" {
        MarkerSpec::Recording
    } else {
        let q = args.markers.strip_prefix("lsl:").with_context(|| {
            format!(
                "--markers {}: expected lsl:NAME, lsl:type=TYPE or recording",
                args.markers
            )
        })?;
        MarkerSpec::Lsl(q.to_string())
    };
    let plan = DecodePlan {
        source: args.source.clone(),
        markers,
        listener: ListenerParams::new(
            paradigm,
            start,
            args.pipeline,
            args.dynamic_stopping.then_some(args.threshold),
        ),
        outlet: (args.outlet != "none").then(|| args.outlet.clone()),
        paced: !args.fast,
        // A live stream sample by sample (a decision goes as soon as its last sample is in); a
        // recording played back, ten at a time.
        block: if matches!(args.source, SourceSpec::Replay(_)) {
            10
        } else {
            1
        },
        resolve_timeout_s: args.resolve_timeout,
        nic: NicFormat::starstim(NicMode::Binary),
        nic_sfreq: 500.0,
    };
    let mut sink: Box<dyn Write> = if args.out == "-" {
        Box::new(std::io::stdout())
    } else {
        let path = PathBuf::from(&args.out);
        Box::new(std::io::BufWriter::new(
            std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?,
        ))
    };
    let mut write_error = None;
    let summary = decode::run(plan, &mut |line| {
        if write_error.is_none() {
            if let Err(e) = writeln!(sink, "{line}").and_then(|()| sink.flush()) {
                write_error = Some(e);
            }
        }
    })?;
    if let Some(e) = write_error {
        return Err(e).with_context(|| format!("writing {}", args.out));
    }
    let m = &summary.markers;
    eprintln!(
        "decode: {} decisions ({} abstentions, {} stopped early) from {} samples in {:.1} s; ended: {}",
        summary.decisions, summary.abstentions, summary.stops, summary.samples, summary.seconds, summary.ended
    );
    eprintln!(
        "markers: {} read, {} flashes; unknown {}, too old {}, future {}, out of order {}, duplicate {}, orphan flags {}, rejected epochs {}",
        m.markers, m.flashes, m.unknown, m.too_old, m.future, m.out_of_order, m.duplicate, m.orphan_flags, m.rejected
    );
    if let Some((median, p99)) = summary.latency_ms {
        eprintln!("latency (last epoch's block taken → decision sent): median {median:.2} ms, 99th percentile {p99:.2} ms");
    }
    if let Some((median, p99)) = summary.latency_from_stamp_ms {
        eprintln!("latency (last epoch's sample stamped → decision sent): median {median:.2} ms, 99th percentile {p99:.2} ms");
    }
    if let Some(s) = &summary.marker_stream {
        eprintln!("marker stream: {s}");
    }
    if let Some(path) = &args.summary {
        oddball_io::write_atomic(path, serde_json::to_string_pretty(&summary)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    // The streams ending (the stimulus program done) is how a decode run ends.
    eprintln!("ended: {}", summary.ended);
    Ok(None)
}
