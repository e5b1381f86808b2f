//! Channel faults in a running session: a channel that turns NaN, goes flat or saturates is
//! flagged by name, its epochs are rejected, no NaN reaches a score or the arm, and with no
//! usable epoch at all the session abstains and the arm holds still.

use ndarray::Array2;
use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_decode::preset::Preset;
use oddball_session::decision::TrialOutcome;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::roles::{EegStream, Observer, Presenter};
use oddball_session::subject::{SimulatedSubject, SubjectParams, SubjectPreset};
use oddball_session::SessionError;

#[derive(Debug, Clone, Copy)]
enum Fault {
    NaN,
    Flat,
    /// Stuck at the amplifier's rail.
    Saturated,
}

/// The simulated subject with one channel broken from sample `from` on.
struct Broken {
    sim: SimulatedSubject,
    channel: usize,
    from: u64,
    fault: Fault,
}

impl Presenter for Broken {
    fn show(&mut self, onset: u64, _code: u32, attended: bool) -> Result<(), SessionError> {
        self.sim.flash(onset, attended)
    }
}

impl Observer for Broken {}

impl EegStream for Broken {
    fn sfreq(&self) -> f64 {
        self.sim.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.sim.ch_names()
    }
    fn position(&self) -> u64 {
        self.sim.position()
    }
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        let p0 = self.sim.position();
        let mut d = self.sim.render(n);
        for t in 0..n {
            if p0 + t as u64 >= self.from {
                d[[self.channel, t]] = match self.fault {
                    Fault::NaN => f64::NAN,
                    Fault::Flat => 0.0,
                    Fault::Saturated => 187_500.0,
                };
            }
        }
        Ok(d)
    }
}

fn calibrated(fault: Fault, channel: usize) -> Session<Broken> {
    let sim = SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(3)
        .build()
        .unwrap();
    let mut p = SessionParams::paper(Preset::Lda);
    p.calibration_per_bulb = 3;
    p.decoder.seed = 3;
    let arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
    let subject = Broken {
        sim,
        channel,
        from: u64::MAX,
        fault,
    };
    let mut s = Session::new(p, subject, Some(arm)).unwrap();
    s.calibrate().unwrap();
    assert_eq!(s.channel_report(), None, "a clean calibration");
    s
}

#[test]
fn a_broken_channel_is_flagged_its_epochs_rejected_and_the_arm_holds() {
    for fault in [Fault::NaN, Fault::Flat, Fault::Saturated] {
        let mut s = calibrated(fault, 3);
        // The channel breaks now; a jump to the rail rings through the band-pass for a few
        // seconds (those epochs fail the amplitude threshold), then the channel is flat.
        let now = EegStream::position(s.subject());
        s.subject_mut().from = now;
        s.idle(8.0).unwrap();
        let pen = s.arm().unwrap().pen();
        let t = s.decide(Some(Command::Up)).unwrap();
        assert_eq!(t.outcome, TrialOutcome::Abstained, "{fault:?}: {t:?}");
        assert!(t.posterior.iter().all(|p| p.is_finite()), "{fault:?}");
        s.idle(2.0).unwrap();
        let moved = (s.arm().unwrap().pen() - pen).norm();
        assert!(moved < 1e-9, "{fault:?}: the arm moved {moved} m");
        assert!(s.arm().unwrap().pen().iter().all(|v| v.is_finite()));
        let report = s.channel_report().expect("flagged");
        let name = &s.subject().ch_names()[3];
        assert!(report.contains(name.as_str()), "{fault:?}: {report}");
        let f = s.channel_faults()[3];
        match fault {
            Fault::NaN => assert!(f.non_finite >= 20, "{f:?}"),
            // A constant channel is flat once the filter's transient has passed; the jump to
            // the rail is a huge transient first.
            Fault::Flat | Fault::Saturated => assert!(f.flat + f.over_threshold >= 20, "{f:?}"),
        }
        // The other channels are not blamed.
        for (c, f) in s.channel_faults().iter().enumerate() {
            if c != 3 {
                assert_eq!(f.non_finite, 0, "{fault:?} channel {c}");
            }
        }
        // The channel recovers: decisions resume.
        s.subject_mut().from = u64::MAX;
        s.idle(3.0).unwrap();
        let t = s.decide(Some(Command::Left)).unwrap();
        assert_eq!(
            t.decided(),
            Some(s.params().paradigm.code_of(Command::Left)),
            "{fault:?}: {t:?}"
        );
    }
}

