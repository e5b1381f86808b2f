//! Neuroelectrics NIC's TCP data stream: the wire the paper reads its Starstim through, and a
//! simulated amplifier that serves it.
//!
//! NIC's data server (default port 1234) sends, per sample:
//! * **binary** mode: `n_channels` little-endian `i32` values in nV, then, if enabled, a
//!   little-endian `i32` trigger, then, if enabled, a little-endian `i64` Unix timestamp in ms;
//! * **ASCII** mode: a 6-byte length field (five digits and a tab, e.g. `00042\t`) followed by
//!   that many bytes of tab-separated values in the same order.
//!
//! [`NicDecoder`] turns bytes, cut anywhere, into samples and names the byte at fault in
//! garbage; [`NicSource`] reads a live stream, reconnecting when it drops and counting samples
//! lost in timestamp gaps; [`NicSubject`] is a session [`Subject`] over it. [`serve_simulated`]
//! is a simulated Starstim: a [`SimulatedSubject`] behind a NIC data port. A simulated person
//! also has to see the panel, so the simulator listens on a second, "panel" port for lines
//! `F <onset> <code> <attended>` (a flash at that sample) and `T <sample>` (the panel's clock:
//! the simulator renders no further than that); with a real amplifier that port does not exist.
//! No crate speaks NIC's protocol; it is written here from the description in Neuroelectrics'
//! NIC/MatNIC documentation.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::time::Duration;

use ndarray::Array2;
use serde::{Deserialize, Serialize};

use crate::engine::Subject;
use crate::subject::SimulatedSubject;
use crate::SessionError;

/// Binary or ASCII framing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NicMode {
    Binary,
    Ascii,
}

/// What each sample carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct NicFormat {
    pub mode: NicMode,
    pub n_channels: usize,
    /// A trigger column after the channels.
    pub trigger: bool,
    /// A timestamp (ms) after the trigger.
    pub timestamp: bool,
}

impl NicFormat {
    /// Starstim 8 in binary mode with trigger and timestamp.
    pub fn starstim(mode: NicMode) -> Self {
        Self {
            mode,
            n_channels: 8,
            trigger: true,
            timestamp: true,
        }
    }

    /// Bytes per sample in binary mode.
    pub fn binary_len(&self) -> usize {
        4 * self.n_channels + 4 * usize::from(self.trigger) + 8 * usize::from(self.timestamp)
    }

    /// At least one value per sample and at most [`MAX_NIC_CHANNELS`] channels (an empty
    /// sample would decode forever from no bytes; a huge count would overflow the frame size).
    pub fn validate(&self) -> Result<(), SessionError> {
        let bad = |reason: &str| {
            Err(SessionError::InvalidParameter {
                name: "NIC format",
                value: format!(
                    "{} channels, trigger {}, timestamp {}",
                    self.n_channels, self.trigger, self.timestamp
                ),
                reason: reason.into(),
            })
        };
        if self.n_channels > MAX_NIC_CHANNELS {
            return bad(&format!("more than {MAX_NIC_CHANNELS} channels"));
        }
        if self.n_channels == 0 && !self.trigger && !self.timestamp {
            return bad("a sample of no values");
        }
        Ok(())
    }
}

/// Most channels a NIC stream may declare.
pub const MAX_NIC_CHANNELS: usize = 1024;

/// One sample off the wire.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NicSample {
    /// Channel values, nV.
    pub nv: Vec<i32>,
    pub trigger: Option<i32>,
    pub timestamp_ms: Option<i64>,
}

/// Largest ASCII payload accepted: 38 channels of 11 characters plus separators.
const MAX_ASCII_LEN: usize = 1024;

/// Appends one encoded sample to `out`.
pub fn encode(format: &NicFormat, s: &NicSample, out: &mut Vec<u8>) {
    match format.mode {
        NicMode::Binary => {
            for v in &s.nv {
                out.extend_from_slice(&v.to_le_bytes());
            }
            if format.trigger {
                out.extend_from_slice(&s.trigger.unwrap_or(0).to_le_bytes());
            }
            if format.timestamp {
                out.extend_from_slice(&s.timestamp_ms.unwrap_or(0).to_le_bytes());
            }
        }
        NicMode::Ascii => {
            let mut fields: Vec<String> = s.nv.iter().map(|v| v.to_string()).collect();
            if format.trigger {
                fields.push(s.trigger.unwrap_or(0).to_string());
            }
            if format.timestamp {
                fields.push(s.timestamp_ms.unwrap_or(0).to_string());
            }
            let body = fields.join("\t");
            out.extend_from_slice(format!("{:05}\t", body.len()).as_bytes());
            out.extend_from_slice(body.as_bytes());
        }
    }
}

