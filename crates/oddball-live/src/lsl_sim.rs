//! The simulated subject as a live Lab Streaming Layer amplifier that watches the panel's marker
//! stream (`oddball simulate --lsl`): an EEG outlet whose sample i is stamped t0 + i / sfreq on
//! LSL's clock, and a person who follows the markers `cue C` (the bulb attended, 0 = none),
//! `flash C` (a flash at sample round((t − t0) · sfreq)) and `end`. The outlet streams
//! `latency_s` behind real time so that a flash can still change the EEG when its marker
//! arrives; later markers are counted. The NIC counterpart is [`crate::nic::serve_simulated`].

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use oddball_session::subject::SimulatedSubject;

use crate::lsl::{local_clock, EegOutlet, MarkerInlet, StreamQuery};
use crate::LiveError;

/// What the marker thread reports.
enum FromMarkers {
    Connected(String),
    Marker(String, f64),
    Lost(String),
}

/// What one marker did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Applied {
    /// `cue C`: the bulb attended from now on (0 = none).
    Cue,
    /// `flash C`: a flash at sample `onset`, attended when C is the cue.
    Flash { onset: u64, attended: bool },
    /// A flash whose onset sample was already sent.
    TooLate,
    /// `decision C` or `abstain`: nothing for the person to see.
    Other,
    /// Not a marker of the panel's.
    Unknown,
    /// `end`: the session is over.
    End,
}

/// The person in front of the panel: the cue they follow and the flashes they see, on the
/// EEG's sample clock (sample i at `t0 + i / sfreq`).
#[derive(Debug)]
pub struct Viewer {
    t0: f64,
    sfreq: f64,
    cue: u32,
    /// Flashes applied to the EEG.
    pub flashes: u64,
    /// Of them, flashes of the cued bulb.
    pub attended: u64,
    /// Flash markers that came after their onset sample was sent.
    pub late: u64,
    /// Markers not understood.
    pub unknown: u64,
}

impl Viewer {
    /// A person who sees nothing yet, on the clock of sample i at `t0 + i / sfreq`.
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

/// What [`serve_simulated`] tells its caller as it runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SimEvent<'a> {
    /// The outlet exists; sample i is stamped `t0 + i / sfreq` on LSL's clock.
    Streaming { t0: f64 },
    /// The marker stream of this name was found and is followed.
    Following(&'a str),
    /// The marker stream failed (it is looked for again).
    MarkersLost(&'a str),
    /// A marker that is not one of the panel's, ignored.
    Ignored(&'a str),
}

/// What a simulated LSL amplifier streamed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimReport {
    /// Samples sent.
    pub samples: u64,
    /// Their rate, Hz.
    pub sfreq: f64,
    /// Flashes applied to the EEG.
    pub flashes: u64,
    /// Of them, flashes of the cued bulb.
    pub attended: u64,
    /// Flash markers that came after their onset sample was sent.
    pub late: u64,
    /// Markers not understood.
    pub unknown: u64,
}

/// Streams `subject` as the LSL EEG outlet `name` (source id `oddball-simulate-NAME`) following
/// the marker stream `markers`, `latency_s` behind real time, until the `end` marker or
/// `duration_s`. `on_event` hears what happens as it happens.
pub fn serve_simulated(
    mut subject: SimulatedSubject,
    name: &str,
    markers: &str,
    latency_s: f64,
    duration_s: Option<f64>,
    mut on_event: impl FnMut(SimEvent<'_>),
) -> Result<SimReport, LiveError> {
    let sfreq = subject.sfreq();
    let outlet = EegOutlet::new(
        name,
        subject.ch_names(),
        sfreq,
        &format!("oddball-simulate-{name}"),
    )?;
    // Sample i is stamped t0 + i / sfreq.
    let t0 = local_clock();
    on_event(SimEvent::Streaming { t0 });
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
                FromMarkers::Connected(m) => on_event(SimEvent::Following(&m)),
                FromMarkers::Lost(e) => on_event(SimEvent::MarkersLost(&e)),
                FromMarkers::Marker(text, ts) => match viewer.apply(&mut subject, &text, ts) {
                    Applied::End => ended = true,
                    Applied::Unknown => on_event(SimEvent::Ignored(&text)),
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
    Ok(SimReport {
        samples: subject.position(),
        sfreq,
        flashes: viewer.flashes,
        attended: viewer.attended,
        late: viewer.late,
        unknown: viewer.unknown,
    })
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
