//! `oddball simulate`: the simulated subject as a live amplifier in another process, so a session
//! runs across processes as with real hardware. Two wires, one of `--nic` or `--lsl`:
//!
//! * `--nic HOST:PORT`: a Neuroelectrics Starstim behind NIC's TCP data protocol (binary or
//!   ASCII, 8 channels in nV, trigger, timestamp in ms). The simulated person also needs to see
//!   the panel: the next port (PORT + 1, or `--panel-port`) takes the panel's flashes and clock
//!   (`F onset code attended`, `T sample`); a real amplifier has no such port. The simulator
//!   serves one session and exits.
//! * `--lsl NAME` (cargo feature `lsl`): a Lab Streaming Layer EEG outlet (500 Hz, the subject's
//!   8 channels, µV) whose sample i is stamped t0 + i / sfreq on LSL's clock. The person watches
//!   the panel through its marker stream (`--markers`, type `Markers`): `cue C` sets the bulb
//!   attended (0 = none), `flash C` stamped t is a flash at sample round((t − t0) · sfreq),
//!   attended when C is the cue; `end` stops. So that a flash can still change the EEG when its
//!   marker arrives, the outlet streams `--latency-ms` behind real time (sample i is sent at
//!   t0 + i / sfreq + latency); markers that come later than that are counted and reported. The
//!   marker stream is looked for in the background: background EEG flows until it appears.

use std::net::{SocketAddr, TcpListener};

use anyhow::{bail, Context, Result};
use oddball_live::nic::serve_simulated;
use oddball_session::subject::{SubjectParams, SubjectPreset, STARSTIM_SFREQ};

use crate::args::{resolve, NicWire};

/// Options of `oddball simulate`.
#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("wire").required(true).args(["nic", "lsl"])))]
pub struct SimulateArgs {
    /// Serve NIC's TCP data stream on this address (loopback unless you say otherwise; port 0
    /// picks a free port, printed on the first line).
    #[arg(long, value_name = "HOST:PORT")]
    pub nic: Option<String>,
    /// Stream as a Lab Streaming Layer EEG outlet of this name, following the panel's marker
    /// stream (needs the `lsl` feature; the name is printed on the first line).
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

#[cfg(not(feature = "lsl"))]
fn run_lsl(_args: &SimulateArgs, name: &str, _preset: SubjectPreset) -> Result<()> {
    bail!("--lsl {name}: built without the lsl feature: cargo build --features lsl")
}

#[cfg(feature = "lsl")]
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
    lsl_sim::serve(
        subject,
        name,
        &args.markers,
        args.latency_ms / 1000.0,
        args.duration_s,
    )
}

