//! Neuroelectrics NIC's TCP data stream as a live [`EegSource`] (the paper reads its Starstim
//! through it), and a simulated Starstim that serves one.
//!
//! The byte codec is [`oddball_io::nic`]. [`NicSource`] reads a live stream, reconnecting when
//! it drops and counting samples lost in timestamp gaps. [`serve_simulated`] is a simulated
//! Starstim: a [`SimulatedSubject`] behind a NIC data port. A simulated person also has to see
//! the panel, so the simulator listens on a second, "panel" port for lines
//! `F <onset> <code> <attended>` (a flash at that sample) and `T <sample>` (the panel's clock:
//! the simulator renders no further than that); [`NicSource::with_panel_port`] speaks to it.
//! With a real amplifier that port does not exist: [`NicSource::with_panel_port_if_any`] reads
//! the stream without it. A panel port that goes away (the simulator stopped) is dropped and
//! sought again after the data stream reconnects: the data stream's own fate (reconnected, or
//! [`LiveError::Reconnect`] after its attempts) is what ends a session, never the panel port.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::time::Duration;

use ndarray::Array2;
use oddball_io::nic::{encode, NicDecoder, NicError, NicFormat, NicSample};
use oddball_session::SimulatedSubject;
use serde::{Deserialize, Serialize};

use crate::clock::{Clock, Pacer};
use crate::live::EegSource;
use crate::LiveError;

/// How a [`NicSource`] treats a dropped or silent connection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reconnect {
    /// Connection attempts after a drop.
    pub attempts: usize,
    pub delay: Duration,
    /// A connection that sends nothing for this long is a stalled stream: the read stops with
    /// [`LiveError::StreamStalled`] (a shorter pause just waits: the session and the arm,
    /// which run on the stream's clock, hold until samples come again). `None`: wait forever.
    pub stall_timeout: Option<Duration>,
}

impl Default for Reconnect {
    fn default() -> Self {
        Self {
            attempts: 5,
            delay: Duration::from_millis(200),
            stall_timeout: Some(Duration::from_secs(10)),
        }
    }
}

/// A live NIC data stream: samples in nV on the wire, µV out, at the nominal `sfreq` (the
/// stream paces itself). Session-clock times are nominal from when the session starts.
#[derive(Debug)]
pub struct NicSource {
    addr: SocketAddr,
    stream: TcpStream,
    decoder: NicDecoder,
    format: NicFormat,
    sfreq: f64,
    ch_names: Vec<String>,
    reconnect: Reconnect,
    ready: VecDeque<NicSample>,
    last_timestamp_ms: Option<i64>,
    /// The simulated amplifier's panel port: flashes and the panel's clock go there.
    panel: Option<TcpStream>,
    /// Where the panel port was found (sought again after a reconnection).
    panel_addr: Option<SocketAddr>,
    /// Samples taken so far.
    position: u64,
    pacer: Pacer,
    /// Samples missing according to timestamp gaps.
    pub lost_samples: u64,
    /// Connections re-established after a drop.
    pub reconnects: usize,
    /// Timestamps that went backwards (or repeated).
    pub timestamp_regressions: u64,
    /// Trigger values seen, by sample (non-zero only).
    pub triggers: Vec<(u64, i32)>,
}

impl NicSource {
    /// Connects to the data port at `addr`; channels named `ch_names` (as many as the format's
    /// channels), `sfreq` Hz.
    pub fn connect(
        addr: SocketAddr,
        format: NicFormat,
        sfreq: f64,
        ch_names: Vec<String>,
        reconnect: Reconnect,
        clock: Clock,
    ) -> Result<Self, LiveError> {
        format.validate()?;
        if ch_names.len() != format.n_channels {
            return Err(LiveError::InvalidParameter {
                name: "NIC channel names",
                value: ch_names.len().to_string(),
                reason: format!("the stream carries {} channels", format.n_channels),
            });
        }
        let stream = connect_with_retries(addr, &reconnect)?;
        Ok(Self {
            addr,
            stream,
            decoder: NicDecoder::new(format),
            format,
            sfreq,
            ch_names,
            reconnect,
            ready: Default::default(),
            last_timestamp_ms: None,
            panel: None,
            panel_addr: None,
            position: 0,
            pacer: Pacer::new(clock, sfreq, false),
            lost_samples: 0,
            reconnects: 0,
            timestamp_regressions: 0,
            triggers: Vec::new(),
        })
    }

