//! Lab Streaming Layer (LSL): EEG in, markers and decisions out.
//!
//! LSL is how lab EEG amplifiers, stimulus programs and recorders find each other and share one
//! clock: every sample carries a timestamp on the sender's `local_clock()`, and an inlet measures
//! the offset to its own clock (`time_correction`). This module wraps liblsl in the few types a
//! session needs, so the rest of the code sees `ndarray` blocks in µV with timestamps on this
//! machine's clock and [`LiveError`]s, never liblsl's handles:
//!
//! * [`EegInlet`]: a regular-rate EEG stream found by name or type ([`StreamQuery`]); its
//!   channel labels and unit come from the stream's `desc/channels`; [`EegInlet::read`] blocks
//!   until `n` more samples have arrived and fails with [`LiveError::StreamStalled`] when the
//!   stream goes quiet, so a session never hangs on a dead amplifier.
//! * [`MarkerOutlet`] / [`MarkerInlet`]: irregular-rate, one-channel string streams (the panel's
//!   `cue C`, `flash C`, `decision C`, `abstain`, `end`; a second outlet of type
//!   `oddball-decisions` carries the decisions). The inlet also reads the numeric marker
//!   streams other stimulus programs send (int8…int64, float32, double64), as decimal text.
//! * [`EegOutlet`]: a regular-rate float32 EEG stream, for the simulated amplifier (`oddball
//!   simulate --lsl`) and for tests.
//!
//! # liblsl, loaded at run time
//! Every build speaks LSL: liblsl's C API is loaded when the first LSL call needs it, once per
//! process ([`library`]), as pylsl loads it. It is looked for, in order ([`find`]):
//! 1. the file `ODDBALL_LIBLSL` names (then only there), or pylsl's `PYLSL_LIB`;
//! 2. the system's (`liblsl.so`, `liblsl.so.2`, …; `liblsl.dylib`; `lsl.dll`) through the
//!    dynamic loader's search path;
//! 3. pylsl's bundled copy (`pylsl/lib/` of pylsl ≥ 1.16 wheels) in the site-packages of
//!    `$VIRTUAL_ENV`, `$CONDA_PREFIX` and `~/.local`, and last the pylsl `python3` imports.
//!
//! When none loads, every LSL call fails with [`LiveError::LiblslNotFound`], which lists the
//! places tried and says how to get it (`pip install pylsl`, or set `ODDBALL_LIBLSL`). The
//! unsafe code of the calls into it is all in [`ffi`].
//!
//! liblsl reads its network settings from the file named by the environment variable
//! `LSLAPICFG` (read once, at the first LSL call of the process); `tools/lsl/lsl_api.cfg` keeps
//! everything on loopback for tests.
//!
//! All types are [`Send`]: a reader may run on its own thread. They are not `Sync`: one thread
//! at a time uses each.

use std::collections::VecDeque;
use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

use ndarray::{Array2, ArrayView2};
use oddball_io::units::stream_microvolts_per;

use crate::LiveError;
use ffi::{Fault, Format, Inlet, Outlet, StreamInfo};

pub mod ffi;
pub mod find;

pub use ffi::{load_from, Liblsl};
pub use find::{candidates, liblsl_of_python, Candidate};

/// Seconds of data liblsl buffers per inlet and outlet before dropping the oldest.
const MAX_BUFFERED_S: i32 = 360;
/// How often the clock offset to the sender is refreshed, s.
const CORRECTION_INTERVAL_S: f64 = 5.0;
/// Longest single wait inside [`EegInlet::read`], s (the stall timeout is checked between).
const POLL_S: f64 = 0.05;
/// liblsl's nominal rate of an irregular stream.
const IRREGULAR_RATE: f64 = 0.0;
/// Default stall timeout of [`EegInlet::read`], s.
pub const DEFAULT_STALL_TIMEOUT_S: f64 = 5.0;
/// Marker stream type of the panel's markers.
pub const MARKER_TYPE: &str = "Markers";
/// Marker stream type of the decisions.
pub const DECISION_TYPE: &str = "oddball-decisions";

/// Samples pulled from liblsl at a time.
const CHUNK: usize = 256;

