//! Channel faults in a running session: a channel that turns NaN, goes flat or saturates is
//! flagged by name, its epochs are rejected, no NaN reaches a score or the arm, and with no
//! usable epoch at all the session abstains and the arm holds still.

use ndarray::Array2;
use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_session::engine::{Session, SessionParams, TrialOutcome};
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
    let mut p = SessionParams::paper("lda");
    p.calibration_per_bulb = 3;
    p.seed = 3;
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
