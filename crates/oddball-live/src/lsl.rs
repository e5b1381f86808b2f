//! Lab Streaming Layer (LSL): EEG in, markers and decisions out.
//!
//! LSL is how lab EEG amplifiers, stimulus programs and recorders find each other and share one
//! clock: every sample carries a timestamp on the sender's `local_clock()`, and an inlet measures
//! the offset to its own clock (`time_correction`). This module wraps the `lsl` crate (Rust
//! bindings over liblsl, built from source with cmake) in the few types a session needs, so the
//! rest of the code sees `ndarray` blocks in µV with timestamps on this machine's clock and
//! [`LiveError`]s, never liblsl's handles:
//!
//! * [`EegInlet`]: a regular-rate EEG stream found by name or type ([`StreamQuery`]); its
//!   channel labels and unit come from the stream's `desc/channels`; [`EegInlet::read`] blocks
//!   until `n` more samples have arrived and fails with [`LiveError::StreamStalled`] when the
//!   stream goes quiet, so a session never hangs on a dead amplifier.
//! * [`MarkerOutlet`] / [`MarkerInlet`]: irregular-rate, one-channel string streams (the panel's
//!   `cue C`, `flash C`, `decision C`, `abstain`, `end`; a second outlet of type
//!   `oddball-decisions` carries the decisions).
//! * [`EegOutlet`]: a regular-rate float32 EEG stream, for the simulated amplifier (`oddball
//!   simulate --lsl`) and for tests.
//!
//! liblsl reads its network settings from the file named by the environment variable
//! `LSLAPICFG` (read once, at the first LSL call of the process); `tools/lsl/lsl_api.cfg` keeps
//! everything on loopback for tests.
//!
//! All types are [`Send`]: a reader may run on its own thread. liblsl's inlets and outlets are
//! C++ objects behind opaque handles with no thread affinity; the `lsl` crate only fails to say
//! so because it stores raw pointers. They are not `Sync`: one thread at a time uses each.

use std::collections::VecDeque;
use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

use lsl::{ExPushable, Pullable};
use ndarray::{Array2, ArrayView2};
use oddball_io::units::stream_microvolts_per;

use crate::LiveError;

/// Seconds of data liblsl buffers per inlet and outlet before dropping the oldest.
const MAX_BUFFERED_S: i32 = 360;
/// How often the clock offset to the sender is refreshed, s.
const CORRECTION_INTERVAL_S: f64 = 5.0;
/// Longest single wait inside [`EegInlet::read`], s (the stall timeout is checked between).
const POLL_S: f64 = 0.05;
/// Default stall timeout of [`EegInlet::read`], s.
pub const DEFAULT_STALL_TIMEOUT_S: f64 = 5.0;
/// Marker stream type of the panel's markers.
pub const MARKER_TYPE: &str = "Markers";
/// Marker stream type of the decisions.
pub const DECISION_TYPE: &str = "oddball-decisions";

