//! Every live EEG source behind one type: what `--source` names on the command line
//! ([`SourceSpec`]: `sim`, `nic:HOST:PORT`, `lsl:NAME` or `lsl:type=TYPE`, `replay:FILE`) and
//! the source it opens ([`AnySource`], an [`EegSource`]).

use std::fmt;
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::str::FromStr;

use ndarray::Array2;
use oddball_io::nic::NicFormat;
use oddball_session::SimulatedSubject;

use crate::clock::Clock;
use crate::live::{EegSource, MarkerSink};
use crate::nic::{NicSource, Reconnect};
use crate::playback::PlaybackSource;
use crate::sim::SimSource;
use crate::LiveError;

/// Where a session's EEG comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SourceSpec {
    /// The simulated subject in this process (`sim`).
    Sim,
    /// A NIC TCP data stream (`nic:HOST:PORT`), e.g. from `oddball simulate --nic HOST:PORT`,
    /// whose simulated panel port is PORT + 1.
    Nic(String),
    /// A Lab Streaming Layer EEG stream by name (`lsl:NAME`) or type (`lsl:type=EEG`); needs
    /// liblsl at run time ([`crate::lsl`]).
    Lsl(String),
    /// A recording played back at its own rate from its first sample (`replay:FILE`).
    Replay(PathBuf),
}

/// The one help text of `--source`.
pub const SOURCE_HELP: &str = "Where the EEG comes from: sim (the simulated subject in this process), nic:HOST:PORT (a NIC TCP data stream, e.g. from `oddball simulate --nic HOST:PORT`, whose panel port is PORT + 1), lsl:NAME or lsl:type=EEG (a Lab Streaming Layer EEG stream; needs liblsl: pip install pylsl, or set ODDBALL_LIBLSL), or replay:FILE (a recording in any format `oddball inspect` reads, played back at its own rate from its first sample; the session stops at the end of the file)";

impl FromStr for SourceSpec {
    type Err = LiveError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |reason: &str| LiveError::InvalidParameter {
            name: "source",
            value: s.to_string(),
            reason: reason.into(),
        };
        if s == "sim" {
            return Ok(Self::Sim);
        }
        let (kind, rest) = s
            .split_once(':')
            .ok_or_else(|| bad("expected sim, nic:HOST:PORT, lsl:NAME or replay:FILE"))?;
        if rest.is_empty() {
            return Err(bad("nothing after the colon"));
        }
        match kind {
            "nic" => {
                if rest
                    .rsplit_once(':')
                    .is_none_or(|(h, p)| h.is_empty() || p.is_empty())
                {
                    return Err(bad("expected nic:HOST:PORT"));
                }
                Ok(Self::Nic(rest.to_string()))
            }
            "lsl" => Ok(Self::Lsl(rest.to_string())),
            "replay" => Ok(Self::Replay(PathBuf::from(rest))),
            _ => Err(bad("expected sim, nic:HOST:PORT, lsl:NAME or replay:FILE")),
        }
    }
}

impl fmt::Display for SourceSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Sim => write!(f, "sim"),
            Self::Nic(a) => write!(f, "nic:{a}"),
            Self::Lsl(q) => write!(f, "lsl:{q}"),
            Self::Replay(p) => write!(f, "replay:{}", p.display()),
        }
    }
}

/// How to open a source.
#[derive(Debug, Clone)]
pub struct OpenOptions {
    /// The simulated subject (`sim`); its channel names also name a NIC stream's channels
    /// when the stream carries as many.
    pub subject: SimulatedSubject,
    /// Pace simulated and played-back EEG by the wall clock (`false`: as fast as it is
    /// processed).
    pub paced: bool,
    /// How late the simulated amplifier's samples arrive, ms.
    pub sim_latency_ms: f64,
    /// NIC's framing.
    pub nic: NicFormat,
    /// NIC's nominal sampling rate, Hz.
    pub nic_sfreq: f64,
    /// The LSL marker outlet of the flashes, cues and decisions (LSL sources).
    pub markers: String,
}

/// The most a simulated amplifier's samples may lag, ms (a latency beyond it, say 10¹² ms, kept
/// a paced session waiting for ever).
pub const MAX_SIM_LATENCY_MS: f64 = 10_000.0;

impl OpenOptions {
    /// The options' own rules, checked before anything is opened.
    pub fn check(&self) -> Result<(), LiveError> {
        if !(0.0..=MAX_SIM_LATENCY_MS).contains(&self.sim_latency_ms) {
            return Err(LiveError::InvalidParameter {
                name: "sim_latency_ms",
                value: self.sim_latency_ms.to_string(),
                reason: format!("a latency from 0 to {MAX_SIM_LATENCY_MS} ms"),
            });
        }
        oddball_signal::check_sfreq(self.nic_sfreq).map_err(|e| LiveError::InvalidParameter {
            name: "nic_sfreq",
            value: self.nic_sfreq.to_string(),
            reason: e.to_string(),
        })
    }
}

