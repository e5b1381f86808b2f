//! Stimulus paradigms: schedules of (onset time, stimulus code) that the panel shows and the
//! decoder epochs.
//!
//! * [`FourBulbParams`]: the paper's panel of four bulbs (up, right, down, left by default). Each
//!   flash is lit `flash_s` = 100 ms, the next starts `gap_s` = 150 ms after it goes off, a round
//!   of all four in random order is padded to `round_s` = 1 s, `n_rounds` = 5 rounds make one
//!   decision, after a `countdown_s` = 5 s countdown. No bulb flashes twice in a row, also across
//!   a round boundary.
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

impl FourBulbParams {
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
