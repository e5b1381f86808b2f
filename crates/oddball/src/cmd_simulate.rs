//! `oddball simulate --nic HOST:PORT`: the simulated subject as a Neuroelectrics Starstim behind
//! NIC's TCP data protocol, so a session runs across processes as with the real amplifier.
//!
//! The data port speaks NIC (binary or ASCII, 8 channels in nV, trigger, timestamp in ms). The
//! simulated person also needs to see the panel: the next port (PORT + 1, or `--panel-port`)
//! takes the panel's flashes and clock (`F onset code attended`, `T sample`); a real amplifier
//! has no such port. The simulator serves one session and exits.

use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};

use anyhow::{bail, Context, Result};
use oddball_session::nic::{serve_simulated, NicFormat, NicMode, NicSource, NicSubject, Reconnect};
use oddball_session::subject::{SubjectParams, SubjectPreset, STARSTIM_SFREQ};

/// Options of `oddball simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Serve NIC's TCP data stream on this address (loopback unless you say otherwise; port 0
    /// picks a free port, printed on the first line).
    #[arg(long, value_name = "HOST:PORT")]
    pub nic: String,
    /// Port of the panel's flashes and clock [default: the data port + 1].
    #[arg(long)]
    pub panel_port: Option<u16>,
    #[command(flatten)]
    pub wire: NicWire,
    /// easy, typical or hard.
    #[arg(long, default_value = "typical")]
    pub subject: String,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// How NIC's stream is framed: shared by the simulator and the session reading it.
#[derive(Debug, Clone, clap::Args)]
pub struct NicWire {
    /// binary or ascii framing.
    #[arg(long, default_value = "binary")]
    pub nic_mode: String,
    /// EEG channels per sample (the simulated Starstim has 8).
    #[arg(long, default_value_t = 8)]
    pub nic_channels: usize,
    /// The stream carries no trigger column.
    #[arg(long)]
    pub nic_no_trigger: bool,
    /// The stream carries no timestamp (lost samples cannot be counted).
    #[arg(long)]
    pub nic_no_timestamp: bool,
}

impl NicWire {
    pub fn format(&self) -> Result<NicFormat> {
        if !(1..=64).contains(&self.nic_channels) {
            bail!("--nic-channels {}: expected 1..=64", self.nic_channels);
        }
        Ok(NicFormat {
            mode: mode(&self.nic_mode)?,
            n_channels: self.nic_channels,
            trigger: !self.nic_no_trigger,
            timestamp: !self.nic_no_timestamp,
        })
    }
}

pub fn mode(name: &str) -> Result<NicMode> {
    match name {
        "binary" => Ok(NicMode::Binary),
        "ascii" => Ok(NicMode::Ascii),
        other => bail!("NIC mode {other:?}: expected binary or ascii"),
    }
}

fn resolve(addr: &str) -> Result<SocketAddr> {
    addr.to_socket_addrs()
        .with_context(|| format!("{addr}: expected HOST:PORT"))?
        .next()
        .with_context(|| format!("{addr}: no address"))
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let preset: SubjectPreset = args
        .subject
        .parse()
        .map_err(|e| anyhow::anyhow!("--subject {}: {e}", args.subject))?;
    let format = args.wire.format()?;
    let addr = resolve(&args.nic)?;
    let data = TcpListener::bind(addr).with_context(|| format!("binding {addr}"))?;
    let data_addr = data.local_addr()?;
    let panel_addr = SocketAddr::new(
        data_addr.ip(),
        args.panel_port.unwrap_or(data_addr.port().wrapping_add(1)),
    );
    let panel = TcpListener::bind(panel_addr).with_context(|| format!("binding {panel_addr}"))?;
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
        args.wire.nic_mode,
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

/// Connects a session subject to a NIC stream at `addr`, with the simulator's panel port
/// (PORT + 1) when there is one. Channel names: the simulated montage for 8 channels, else
/// `Ch1..ChN`.
pub fn connect_nic(addr: &str, wire: &NicWire, preset: SubjectPreset) -> Result<NicSubject> {
    let data = resolve(addr)?;
    let format = wire.format()?;
    let source = NicSource::connect(data, format, STARSTIM_SFREQ, Reconnect::default())
        .with_context(|| format!("connecting to the NIC stream at {data}"))?;
    let panel_addr = SocketAddr::new(data.ip(), data.port().wrapping_add(1));
    let panel = TcpStream::connect(panel_addr)
        .with_context(|| format!("connecting to the simulator's panel port {panel_addr}"))?;
    let ch_names = SubjectParams::preset(preset).ch_names;
    Ok(NicSubject::new(
        source,
        Some(panel),
        STARSTIM_SFREQ,
        ch_names,
    ))
}