    /// Tells the simulated amplifier's panel port at `addr` the flashes and the panel's clock.
    pub fn with_panel_port(mut self, addr: SocketAddr) -> Result<Self, LiveError> {
        let s = TcpStream::connect(addr).map_err(|e| LiveError::Connect {
            addr: format!("{addr} (the simulator's panel port)"),
            reason: e.to_string(),
        })?;
        s.set_nodelay(true).ok();
        self.panel = Some(s);
        self.panel_addr = Some(addr);
        Ok(self)
    }

    /// [`NicSource::with_panel_port`] when something listens at `addr` (the simulator), else
    /// the stream alone (a real amplifier has no panel port).
    pub fn with_panel_port_if_any(mut self, addr: SocketAddr) -> Self {
        if let Ok(s) = TcpStream::connect_timeout(&addr, Duration::from_millis(500)) {
            s.set_nodelay(true).ok();
            self.panel = Some(s);
            self.panel_addr = Some(addr);
        }
        self
    }

    /// Whether flashes are told to a simulator's panel port.
    pub fn has_panel_port(&self) -> bool {
        self.panel.is_some()
    }

    pub fn format(&self) -> NicFormat {
        self.format
    }

    /// Tells the simulator's panel port `line`; a port that went away is dropped (the data
    /// stream says whether the amplifier is gone).
    fn tell_panel(&mut self, line: String) -> Result<(), LiveError> {
        if let Some(p) = &mut self.panel {
            if p.write_all(line.as_bytes()).is_err() {
                self.panel = None;
            }
        }
        Ok(())
    }

    /// The next `n` samples off the wire (blocking), reconnecting if the server drops.
    pub fn read(&mut self, n: usize) -> Result<Vec<NicSample>, LiveError> {
        self.fill(n)?;
        Ok(self.ready.drain(..n).collect())
    }

    /// Reads until `n` samples are ready.
    fn fill(&mut self, n: usize) -> Result<(), LiveError> {
        let mut buf = [0u8; 8192];
        while self.ready.len() < n {
            let got = match self.stream.read(&mut buf) {
                Ok(0) => None,
                Ok(k) => Some(k),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return Err(LiveError::StreamStalled {
                        name: self.addr.to_string(),
                        seconds: self
                            .reconnect
                            .stall_timeout
                            .map_or(0.0, |d| d.as_secs_f64()),
                    });
                }
                Err(_) => None,
            };
            match got {
                Some(k) => {
                    for s in self.decoder.push(&buf[..k])? {
                        if let (Some(t), Some(last)) = (s.timestamp_ms, self.last_timestamp_ms) {
                            let period = 1000.0 / self.sfreq;
                            let gap = ((t - last) as f64 / period).round() as i64 - 1;
                            if gap > 0 {
                                self.lost_samples += gap as u64;
                            } else if t <= last {
                                self.timestamp_regressions += 1;
                            }
                        }
                        self.last_timestamp_ms = s.timestamp_ms.or(self.last_timestamp_ms);
                        self.ready.push_back(s);
                    }
                }
                None => {
                    // Dropped: a partial sample is lost; reconnect or give up.
                    self.decoder.reset();
                    self.stream =
                        connect_with_retries(self.addr, &self.reconnect).map_err(|_| {
                            LiveError::Reconnect {
                                addr: self.addr.to_string(),
                                attempts: self.reconnect.attempts,
                            }
                        })?;
                    self.reconnects += 1;
                    // A restarted simulator listens on its panel port again.
                    if let Some(addr) = self.panel_addr {
                        self.panel = connect_with_retries(addr, &self.reconnect).ok();
                    }
                }
            }
        }
        Ok(())
    }
}

impl EegSource for NicSource {
    fn sfreq(&self) -> f64 {
        self.sfreq
    }
    fn ch_names(&self) -> &[String] {
        &self.ch_names
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        // The simulated world may run this far ahead of what the panel has seen.
        let horizon = self.position + n as u64;
        self.tell_panel(format!("T {horizon}\n"))?;
        self.fill(n)
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        let samples = self.read(n)?;
        let mut out = Array2::zeros((self.ch_names.len(), n));
        for (t, s) in samples.iter().enumerate() {
            for (c, &v) in s.nv.iter().enumerate().take(self.ch_names.len()) {
                out[[c, t]] = f64::from(v) / 1000.0;
            }
            if let Some(tr) = s.trigger.filter(|&v| v != 0) {
                self.triggers.push((self.position + t as u64, tr));
            }
        }
        self.position += n as u64;
        Ok(out)
    }
    fn time_of(&self, sample: u64) -> f64 {
        self.pacer.time_of(sample)
    }
    fn start_now(&mut self) {
        self.pacer.restart_at(self.position);
    }
    fn saw(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), LiveError> {
        self.tell_panel(format!("F {onset} {code} {}\n", u8::from(attended)))
    }
    fn health(&self) -> Option<String> {
        Some(format!(
            "{} samples lost (timestamp gaps), {} timestamps going backwards, {} reconnections",
            self.lost_samples, self.timestamp_regressions, self.reconnects
        ))
    }
}

