//! Who turns intentions into arm moves: a live or simulated session, or replayed speller EEG.

use oddball_arm::{ArmSim, Command};

use crate::decision::Decision;
use crate::engine::Session;
use crate::replay::ReplaySource;
use crate::roles::Subject;
use crate::SessionError;

/// Something that turns intentions into arm moves.
pub trait Pilot {
    /// One decision while the person intends `intended`; `None` when the source has no more
    /// data (a replayed recording used up).
    fn decide(&mut self, intended: Command) -> Result<Option<Decision>, SessionError>;
    fn arm(&self) -> &ArmSim;
    /// Lets time pass (the arm settles).
    fn wait(&mut self, seconds: f64) -> Result<(), SessionError>;
    /// Seconds since the start of the task clock.
    fn time_s(&self) -> f64;
}

impl<S: Subject> Pilot for Session<S> {
    fn decide(&mut self, intended: Command) -> Result<Option<Decision>, SessionError> {
        let t = Session::decide(self, Some(intended))?;
        Ok(Some(Decision::of_trial(
            &t,
            intended,
            &self.params().paradigm,
            self.sfreq(),
        )))
    }

    fn arm(&self) -> &ArmSim {
        Session::arm(self).expect("a task session drives an arm")
    }

    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        self.idle(seconds)
    }

    fn time_s(&self) -> f64 {
        Session::time_s(self)
    }
}

/// Replayed speller EEG driving an arm: each decision lasts its four-bulb panel time.
#[derive(Debug)]
pub struct ReplayPilot {
    source: ReplaySource,
    arm: ArmSim,
}

impl ReplayPilot {
    pub fn new(source: ReplaySource, arm: ArmSim) -> Self {
        Self { source, arm }
    }

    pub fn into_arm(self) -> ArmSim {
        self.arm
    }
}

impl Pilot for ReplayPilot {
    fn decide(&mut self, intended: Command) -> Result<Option<Decision>, SessionError> {
        let Some((mut d, _)) = self.source.decide(intended) else {
            return Ok(None);
        };
        self.arm.run_for(d.seconds)?;
        d.pen_m = Some([self.arm.pen()[0], self.arm.pen()[1]]);
        d.arm_refusal = match d.decided {
            Some(c) => self.arm.issue(c).err().map(|e| e.to_string()),
            None => None,
        };
        Ok(Some(d))
    }

    fn arm(&self) -> &ArmSim {
        &self.arm
    }

    fn wait(&mut self, seconds: f64) -> Result<(), SessionError> {
        self.arm.run_for(seconds)?;
        Ok(())
    }

    fn time_s(&self) -> f64 {
        self.arm.time_s()
    }
}