/// Incremental decoder: feed bytes as they arrive, get whole samples.
#[derive(Debug, Clone)]
pub struct NicDecoder {
    format: NicFormat,
    buf: Vec<u8>,
    /// Bytes consumed so far (for error offsets).
    consumed: u64,
}

impl NicDecoder {
    pub fn new(format: NicFormat) -> Self {
        Self {
            format,
            buf: Vec::new(),
            consumed: 0,
        }
    }

    /// Bytes received but not yet a whole sample.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// Forgets a partial sample (after a reconnect).
    pub fn reset(&mut self) {
        self.consumed += self.buf.len() as u64;
        self.buf.clear();
    }

    /// Decodes every whole sample in `bytes` (plus what was pending).
    pub fn push(&mut self, bytes: &[u8]) -> Result<Vec<NicSample>, SessionError> {
        self.format.validate()?;
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        let mut at = 0;
        let f = self.format;
        loop {
            match f.mode {
                NicMode::Binary => {
                    let len = f.binary_len();
                    if self.buf.len() - at < len {
                        break;
                    }
                    let b = &self.buf[at..at + len];
                    let i32_at = |k: usize| {
                        i32::from_le_bytes(b[4 * k..4 * k + 4].try_into().expect("4 bytes"))
                    };
                    let nv = (0..f.n_channels).map(i32_at).collect();
                    let trigger = f.trigger.then(|| i32_at(f.n_channels));
                    let ts_at = 4 * f.n_channels + 4 * usize::from(f.trigger);
                    let timestamp_ms = f.timestamp.then(|| {
                        i64::from_le_bytes(b[ts_at..ts_at + 8].try_into().expect("8 bytes"))
                    });
                    out.push(NicSample {
                        nv,
                        trigger,
                        timestamp_ms,
                    });
                    at += len;
                }
                NicMode::Ascii => {
                    if self.buf.len() - at < 6 {
                        break;
                    }
                    let head = &self.buf[at..at + 6];
                    let offset = self.consumed + at as u64;
                    let len = parse_length(head).ok_or_else(|| SessionError::NicProtocol {
                        offset,
                        reason: format!(
                            "length field {:?} is not five digits and a tab",
                            String::from_utf8_lossy(head)
                        ),
                    })?;
                    if len > MAX_ASCII_LEN {
                        return Err(SessionError::NicProtocol {
                            offset,
                            reason: format!("length {len} exceeds {MAX_ASCII_LEN} bytes"),
                        });
                    }
                    if self.buf.len() - at < 6 + len {
                        break;
                    }
                    let body = &self.buf[at + 6..at + 6 + len];
                    out.push(parse_ascii(&f, body, offset + 6)?);
                    at += 6 + len;
                }
            }
        }
        self.buf.drain(..at);
        self.consumed += at as u64;
        Ok(out)
    }
}

fn parse_length(head: &[u8]) -> Option<usize> {
    if head.len() != 6 || head[5] != b'\t' || !head[..5].iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(&head[..5]).ok()?.parse().ok()
}

fn parse_ascii(f: &NicFormat, body: &[u8], offset: u64) -> Result<NicSample, SessionError> {
    let text = std::str::from_utf8(body).map_err(|e| SessionError::NicProtocol {
        offset: offset + e.valid_up_to() as u64,
        reason: "a sample is not UTF-8 text".into(),
    })?;
    let fields: Vec<&str> = text.split('\t').collect();
    let want = f.n_channels + usize::from(f.trigger) + usize::from(f.timestamp);
    if fields.len() != want {
        return Err(SessionError::NicProtocol {
            offset,
            reason: format!("{} values in a sample, expected {want}", fields.len()),
        });
    }
    let mut pos = offset;
    let mut ints = Vec::with_capacity(want);
    for v in &fields {
        let n: i64 = v.trim().parse().map_err(|_| SessionError::NicProtocol {
            offset: pos,
            reason: format!("value {v:?} is not an integer"),
        })?;
        ints.push(n);
        pos += v.len() as u64 + 1;
    }
    let to_i32 = |k: usize| {
        i32::try_from(ints[k]).map_err(|_| SessionError::NicProtocol {
            offset,
            reason: format!("value {} does not fit 32 bits", ints[k]),
        })
    };
    Ok(NicSample {
        nv: (0..f.n_channels).map(to_i32).collect::<Result<_, _>>()?,
        trigger: if f.trigger {
            Some(to_i32(f.n_channels)?)
        } else {
            None
        },
        timestamp_ms: f.timestamp.then(|| ints[want - 1]),
    })
}

