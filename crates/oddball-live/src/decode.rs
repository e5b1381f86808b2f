//! `oddball decode`: the online decoder behind another program's stimuli.
//!
//! EEG from any source (an LSL stream, NIC, a recording played back), the stimulus program's
//! markers from an LSL marker stream (or, to test without LSL, the played-back recording's own
//! events), an [`oddball_session::listener::Listener`] deciding, and each decision out as JSON:
//! on an LSL marker outlet the stimulus program can read (a `stop` first when dynamic stopping is
//! sure before the trial's end) and to the caller (JSON lines on a file or stdout).
//!
//! **One clock.** Everything is put on the session clock ([`Clock`], s here): the EEG by its
//! source ([`EegSource::time_of`]: an LSL stream's own timestamps), the markers by their LSL
//! timestamps, which the inlet has already moved onto this machine's LSL clock with LSL's time
//! correction, minus the LSL clock's offset to the session clock. The arrival order of the two
//! streams plays no part.
//!
//! **Stopping.** A stalled or lost EEG stream, the end of a played-back recording and a stop
//! request (SIGINT) end the run cleanly: the trials in flight are decided on what arrived and
//! the summary says why it stopped. Bad markers and a marker stream that disappears are counted,
//! never fatal.

use std::time::Instant;

use oddball_io::paradigm::MarkerKind;
use oddball_session::listener::{Listener, ListenerParams, MarkerCounts, Output};
use serde::Serialize;

use crate::clock::Clock;
use crate::live::EegSource;
use crate::source::{AnySource, OpenOptions, SourceSpec};
use crate::LiveError;

/// Where the stimulus markers come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MarkerSpec {
    /// An LSL marker stream (`lsl:NAME`, `lsl:type=Markers`).
    Lsl(String),
    /// The played-back recording's own events (`--source replay:FILE` only): its flashes, their
    /// target flags, and trials from its speller characters or the gaps between its flashes.
    Recording,
}

/// A decode run's plan.
#[derive(Debug, Clone)]
pub struct DecodePlan {
    pub source: SourceSpec,
    pub markers: MarkerSpec,
    pub listener: ListenerParams,
    /// Name of the LSL outlet the decisions go out on (`None`: none).
    pub outlet: Option<String>,
    /// Pace a played-back recording by the wall clock (`false`: as fast as it decodes).
    pub paced: bool,
    /// Samples taken from the source at a time.
    pub block: usize,
    /// Seconds an LSL stream may take to be found.
    pub resolve_timeout_s: f64,
    /// NIC's framing and rate (`nic:` sources).
    pub nic: oddball_io::nic::NicFormat,
    pub nic_sfreq: f64,
}

/// Why a run ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DecodeSummary {
    pub decisions: usize,
    pub abstentions: usize,
    pub stops: usize,
    pub samples: u64,
    pub seconds: f64,
    pub markers: MarkerCounts,
    /// Milliseconds from taking the block that completed a decision's last epoch to the
    /// decision sent: median and 99th percentile (`None` without decisions).
    pub latency_ms: Option<(f64, f64)>,
    /// Milliseconds from the time stamped on the sample that completed a decision's last epoch
    /// (the amplifier's clock, mapped onto this machine's) to the decision sent: the above plus
    /// the stream's own delivery (its chunks, the network). Live sources only.
    pub latency_from_stamp_ms: Option<(f64, f64)>,
    /// Why the run ended (the recording's end, a stalled stream, a stop request).
    pub ended: String,
    /// The marker stream's state at the end (lost, or its time correction).
    pub marker_stream: Option<String>,
}

