//! Stimulus paradigms: schedules of (onset time, stimulus code) that the panel shows and the
//! decoder epochs.
//!
//! * [`FourBulbParams`]: the paper's panel of four bulbs (up, right, down, left by default). Each
//!   flash is lit `flash_s` = 100 ms, the next starts `gap_s` = 150 ms after it goes off, a round
//!   of all four in random order is padded to `round_s` = 1 s, `n_rounds` = 5 rounds make one
//!   decision, after a `countdown_s` = 5 s countdown. No bulb flashes twice in a row, also across
//!   a round boundary.
//! * [`ParadigmPreset`]: the four-bulb panel's named timings, `paper` (above) and `fast`
//!   (100 ms on, 75 ms off, rounds not padded, so every flash comes 175 ms after the one before
//!   as in the BCI2000 speller, and a 1 s cue instead of the 5 s countdown); any field can be set
//!   from the command line ([`TimingOverrides`]). The schedule ([`FourBulbParams::trial`]) is the
//!   one home of the timing: the panel draws it, the simulated subject sees it, replay and the
//!   bit rate ([`FourBulbParams::time_split`]) count its seconds.
//! * [`SpellerParams`]: the 6 × 6 row/column speller of the BCI2000 sample files: rows are codes
//!   1–6, columns 7–12, each sequence flashes all twelve in random order.
//!
//! Times are seconds from the start of the trial (the start of its countdown). Stimulus codes
//! start at 1 (0 means "no stimulus", as in BCI2000's `StimulusCode`).

use oddball_arm::Command;
use rand::seq::SliceRandom;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::SessionError;

/// One flash of a schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Flash {
    /// Onset, seconds from the start of the trial.
    pub onset_s: f64,
    /// How long the stimulus stays lit, seconds.
    pub duration_s: f64,
    /// Stimulus code (bulb 1..=4, speller row 1..=6 or column 7..=12).
    pub code: u32,
    /// Round (sequence) the flash belongs to, from 0.
    pub round: usize,
}

/// The flashes of one trial (one decision or one spelled character).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialSchedule {
    /// Seconds before the first flash (the countdown).
    pub countdown_s: f64,
    pub flashes: Vec<Flash>,
    /// Length of the trial: countdown plus every round, seconds.
    pub duration_s: f64,
}

/// The paper's four-bulb panel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FourBulbParams {
    /// The command of each bulb; bulb `i` has stimulus code `i + 1`.
    pub bulbs: [Command; 4],
    /// Time a bulb stays lit, seconds.
    pub flash_s: f64,
    /// Dark time between one flash going off and the next coming on, seconds.
    pub gap_s: f64,
    /// A round of four flashes is padded to this length, seconds.
    pub round_s: f64,
    /// Rounds per decision.
    pub n_rounds: usize,
    /// Countdown before the first flash of a decision, seconds.
    pub countdown_s: f64,
}

impl Default for FourBulbParams {
    fn default() -> Self {
        Self::paper()
    }
}

/// Every command has exactly one bulb (four bulbs all meaning "up" steer nowhere): the one
/// rule, for settings and for session files read back.
pub fn check_bulbs(bulbs: &[Command; 4]) -> Result<(), SessionError> {
    for c in Command::ALL {
        if bulbs.iter().filter(|&&b| b == c).count() != 1 {
            return Err(SessionError::InvalidParameter {
                name: "bulbs",
                value: format!("{bulbs:?}"),
                reason: format!("every command needs exactly one bulb; {c} has not"),
            });
        }
    }
    Ok(())
}

/// The four-bulb panel's named timings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ParadigmPreset {
    /// The paper's: 100 ms on, 150 ms gap, rounds padded to 1 s, 5 s countdown.
    Paper,
    /// 100 ms on, 75 ms off (a flash every 175 ms, the BCI2000 speller's rate), no padding of
    /// rounds, a 1 s cue between decisions.
    Fast,
}

impl ParadigmPreset {
    pub const ALL: [ParadigmPreset; 2] = [ParadigmPreset::Paper, ParadigmPreset::Fast];

    pub fn name(self) -> &'static str {
        match self {
            ParadigmPreset::Paper => "paper",
            ParadigmPreset::Fast => "fast",
        }
    }
}