/// LSL's clock (monotonic, shared by every LSL program on this machine), seconds.
pub fn local_clock() -> f64 {
    lsl::local_clock()
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

fn lsl_error(what: impl fmt::Display, e: lsl::Error) -> LiveError {
    LiveError::Lsl(format!("{what}: {e}"))
}

/// Maps liblsl's errors on a connected stream; a lost stream is its own variant.
fn stream_error(name: &str, e: lsl::Error) -> LiveError {
    match e {
        lsl::Error::StreamLost => LiveError::StreamLost {
            name: name.to_string(),
        },
        e => lsl_error(format!("reading {name}"), e),
    }
}

/// Resolves the first stream matching `query`, opens an inlet on it and fetches its full info
/// (with `desc`). Returns the inlet, the info and the stream's name.
fn open_inlet(
    query: &StreamQuery,
    timeout_s: f64,
) -> Result<(lsl::StreamInlet, lsl::StreamInfo, String), LiveError> {
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
    let found = lsl::resolve_byprop(prop, value, 1, timeout_s)
        .map_err(|e| lsl_error(format!("resolving {query}"), e))?;
    let info = found.into_iter().next().ok_or_else(not_found)?;
    let name = info.stream_name();
    let inlet = lsl::StreamInlet::new(&info, MAX_BUFFERED_S, 0, true)
        .map_err(|e| lsl_error(format!("opening an inlet on {name}"), e))?;
    // The stream was just seen: its full info and the connection come within a few round
    // trips; allow at least a second even for a zero resolve timeout.
    let wait = timeout_s.max(1.0);
    let full = inlet
        .info(wait)
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
    fn new(inlet: &lsl::StreamInlet, timeout_s: f64) -> Self {
        let offset = inlet.time_correction(timeout_s).unwrap_or(0.0);
        Self {
            offset,
            next: Instant::now() + Duration::from_secs_f64(CORRECTION_INTERVAL_S),
        }
    }

    /// The current offset; liblsl measures it in the background, so this never waits.
    fn get(&mut self, inlet: &lsl::StreamInlet) -> f64 {
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
    inlet: lsl::StreamInlet,
    name: String,
    sfreq: f64,
    ch_names: Vec<String>,
    /// Per channel, the factor to µV.
    scale: Vec<f64>,
    clock: ClockOffset,
    stall_timeout: f64,
    /// Samples pulled but not yet read: values (channel after channel) and timestamps.
    pending: VecDeque<f32>,
    pending_ts: VecDeque<f64>,
    sample: Vec<f32>,
    last_ts: Option<f64>,
    lost: u64,
}

// SAFETY: liblsl's inlet is a C++ object reached through an opaque handle, with no thread
// affinity; `EegInlet` is not `Sync`, so only one thread at a time calls into it.
#[allow(unsafe_code)]
unsafe impl Send for EegInlet {}

impl EegInlet {
    /// Finds the first stream matching `query` within `timeout_s` seconds and connects to it.
    /// It must have a nominal rate and a numeric format; channel labels and units come from
    /// `desc/channels/channel/{label,unit}` (labels `ch1..chN` when missing; units µV when
    /// missing; volts, millivolts and nanovolts are converted).
    pub fn resolve(query: &StreamQuery, timeout_s: f64) -> Result<Self, LiveError> {
        let (inlet, mut info, name) = open_inlet(query, timeout_s)?;
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
        if matches!(
            format,
            lsl::ChannelFormat::String | lsl::ChannelFormat::Undefined
        ) {
            return Err(bad(
                "channel format",
                format.to_string(),
                "an EEG stream carries numbers",
            ));
        }
        let (mut labels, mut units) = (Vec::new(), Vec::new());
        let mut ch = info.desc().child("channels").child("channel");
        while !ch.empty() {
            labels.push(ch.child_value_named("label"));
            units.push(ch.child_value_named("unit"));
            ch = ch.next_sibling_named("channel");
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
                *v = f64::from(self.pending[i * nc + c]) * self.scale[c];
            }
        }
        self.pending.drain(..n * nc);
        let ts = self.pending_ts.drain(..n).collect();
        Ok((data, ts))
    }

    /// Pulls what has arrived, waiting up to `wait` s for the first sample. Returns the count.
    fn pull(&mut self, wait: f64) -> Result<usize, LiveError> {
        let mut timeout = wait;
        let mut count = 0;
        loop {
            let ts = self
                .inlet
                .pull_sample_buf(&mut self.sample, timeout)
                .map_err(|e| stream_error(&self.name, e))?;
            if ts == 0.0 {
                break;
            }
            timeout = 0.0;
            let ts = ts + self.clock.get(&self.inlet);
            if let Some(prev) = self.last_ts {
                let periods = (ts - prev) * self.sfreq;
                if periods > 1.5 {
                    self.lost += (periods.round() as u64).saturating_sub(1);
                }
            }
            self.last_ts = Some(ts);
            self.pending.extend(&self.sample);
            self.pending_ts.push_back(ts);
            count += 1;
        }
        Ok(count)
    }
}

/// An irregular-rate, one-channel string stream of markers.
#[derive(Debug)]
pub struct MarkerOutlet {
    outlet: lsl::StreamOutlet,
    name: String,
}

// SAFETY: as for `EegInlet`: an opaque liblsl handle without thread affinity, not `Sync`.
#[allow(unsafe_code)]
unsafe impl Send for MarkerOutlet {}

impl MarkerOutlet {
    /// A marker stream of type `Markers` (the panel's `cue`, `flash`, `decision`, `abstain`,
    /// `end`). `source_id` lets receivers reconnect to it after a restart.
    pub fn new(name: &str, source_id: &str) -> Result<Self, LiveError> {
        Self::with_type(name, MARKER_TYPE, source_id)
    }

    /// A marker stream of another type, e.g. [`DECISION_TYPE`].
    pub fn with_type(name: &str, stream_type: &str, source_id: &str) -> Result<Self, LiveError> {
        let what = || format!("creating the marker stream {name}");
        let mut info = lsl::StreamInfo::new(
            name,
            stream_type,
            1,
            lsl::IRREGULAR_RATE,
            lsl::ChannelFormat::String,
            source_id,
        )
        .map_err(|e| lsl_error(what(), e))?;
        info.desc().append_child_value("manufacturer", "oddball");
        let outlet =
            lsl::StreamOutlet::new(&info, 0, MAX_BUFFERED_S).map_err(|e| lsl_error(what(), e))?;
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
        let _ = self
            .outlet
            .push_sample_ex(&vec![marker.to_string()], timestamp, true);
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

/// A marker stream being received.
#[derive(Debug)]
pub struct MarkerInlet {
    inlet: lsl::StreamInlet,
    name: String,
    clock: ClockOffset,
}

// SAFETY: as for `EegInlet`.
#[allow(unsafe_code)]
unsafe impl Send for MarkerInlet {}

impl MarkerInlet {
    /// Finds the first stream matching `query` within `timeout_s` seconds and connects to it;
    /// markers sent from then on are received.
    pub fn resolve(query: &StreamQuery, timeout_s: f64) -> Result<Self, LiveError> {
        let (inlet, _info, name) = open_inlet(query, timeout_s)?;
        let clock = ClockOffset::new(&inlet, timeout_s.clamp(0.5, 2.0));
        Ok(Self { inlet, name, clock })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The markers that have arrived, with their timestamps on this machine's LSL clock;
    /// never waits. Multi-channel samples are joined with spaces.
    pub fn pull(&mut self) -> Result<Vec<(String, f64)>, LiveError> {
        let mut out = Vec::new();
        loop {
            let (sample, ts): (Vec<String>, f64) = self
                .inlet
                .pull_sample(0.0)
                .map_err(|e| stream_error(&self.name, e))?;
            if ts == 0.0 {
                return Ok(out);
            }
            out.push((sample.join(" "), ts + self.clock.get(&self.inlet)));
        }
    }
}

/// A regular-rate float32 EEG stream with channel labels and units in its description.
#[derive(Debug)]
pub struct EegOutlet {
    outlet: lsl::StreamOutlet,
    sfreq: f64,
    n_channels: usize,
}

// SAFETY: as for `EegInlet`.
#[allow(unsafe_code)]
unsafe impl Send for EegOutlet {}

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
        let mut info = lsl::StreamInfo::new(
            name,
            "EEG",
            ch_names.len() as u32,
            sfreq,
            lsl::ChannelFormat::Float32,
            source_id,
        )
        .map_err(|e| lsl_error(what(), e))?;
        let mut desc = info.desc();
        desc.append_child_value("manufacturer", "oddball");
        let mut channels = desc.append_child("channels");
        for label in ch_names {
            channels
                .append_child("channel")
                .append_child_value("label", label)
                .append_child_value("unit", unit)
                .append_child_value("type", "EEG");
        }
        let outlet =
            lsl::StreamOutlet::new(&info, 0, MAX_BUFFERED_S).map_err(|e| lsl_error(what(), e))?;
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
        let n = data.ncols();
        let mut sample = vec![0f32; self.n_channels];
        for (i, col) in data.columns().into_iter().enumerate() {
            for (s, v) in sample.iter_mut().zip(col) {
                *s = *v as f32;
            }
            // Only a wrong channel count could fail, checked above.
            let _ = self.outlet.push_sample_ex(
                &sample,
                first_timestamp + i as f64 / self.sfreq,
                i + 1 == n,
            );
        }
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