/// This process's liblsl ([`ffi::liblsl`]): loaded at the first call, the same one (or the same
/// [`LiveError::LiblslNotFound`]) from then on.
pub fn library() -> Result<&'static Liblsl, LiveError> {
    ffi::liblsl()
}

/// What this build can do with LSL, for a version line: `liblsl 1.18.0 loaded from PATH`, or
/// `liblsl not found — pip install pylsl, or set ODDBALL_LIBLSL` (loads liblsl to know).
pub fn library_status() -> String {
    match library() {
        Ok(lib) => format!("liblsl {} loaded from {}", lib.version_text(), lib.place()),
        Err(_) => "liblsl not found — pip install pylsl, or set ODDBALL_LIBLSL".to_string(),
    }
}

/// LSL's clock (monotonic, shared by every LSL program on this machine), seconds. Without
/// liblsl (see [`library`]) no LSL stream exists to agree with, and the process's own monotonic
/// clock stands in.
pub fn local_clock() -> f64 {
    match library() {
        Ok(lib) => lib.local_clock(),
        Err(_) => {
            static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
            START.get_or_init(Instant::now).elapsed().as_secs_f64()
        }
    }
}

/// Which stream to resolve.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum StreamQuery {
    /// The stream's name (`lsl:NAME` on the command line).
    Name(String),
    /// The stream's content type, e.g. `EEG` (`lsl:type=EEG` on the command line).
    Type(String),
}

impl StreamQuery {
    fn prop(&self) -> (&'static str, &str) {
        match self {
            Self::Name(v) => ("name", v),
            Self::Type(v) => ("type", v),
        }
    }
}

impl fmt::Display for StreamQuery {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (prop, value) = self.prop();
        write!(f, "{prop}={value}")
    }
}

impl FromStr for StreamQuery {
    type Err = LiveError;

    /// `NAME`, `name=NAME` or `type=TYPE`, optionally after `lsl:`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let body = s.strip_prefix("lsl:").unwrap_or(s);
        let query = if let Some(t) = body.strip_prefix("type=") {
            Self::Type(t.to_string())
        } else {
            Self::Name(body.strip_prefix("name=").unwrap_or(body).to_string())
        };
        if query.prop().1.is_empty() {
            return Err(LiveError::InvalidParameter {
                name: "LSL stream",
                value: s.to_string(),
                reason: "expected lsl:NAME, lsl:name=NAME or lsl:type=TYPE".to_string(),
            });
        }
        Ok(query)
    }
}

fn lsl_error(what: impl fmt::Display, e: Fault) -> LiveError {
    LiveError::Lsl(format!("{what}: {e}"))
}

/// Maps liblsl's errors on a connected stream; a lost stream is its own variant.
fn stream_error(name: &str, e: Fault) -> LiveError {
    if e.is_lost() {
        LiveError::StreamLost {
            name: name.to_string(),
        }
    } else {
        lsl_error(format!("reading {name}"), e)
    }
}

/// Resolves the first stream matching `query`, opens an inlet on it (`recover`: wait for a
/// stream with a source id that goes away, instead of failing) and fetches its full info (with
/// `desc`). Returns the inlet, the info and the stream's name.
fn open_inlet(
    query: &StreamQuery,
    timeout_s: f64,
    recover: bool,
) -> Result<(Inlet, StreamInfo, String), LiveError> {
    let (prop, value) = query.prop();
    let not_found = || LiveError::StreamNotFound {
        query: query.to_string(),
        timeout_s,
    };
    if !timeout_s.is_finite() || timeout_s < 0.0 {
        return Err(LiveError::InvalidParameter {
            name: "resolve timeout",
            value: timeout_s.to_string(),
            reason: "seconds, finite and ≥ 0".to_string(),
        });
    }
    let lib = library()?;
    let found = ffi::resolve_byprop(lib, prop, value, 1, 1, timeout_s)
        .map_err(|e| lsl_error(format!("resolving {query}"), e))?;
    let info = found.into_iter().next().ok_or_else(not_found)?;
    let name = info.name();
    let inlet = Inlet::new(&info, MAX_BUFFERED_S, 0, recover)
        .map_err(|e| lsl_error(format!("opening an inlet on {name}"), e))?;
    // The stream was just seen: its full info and the connection come within a few round
    // trips; allow at least a second even for a zero resolve timeout.
    let wait = timeout_s.max(1.0);
    let full = inlet
        .full_info(wait)
        .map_err(|e| lsl_error(format!("reading the description of {name}"), e))?;
    inlet
        .open_stream(wait)
        .map_err(|e| lsl_error(format!("connecting to {name}"), e))?;
    Ok((inlet, full, name))
}