/// How a [`NicSource`] treats a dropped or silent connection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Reconnect {
    /// Connection attempts after a drop.
    pub attempts: usize,
    pub delay: Duration,
    /// A connection that sends nothing for this long is a stalled stream: the read stops with
    /// [`SessionError::StreamStalled`] (a shorter pause just waits: the session and the arm,
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

/// A live NIC data stream.
#[derive(Debug)]
pub struct NicSource {
    addr: SocketAddr,
    stream: TcpStream,
    decoder: NicDecoder,
    format: NicFormat,
    sfreq: f64,
    reconnect: Reconnect,
    ready: std::collections::VecDeque<NicSample>,
    last_timestamp_ms: Option<i64>,
    /// Samples missing according to timestamp gaps.
    pub lost_samples: u64,
    /// Connections re-established after a drop.
    pub reconnects: usize,
    /// Timestamps that went backwards (or repeated).
    pub timestamp_regressions: u64,
}

impl NicSource {
    pub fn connect(
        addr: SocketAddr,
        format: NicFormat,
        sfreq: f64,
        reconnect: Reconnect,
    ) -> Result<Self, SessionError> {
        let stream = connect_with_retries(addr, &reconnect)?;
        stream.set_read_timeout(reconnect.stall_timeout).ok();
        Ok(Self {
            addr,
            stream,
            decoder: NicDecoder::new(format),
            format,
            sfreq,
            reconnect,
            ready: Default::default(),
            last_timestamp_ms: None,
            lost_samples: 0,
            reconnects: 0,
            timestamp_regressions: 0,
        })
    }

    pub fn format(&self) -> NicFormat {
        self.format
    }

    /// The next `n` samples (blocking), reconnecting if the server drops.
    pub fn read(&mut self, n: usize) -> Result<Vec<NicSample>, SessionError> {
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
                    return Err(SessionError::StreamStalled {
                        addr: self.addr.to_string(),
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
                            SessionError::StreamLost {
                                addr: self.addr.to_string(),
                                attempts: self.reconnect.attempts,
                            }
                        })?;
                    self.reconnects += 1;
                }
            }
        }
        Ok(self.ready.drain(..n).collect())
    }
}