impl std::fmt::Display for ParadigmPreset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ParadigmPreset {
    type Err = SessionError;
    fn from_str(s: &str) -> Result<Self, SessionError> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| SessionError::InvalidParameter {
                name: "paradigm",
                value: s.to_string(),
                reason: "expected paper or fast".into(),
            })
    }
}

/// Changes to a preset's timing, in milliseconds (`None`: keep the preset's).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct TimingOverrides {
    /// Time a bulb stays lit.
    pub flash_ms: Option<f64>,
    /// Dark time between one flash going off and the next coming on.
    pub gap_ms: Option<f64>,
    /// The cue (countdown) before the first flash of a decision.
    pub cue_ms: Option<f64>,
    /// Length a round of four flashes is padded to; 0 pads nothing (a round is four flashes
    /// with their gaps). When not given, a padded preset keeps its round length and an unpadded
    /// one stays unpadded.
    pub round_ms: Option<f64>,
}

/// Where one decision's seconds go.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeSplit {
    /// The cue (countdown) before the first flash.
    pub cue_s: f64,
    /// From the first flash's onset to the last flash's onset plus one flash period.
    pub flashing_s: f64,
    /// From then until the last flash's epoch is complete and the decision is made.
    pub decoding_s: f64,
}

impl TimeSplit {
    pub fn total_s(&self) -> f64 {
        self.cue_s + self.flashing_s + self.decoding_s
    }
}

impl FourBulbParams {
    /// A named timing.
    pub fn preset(preset: ParadigmPreset) -> Self {
        match preset {
            ParadigmPreset::Paper => Self::paper(),
            ParadigmPreset::Fast => Self::fast(),
        }
    }

    /// The fast timing: 100 ms on, 75 ms off, rounds of 700 ms (not padded), 1 s cue.
    pub fn fast() -> Self {
        Self {
            flash_s: 0.1,
            gap_s: 0.075,
            round_s: 0.7,
            countdown_s: 1.0,
            ..Self::paper()
        }
    }

    /// Onset to onset of successive flashes within a round, seconds.
    pub fn flash_period_s(&self) -> f64 {
        self.flash_s + self.gap_s
    }

    /// Rounds are not padded: a round is four flash periods.
    pub fn unpadded(&self) -> bool {
        (self.round_s - 4.0 * self.flash_period_s()).abs() < 1e-9
    }