/// An open live source.
#[derive(Debug)]
pub enum AnySource {
    /// The simulated subject is large (its processes' state): boxed.
    Sim(Box<SimSource>),
    Nic(NicSource),
    Playback(PlaybackSource),
    Lsl(crate::lsl_live::LslSource),
    /// Another source at another rate ([`AnySource::resampled`]).
    Resampled(Box<Resampled>),
}

impl AnySource {
    /// This source resampled to `sfreq` Hz as it streams (polyphase,
    /// [`oddball_signal::resample::StreamResampler`]): for a model at another rate than the
    /// amplifier's. The session then runs, and records, at `sfreq`.
    pub fn resampled(self, sfreq: f64) -> Result<AnySource, LiveError> {
        let (up, down) = oddball_signal::resample::ratio(self.sfreq(), sfreq)
            .map_err(oddball_session::SessionError::from)?;
        let r = oddball_signal::resample::StreamResampler::new(self.ch_names().len(), up, down)
            .map_err(oddball_session::SessionError::from)?;
        Ok(AnySource::Resampled(Box::new(Resampled {
            inner: self,
            resampler: r,
            sfreq,
            ratio: down as f64 / up as f64,
            pulled: 0,
        })))
    }
}

/// How [`AnySource::at_rate`] brought a source to a model's rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateChange {
    pub from_sfreq: f64,
    pub to_sfreq: f64,
    /// A played-back file, resampled whole (else resampled as it streams).
    pub whole_file: bool,
}

impl std::fmt::Display for RateChange {
    /// `resampling the file from 512 Hz to the model's 256 Hz (polyphase)`, or for a stream
    /// `… as it streams (polyphase)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.whole_file {
            write!(
                f,
                "resampling the file from {} Hz to the model's {} Hz (polyphase)",
                self.from_sfreq, self.to_sfreq
            )
        } else {
            write!(
                f,
                "resampling the stream from {} Hz to the model's {} Hz as it streams (polyphase)",
                self.from_sfreq, self.to_sfreq
            )
        }
    }
}

impl AnySource {
    /// This source at a model's rate `sfreq`: as it is when it has that rate; a played-back
    /// file resampled whole ([`PlaybackSource::resampled`], as offline evaluation resamples
    /// it); any other source resampled as it streams ([`AnySource::resampled`]). Says what it
    /// changed.
    pub fn at_rate(self, sfreq: f64) -> Result<(AnySource, Option<RateChange>), LiveError> {
        let from_sfreq = self.sfreq();
        if oddball_signal::rate::same_sfreq(from_sfreq, sfreq) {
            return Ok((self, None));
        }
        let change = |whole_file| RateChange {
            from_sfreq,
            to_sfreq: sfreq,
            whole_file,
        };
        Ok(match self {
            AnySource::Playback(p) => {
                (AnySource::Playback(p.resampled(sfreq)?), Some(change(true)))
            }
            s => (s.resampled(sfreq)?, Some(change(false))),
        })
    }
}

/// A source resampled as it streams: sample `k` here is at the source's sample `k · down / up`.
#[derive(Debug)]
pub struct Resampled {
    inner: AnySource,
    resampler: oddball_signal::resample::StreamResampler,
    sfreq: f64,
    /// Source samples per sample here (`down / up`).
    ratio: f64,
    /// Source samples taken in.
    pulled: usize,
}

impl Resampled {
    /// The source's rate.
    pub fn source_sfreq(&self) -> f64 {
        self.inner.sfreq()
    }
}

impl EegSource for Resampled {
    fn sfreq(&self) -> f64 {
        self.sfreq
    }
    fn ch_names(&self) -> &[String] {
        self.inner.ch_names()
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        let need = self.resampler.input_needed(n);
        if need > self.pulled {
            self.inner.wait(need - self.pulled)?;
            let x = self.inner.take(need - self.pulled)?;
            self.resampler.push(x.view());
            self.pulled = need;
        }
        Ok(())
    }
    fn take(&mut self, n: usize) -> Result<ndarray::Array2<f64>, LiveError> {
        self.wait(n)?;
        Ok(self.resampler.take(n))
    }
    fn time_of(&self, sample: u64) -> f64 {
        let pos = sample as f64 * self.ratio;
        let i = pos.floor();
        let (a, b) = (
            self.inner.time_of(i as u64),
            self.inner.time_of(i as u64 + 1),
        );
        a + (pos - i) * (b - a)
    }
    fn saw(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), LiveError> {
        self.inner
            .saw((onset as f64 * self.ratio).round() as u64, code, attended)
    }
    fn start_now(&mut self) {
        self.inner.start_now()
    }
    fn health(&self) -> Option<String> {
        self.inner.health()
    }
}