fn connect_with_retries(addr: SocketAddr, r: &Reconnect) -> Result<TcpStream, SessionError> {
    let mut last = None;
    for attempt in 0..r.attempts.max(1) {
        if attempt > 0 {
            std::thread::sleep(r.delay);
        }
        match TcpStream::connect_timeout(&addr, Duration::from_secs(2)) {
            Ok(s) => {
                s.set_nodelay(true).ok();
                return Ok(s);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(SessionError::Connect {
        addr: addr.to_string(),
        reason: last.map_or("no attempt".into(), |e| e.to_string()),
    })
}

/// A session [`Subject`] whose EEG comes over NIC's TCP stream and whose flashes go to the
/// simulated amplifier's panel port (a real person just sees them).
#[derive(Debug)]
pub struct NicSubject {
    source: NicSource,
    panel: Option<TcpStream>,
    sfreq: f64,
    ch_names: Vec<String>,
    position: u64,
    /// Trigger values seen, by sample (non-zero only).
    pub triggers: Vec<(u64, i32)>,
}

impl NicSubject {
    pub fn new(
        source: NicSource,
        panel: Option<TcpStream>,
        sfreq: f64,
        ch_names: Vec<String>,
    ) -> Self {
        Self {
            source,
            panel,
            sfreq,
            ch_names,
            position: 0,
            triggers: Vec::new(),
        }
    }

    pub fn source(&self) -> &NicSource {
        &self.source
    }

    fn tell_panel(&mut self, line: String) -> Result<(), SessionError> {
        if let Some(p) = &mut self.panel {
            p.write_all(line.as_bytes())
                .map_err(|e| SessionError::Connect {
                    addr: "panel port".into(),
                    reason: e.to_string(),
                })?;
        }
        Ok(())
    }

    /// The next `n` samples, µV; errors instead of panicking when the stream is gone.
    pub fn try_render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        // The simulated world may run this far ahead of what the panel has seen.
        let horizon = self.position + n as u64;
        self.tell_panel(format!("T {horizon}\n"))?;
        let samples = self.source.read(n)?;
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
}

impl Subject for NicSubject {
    fn sfreq(&self) -> f64 {
        self.sfreq
    }
    fn ch_names(&self) -> &[String] {
        &self.ch_names
    }
    fn position(&self) -> u64 {
        self.position
    }
    fn show(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), SessionError> {
        self.tell_panel(format!("F {onset} {code} {}\n", u8::from(attended)))
    }
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        self.try_render(n)
    }
    fn stream_health(&self) -> Option<String> {
        Some(format!(
            "{} samples lost (timestamp gaps), {} timestamps going backwards, {} reconnections",
            self.source.lost_samples, self.source.timestamp_regressions, self.source.reconnects
        ))
    }
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
) -> Result<ServeReport, SessionError> {
    let io = |e: std::io::Error| SessionError::Connect {
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

fn bad_line(line: &str) -> SessionError {
    SessionError::NicProtocol {
        offset: 0,
        reason: format!(
            "panel line {:?} is not `F onset code attended` or `T sample`",
            line.trim()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sample(k: i32, f: &NicFormat) -> NicSample {
        NicSample {
            nv: (0..f.n_channels as i32)
                .map(|c| k * 1000 - c * 7 + i32::MIN / 3)
                .collect(),
            trigger: f.trigger.then_some(k % 5),
            timestamp_ms: f.timestamp.then_some(1_700_000_000_000 + 2 * i64::from(k)),
        }
    }

    proptest! {
        /// Any cut of the byte stream decodes to the samples sent, in both modes.
        #[test]
        fn decoding_survives_any_cuts(
            cuts in proptest::collection::vec(1usize..200, 1..30),
            ascii in any::<bool>(),
            trigger in any::<bool>(),
            timestamp in any::<bool>(),
        ) {
            let f = NicFormat { mode: if ascii { NicMode::Ascii } else { NicMode::Binary }, n_channels: 8, trigger, timestamp };
            let sent: Vec<NicSample> = (0..40).map(|k| sample(k, &f)).collect();
            let mut bytes = Vec::new();
            for s in &sent { encode(&f, s, &mut bytes); }
            let mut d = NicDecoder::new(f);
            let mut got = Vec::new();
            let mut at = 0;
            for c in cuts.iter().cycle() {
                if at >= bytes.len() { break; }
                let end = (at + c).min(bytes.len());
                got.extend(d.push(&bytes[at..end]).unwrap());
                at = end;
            }
            prop_assert_eq!(got, sent);
            prop_assert_eq!(d.pending(), 0);
        }
    }

    #[test]
    fn ascii_framing_is_five_digits_and_a_tab() {
        let f = NicFormat {
            mode: NicMode::Ascii,
            n_channels: 2,
            trigger: true,
            timestamp: false,
        };
        let mut b = Vec::new();
        encode(
            &f,
            &NicSample {
                nv: vec![-12, 345],
                trigger: Some(7),
                timestamp_ms: None,
            },
            &mut b,
        );
        assert_eq!(b, b"00009\t-12\t345\t7");
    }

    #[test]
    fn garbage_is_an_error_naming_the_byte() {
        let f = NicFormat {
            mode: NicMode::Ascii,
            n_channels: 2,
            trigger: false,
            timestamp: false,
        };
        let mut d = NicDecoder::new(f);
        assert_eq!(d.push(b"00003\t1\t2").unwrap().len(), 1);
        let err = d.push(b"0x003\t1\t2").unwrap_err();
        assert!(
            matches!(err, SessionError::NicProtocol { offset: 9, .. }),
            "{err}"
        );
        let mut d = NicDecoder::new(f);
        let err = d.push(b"99999\t").unwrap_err();
        assert!(err.to_string().contains("exceeds"), "{err}");
        let mut d = NicDecoder::new(f);
        let err = d.push(b"00004\t1\tzz").unwrap_err();
        assert!(
            matches!(err, SessionError::NicProtocol { offset: 8, .. }),
            "{err}"
        );
        let mut d = NicDecoder::new(f);
        let err = d.push(b"00005\t1\t2\t3").unwrap_err();
        assert!(err.to_string().contains("3 values"), "{err}");
    }
}
