//! The session engine end to end on the simulated subject: calibration, online decisions driving
//! the arm, dynamic stopping, abstention, and the saved session re-evaluated offline.

use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_decode::decision::DecisionRule;
use oddball_decode::preset::Preset;
use oddball_session::decision::TrialOutcome;
use oddball_session::decoder::{LearningRounds, Start, UncalibratedParams};
use oddball_session::engine::{Session, SessionParams};
use oddball_session::paradigm::FourBulbParams;
use oddball_session::prequential::HonestParams;
use oddball_session::record::{read_session, reevaluate, save_session};
use oddball_session::subject::{SimulatedSubject, SubjectParams, SubjectPreset};

fn session(preset: SubjectPreset, seed: u64, rule: DecisionRule) -> Session<SimulatedSubject> {
    let subject = SubjectParams::preset(preset)
        .with_seed(seed)
        .build()
        .unwrap();
    let mut params = SessionParams::paper(Preset::Lda);
    params.decoder.seed = seed;
    params.decoder.rule = rule;
    let arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
    Session::new(params, subject, Some(arm)).unwrap()
}

const FIXED: DecisionRule = DecisionRule::Fixed { rounds: 5 };

#[test]
fn the_typical_subject_draws_the_letter_g_and_the_saved_session_re_evaluates_identically() {
    let mut s = session(SubjectPreset::Typical, 1, FIXED);
    let cal = s.calibrate().unwrap();
    assert_eq!((cal.n_trials, cal.n_epochs), (40, 800));
    assert!(cal.cv_auc > 0.85, "calibration AUC {}", cal.cv_auc);
    let start = s.arm().unwrap().pen();
    for &c in &Command::LETTER_G {
        let t = s.decide(Some(c)).unwrap();
        assert_eq!(t.rounds, 5);
        assert_eq!(t.decided(), Some(s.params().paradigm.code_of(c)), "{t:?}");
        assert!(t.arm_refusal.is_none());
    }
    s.idle(1.5).unwrap();
    // The pen ends where the G ends: up, left, down, right, up, left = (−h, +h) from the start.
    let h = ArmConfig::default().reference.step_m;
    let end = s.arm().unwrap().pen();
    assert!(((end - start) - nalgebra::Vector2::new(-h, h)).norm() < 0.5e-3);

    let paradigm = s.params().paradigm;
    let (log, model, _) = s.finish().unwrap();
    let model = model.unwrap();
    let dir = oddball_testkit::TempDir::new("session");
    let path = dir.join("session.dat");
    save_session(&path, &log, &paradigm).unwrap();
    let rec = oddball_io::read(&path).unwrap();
    assert_eq!(
        rec.raw.data(),
        &log.samples.as_ref().unwrap().to_array().unwrap(),
        "float32 samples come back bit for bit"
    );
    let saved = read_session(&rec).unwrap();
    assert_eq!(saved.trials.len(), 46);
    assert_eq!(saved.bulbs, paradigm.bulbs);
    let again = reevaluate(&rec, &saved, &model).unwrap();
    let online: Vec<_> = log
        .trials
        .iter()
        .filter(|t| t.outcome != TrialOutcome::Labelled)
        .collect();
    assert_eq!(again.len(), online.len());
    for (a, o) in again.iter().zip(online) {
        assert_eq!(a.outcome, o.outcome);
        assert_eq!(a.rounds, o.rounds);
        assert_eq!(a.posterior, o.posterior, "posteriors equal bit for bit");
        assert_eq!(a.recorded, o.decided());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_same_seed_gives_the_same_session() {
    let run = || {
        let mut s = session(SubjectPreset::Typical, 7, FIXED);
        s.calibrate().unwrap();
        s.decide(Some(Command::Up)).unwrap();
        let (log, model, _) = s.finish().unwrap();
        (log, model.unwrap().to_json())
    };
    let (a, ma) = run();
    let (b, mb) = run();
    let samples =
        |l: &oddball_session::decision::SessionLog| l.samples.as_ref().unwrap().to_array().unwrap();
    assert_eq!(samples(&a), samples(&b));
    assert_eq!(
        (a.n_times, &a.flashes, &a.trials),
        (b.n_times, &b.flashes, &b.trials)
    );
    assert_eq!((a.sfreq, &a.ch_names), (b.sfreq, &b.ch_names));
    assert_eq!(ma, mb);
}

#[test]
fn dynamic_stopping_saves_rounds_and_a_person_attending_nothing_gets_abstentions() {
    let mut s = session(SubjectPreset::Easy, 3, DecisionRule::dynamic(5));
    s.calibrate().unwrap();
    let mut rounds = 0;
    let mut right = 0;
    for &c in Command::LETTER_G.iter().chain(&Command::LETTER_G) {
        let t = s.decide(Some(c)).unwrap();
        rounds += t.rounds;
        right += usize::from(t.decided() == Some(s.params().paradigm.code_of(c)));
    }
    let mean = rounds as f64 / 12.0;
    assert!(mean < 4.0, "mean rounds {mean}");
    assert!(right >= 11, "{right}/12 right");
    let mut abstained = 0;
    for _ in 0..10 {
        let t = s.decide(None).unwrap();
        abstained += usize::from(t.outcome == TrialOutcome::Abstained);
    }
    assert!(
        abstained >= 8,
        "abstained {abstained}/10 while attending nothing"
    );
}

#[test]
fn deciding_before_calibration_is_an_error() {
    let mut s = session(SubjectPreset::Easy, 1, FIXED);
    assert!(s.decide(Some(Command::Up)).is_err());
}

/// An amplifier whose true rate is 2 % above the nominal rate it reports.
struct Fast(SimulatedSubject);

impl oddball_session::roles::EegStream for Fast {
    fn sfreq(&self) -> f64 {
        500.0
    }
    fn ch_names(&self) -> &[String] {
        self.0.ch_names()
    }
    fn position(&self) -> u64 {
        self.0.position()
    }
    fn render(&mut self, n: usize) -> Result<ndarray::Array2<f64>, oddball_session::SessionError> {
        Ok(self.0.render(n))
    }
}

impl oddball_session::roles::Presenter for Fast {
    fn show(
        &mut self,
        onset: u64,
        _code: u32,
        attended: bool,
    ) -> Result<(), oddball_session::SessionError> {
        self.0.flash(onset, attended)
    }
}

impl oddball_session::roles::Observer for Fast {}

#[test]
fn a_sample_rate_two_percent_off_nominal_still_draws_the_g() {
    let mut params = SubjectParams::preset(SubjectPreset::Typical).with_seed(4);
    params.sfreq = 510.0;
    let subject = Fast(params.build().unwrap());
    let mut p = SessionParams::paper(Preset::Lda);
    p.decoder.seed = 4;
    let mut s = Session::new(p, subject, None).unwrap();
    let cal = s.calibrate().unwrap();
    assert!(cal.cv_auc > 0.85, "{cal:?}");
    let mut right = 0;
    for &c in &Command::LETTER_G {
        let t = s.decide(Some(c)).unwrap();
        right += usize::from(t.decided() == Some(s.params().paradigm.code_of(c)));
    }
    assert!(
        right >= 6,
        "{right}/6 with a 510 Hz amplifier read as 500 Hz"
    );
}

/// An operator who pauses after the first trial for two seconds of EEG: what the engine asked,
/// showed and reported.
struct Paused {
    sim: SimulatedSubject,
    trials_ended: usize,
    /// EEG position when the hold began and when it was lifted.
    held: Option<(u64, Option<u64>)>,
    /// Trial starts and flash onsets, samples.
    starts: Vec<u64>,
    onsets: Vec<u64>,
    /// Channels in each per-trial quality report.
    quality_reports: Vec<usize>,
}

impl oddball_session::roles::EegStream for Paused {
    fn sfreq(&self) -> f64 {
        self.sim.sfreq()
    }
    fn ch_names(&self) -> &[String] {
        self.sim.ch_names()
    }
    fn position(&self) -> u64 {
        self.sim.position()
    }
    fn render(&mut self, n: usize) -> Result<ndarray::Array2<f64>, oddball_session::SessionError> {
        Ok(self.sim.render(n))
    }
}

impl oddball_session::roles::Presenter for Paused {
    fn show(
        &mut self,
        onset: u64,
        _code: u32,
        attended: bool,
    ) -> Result<(), oddball_session::SessionError> {
        self.onsets.push(onset);
        self.sim.flash(onset, attended)
    }
    fn trial_started(
        &mut self,
        start: u64,
        _phase: oddball_session::decision::Phase,
        _intended: Option<u32>,
    ) -> Result<(), oddball_session::SessionError> {
        self.starts.push(start);
        Ok(())
    }
    fn hold(&mut self) -> Result<bool, oddball_session::SessionError> {
        if self.trials_ended != 1 {
            return Ok(false);
        }
        let now = self.sim.position();
        let (from, _) = *self.held.get_or_insert((now, None));
        let hold = now < from + 2 * self.sim.sfreq() as u64;
        if !hold {
            self.held = Some((from, Some(now)));
            self.trials_ended += 1;
        }
        Ok(hold)
    }
}

impl oddball_session::roles::Observer for Paused {
    fn trial_ended(
        &mut self,
        _t: &oddball_session::decision::TrialRecord,
    ) -> Result<(), oddball_session::SessionError> {
        self.trials_ended += 1;
        Ok(())
    }
    fn channel_faults(
        &mut self,
        faults: &[oddball_session::online::ChannelFaults],
    ) -> Result<(), oddball_session::SessionError> {
        self.quality_reports.push(faults.len());
        Ok(())
    }
}

/// Issue #20, part 3: a pause holds the session between trials: the EEG runs on, no trial
/// starts and nothing flashes until it is lifted, and calibration then completes as usual; the
/// observer hears every channel's faults after every trial.
#[test]
fn a_pause_holds_the_session_between_trials_without_flashing() {
    let sim = SubjectParams::preset(SubjectPreset::Easy)
        .with_seed(2)
        .build()
        .unwrap();
    let n_channels = sim.ch_names().len();
    let subject = Paused {
        sim,
        trials_ended: 0,
        held: None,
        starts: Vec::new(),
        onsets: Vec::new(),
        quality_reports: Vec::new(),
    };
    let mut p = SessionParams::paper(Preset::Lda);
    p.calibration_per_bulb = 2;
    p.decoder.seed = 2;
    assert_eq!(p.calibration_trials(), 8);
    let mut s = Session::new(p, subject, None).unwrap();
    let cal = s.calibrate().unwrap();
    assert_eq!(cal.n_trials, 8);
    let sub = s.subject();
    let (from, to) = sub.held.expect("held after the first trial");
    let to = to.expect("and released");
    let sfreq = sub.sim.sfreq() as u64;
    assert!(to >= from + 2 * sfreq, "held {from}..{to}");
    // No trial started and no flash fell inside the hold; the second trial starts at its end.
    assert!(sub.onsets.iter().all(|&o| o < from || o >= to));
    assert!(sub.onsets.iter().any(|&o| o < from) && sub.onsets.iter().any(|&o| o >= to));
    assert_eq!(sub.starts.len(), 8);
    assert!(
        sub.starts[0] < from && sub.starts[1] == to,
        "{:?}",
        sub.starts
    );
    assert_eq!(sub.quality_reports, vec![n_channels; 8]);
}

/// An uncalibrated session of the typical subject at the fast timing, 40 decisions (up, left,
/// down, right, …), dynamic stopping at 0.95 within 5 rounds, with `honest` weighing the
/// stopping rule's evidence and `learning` the first trials' rounds. Returns each decision's
/// (right, rounds, confidence).
fn uncalibrated_fast(
    seed: u64,
    honest: HonestParams,
    learning: LearningRounds,
) -> Vec<(bool, usize, f64)> {
    let subject = SubjectParams::preset(SubjectPreset::Typical)
        .with_seed(seed)
        .build()
        .unwrap();
    let mut params = SessionParams::paper(Preset::Lda);
    params.paradigm = FourBulbParams::fast();
    params.decoder.seed = seed;
    params.decoder.rule = DecisionRule::dynamic(5);
    let mut s = Session::new(params, subject, None).unwrap();
    let mut p = UncalibratedParams::for_sfreq(s.sfreq()).unwrap();
    p.honest = honest;
    p.learning = learning;
    s.start(
        Start::Uncalibrated {
            params: Some(Box::new(p)),
            transfer: None,
        },
        &mut |_| {},
    )
    .unwrap();
    let bulbs = [Command::Up, Command::Left, Command::Down, Command::Right];
    (0..40)
        .map(|i| {
            let c = bulbs[i % 4];
            let t = s.decide(Some(c)).unwrap();
            let right = t.decided() == Some(s.params().paradigm.code_of(c));
            (right, t.rounds, t.confidence())
        })
        .collect()
}

#[test]
fn an_uncalibrated_session_stops_early_only_on_out_of_sample_evidence() {
    // Seed 13: the second decision's in-sample EM posterior is 1.0 and wrong (a fit on two
    // trials finds noise). Weighed in-sample, dynamic stopping would have stopped on it; the
    // out-of-sample score model has no evidence yet, so the trial runs its five rounds. (The
    // rule alone: learning trials, which run longer, are off.)
    let off = LearningRounds::off();
    let honest = uncalibrated_fast(13, HonestParams::default(), off);
    let (right, rounds, confidence) = honest[1];
    assert!(
        !right && confidence > 0.999 && rounds == 5,
        "{:?}",
        honest[1]
    );
    // Never sure too early: no stop before the score model has trials to go on; then many
    // early stops, right at least as often as the 0.95 threshold promises, give or take one
    // (measured: 22 early stops, 1 wrong, at trial 7).
    assert!(honest[..3].iter().all(|d| d.1 == 5), "{honest:?}");
    let early: Vec<_> = honest.iter().filter(|d| d.1 < 5).collect();
    let wrong = early.iter().filter(|d| !d.0).count();
    assert!(early.len() >= 10, "{honest:?}");
    assert!(
        wrong as f64 <= 0.05 * early.len() as f64 + 1.0,
        "{honest:?}"
    );
    // Without the score model (it never has enough trials) nothing stops early: the rounds saved
    // are the out-of-sample evidence's.
    let never = HonestParams {
        window: 1000,
        min_trials: 1000,
        ..HonestParams::default()
    };
    let plain = uncalibrated_fast(13, never, off);
    assert!(plain.iter().all(|d| d.1 == 5));
    let rounds = |v: &[(bool, usize, f64)]| v.iter().map(|d| d.1).sum::<usize>();
    assert!(rounds(&honest) + 4 <= rounds(&plain));
}

#[test]
fn an_uncalibrated_session_learns_from_longer_first_trials() {
    // With five rounds from the start, a fit of the first few trials can land on a wrong
    // labelling that the warm start then follows. Seeds 11–16 (the default was tuned on
    // 11–20), each run with its most rounds every trial (no early stops: the score model never
    // has enough trials) and with the default stopping.
    let never = HonestParams {
        window: 1000,
        min_trials: 1000,
        ..HonestParams::default()
    };
    let right = |v: &[(bool, usize, f64)]| v.iter().filter(|d| d.0).count();
    let (mut fixed, mut stopping) = ([0, 0], [0, 0]);
    for seed in 11..=16 {
        for (k, learning) in [LearningRounds::off(), LearningRounds::default()]
            .into_iter()
            .enumerate()
        {
            let all = uncalibrated_fast(seed, never, learning);
            let stop = uncalibrated_fast(seed, HonestParams::default(), learning);
            if k == 1 {
                // Learning trials run 3 × 5 rounds while the decoder holds fewer than 2 epochs
                // per feature (8 channels × 16 bins at 500 Hz: 256 epochs; a learning trial
                // flashes 4 × 15, fewer when the amplitude rejection drops some): the first few
                // trials, then the rule's 5. With stopping they may end early, once the score
                // model is sure; none runs more than 15 rounds.
                let p = 8 * 16;
                let n = all.iter().take_while(|d| d.1 == 15).count();
                assert!(
                    n >= 1 && 4 * 15 * (n - 1) < 2 * p && 4 * 15 * n >= 2 * p - 4 * 15,
                    "seed {seed}: {n} learning trials: {all:?}"
                );
                assert!(all[n..].iter().all(|d| d.1 == 5), "seed {seed}: {all:?}");
                assert!(stop.iter().all(|d| d.1 <= 15), "seed {seed}: {stop:?}");
            } else {
                assert!(all.iter().all(|d| d.1 == 5), "seed {seed}: {all:?}");
            }
            fixed[k] += right(&all);
            stopping[k] += right(&stop);
        }
    }
    // Measured (of 240): 212 → 226 right with every round run, 209 → 227 with stopping.
    assert!(fixed[1] >= fixed[0] + 8, "{fixed:?}");
    assert!(stopping[1] >= stopping[0] + 8, "{stopping:?} with stopping");
}

#[test]
fn an_uncalibrated_session_epochs_with_its_own_band() {
    use oddball_decode::preprocess::Preprocess;
    let subject = || {
        SubjectParams::preset(SubjectPreset::Typical)
            .with_seed(3)
            .build()
            .unwrap()
    };
    let params = SessionParams::paper(Preset::Lda);
    assert_eq!(params.decoder.preprocess, Preprocess::online());
    // The default: the wider band, the online window and rejection.
    let mut s = Session::new(params.clone(), subject(), None).unwrap();
    s.start(
        Start::Uncalibrated {
            params: None,
            transfer: None,
        },
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(
        s.params().decoder.preprocess,
        Preprocess::online_unsupervised()
    );
    assert_ne!(
        Preprocess::online_unsupervised().band,
        Preprocess::online().band
    );
    assert!(s.decide(Some(Command::Up)).is_ok());
    // Settings without one (saved before the field) keep the session's.
    let mut s = Session::new(params, subject(), None).unwrap();
    let mut p = UncalibratedParams::for_sfreq(s.sfreq()).unwrap();
    p.preprocess = None;
    s.start(
        Start::Uncalibrated {
            params: Some(Box::new(p)),
            transfer: None,
        },
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(s.params().decoder.preprocess, Preprocess::online());
    let old: UncalibratedParams = serde_json::from_value({
        let mut v = serde_json::to_value(UncalibratedParams::for_sfreq(500.0).unwrap()).unwrap();
        v.as_object_mut().unwrap().remove("preprocess");
        v
    })
    .unwrap();
    assert_eq!(old.preprocess, None);
}