    /// The timing of `preset` with `o` applied, validated. Without `round_ms`, `paper` pads
    /// its rounds to 1 s and `fast` pads nothing.
    pub fn timed(preset: ParadigmPreset, o: &TimingOverrides) -> Result<Self, SessionError> {
        let mut p = Self::preset(preset);
        let seconds = |name: &'static str, ms: f64| {
            if ms.is_finite() && ms >= 0.0 {
                Ok(ms / 1000.0)
            } else {
                Err(SessionError::InvalidParameter {
                    name,
                    value: ms.to_string(),
                    reason: "must be a non-negative number of milliseconds".into(),
                })
            }
        };
        if let Some(ms) = o.flash_ms {
            p.flash_s = seconds("flash_ms", ms)?;
        }
        if let Some(ms) = o.gap_ms {
            p.gap_s = seconds("gap_ms", ms)?;
        }
        if let Some(ms) = o.cue_ms {
            p.countdown_s = seconds("cue_ms", ms)?;
        }
        p.round_s = match (o.round_ms, preset) {
            (Some(ms), _) if seconds("round_ms", ms)? > 0.0 => ms / 1000.0,
            (None, ParadigmPreset::Paper) => p.round_s,
            _ => 4.0 * p.flash_period_s(),
        };
        p.validate()?;
        Ok(p)
    }

    /// The timing in words: `100 ms on, 75 ms off, rounds of 700 ms, 1.0 s cue`.
    pub fn describe(&self) -> String {
        format!(
            "{:.0} ms on, {:.0} ms off, rounds of {:.0} ms{}, {:.1} s cue",
            self.flash_s * 1e3,
            self.gap_s * 1e3,
            self.round_s * 1e3,
            if self.unpadded() { "" } else { " (padded)" },
            self.countdown_s
        )
    }

    /// Where the seconds of a decision that used `rounds` rounds go, when each epoch ends
    /// `epoch_tmax_s` after its flash's onset and the decision waits for the last one.
    pub fn time_split(&self, rounds: usize, epoch_tmax_s: f64) -> TimeSplit {
        let last_onset = rounds.saturating_sub(1) as f64 * self.round_s + self.onset_in_round(3);
        let flashing_s = last_onset + self.flash_period_s();
        TimeSplit {
            cue_s: self.countdown_s,
            flashing_s,
            decoding_s: (last_onset + epoch_tmax_s - flashing_s).max(0.0),
        }
    }

    /// The paper's timing: bulbs up, right, down, left; 100 ms on, 150 ms gap, rounds of 1 s, 5
    /// rounds, 5 s countdown.
    pub fn paper() -> Self {
        Self {
            bulbs: [Command::Up, Command::Right, Command::Down, Command::Left],
            flash_s: 0.1,
            gap_s: 0.15,
            round_s: 1.0,
            n_rounds: 5,
            countdown_s: 5.0,
        }
    }

    /// Checks the timing adds up and every command has exactly one bulb.
    pub fn validate(&self) -> Result<(), SessionError> {
        let bad = |name: &'static str, value: f64, reason: &str| SessionError::InvalidParameter {
            name,
            value: value.to_string(),
            reason: reason.to_string(),
        };
        for (name, v) in [("flash_s", self.flash_s), ("round_s", self.round_s)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, v, "must be a positive number of seconds"));
            }
        }
        for (name, v) in [("gap_s", self.gap_s), ("countdown_s", self.countdown_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v, "must be a non-negative number of seconds"));
            }
        }
        let busy = 4.0 * self.flash_s + 3.0 * self.gap_s;
        if busy > self.round_s + 1e-12 {
            return Err(bad(
                "round_s",
                self.round_s,
                &format!("four flashes with their gaps need {busy} s"),
            ));
        }
        if self.n_rounds == 0 {
            return Err(bad("n_rounds", 0.0, "at least one round"));
        }
        check_bulbs(&self.bulbs)
    }

    /// The stimulus code (1..=4) of a command's bulb.
    pub fn code_of(&self, command: Command) -> u32 {
        self.bulbs
            .iter()
            .position(|&b| b == command)
            .map_or(0, |i| i as u32 + 1)
    }

    /// The command of a stimulus code, `None` outside 1..=4.
    pub fn command_of(&self, code: u32) -> Option<Command> {
        (1..=4)
            .contains(&code)
            .then(|| self.bulbs[code as usize - 1])
    }

    /// Onset of the `i`-th flash of a round, seconds from the round's start.
    pub fn onset_in_round(&self, i: usize) -> f64 {
        i as f64 * (self.flash_s + self.gap_s)
    }

    /// Length of a decision with `n_rounds` rounds, countdown included, seconds.
    pub fn trial_duration_s(&self, n_rounds: usize) -> f64 {
        self.countdown_s + n_rounds as f64 * self.round_s
    }

    /// A random order of the four codes that does not start with `previous` (the last code of the
    /// round before, if any).
    pub fn round_order<R: Rng + ?Sized>(&self, rng: &mut R, previous: Option<u32>) -> [u32; 4] {
        let mut order = [1, 2, 3, 4];
        order.shuffle(rng);
        if let Some(p) = previous {
            if order[0] == p {
                // Swap the repeated first code with a uniformly chosen later one.
                let j = rng.gen_range(1..4);
                order.swap(0, j);
            }
        }
        order
    }

    /// The schedule of one decision with `n_rounds` rounds.
    pub fn trial<R: Rng + ?Sized>(&self, rng: &mut R, n_rounds: usize) -> TrialSchedule {
        let mut flashes = Vec::with_capacity(4 * n_rounds);
        let mut previous = None;
        for round in 0..n_rounds {
            let order = self.round_order(rng, previous);
            previous = Some(order[3]);
            let start = self.countdown_s + round as f64 * self.round_s;
            for (i, &code) in order.iter().enumerate() {
                flashes.push(Flash {
                    onset_s: start + self.onset_in_round(i),
                    duration_s: self.flash_s,
                    code,
                    round,
                });
            }
        }
        TrialSchedule {
            countdown_s: self.countdown_s,
            flashes,
            duration_s: self.trial_duration_s(n_rounds),
        }
    }
}

/// The row/column P300 speller.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpellerParams {
    pub n_rows: usize,
    pub n_cols: usize,
    /// Time a row or column stays lit, seconds.
    pub flash_s: f64,
    /// Dark time after each flash, seconds.
    pub isi_s: f64,
    /// Sequences (each flashes every row and column once) per character.
    pub n_sequences: usize,
    /// Pause before the first flash of a character, seconds.
    pub pre_s: f64,
}