fn run_nic(args: &SimulateArgs, nic: &str, preset: SubjectPreset) -> Result<()> {
    let format = args.wire.format()?;
    let addr = resolve(nic)?;
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

/// The simulated subject as a live LSL amplifier that watches the panel's marker stream.
#[cfg(feature = "lsl")]
mod lsl_sim {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{mpsc, Arc};
    use std::time::Duration;

    use anyhow::{Context, Result};
    use oddball_live::lsl::{local_clock, EegOutlet, MarkerInlet, StreamQuery};
    use oddball_live::LiveError;
    use oddball_session::subject::SimulatedSubject;

    /// What the marker thread reports.
    enum FromMarkers {
        Connected(String),
        Marker(String, f64),
        Lost(String),
    }

    /// What one marker did.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub(super) enum Applied {
        Cue,
        Flash { onset: u64, attended: bool },
        TooLate,
        Other,
        Unknown,
        End,
    }

    /// The person in front of the panel: the cue they follow and the flashes they see, on the
    /// EEG's sample clock (sample i at `t0 + i / sfreq`).
    #[derive(Debug)]
    pub(super) struct Viewer {
        t0: f64,
        sfreq: f64,
        cue: u32,
        pub flashes: u64,
        pub attended: u64,
        pub late: u64,
        pub unknown: u64,
    }

    impl Viewer {
        pub fn new(t0: f64, sfreq: f64) -> Self {
            Self {
                t0,
                sfreq,
                cue: 0,
                flashes: 0,
                attended: 0,
                late: 0,
                unknown: 0,
            }
        }

        /// Applies one marker stamped `ts` (LSL clock) to `subject`.
        pub fn apply(&mut self, subject: &mut SimulatedSubject, text: &str, ts: f64) -> Applied {
            let mut words = text.split_whitespace();
            let code = |w: Option<&str>| w.and_then(|c| c.parse::<u32>().ok());
            match (words.next(), code(words.next()), words.next()) {
                (Some("cue"), Some(c), None) => {
                    self.cue = c;
                    Applied::Cue
                }
                (Some("flash"), Some(c), None) => {
                    let onset = ((ts - self.t0) * self.sfreq).round();
                    let attended = self.cue != 0 && c == self.cue;
                    if onset < subject.position() as f64 || !onset.is_finite() {
                        self.late += 1;
                        return Applied::TooLate;
                    }
                    let onset = onset as u64;
                    match subject.flash(onset, attended) {
                        Ok(()) => {
                            self.flashes += 1;
                            self.attended += u64::from(attended);
                            Applied::Flash { onset, attended }
                        }
                        Err(_) => {
                            self.late += 1;
                            Applied::TooLate
                        }
                    }
                }
                (Some("decision"), Some(_), None) | (Some("abstain"), None, None) => Applied::Other,
                (Some("end"), None, None) => Applied::End,
                _ => {
                    self.unknown += 1;
                    Applied::Unknown
                }
            }
        }
    }

    /// Finds the marker stream (retrying until `stop`), then forwards its markers.
    fn follow(query: StreamQuery, tx: mpsc::Sender<FromMarkers>, stop: Arc<AtomicBool>) {
        while !stop.load(Ordering::Relaxed) {
            // Each attempt listens 1 s for the stream's answer (0.5 s missed it under load).
            let mut inlet = match MarkerInlet::resolve(&query, 1.0) {
                Ok(inlet) => inlet,
                Err(LiveError::StreamNotFound { .. }) => continue,
                Err(e) => {
                    let _ = tx.send(FromMarkers::Lost(e.to_string()));
                    std::thread::sleep(Duration::from_millis(500));
                    continue;
                }
            };
            if tx
                .send(FromMarkers::Connected(inlet.name().to_string()))
                .is_err()
            {
                return;
            }
            while !stop.load(Ordering::Relaxed) {
                match inlet.pull() {
                    Ok(markers) => {
                        for (text, ts) in markers {
                            if tx.send(FromMarkers::Marker(text, ts)).is_err() {
                                return;
                            }
                        }
                    }
                    Err(e) => {
                        let _ = tx.send(FromMarkers::Lost(e.to_string()));
                        break;
                    }
                }
                std::thread::sleep(Duration::from_millis(2));
            }
        }
    }

    /// Streams `subject` as the LSL EEG outlet `name` until `end`, or `duration_s`.
    pub fn serve(
        mut subject: SimulatedSubject,
        name: &str,
        markers: &str,
        latency_s: f64,
        duration_s: Option<f64>,
    ) -> Result<()> {
        let sfreq = subject.sfreq();
        let outlet = EegOutlet::new(
            name,
            subject.ch_names(),
            sfreq,
            &format!("oddball-simulate-{name}"),
        )
        .with_context(|| format!("creating the LSL stream {name}"))?;
        // Sample i is stamped t0 + i / sfreq.
        let t0 = local_clock();
        println!(
            "streaming LSL EEG {name}: {} channels at {sfreq} Hz from t0 = {t0} (LSL clock), {:.0} ms behind; following the marker stream {markers}",
            subject.n_channels(),
            latency_s * 1000.0
        );
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, rx) = mpsc::channel();
        let follower = {
            let (query, stop) = (StreamQuery::Name(markers.to_string()), stop.clone());
            std::thread::spawn(move || follow(query, tx, stop))
        };

        let mut viewer = Viewer::new(t0, sfreq);
        let mut ended = false;
        while !ended {
            for msg in rx.try_iter() {
                match msg {
                    FromMarkers::Connected(m) => println!("following markers from {m}"),
                    FromMarkers::Lost(e) => eprintln!("oddball simulate: marker stream: {e}"),
                    FromMarkers::Marker(text, ts) => match viewer.apply(&mut subject, &text, ts) {
                        Applied::End => ended = true,
                        Applied::Unknown => {
                            eprintln!("oddball simulate: ignoring the marker {text:?}")
                        }
                        _ => {}
                    },
                }
            }
            let now = local_clock();
            // Sample i is sent once t0 + i / sfreq + latency has passed.
            let due = (((now - latency_s - t0) * sfreq).floor() + 1.0).max(0.0) as u64;
            let position = subject.position();
            if due > position {
                let chunk = subject.render((due - position) as usize);
                outlet.push_chunk(chunk.view(), t0 + position as f64 / sfreq);
            }
            if duration_s.is_some_and(|d| now - t0 >= d) {
                break;
            }
            std::thread::sleep(Duration::from_millis(4));
        }
        stop.store(true, Ordering::Relaxed);
        let _ = follower.join();
        println!(
            "streamed {} samples ({:.1} s), {} flashes ({} attended), {} markers too late, {} not understood",
            subject.position(),
            subject.position() as f64 / sfreq,
            viewer.flashes,
            viewer.attended,
            viewer.late,
            viewer.unknown
        );
        Ok(())
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use oddball_session::subject::{SubjectParams, SubjectPreset};

        #[test]
        fn markers_become_flashes_on_the_sample_clock() {
            let mut s = SubjectParams::preset(SubjectPreset::Typical)
                .build()
                .unwrap();
            let t0 = 1000.0;
            let mut v = Viewer::new(t0, 500.0);
            assert_eq!(v.apply(&mut s, "cue 2", t0), Applied::Cue);
            assert_eq!(
                v.apply(&mut s, "flash 2", t0 + 0.5011),
                Applied::Flash {
                    onset: 251,
                    attended: true
                }
            );
            assert_eq!(
                v.apply(&mut s, "flash 3", t0 + 0.75),
                Applied::Flash {
                    onset: 375,
                    attended: false
                }
            );
            s.render(300);
            assert_eq!(v.apply(&mut s, "flash 1", t0 + 0.5), Applied::TooLate);
            assert_eq!(v.apply(&mut s, "flash 1", t0 - 1.0), Applied::TooLate);
            assert_eq!(v.apply(&mut s, "cue 0", t0), Applied::Cue);
            assert_eq!(
                v.apply(&mut s, "flash 2", t0 + 1.0),
                Applied::Flash {
                    onset: 500,
                    attended: false
                }
            );
            assert_eq!(v.apply(&mut s, "decision 2", t0), Applied::Other);
            assert_eq!(v.apply(&mut s, "abstain", t0), Applied::Other);
            assert_eq!(v.apply(&mut s, "flash x", t0 + 2.0), Applied::Unknown);
            assert_eq!(v.apply(&mut s, "end", t0), Applied::End);
            assert_eq!((v.flashes, v.attended, v.late, v.unknown), (3, 1, 2, 1));
            assert_eq!(s.n_pending_flashes(), 3);
        }
    }
}