/// Where a hostile page says flashes were drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stamp {
    /// On schedule.
    Honest,
    /// At the session's first sample (`{"t":"on","on_ms":0}`): long before the buffer.
    Stale,
    /// Ages ahead (`on_ms: 1e15`).
    FarFuture,
}

/// The simulated subject seen through a page that stamps every `every`-th flash `stamp`.
struct Stamped {
    sim: SimulatedSubject,
    stamp: Stamp,
    every: usize,
    shown: usize,
    drawn: Vec<oddball_session::roles::Drawn>,
}

impl Presenter for Stamped {
    fn lead(&self) -> u64 {
        // Announced ahead like a live panel, so measured onsets arrive before their epochs end.
        (0.5 * self.sim.sfreq()) as u64
    }
    fn show(&mut self, onset: u64, code: u32, attended: bool) -> Result<(), SessionError> {
        self.shown += 1;
        let measured = match self.stamp {
            _ if self.shown % self.every != 0 => onset,
            Stamp::Honest => onset,
            Stamp::Stale => 0,
            Stamp::FarFuture => onset + (1e15 / 1e3 * self.sim.sfreq()) as u64,
        };
        self.drawn.push(oddball_session::roles::Drawn {
            planned: onset,
            code,
            onset: Some(measured),
        });
        self.sim.flash(onset, attended)
    }
    fn drawn(&mut self) -> Vec<oddball_session::roles::Drawn> {
        // Reported once the stream has passed the flash's onset, as a page would.
        let pos = self.sim.position();
        let (now, later): (Vec<_>, Vec<_>) = self.drawn.drain(..).partition(|d| d.planned < pos);
        self.drawn = later;
        now
    }
}

impl Observer for Stamped {}

impl EegStream for Stamped {
    fn sfreq(&self) -> f64 {
        self.sim.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.sim.ch_names()
    }
    fn position(&self) -> u64 {
        self.sim.position()
    }
    fn render(&mut self, n: usize) -> Result<Array2<f64>, SessionError> {
        Ok(self.sim.render(n))
    }
}

/// Issue #19, defects 1 and 2: one stale stamp (`on_ms: 0`) ended the session with "marker at
/// sample 0 arrived too late"; one far-future stamp (`on_ms: 1e15`) left its trial waiting for
/// an epoch that never completes. Both are refused and counted; the session calibrates and
/// decides on.
#[test]
fn stale_and_far_future_stamps_are_refused_and_counted_never_ending_the_session() {
    for stamp in [Stamp::Honest, Stamp::Stale, Stamp::FarFuture] {
        let sim = SubjectParams::preset(SubjectPreset::Easy)
            .with_seed(5)
            .build()
            .unwrap();
        let mut p = SessionParams::paper(Preset::Lda);
        p.calibration_per_bulb = 3;
        p.decoder.seed = 5;
        let subject = Stamped {
            sim,
            stamp,
            every: 7,
            shown: 0,
            drawn: Vec::new(),
        };
        let mut s = Session::new(p, subject, None).unwrap();
        s.calibrate()
            .unwrap_or_else(|e| panic!("{stamp:?}: calibration ended: {e}"));
        let t = s
            .decide(Some(Command::Up))
            .unwrap_or_else(|e| panic!("{stamp:?}: decision ended the session: {e}"));
        assert!(t.posterior.iter().all(|p| p.is_finite()), "{stamp:?}");
        let shown = s.subject().shown as u64;
        match stamp {
            Stamp::Honest => assert_eq!(s.refused_onsets(), 0),
            _ => {
                // Every hostile stamp that arrived before its epoch completed is refused.
                assert!(
                    s.refused_onsets() >= shown / 7 - 2,
                    "{stamp:?}: {} of {shown}",
                    s.refused_onsets()
                );
                assert!(s.refused_onsets() <= shown / 7, "{stamp:?}");
            }
        }
    }
}