/// Runs the plan until the EEG ends or a stop is asked; `emit(json)` after every decision or
/// stop (in the order sent).
pub fn run(plan: DecodePlan, emit: &mut dyn FnMut(&str)) -> Result<DecodeSummary, LiveError> {
    if plan.block == 0 || plan.block > 10_000 {
        return Err(LiveError::InvalidParameter {
            name: "block",
            value: plan.block.to_string(),
            reason: "1 to 10000 samples".into(),
        });
    }
    if plan.markers == MarkerSpec::Recording && !matches!(plan.source, SourceSpec::Replay(_)) {
        return Err(LiveError::InvalidParameter {
            name: "markers",
            value: "the recording's".into(),
            reason: "only a played-back recording (--source replay:FILE) has its own markers; \
                     give an LSL marker stream"
                .into(),
        });
    }
    let clock = Clock::new();
    // The decisions' outlet before anything else: a stimulus program may wait for it (to hear
    // stops) before it sends its first sample.
    let outlet = match &plan.outlet {
        Some(name) => Some(crate::lsl::MarkerOutlet::with_type(
            name,
            crate::lsl::DECISION_TYPE,
            "oddball-decode",
        )?),
        None => None,
    };
    // Then the marker inlet: a stimulus program may wait for both its streams to have a
    // listener before it sends its first sample, which the EEG source waits for.
    let mut markers = Markers::open(&plan, clock)?;
    let mut source = open_source(&plan, clock)?;
    let labels = plan.listener.paradigm.labels.clone();
    let sfreq = source.sfreq();
    let ch_names = source.ch_names().to_vec();
    let mut listener = Listener::new(plan.listener.clone(), sfreq, &ch_names)?;
    let t0 = Instant::now();
    let mut summary = DecodeSummary {
        decisions: 0,
        abstentions: 0,
        stops: 0,
        samples: 0,
        seconds: 0.0,
        markers: MarkerCounts::default(),
        latency_ms: None,
        latency_from_stamp_ms: None,
        ended: String::new(),
        marker_stream: None,
    };
    let mut latencies = Vec::new();
    let mut from_stamp = Vec::new();
    let live = !matches!(plan.source, SourceSpec::Replay(_));
    let mut position: u64 = 0;
    // Each decision's completing sample's stamp (session ms), taken before the outputs go.
    let stamps = |outs: &[Output], source: &AnySource| -> Vec<Option<f64>> {
        outs.iter()
            .map(|o| match o {
                Output::Decision(d) => Some(source.time_of(d.completed_at)),
                _ => None,
            })
            .collect()
    };
    let mut send = |outs: Vec<Output>,
                    stamp: Vec<Option<f64>>,
                    taken: Instant,
                    summary: &mut DecodeSummary| {
        for (o, stamp) in outs.into_iter().zip(stamp) {
            let json = o.to_json(&labels, clock.now_ms() / 1e3);
            if let Some(outlet) = &outlet {
                outlet.push(&json, crate::lsl::local_clock());
            }
            match &o {
                Output::Decision(d) => {
                    summary.decisions += 1;
                    if d.choice.is_none() {
                        summary.abstentions += 1;
                    }
                    latencies.push(taken.elapsed().as_secs_f64() * 1e3);
                    if let (Some(ms), true) = (stamp, live) {
                        from_stamp.push(clock.now_ms() - ms);
                    }
                }
                Output::Stop { .. } => summary.stops += 1,
                Output::Calibrated { .. } => {}
            }
            emit(&json);
        }
    };
    let ended = loop {
        if crate::stop::requested() {
            break "stop requested".to_string();
        }
        match source.wait(plan.block) {
            Ok(()) => {}
            Err(e) => break end_reason(e)?,
        }
        let block = source.take(plan.block)?;
        let taken = Instant::now();
        let last = position + plan.block as u64 - 1;
        let last_time = source.time_of(last) / 1e3;
        // Markers first (a marker waits in the listener for its epoch's samples).
        for (kind, time) in markers.pull(&source, &listener, last_time)? {
            let outs = match kind {
                Incoming::Text(t) => listener.push_marker(&t, time)?,
                Incoming::Kind(k) => listener.push_event(k, time)?,
            };
            let at = stamps(&outs, &source);
            send(outs, at, taken, &mut summary);
        }
        let outs = listener.push_eeg(block.view(), last_time)?;
        let at = stamps(&outs, &source);
        send(outs, at, taken, &mut summary);
        position += plan.block as u64;
    };
    let outs = listener.finish()?;
    let at = vec![None; outs.len()];
    send(outs, at, Instant::now(), &mut summary);
    summary.samples = position;
    summary.seconds = t0.elapsed().as_secs_f64();
    summary.markers = listener.counts().clone();
    summary.ended = ended;
    summary.marker_stream = markers.state();
    summary.latency_ms = percentiles(&mut latencies);
    summary.latency_from_stamp_ms = percentiles(&mut from_stamp);
    Ok(summary)
}