impl Default for SpellerParams {
    fn default() -> Self {
        Self::bci2000()
    }
}

impl SpellerParams {
    /// The BCI2000 sample files' speller: 6 × 6, 100 ms flashes, 75 ms dark, 15 sequences.
    pub fn bci2000() -> Self {
        Self {
            n_rows: 6,
            n_cols: 6,
            flash_s: 0.1,
            isi_s: 0.075,
            n_sequences: 15,
            pre_s: 2.0,
        }
    }

    /// Codes of one sequence: rows 1..=n_rows and columns n_rows+1..=n_rows+n_cols.
    pub fn n_codes(&self) -> usize {
        self.n_rows + self.n_cols
    }

    /// The schedule of one character.
    pub fn trial<R: Rng + ?Sized>(&self, rng: &mut R) -> TrialSchedule {
        let n = self.n_codes() as u32;
        let period = self.flash_s + self.isi_s;
        let mut flashes = Vec::with_capacity(self.n_codes() * self.n_sequences);
        let mut previous: Option<u32> = None;
        for round in 0..self.n_sequences {
            let mut order: Vec<u32> = (1..=n).collect();
            order.shuffle(rng);
            if n > 1 && previous == Some(order[0]) {
                let j = rng.gen_range(1..order.len());
                order.swap(0, j);
            }
            previous = order.last().copied();
            for code in order {
                let k = flashes.len();
                flashes.push(Flash {
                    onset_s: self.pre_s + k as f64 * period,
                    duration_s: self.flash_s,
                    code,
                    round,
                });
            }
        }
        TrialSchedule {
            countdown_s: self.pre_s,
            duration_s: self.pre_s + flashes.len() as f64 * period,
            flashes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn four_bulb_trial_follows_the_paper_timing() {
        let p = FourBulbParams::paper();
        p.validate().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let t = p.trial(&mut rng, 5);
        assert_eq!(t.flashes.len(), 20);
        assert!((t.duration_s - 10.0).abs() < 1e-12);
        assert!((t.flashes[0].onset_s - 5.0).abs() < 1e-12);
        for (i, f) in t.flashes.iter().enumerate() {
            let expected = 5.0 + (i / 4) as f64 + (i % 4) as f64 * 0.25;
            assert!((f.onset_s - expected).abs() < 1e-12, "flash {i}");
            assert_eq!(f.round, i / 4);
        }
        for r in t.flashes.chunks(4) {
            let mut codes: Vec<u32> = r.iter().map(|f| f.code).collect();
            codes.sort_unstable();
            assert_eq!(codes, [1, 2, 3, 4]);
        }
    }

    #[test]
    fn no_bulb_flashes_twice_in_a_row_and_orders_are_balanced() {
        let p = FourBulbParams::paper();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut first = [0usize; 4];
        for _ in 0..2000 {
            let t = p.trial(&mut rng, 5);
            for w in t.flashes.windows(2) {
                assert_ne!(w[0].code, w[1].code);
            }
            first[t.flashes[0].code as usize - 1] += 1;
        }
        for n in first {
            assert!((400..600).contains(&n), "first-flash counts {first:?}");
        }
    }

    #[test]
    fn codes_map_to_commands_and_bad_settings_are_refused() {
        let p = FourBulbParams::paper();
        for c in Command::ALL {
            assert_eq!(p.command_of(p.code_of(c)), Some(c));
        }
        assert_eq!(p.command_of(0), None);
        assert_eq!(p.command_of(5), None);
        let mut q = p;
        q.bulbs[1] = Command::Up;
        assert!(q.validate().is_err());
        let mut q = p;
        q.round_s = 0.5;
        assert!(q.validate().is_err());
        let mut q = p;
        q.flash_s = f64::NAN;
        assert!(q.validate().is_err());
    }

    #[test]
    fn presets_parse_and_the_fast_one_is_unpadded() {
        for p in ParadigmPreset::ALL {
            assert_eq!(p.to_string().parse::<ParadigmPreset>().unwrap(), p);
            FourBulbParams::preset(p).validate().unwrap();
        }
        assert!("Fast".parse::<ParadigmPreset>().is_err());
        assert_eq!(
            FourBulbParams::preset(ParadigmPreset::Paper),
            FourBulbParams::paper()
        );
        let p = FourBulbParams::fast();
        assert!(p.unpadded());
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let t = p.trial(&mut rng, 3);
        assert!((t.flashes[0].onset_s - 1.0).abs() < 1e-12);
        // Every flash 175 ms after the one before, across rounds too.
        for w in t.flashes.windows(2) {
            assert!((w[1].onset_s - w[0].onset_s - 0.175).abs() < 1e-9);
            assert_ne!(w[0].code, w[1].code);
        }
        assert!((t.duration_s - (1.0 + 3.0 * 0.7)).abs() < 1e-12);
        assert_eq!(
            p.describe(),
            "100 ms on, 75 ms off, rounds of 700 ms, 1.0 s cue"
        );
    }

    #[test]
    fn overrides_change_the_timing_and_are_checked() {
        let o = |flash, gap, cue, round| TimingOverrides {
            flash_ms: flash,
            gap_ms: gap,
            cue_ms: cue,
            round_ms: round,
        };
        let fast = |o| FourBulbParams::timed(ParadigmPreset::Fast, &o);
        let paper = |o| FourBulbParams::timed(ParadigmPreset::Paper, &o);
        assert_eq!(
            fast(o(None, None, None, None)).unwrap(),
            FourBulbParams::fast()
        );
        // The fast preset stays unpadded.
        let p = fast(o(Some(80.0), Some(45.0), Some(500.0), None)).unwrap();
        assert!((p.round_s - 0.5).abs() < 1e-12 && p.unpadded());
        assert!((p.countdown_s - 0.5).abs() < 1e-12);
        // A padded one keeps its round unless told; round 0 means no padding.
        let p = paper(o(None, Some(100.0), None, None)).unwrap();
        assert_eq!(p.round_s, 1.0);
        assert!(!p.unpadded());
        let p = paper(o(None, Some(50.0), None, Some(0.0))).unwrap();
        assert!((p.round_s - 0.6).abs() < 1e-12 && p.unpadded());
        let p = fast(o(None, None, None, Some(900.0))).unwrap();
        assert!((p.round_s - 0.9).abs() < 1e-12);
        // Four flashes that do not fit the round, a zero flash, NaN: refused by name.
        for (bad, name) in [
            (o(None, Some(300.0), None, None), "round_s"),
            (o(Some(0.0), None, None, None), "flash_s"),
            (o(None, None, Some(f64::NAN), None), "cue_ms"),
            (o(None, Some(-5.0), None, None), "gap_ms"),
        ] {
            match paper(bad) {
                Err(SessionError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{bad:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_decision_splits_into_cue_flashing_and_decoding() {
        // Paper, 5 rounds, 600 ms epochs: 5 s cue; last onset at 4.75 s, flashing to 5.0 s;
        // its epoch ends at 5.35 s.
        let s = FourBulbParams::paper().time_split(5, 0.6);
        assert!((s.cue_s - 5.0).abs() < 1e-12);
        assert!((s.flashing_s - 5.0).abs() < 1e-12);
        assert!((s.decoding_s - 0.35).abs() < 1e-12);
        assert!((s.total_s() - 10.35).abs() < 1e-12);
        // Fast, 2 rounds: last onset 0.7 + 0.525 = 1.225 s.
        let s = FourBulbParams::fast().time_split(2, 0.6);
        assert!((s.cue_s - 1.0).abs() < 1e-12);
        assert!((s.flashing_s - 1.4).abs() < 1e-12);
        assert!((s.decoding_s - 0.425).abs() < 1e-12);
    }

    #[test]
    fn speller_sequences_flash_every_row_and_column_once() {
        let p = SpellerParams::bci2000();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let t = p.trial(&mut rng);
        assert_eq!(t.flashes.len(), 12 * 15);
        for seq in t.flashes.chunks(12) {
            let mut codes: Vec<u32> = seq.iter().map(|f| f.code).collect();
            codes.sort_unstable();
            assert_eq!(codes, (1..=12).collect::<Vec<_>>());
        }
        for w in t.flashes.windows(2) {
            assert_ne!(w[0].code, w[1].code);
            assert!((w[1].onset_s - w[0].onset_s - 0.175).abs() < 1e-9);
        }
    }
}