/// The offset from a sender's clock to ours, refreshed now and then.
#[derive(Debug)]
struct ClockOffset {
    offset: f64,
    next: Instant,
}

impl ClockOffset {
    /// A first estimate, waiting up to `timeout_s` for it (0 when none comes: same machine).
    fn new(inlet: &Inlet, timeout_s: f64) -> Self {
        let offset = inlet.time_correction(timeout_s).unwrap_or(0.0);
        Self {
            offset,
            next: Instant::now() + Duration::from_secs_f64(CORRECTION_INTERVAL_S),
        }
    }

    /// The current offset; liblsl measures it in the background, so this never waits.
    fn get(&mut self, inlet: &Inlet) -> f64 {
        if Instant::now() >= self.next {
            if let Ok(c) = inlet.time_correction(0.0) {
                self.offset = c;
            }
            self.next = Instant::now() + Duration::from_secs_f64(CORRECTION_INTERVAL_S);
        }
        self.offset
    }
}

/// A live EEG stream: samples in µV with timestamps on this machine's LSL clock.
#[derive(Debug)]
pub struct EegInlet {
    inlet: Inlet,
    name: String,
    sfreq: f64,
    ch_names: Vec<String>,
    /// Per channel, the factor to µV.
    scale: Vec<f64>,
    clock: ClockOffset,
    stall_timeout: f64,
    /// Samples pulled but not yet read: values (channel after channel) and timestamps.
    pending: VecDeque<f64>,
    pending_ts: VecDeque<f64>,
    /// liblsl's buffers: one sample, and a chunk of samples with their timestamps.
    sample: Vec<f64>,
    chunk: Vec<f64>,
    chunk_ts: Vec<f64>,
    last_ts: Option<f64>,
    lost: u64,
}