/// Median and 99th percentile (nearest rank).
fn percentiles(v: &mut [f64]) -> Option<(f64, f64)> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some((at(0.5), at(0.99)))
}

/// The ends of a run that are not failures: the recording played out, a stream that stalled or
/// went away (what was decided is kept).
fn end_reason(e: LiveError) -> Result<String, LiveError> {
    match e {
        LiveError::StreamStalled { .. }
        | LiveError::StreamLost { .. }
        | LiveError::Reconnect { .. }
        | LiveError::Stopped
        | LiveError::Aborted => Ok(e.to_string()),
        LiveError::RecordingEnded { .. } => Ok("the recording ended".into()),
        e => Err(e),
    }
}

fn open_source(plan: &DecodePlan, clock: Clock) -> Result<AnySource, LiveError> {
    match &plan.source {
        SourceSpec::Lsl(query) => {
            let query: crate::lsl::StreamQuery = query.parse()?;
            let s = crate::lsl_live::LslSource::resolve(&query, plan.resolve_timeout_s, clock)?;
            Ok(AnySource::Lsl(s))
        }
        SourceSpec::Sim => Err(LiveError::InvalidParameter {
            name: "source",
            value: "sim".into(),
            reason: "decode listens to another program's EEG: lsl:NAME, nic:HOST:PORT or \
                     replay:FILE"
                .into(),
        }),
        spec => {
            let opts = OpenOptions {
                // Unused by the sources decode opens (no simulated subject there).
                subject: oddball_session::SubjectParams::preset(
                    oddball_session::SubjectPreset::Typical,
                )
                .build()
                .map_err(|e| LiveError::InvalidParameter {
                    name: "subject",
                    value: String::new(),
                    reason: e.to_string(),
                })?,
                paced: plan.paced,
                sim_latency_ms: 0.0,
                nic: plan.nic,
                nic_sfreq: plan.nic_sfreq,
                markers: "oddball-decode-unused".into(),
            };
            let (s, _) = spec.open(opts, clock)?;
            Ok(s)
        }
    }
}

enum Incoming {
    Text(String),
    Kind(MarkerKind),
}

/// The marker source of a run.
enum Markers {
    Lsl {
        inlet: crate::lsl::MarkerInlet,
        /// LSL clock − session clock, s.
        offset_s: f64,
        lost: Option<String>,
    },
    /// A recording's events, fed in time: (onset sample, what it is), in onset order.
    Recording {
        events: std::collections::VecDeque<(u64, MarkerKind)>,
        sfreq: f64,
    },
}