fn connect_with_retries(addr: SocketAddr, r: &Reconnect) -> Result<TcpStream, LiveError> {
    let mut last = None;
    for attempt in 0..r.attempts.max(1) {
        if attempt > 0 {
            std::thread::sleep(r.delay);
        }
        match TcpStream::connect_timeout(&addr, Duration::from_secs(2)) {
            Ok(s) => {
                s.set_nodelay(true).ok();
                // Every connection, the first and each after a drop, stops waiting after the
                // stall timeout (a reconnected stream that went silent waited for ever).
                s.set_read_timeout(r.stall_timeout).ok();
                return Ok(s);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(LiveError::Connect {
        addr: addr.to_string(),
        reason: last.map_or("no attempt".into(), |e| e.to_string()),
    })
}

/// What the simulated amplifier did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ServeReport {
    pub samples: u64,
    pub flashes: usize,
}

/// Serves `subject` as a NIC data stream on `data` to one client, following the panel's flashes
/// and clock from one client of `panel` (lines `F onset code attended`, `T sample`). Returns
/// when the data client disconnects or the panel closes. Samples carry the flash code in the
/// trigger column at each onset and timestamps from `start_ms` at the sampling rate.
pub fn serve_simulated(
    data: TcpListener,
    panel: TcpListener,
    mut subject: SimulatedSubject,
    format: NicFormat,
    start_ms: i64,
) -> Result<ServeReport, LiveError> {
    let io = |e: std::io::Error| LiveError::Connect {
        addr: "simulated NIC".into(),
        reason: e.to_string(),
    };
    let (mut out, _) = data.accept().map_err(io)?;
    out.set_nodelay(true).ok();
    let (panel_stream, _) = panel.accept().map_err(io)?;
    let mut lines = BufReader::new(panel_stream);
    let sfreq = subject.sfreq();
    let mut report = ServeReport::default();
    let mut triggers: std::collections::BTreeMap<u64, i32> = Default::default();
    let mut line = String::new();
    let mut bytes = Vec::new();
    loop {
        line.clear();
        if lines.read_line(&mut line).map_err(io)? == 0 {
            return Ok(report);
        }
        let mut w = line.split_whitespace();
        match (w.next(), w.next(), w.next(), w.next()) {
            (Some("F"), Some(onset), Some(code), Some(att)) => {
                let onset: u64 = onset.parse().map_err(|_| bad_line(&line))?;
                let code: i32 = code.parse().map_err(|_| bad_line(&line))?;
                subject.flash(onset, att == "1")?;
                triggers.insert(onset, code);
                report.flashes += 1;
            }
            (Some("T"), Some(until), None, None) => {
                let until: u64 = until.parse().map_err(|_| bad_line(&line))?;
                let from = subject.position();
                if until <= from {
                    continue;
                }
                let chunk = subject.render((until - from) as usize);
                bytes.clear();
                for t in 0..chunk.ncols() {
                    let i = from + t as u64;
                    let s = NicSample {
                        nv: chunk
                            .column(t)
                            .iter()
                            .map(|&uv| (uv * 1000.0).round() as i32)
                            .collect(),
                        trigger: Some(triggers.remove(&i).unwrap_or(0)),
                        timestamp_ms: Some(start_ms + (i as f64 * 1000.0 / sfreq).round() as i64),
                    };
                    encode(&format, &s, &mut bytes);
                }
                if out.write_all(&bytes).is_err() {
                    return Ok(report);
                }
                report.samples = until;
            }
            _ => return Err(bad_line(&line)),
        }
    }
}

fn bad_line(line: &str) -> LiveError {
    LiveError::Nic(NicError::Protocol {
        offset: 0,
        reason: format!(
            "panel line {:?} is not `F onset code attended` or `T sample`",
            line.trim()
        ),
    })
}