impl SourceSpec {
    /// Opens the source on `clock`; an LSL source comes with its marker outlet.
    pub fn open(
        &self,
        opts: OpenOptions,
        clock: Clock,
    ) -> Result<(AnySource, Option<Box<dyn MarkerSink>>), LiveError> {
        opts.check()?;
        match self {
            Self::Sim => {
                let source = if opts.paced {
                    SimSource::new(opts.subject, clock, opts.sim_latency_ms)
                } else {
                    SimSource::unpaced(opts.subject, clock)
                };
                Ok((AnySource::Sim(Box::new(source)), None))
            }
            Self::Nic(addr) => {
                let data = resolve(addr)?;
                let ch_names = if opts.nic.n_channels == opts.subject.n_channels() {
                    opts.subject.ch_names().to_vec()
                } else {
                    (1..=opts.nic.n_channels)
                        .map(|i| format!("Ch{i}"))
                        .collect()
                };
                let panel = SocketAddr::new(data.ip(), data.port().wrapping_add(1));
                // An amplifier that drops out has ten seconds to come back.
                let reconnect = Reconnect {
                    attempts: 20,
                    delay: std::time::Duration::from_millis(500),
                    ..Reconnect::default()
                };
                let source =
                    NicSource::connect(data, opts.nic, opts.nic_sfreq, ch_names, reconnect, clock)?
                        .with_panel_port_if_any(panel);
                Ok((AnySource::Nic(source), None))
            }
            Self::Replay(path) => {
                let mut source = PlaybackSource::open(path, clock)?;
                if !opts.paced {
                    source = source.unpaced();
                }
                Ok((AnySource::Playback(source), None))
            }
            Self::Lsl(query) => {
                use crate::lsl::StreamQuery;
                use crate::lsl_live::{LslMarkers, LslSource};
                let markers = LslMarkers::new(&opts.markers, clock)?;
                let query: StreamQuery = query.parse()?;
                let source = LslSource::resolve(&query, 30.0, clock)?;
                // Markers pushed before anyone listens are lost (the first cue, say).
                markers.wait_for_consumers(10.0);
                let markers: Box<dyn MarkerSink> = Box::new(markers);
                Ok((AnySource::Lsl(source), Some(markers)))
            }
        }
    }
}

fn resolve(addr: &str) -> Result<SocketAddr, LiveError> {
    let bad = |reason: String| LiveError::InvalidParameter {
        name: "address",
        value: addr.to_string(),
        reason,
    };
    addr.to_socket_addrs()
        .map_err(|e| bad(format!("expected HOST:PORT ({e})")))?
        .next()
        .ok_or_else(|| bad("no address".into()))
}

macro_rules! each {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnySource::Sim($s) => $e,
            AnySource::Nic($s) => $e,
            AnySource::Playback($s) => $e,
            AnySource::Lsl($s) => $e,
            AnySource::Resampled($s) => $e,
        }
    };
}

impl EegSource for AnySource {
    fn sfreq(&self) -> f64 {
        each!(self, s => s.sfreq())
    }
    fn ch_names(&self) -> &[String] {
        each!(self, s => s.ch_names())
    }
    fn wait(&mut self, n: usize) -> Result<(), LiveError> {
        each!(self, s => s.wait(n))
    }
    fn take(&mut self, n: usize) -> Result<Array2<f64>, LiveError> {
        each!(self, s => s.take(n))
    }
    fn time_of(&self, sample: u64) -> f64 {
        each!(self, s => s.time_of(sample))
    }
    fn saw(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), LiveError> {
        each!(self, s => s.saw(onset, code, attended))
    }
    fn start_now(&mut self) {
        each!(self, s => s.start_now())
    }
    fn health(&self) -> Option<String> {
        each!(self, s => s.health())
    }
    fn recorded_flash(
        &mut self,
        planned: u64,
        code: u32,
    ) -> Result<Option<oddball_session::roles::Drawn>, LiveError> {
        each!(self, s => s.recorded_flash(planned, code))
    }
    fn recorded_hold(&self, position: u64) -> Option<bool> {
        each!(self, s => s.recorded_hold(position))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spelling_parses_and_prints_back() {
        for s in [
            "sim",
            "nic:127.0.0.1:1234",
            "lsl:oddball-eeg",
            "lsl:type=EEG",
            "replay:a/b.xdf",
        ] {
            let spec: SourceSpec = s.parse().unwrap();
            assert_eq!(spec.to_string(), s);
        }
        assert_eq!(
            "nic:localhost:9".parse::<SourceSpec>().unwrap(),
            SourceSpec::Nic("localhost:9".into())
        );
        for bad in [
            "",
            "simulated",
            "nic:",
            "nic:1234",
            "lsl:",
            "replay:",
            "tcp:a:1",
        ] {
            let err = bad.parse::<SourceSpec>().unwrap_err();
            assert!(err.to_string().contains("source"), "{bad}: {err}");
        }
    }
}
