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
    /// binary or ascii framing.
    #[arg(long, default_value = "binary")]
    pub nic_mode: String,
    /// easy, typical or hard.
    #[arg(long, default_value = "typical")]
    pub subject: String,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
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
    let format = NicFormat::starstim(mode(&args.nic_mode)?);
    let addr = resolve(&args.nic)?;
    let data = TcpListener::bind(addr).with_context(|| format!("binding {addr}"))?;
    let data_addr = data.local_addr()?;
    let panel_addr = SocketAddr::new(
        data_addr.ip(),
        args.panel_port.unwrap_or(data_addr.port().wrapping_add(1)),
    );
    let panel = TcpListener::bind(panel_addr).with_context(|| format!("binding {panel_addr}"))?;
    println!(
        "serving NIC {} data on {data_addr}, panel on {}",
        args.nic_mode,
        panel.local_addr()?
    );
    let subject = SubjectParams::preset(preset)
        .with_seed(args.seed)
        .build()
        .context("building the simulated subject")?;
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

/// Connects a session subject to `oddball simulate --nic HOST:PORT` (panel on PORT + 1).
pub fn connect_nic(addr: &str, mode_name: &str, preset: SubjectPreset) -> Result<NicSubject> {
    let data = resolve(addr)?;
    let format = NicFormat::starstim(mode(mode_name)?);
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
