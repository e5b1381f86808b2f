//! `oddball simulate`: the simulated subject as a live amplifier in another process, so a session
//! runs across processes as with real hardware. Two wires, one of `--nic` or `--lsl`:
//!
//! * `--nic HOST:PORT`: a Neuroelectrics Starstim behind NIC's TCP data protocol (binary or
//!   ASCII, 8 channels in nV, trigger, timestamp in ms). The simulated person also needs to see
//!   the panel: the next port (PORT + 1, or `--panel-port`) takes the panel's flashes and clock
//!   (`F onset code attended`, `T sample`); a real amplifier has no such port. The simulator
//!   serves one session and exits.
//! * `--lsl NAME` (liblsl loaded at run time, see `oddball_live::lsl`): a Lab Streaming Layer EEG outlet (500 Hz, the subject's
//!   8 channels, µV) whose sample i is stamped t0 + i / sfreq on LSL's clock. The person watches
//!   the panel through its marker stream (`--markers`, type `Markers`): `cue C` sets the bulb
//!   attended (0 = none), `flash C` stamped t is a flash at sample round((t − t0) · sfreq),
//!   attended when C is the cue; `end` stops. So that a flash can still change the EEG when its
//!   marker arrives, the outlet streams `--latency-ms` behind real time (sample i is sent at
//!   t0 + i / sfreq + latency); markers that come later than that are counted and reported. The
//!   marker stream is looked for in the background: background EEG flows until it appears.

use std::net::SocketAddr;

use anyhow::{bail, Context, Result};
use oddball_live::lsl_sim::SimEvent;
use oddball_live::nic::serve_simulated;
use oddball_session::subject::{SubjectParams, SubjectPreset, STARSTIM_SFREQ};

use crate::args::{resolve, NicWire};

/// Options of `oddball simulate`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("wire").required(true).args(["nic", "lsl"])))]
pub struct SimulateArgs {
    /// Serve NIC's TCP data stream on this address (loopback unless --allow-remote; port 0
    /// picks a free port, printed on the first line).
    #[arg(long, value_name = "HOST:PORT")]
    pub nic: Option<String>,
    /// Let --nic bind a non-loopback address (its data and panel ports are then reachable from
    /// the network).
    #[arg(long, requires = "nic")]
    pub allow_remote: bool,
    /// Stream as a Lab Streaming Layer EEG outlet of this name, following the panel's marker
    /// stream (needs liblsl: pip install pylsl, or set ODDBALL_LIBLSL; the name is printed on
    /// the first line).
    #[arg(long, value_name = "NAME")]
    pub lsl: Option<String>,
    /// LSL: name of the panel's marker stream to follow.
    #[arg(long, default_value = "oddball-markers", value_name = "NAME")]
    pub markers: String,
    /// LSL: how far behind real time the EEG is sent, ms (a flash marker must arrive before its
    /// onset sample is sent).
    #[arg(long, default_value_t = 250.0)]
    pub latency_ms: f64,
    /// LSL: stop after this many seconds [default: at the `end` marker].
    #[arg(long)]
    pub duration_s: Option<f64>,
    /// Port of the panel's flashes and clock [default: the data port + 1].
    #[arg(long)]
    pub panel_port: Option<u16>,
    #[command(flatten)]
    pub wire: NicWire,
    /// easy, typical or hard.
    #[arg(long, default_value = "typical")]
    pub subject: SubjectPreset,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let preset = args.subject;
    match (&args.nic, &args.lsl) {
        (Some(nic), None) => run_nic(args, nic, preset),
        (None, Some(name)) => run_lsl(args, name, preset),
        _ => bail!("give one of --nic HOST:PORT or --lsl NAME"),
    }
}

fn run_lsl(args: &SimulateArgs, name: &str, preset: SubjectPreset) -> Result<()> {
    if !(args.latency_ms.is_finite() && (0.0..=10_000.0).contains(&args.latency_ms)) {
        bail!("--latency-ms {}: expected 0..=10000", args.latency_ms);
    }
    if let Some(d) = args.duration_s {
        if !(d.is_finite() && d > 0.0) {
            bail!("--duration-s {d}: expected a positive number of seconds");
        }
    }
    let subject = SubjectParams::preset(preset)
        .with_seed(args.seed)
        .build()
        .context("building the simulated subject")?;
    let (n_channels, sfreq) = (subject.n_channels(), subject.sfreq());
    let latency_s = args.latency_ms / 1000.0;
    let markers = &args.markers;
    let report = oddball_live::lsl_sim::serve_simulated(
        subject,
        name,
        markers,
        latency_s,
        args.duration_s,
        |event| match event {
            SimEvent::Streaming { t0 } => println!(
                "streaming LSL EEG {name}: {n_channels} channels at {sfreq} Hz from t0 = {t0} (LSL clock), {:.0} ms behind; following the marker stream {markers}",
                latency_s * 1000.0
            ),
            SimEvent::Following(m) => println!("following markers from {m}"),
            SimEvent::MarkersLost(e) => eprintln!("oddball simulate: marker stream: {e}"),
            SimEvent::Ignored(text) => eprintln!("oddball simulate: ignoring the marker {text:?}"),
        },
    )
    .with_context(|| format!("creating the LSL stream {name}"))?;
    println!(
        "streamed {} samples ({:.1} s), {} flashes ({} attended), {} markers too late, {} not understood",
        report.samples,
        report.samples as f64 / report.sfreq,
        report.flashes,
        report.attended,
        report.late,
        report.unknown
    );
    Ok(())
}

fn run_nic(args: &SimulateArgs, nic: &str, preset: SubjectPreset) -> Result<()> {
    let format = args.wire.format()?;
    let addr = resolve(nic)?;
    let data = oddball_live::listen::bind(addr, args.allow_remote, "nic")
        .with_context(|| format!("--nic {nic}"))?;
    let data_addr = data.local_addr()?;
    let panel_addr = SocketAddr::new(
        data_addr.ip(),
        args.panel_port.unwrap_or(data_addr.port().wrapping_add(1)),
    );
    let panel = oddball_live::listen::bind(panel_addr, args.allow_remote, "panel-port")
        .with_context(|| format!("the panel port {panel_addr}"))?;
    let subject = SubjectParams::preset(preset)
        .with_seed(args.seed)
        .build()
        .context("building the simulated subject")?;
    if format.n_channels != subject.n_channels() {
        bail!(
            "--nic-channels {}: the simulated Starstim has {} channels",
            format.n_channels,
            subject.n_channels()
        );
    }
    println!(
        "serving NIC {} data on {data_addr}, panel on {}",
        args.wire.nic_mode.name(),
        panel.local_addr()?
    );
    let start_ms = 1_700_000_000_000;
    let report = serve_simulated(data, panel, subject, format, start_ms)?;
    println!(
        "served {} samples ({:.1} s) and {} flashes",
        report.samples,
        report.samples as f64 / STARSTIM_SFREQ,
        report.flashes
    );
    Ok(())
}