/// A recording's flashes as a stimulus program would announce them: a trial start before each
/// trial's first flash, each flash with its target flag, a trial end after its last. Trials are
/// the speller's characters, or runs of flashes separated by more than three times the median
/// gap between flashes.
pub fn recording_markers(rec: &oddball_io::Recording) -> Vec<(u64, MarkerKind)> {
    let events = rec.raw.events();
    let flashes: Vec<&oddball_signal::Event> = events.iter().collect();
    let mut bounds: Vec<usize> = Vec::new();
    if let Some(n) = rec.speller.as_ref().and_then(|s| s.flashes_per_character) {
        bounds.extend((0..flashes.len()).step_by(n.max(1)));
    } else {
        let mut gaps: Vec<usize> = flashes
            .windows(2)
            .map(|w| w[1].onset.saturating_sub(w[0].onset))
            .collect();
        let gap_limit = if gaps.is_empty() {
            usize::MAX
        } else {
            gaps.sort_unstable();
            3 * gaps[gaps.len() / 2].max(1)
        };
        for (i, f) in flashes.iter().enumerate() {
            if i == 0 || f.onset.saturating_sub(flashes[i - 1].onset) > gap_limit {
                bounds.push(i);
            }
        }
    }
    let mut out = Vec::with_capacity(flashes.len() * 2 + bounds.len() * 2);
    for (k, &b) in bounds.iter().enumerate() {
        let e = bounds.get(k + 1).copied().unwrap_or(flashes.len());
        if b >= e {
            continue;
        }
        out.push((flashes[b].onset as u64, MarkerKind::TrialStart));
        for f in &flashes[b..e] {
            out.push((f.onset as u64, MarkerKind::Flash { code: f.code }));
            if let Some(t) = f.target {
                out.push((f.onset as u64, MarkerKind::Flag { target: t }));
            }
        }
        out.push((flashes[e - 1].onset as u64, MarkerKind::TrialEnd));
    }
    out
}

impl Markers {
    fn open(plan: &DecodePlan, clock: Clock) -> Result<Self, LiveError> {
        match (&plan.markers, &plan.source) {
            (MarkerSpec::Recording, SourceSpec::Replay(path)) => {
                let rec = oddball_io::read(path)?;
                Ok(Self::Recording {
                    events: recording_markers(&rec).into(),
                    sfreq: rec.raw.sfreq(),
                })
            }
            (MarkerSpec::Recording, _) => unreachable!("checked by run"),
            (MarkerSpec::Lsl(q), _) => {
                let query: crate::lsl::StreamQuery = q.parse()?;
                let inlet = crate::lsl::MarkerInlet::resolve(&query, plan.resolve_timeout_s)?;
                Ok(Self::Lsl {
                    inlet,
                    offset_s: crate::lsl::local_clock() - clock.now_ms() / 1e3,
                    lost: None,
                })
            }
        }
    }

    /// Markers that have arrived (LSL), or are due by `last_time` plus the epoch window (a
    /// recording), with their times on the session clock (s).
    fn pull(
        &mut self,
        source: &AnySource,
        listener: &Listener,
        last_time: f64,
    ) -> Result<Vec<(Incoming, f64)>, LiveError> {
        match self {
            Self::Lsl {
                inlet,
                offset_s,
                lost,
            } => {
                let _ = (source, listener, last_time);
                if lost.is_some() {
                    return Ok(Vec::new());
                }
                match inlet.pull() {
                    Ok(v) => Ok(v
                        .into_iter()
                        .map(|(t, ts)| (Incoming::Text(t), ts - *offset_s))
                        .collect()),
                    Err(e @ LiveError::StreamLost { .. }) => {
                        *lost = Some(e.to_string());
                        Ok(Vec::new())
                    }
                    Err(e) => Err(e),
                }
            }
            Self::Recording { events, sfreq } => {
                // A flash is announced as its epoch's first sample arrives.
                let t0 = source.time_of(0) / 1e3;
                let lead = listener.preprocess().tmin.min(0.0);
                let mut out = Vec::new();
                while let Some(&(onset, _)) = events.front() {
                    let t = t0 + onset as f64 / *sfreq;
                    if t + lead > last_time {
                        break;
                    }
                    let (_, kind) = events.pop_front().expect("front exists");
                    out.push((Incoming::Kind(kind), t));
                }
                Ok(out)
            }
        }
    }

    fn state(&self) -> Option<String> {
        match self {
            Self::Lsl { lost, .. } => Some(lost.clone().unwrap_or_else(|| "connected".into())),
            Self::Recording { .. } => None,
        }
    }
}