impl EegInlet {
    /// Finds the first stream matching `query` within `timeout_s` seconds and connects to it.
    /// It must have a nominal rate and a numeric format; channel labels and units come from
    /// `desc/channels/channel/{label,unit}` (labels `ch1..chN` when missing; units µV when
    /// missing; volts, millivolts and nanovolts are converted).
    pub fn resolve(query: &StreamQuery, timeout_s: f64) -> Result<Self, LiveError> {
        let (inlet, info, name) = open_inlet(query, timeout_s, true)?;
        let sfreq = info.nominal_srate();
        let n = usize::try_from(info.channel_count()).unwrap_or(0);
        let bad = |what: &'static str, value: String, reason: &str| LiveError::InvalidParameter {
            name: what,
            value,
            reason: format!("stream {name}: {reason}"),
        };
        if !(sfreq.is_finite() && sfreq > 0.0) {
            return Err(bad(
                "sampling rate",
                sfreq.to_string(),
                "an EEG stream needs a nominal sampling rate",
            ));
        }
        if n == 0 {
            return Err(bad("channel count", "0".into(), "no channels"));
        }
        let format = info.channel_format();
        if matches!(format, Format::String | Format::Undefined) {
            return Err(bad(
                "channel format",
                format.to_string(),
                "an EEG stream carries numbers",
            ));
        }
        let (mut labels, mut units) = (Vec::new(), Vec::new());
        let mut ch = info.desc().child("channels").child("channel");
        while !ch.is_empty() {
            labels.push(ch.child_value("label"));
            units.push(ch.child_value("unit"));
            ch = ch.next_sibling("channel");
        }
        let described = labels.len() == n;
        let ch_names: Vec<String> = (0..n)
            .map(|c| match labels.get(c) {
                Some(l) if described && !l.trim().is_empty() => l.trim().to_string(),
                _ => format!("ch{}", c + 1),
            })
            .collect();
        let scale = (0..n)
            .map(|c| {
                let unit = if described { units[c].as_str() } else { "" };
                stream_microvolts_per(unit).ok_or_else(|| {
                    bad(
                        "channel unit",
                        unit.to_string(),
                        &format!("channel {}: not a voltage unit", ch_names[c]),
                    )
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let clock = ClockOffset::new(&inlet, timeout_s.clamp(0.5, 2.0));
        Ok(Self {
            inlet,
            name,
            sfreq,
            ch_names,
            scale,
            clock,
            stall_timeout: DEFAULT_STALL_TIMEOUT_S,
            pending: VecDeque::new(),
            pending_ts: VecDeque::new(),
            sample: vec![0.0; n],
            chunk: vec![0.0; n * CHUNK],
            chunk_ts: vec![0.0; CHUNK],
            last_ts: None,
            lost: 0,
        })
    }

    /// The stream's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Nominal sampling rate, Hz.
    pub fn sfreq(&self) -> f64 {
        self.sfreq
    }

    pub fn n_channels(&self) -> usize {
        self.ch_names.len()
    }

    /// Channel labels from the stream's description, else `ch1..chN`.
    pub fn ch_names(&self) -> &[String] {
        &self.ch_names
    }

    /// How long [`EegInlet::read`] waits for a sample before giving up, seconds (default 5).
    pub fn set_stall_timeout(&mut self, s: f64) {
        self.stall_timeout = if s.is_finite() && s > 0.0 {
            s
        } else {
            DEFAULT_STALL_TIMEOUT_S
        };
    }

    /// Samples missing from the stream so far, counted from timestamp gaps longer than 1.5
    /// sample periods.
    pub fn lost_samples(&self) -> u64 {
        self.lost
    }

    /// The current offset from the sender's clock to ours, s (≈ 0 on one machine).
    pub fn time_correction(&mut self) -> f64 {
        self.clock.get(&self.inlet)
    }

    /// Samples that have arrived and wait to be read (without waiting for more).
    pub fn available(&mut self) -> Result<usize, LiveError> {
        self.pull(0.0)?;
        Ok(self.pending_ts.len())
    }

    /// Blocks until `n` more samples have arrived: data `(n_channels, n)` in µV and each
    /// sample's timestamp on this machine's LSL clock. Fails with
    /// [`LiveError::StreamStalled`] when nothing arrives for the stall timeout, and with
    /// [`LiveError::StreamLost`] when liblsl gives the stream up.
    pub fn read(&mut self, n: usize) -> Result<(Array2<f64>, Vec<f64>), LiveError> {
        let mut last_arrival = Instant::now();
        while self.pending_ts.len() < n {
            let waited = last_arrival.elapsed().as_secs_f64();
            if waited >= self.stall_timeout {
                return Err(LiveError::StreamStalled {
                    name: self.name.clone(),
                    seconds: self.stall_timeout,
                });
            }
            if self.pull(POLL_S.min(self.stall_timeout - waited))? > 0 {
                last_arrival = Instant::now();
            }
        }
        let nc = self.n_channels();
        let mut data = Array2::zeros((nc, n));
        for (i, mut col) in data.columns_mut().into_iter().enumerate() {
            for (c, v) in col.iter_mut().enumerate() {
                *v = self.pending[i * nc + c] * self.scale[c];
            }
        }
        self.pending.drain(..n * nc);
        let ts = self.pending_ts.drain(..n).collect();
        Ok((data, ts))
    }

    /// Pulls what has arrived, waiting up to `wait` s for the first sample. Returns the count.
    fn pull(&mut self, wait: f64) -> Result<usize, LiveError> {
        let ts = self
            .inlet
            .pull_sample_f64(&mut self.sample, wait)
            .map_err(|e| stream_error(&self.name, e))?;
        if ts == 0.0 {
            return Ok(0);
        }
        let sample = std::mem::take(&mut self.sample);
        self.push_pending(&sample, ts);
        self.sample = sample;
        let mut count = 1;
        loop {
            let n = self
                .inlet
                .pull_chunk_f64(&mut self.chunk, &mut self.chunk_ts)
                .map_err(|e| stream_error(&self.name, e))?;
            let (chunk, chunk_ts) = (
                std::mem::take(&mut self.chunk),
                std::mem::take(&mut self.chunk_ts),
            );
            let nc = self.n_channels();
            for (i, &ts) in chunk_ts[..n].iter().enumerate() {
                self.push_pending(&chunk[i * nc..(i + 1) * nc], ts);
            }
            (self.chunk, self.chunk_ts) = (chunk, chunk_ts);
            count += n;
            if n < CHUNK {
                return Ok(count);
            }
        }
    }

    /// Keeps one pulled sample stamped `ts` (sender's clock), counting samples lost before it.
    fn push_pending(&mut self, sample: &[f64], ts: f64) {
        let ts = ts + self.clock.get(&self.inlet);
        if let Some(prev) = self.last_ts {
            let periods = (ts - prev) * self.sfreq;
            if periods > 1.5 {
                self.lost += (periods.round() as u64).saturating_sub(1);
            }
        }
        self.last_ts = Some(ts);
        self.pending.extend(sample);
        self.pending_ts.push_back(ts);
    }
}

/// An irregular-rate, one-channel string stream of markers.
#[derive(Debug)]
pub struct MarkerOutlet {
    outlet: Outlet,
    name: String,
}

impl MarkerOutlet {
    /// A marker stream of type `Markers` (the panel's `cue`, `flash`, `decision`, `abstain`,
    /// `end`). `source_id` lets receivers reconnect to it after a restart.
    pub fn new(name: &str, source_id: &str) -> Result<Self, LiveError> {
        Self::with_type(name, MARKER_TYPE, source_id)
    }

    /// A marker stream of another type, e.g. [`DECISION_TYPE`].
    pub fn with_type(name: &str, stream_type: &str, source_id: &str) -> Result<Self, LiveError> {
        let what = || format!("creating the marker stream {name}");
        let info = StreamInfo::new(
            library()?,
            name,
            stream_type,
            1,
            IRREGULAR_RATE,
            Format::String,
            source_id,
        )
        .map_err(|e| lsl_error(what(), e))?;
        info.desc().append_child_value("manufacturer", "oddball");
        let outlet = Outlet::new(&info, 0, MAX_BUFFERED_S).map_err(|e| lsl_error(what(), e))?;
        Ok(Self {
            outlet,
            name: name.to_string(),
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Sends `marker` stamped `timestamp` (LSL clock; 0 = now). Only receivers connected at the
    /// time get it.
    pub fn push(&self, marker: &str, timestamp: f64) {
        // Only a wrong channel count could fail, and there is always one channel.
        let _ = self.outlet.push_strings(&[marker], timestamp, true);
    }

    /// Whether a receiver is connected.
    pub fn have_consumers(&self) -> bool {
        self.outlet.have_consumers()
    }

    /// Waits up to `timeout_s` for a receiver; whether one is connected.
    pub fn wait_for_consumers(&self, timeout_s: f64) -> bool {
        self.outlet.wait_for_consumers(timeout_s)
    }
}

/// A marker stream being received: strings, or numbers as their decimal text.
#[derive(Debug)]
pub struct MarkerInlet {
    inlet: Inlet,
    name: String,
    hostname: String,
    values: MarkerValues,
    clock: ClockOffset,
}

/// The buffer one marker sample is pulled into, by the stream's channel format.
#[derive(Debug)]
enum MarkerValues {
    Strings(usize, Vec<String>),
    Float(Vec<f32>),
    Double(Vec<f64>),
    Int(Vec<i32>),
}

impl MarkerInlet {
    /// Finds the first stream matching `query` within `timeout_s` seconds and connects to it;
    /// markers sent from then on are received. Any channel format: strings, or numbers
    /// (int8…int64, float32, double64) received as their decimal text. A stream that goes away
    /// is not waited for: [`MarkerInlet::pull`] then fails with [`LiveError::StreamLost`].
    pub fn resolve(query: &StreamQuery, timeout_s: f64) -> Result<Self, LiveError> {
        let (inlet, info, name) = open_inlet(query, timeout_s, false)?;
        let n = usize::try_from(info.channel_count()).unwrap_or(0).max(1);
        let values = match info.channel_format() {
            Format::String | Format::Undefined => MarkerValues::Strings(n, Vec::new()),
            Format::Float32 => MarkerValues::Float(vec![0.0; n]),
            // int64 through double: exact up to 2^53, far beyond any marker code.
            Format::Double64 | Format::Int64 => MarkerValues::Double(vec![0.0; n]),
            Format::Int32 | Format::Int16 | Format::Int8 => MarkerValues::Int(vec![0; n]),
        };
        let clock = ClockOffset::new(&inlet, timeout_s.clamp(0.5, 2.0));
        Ok(Self {
            inlet,
            name,
            hostname: info.hostname(),
            values,
            clock,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The host the stream comes from (as its outlet reports it), for reports.
    pub fn hostname(&self) -> &str {
        &self.hostname
    }

    /// The current offset from the sender's clock to ours, s (≈ 0 on one machine), for reports;
    /// [`MarkerInlet::pull`] adds it to every timestamp.
    pub fn time_correction(&mut self) -> f64 {
        self.clock.get(&self.inlet)
    }

    /// The markers that have arrived, with their timestamps on this machine's LSL clock;
    /// never waits. Multi-channel samples are joined with spaces; a number is its shortest
    /// decimal text (`3`, not `3.0`; `0.25`). Fails with [`LiveError::StreamLost`] once the
    /// stream is gone.
    pub fn pull(&mut self) -> Result<Vec<(String, f64)>, LiveError> {
        let mut out = Vec::new();
        loop {
            let inlet = &self.inlet;
            let (ts, text) = match &mut self.values {
                MarkerValues::Strings(n, buf) => {
                    let ts = inlet.pull_sample_strings(*n, buf, 0.0);
                    (ts, buf.join(" "))
                }
                MarkerValues::Float(buf) => {
                    let ts = inlet.pull_sample_f32(buf, 0.0);
                    (ts, join_numbers(buf))
                }
                MarkerValues::Double(buf) => {
                    let ts = inlet.pull_sample_f64(buf, 0.0);
                    (ts, join_numbers(buf))
                }
                MarkerValues::Int(buf) => {
                    let ts = inlet.pull_sample_i32(buf, 0.0);
                    (ts, join_numbers(buf))
                }
            };
            let ts = ts.map_err(|e| stream_error(&self.name, e))?;
            if ts == 0.0 {
                return Ok(out);
            }
            out.push((text, ts + self.clock.get(&self.inlet)));
        }
    }
}

/// Numbers as decimal text, joined with spaces (Rust's shortest form: `3` for 3.0).
fn join_numbers<T: fmt::Display>(values: &[T]) -> String {
    values
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// A regular-rate float32 EEG stream with channel labels and units in its description.
#[derive(Debug)]
pub struct EegOutlet {
    outlet: Outlet,
    sfreq: f64,
    n_channels: usize,
}

impl EegOutlet {
    /// An EEG stream (type `EEG`) of `ch_names` at `sfreq` Hz in µV.
    pub fn new(
        name: &str,
        ch_names: &[String],
        sfreq: f64,
        source_id: &str,
    ) -> Result<Self, LiveError> {
        Self::with_unit(name, ch_names, sfreq, source_id, "microvolts")
    }

    /// An EEG stream whose samples are in `unit` (pushed as given, labelled so).
    pub fn with_unit(
        name: &str,
        ch_names: &[String],
        sfreq: f64,
        source_id: &str,
        unit: &str,
    ) -> Result<Self, LiveError> {
        if !(sfreq.is_finite() && sfreq > 0.0) {
            return Err(LiveError::InvalidParameter {
                name: "sampling rate",
                value: sfreq.to_string(),
                reason: "Hz, finite and > 0".to_string(),
            });
        }
        if ch_names.is_empty() {
            return Err(LiveError::InvalidParameter {
                name: "channels",
                value: "[]".to_string(),
                reason: "at least one channel".to_string(),
            });
        }
        let what = || format!("creating the EEG stream {name}");
        let n_channels =
            i32::try_from(ch_names.len()).map_err(|_| LiveError::InvalidParameter {
                name: "channels",
                value: ch_names.len().to_string(),
                reason: "too many for an LSL stream".to_string(),
            })?;
        let info = StreamInfo::new(
            library()?,
            name,
            "EEG",
            n_channels,
            sfreq,
            Format::Float32,
            source_id,
        )
        .map_err(|e| lsl_error(what(), e))?;
        let desc = info.desc();
        desc.append_child_value("manufacturer", "oddball");
        let channels = desc.append_child("channels");
        for label in ch_names {
            channels
                .append_child("channel")
                .append_child_value("label", label)
                .append_child_value("unit", unit)
                .append_child_value("type", "EEG");
        }
        let outlet = Outlet::new(&info, 0, MAX_BUFFERED_S).map_err(|e| lsl_error(what(), e))?;
        Ok(Self {
            outlet,
            sfreq,
            n_channels: ch_names.len(),
        })
    }

    pub fn sfreq(&self) -> f64 {
        self.sfreq
    }

    /// Whether a receiver is connected.
    pub fn have_consumers(&self) -> bool {
        self.outlet.have_consumers()
    }

    /// Waits up to `timeout_s` for a receiver; whether one is connected.
    pub fn wait_for_consumers(&self, timeout_s: f64) -> bool {
        self.outlet.wait_for_consumers(timeout_s)
    }

    /// Sends `data` `(n_channels, n)`; sample `i` is stamped `first_timestamp + i / sfreq`
    /// (LSL clock). Panics when the channel count differs from the stream's.
    pub fn push_chunk(&self, data: ArrayView2<f64>, first_timestamp: f64) {
        assert_eq!(
            data.nrows(),
            self.n_channels,
            "EegOutlet::push_chunk: {} rows for a {}-channel stream",
            data.nrows(),
            self.n_channels
        );
        // Sample after sample (the transpose of `data`), each with its own timestamp.
        let values: Vec<f32> = data.t().iter().map(|v| *v as f32).collect();
        let stamps: Vec<f64> = (0..data.ncols())
            .map(|i| first_timestamp + i as f64 / self.sfreq)
            .collect();
        // Only a wrong channel count could fail, checked above.
        let _ = self.outlet.push_chunk_f32(&values, &stamps, true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_parse_and_print() {
        let q: StreamQuery = "lsl:Starstim".parse().unwrap();
        assert_eq!(q, StreamQuery::Name("Starstim".into()));
        assert_eq!(q.to_string(), "name=Starstim");
        assert_eq!(
            "lsl:type=EEG".parse::<StreamQuery>().unwrap(),
            StreamQuery::Type("EEG".into())
        );
        assert_eq!(
            "name=x".parse::<StreamQuery>().unwrap(),
            StreamQuery::Name("x".into())
        );
        assert!("lsl:".parse::<StreamQuery>().is_err());
        assert!("type=".parse::<StreamQuery>().is_err());
    }

    /// The inlet scales a stream by the rule its XDF recording is read back with: an `MV`
    /// stream is millivolts both live and read back (it was ×1000 live and ×1 read back).
    #[test]
    fn units_convert_to_microvolts_as_their_xdf_recording_reads_back() {
        let tmp = oddball_testkit::TempDir::new("lsl-units");
        for (k, unit) in [
            "",
            "microvolts",
            "uV",
            "µV",
            "muV",
            "volts",
            "V",
            "millivolts",
            "mV",
            "MV",
            "nanovolts",
            "nV",
            "kV",
            "counts",
            "uvs",
        ]
        .into_iter()
        .enumerate()
        {
            let path = tmp.path().join(format!("u{k}.xdf"));
            let mut w = oddball_io::XdfWriter::create(&path).unwrap();
            let mut spec = oddball_io::XdfStream::eeg("Amp", vec!["C3".into()], 100.0);
            spec.unit = unit.to_string();
            let e = w.add_stream(&spec).unwrap();
            w.push_numeric(e, &[0.0, 0.01], Array2::from_elem((1, 2), 2.0).view())
                .unwrap();
            w.finish().unwrap();
            let read_back = oddball_io::read_xdf(&path)
                .unwrap()
                .xdf()
                .unwrap()
                .scale_to_uv[0];
            match stream_microvolts_per(unit) {
                Some(live) => assert_eq!(live, read_back, "{unit:?}"),
                None => assert_eq!(read_back, 1.0, "{unit:?}: refused live, unscaled read back"),
            }
        }
        assert_eq!(stream_microvolts_per("MV"), Some(1e3));
        assert_eq!(stream_microvolts_per(""), Some(1.0));
        assert_eq!(stream_microvolts_per("counts"), None);
    }
}
