//! A simulated subject who watches the panel, attends one stimulus and produces continuous EEG.
//!
//! BrainFlow's synthetic board and MNE's `simulate_raw` make EEG-like noise or add evoked
//! responses offline; none of them reacts to a stimulus schedule as it unfolds, so the subject is
//! written here. The caller registers each flash ([`SimulatedSubject::flash`]) before the stream
//! reaches its onset, and pulls samples ([`SimulatedSubject::render`]) in chunks of any size.
//!
//! # What is simulated
//!
//! Each channel is a sum, in µV, of
//!
//! * **1/f background**: per source, white noise through a cascade of first-order sections
//!   with poles at 0.5, 1.5, 4.5, … Hz (a factor 3 apart) and a zero √3 above each pole, up to
//!   0.45 × `sfreq`: a 1/f power spectrum from 0.5 Hz to ~100 Hz at 500 Hz. Every channel mixes a
//!   source shared by all channels (weight √ρ, ρ = `spatial_correlation`) with its own
//!   (√(1 − ρ)); `pink_rms` is the RMS per channel.
//! * **alpha**: per source, white noise through a two-pole resonator at `alpha_freq` (poles at
//!   radius exp(−π · `alpha_bandwidth` / `sfreq`)): a peak about `alpha_bandwidth` Hz wide whose
//!   amplitude waxes and wanes over ~1 / (π · bandwidth) s. Shared and own sources mix as for the
//!   1/f background; `alpha_rms` at gain 1 of `alpha_topography` (posterior).
//! * **line noise**: a `line_freq` sine, common phase, `line_amplitude` µV (peak) times a fixed
//!   per-channel factor in 0.8–1.2.
//! * **drift**: per channel an AR(1) process with a 0.05 Hz corner (a leaky random walk),
//!   `drift_rms` µV.
//! * **blinks**: Poisson with `blink_rate` per minute; 300 ms (100 ms rise, 200 ms fall, raised
//!   cosines), `blink_amplitude` µV ± 25 % at gain 1 of `blink_topography` (Fz, decaying
//!   towards the back).
//! * **visual evoked response to every flash**: N1 (−`vep_amplitude` at 160 ms, sd 25 ms) and P2
//!   (+0.8 · `vep_amplitude` at 240 ms, sd 40 ms), amplitude ± 25 % per flash, occipital
//!   `vep_topography`.
//! * **P300 to attended flashes**: a Gaussian of sd `p300_width` s at `p300_latency` s plus a
//!   per-flash latency shift of sd `p300_jitter` s, amplitude `p300_amplitude` µV times
//!   max(0, 1 + `p300_variability` · N(0, 1)), spread by `p300_topography` (Pz = 1).
//!
//! Every output sample is rounded to f32 (a session is saved as BCI2000 float32 and must read
//! back bit-exactly).
//!
//! # Determinism
//!
//! Everything follows from `seed`. Each process draws from its own ChaCha8 stream (so the
//! background does not change when, say, blinks are switched off), sample after sample in a
//! fixed order; every flash draws three numbers (P300 latency, P300 amplitude, visual response
//! amplitude, also when not attended) from another stream when it is registered. The output
//! therefore does not depend on how it is chunked, nor on when flashes are registered (as long
//! as it is before their onset is rendered); only the order of the [`SimulatedSubject::flash`]
//! calls matters, for the flashes' draws. Evoked responses are summed in onset order. The
//! innovations of the narrow-band processes (alpha, drift) are uniform with unit variance (they
//! are cheaper than Gaussian ones, and each output sample averages hundreds of them); the 1/f
//! background's are Gaussian.
//!
//! # Presets
//!
//! For the default montage (Fz, Cz, P3, Pz, P4, PO7, Oz, PO8 at 500 Hz):
//!
//! | | easy | typical | hard |
//! |---|---|---|---|
//! | P300 amplitude at Pz, µV | 10 | 9 | 6.5 |
//! | P300 latency / width (sd) / jitter (sd), ms | 320 / 80 / 20 | 350 / 85 / 30 | 400 / 90 / 60 |
//! | P300 amplitude variability (sd of the factor) | 0.2 | 0.3 | 0.5 |
//! | visual N1 amplitude at Oz, µV | 3 | 3 | 3 |
//! | 1/f background RMS, µV / spatial correlation | 5 / 0.4 | 6 / 0.4 | 6 / 0.4 |
//! | alpha RMS at Oz, µV (10 Hz, 1 Hz wide) | 8 | 9 | 10 |
//! | 50 Hz mains peak, µV | 3 | 4 | 5 |
//! | drift RMS, µV | 8 | 10 | 12 |
//! | blinks per minute / peak at Fz, µV | 3 / 80 | 6 / 90 | 12 / 100 |
//! | broadband RMS at Pz, µV (measured) | 11 | 14 | 16 |
//! | 1–15 Hz RMS at Pz, µV (measured) | 7 | 8 | 9 |
//!
//! Calibrating the `lda` pipeline preset on 40 decisions of the four-bulb paradigm (800 epochs,
//! 0–0.6 s, 1–15 Hz causal band-pass) and scoring 300 more, single-epoch ROC-AUC is about 0.96
//! (easy), 0.90 (typical) and 0.73 (hard), and 5-round 4-choice decisions are right 100 %,
//! 99 % and 75–80 % of the time (`tests/subject.rs`).

use std::collections::VecDeque;
use std::f64::consts::{PI, TAU};
use std::fmt;
use std::str::FromStr;

use ndarray::{Array2, ArrayViewMut2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::SessionError;

/// The default montage: eight channels of a Neuroelectrics Starstim-like cap.
pub const STARSTIM_CHANNELS: [&str; 8] = ["Fz", "Cz", "P3", "Pz", "P4", "PO7", "Oz", "PO8"];

/// The default sampling rate (Starstim), Hz.
pub const STARSTIM_SFREQ: f64 = 500.0;

/// P300 gain per channel of [`STARSTIM_CHANNELS`]: parietal maximum, smaller frontally.
const P300_GAINS: [f64; 8] = [0.35, 0.7, 0.8, 1.0, 0.8, 0.55, 0.45, 0.55];
/// Visual evoked response gain: occipital.
const VEP_GAINS: [f64; 8] = [0.1, 0.25, 0.55, 0.5, 0.55, 0.95, 1.0, 0.95];
/// Alpha gain: posterior.
const ALPHA_GAINS: [f64; 8] = [0.3, 0.5, 0.8, 0.85, 0.8, 0.95, 1.0, 0.95];
/// Blink gain: frontal, decaying backwards.
const BLINK_GAINS: [f64; 8] = [1.0, 0.45, 0.15, 0.15, 0.15, 0.06, 0.05, 0.06];

/// Lowest pole of the 1/f background's filter, Hz.
const PINK_LOWEST_HZ: f64 = 0.5;
/// Ratio of successive poles (and zeros).
const PINK_RATIO: f64 = 3.0;
/// Highest zero, as a fraction of `sfreq`.
const PINK_HIGHEST_FRACTION: f64 = 0.45;
/// Processes run this long before the first sample, to start in their stationary state, s.
const BURN_IN_S: f64 = 5.0;
/// Corner of the drift's AR(1) process, Hz.
const DRIFT_CORNER_HZ: f64 = 0.05;
/// Blink rise and fall, seconds.
const BLINK_RISE_S: f64 = 0.1;
const BLINK_FALL_S: f64 = 0.2;
/// Blink amplitudes are uniform in (1 ± this) × `blink_amplitude`.
const BLINK_SPREAD: f64 = 0.25;
/// Visual evoked response: N1 and P2 latency and sd, seconds; P2 relative amplitude.
const VEP_N1: (f64, f64) = (0.16, 0.025);
const VEP_P2: (f64, f64) = (0.24, 0.04);
const VEP_P2_GAIN: f64 = 0.8;
/// Amplitude variability (sd of the factor) of the visual evoked response.
const VEP_VARIABILITY: f64 = 0.25;
/// Gaussians are cut this many sds after their peak.
const TAIL_SDS: f64 = 5.0;

/// ChaCha streams of the processes.
const STREAM_PINK: u64 = 1;
const STREAM_ALPHA: u64 = 2;
const STREAM_DRIFT: u64 = 3;
const STREAM_BLINK: u64 = 4;
const STREAM_FLASH: u64 = 5;
const STREAM_SETUP: u64 = 6;

/// How well the simulated subject's P300 stands out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SubjectPreset {
    /// Large, consistent P300 over a quiet background.
    Easy,
    /// A good BCI user.
    Typical,
    /// Small, late, jittery P300 over a noisy background.
    Hard,
}

impl SubjectPreset {
    pub const ALL: [SubjectPreset; 3] = [Self::Easy, Self::Typical, Self::Hard];

    pub fn name(self) -> &'static str {
        match self {
            Self::Easy => "easy",
            Self::Typical => "typical",
            Self::Hard => "hard",
        }
    }
}

impl fmt::Display for SubjectPreset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SubjectPreset {
    type Err = SessionError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| SessionError::InvalidParameter {
                name: "subject preset",
                value: s.to_string(),
                reason: "known presets: easy, typical, hard".to_string(),
            })
    }
}

/// Settings of a simulated subject (amplitudes µV, times s, frequencies Hz).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubjectParams {
    /// Sampling rate, Hz.
    pub sfreq: f64,
    pub ch_names: Vec<String>,
    /// P300 amplitude at gain 1 of `p300_topography`, µV.
    pub p300_amplitude: f64,
    /// Mean P300 peak latency after the flash onset, s.
    pub p300_latency: f64,
    /// Standard deviation of the P300's Gaussian shape, s.
    pub p300_width: f64,
    /// Standard deviation of the per-flash latency shift, s.
    pub p300_jitter: f64,
    /// Standard deviation of the per-flash amplitude factor (mean 1, cut at 0).
    pub p300_variability: f64,
    /// P300 gain per channel.
    pub p300_topography: Vec<f64>,
    /// Visual N1 amplitude (P2 is 0.8 of it) to every flash at gain 1, µV.
    pub vep_amplitude: f64,
    /// Visual evoked response gain per channel.
    pub vep_topography: Vec<f64>,
    /// RMS of the 1/f background per channel, µV.
    pub pink_rms: f64,
    /// Share of the 1/f and alpha variance common to all channels, 0–1.
    pub spatial_correlation: f64,
    /// RMS of alpha at gain 1 of `alpha_topography`, µV.
    pub alpha_rms: f64,
    /// Alpha peak frequency, Hz.
    pub alpha_freq: f64,
    /// Full width at half maximum of the alpha peak, Hz.
    pub alpha_bandwidth: f64,
    /// Alpha gain per channel.
    pub alpha_topography: Vec<f64>,
    /// Peak amplitude of the mains sine, µV.
    pub line_amplitude: f64,
    /// Mains frequency, Hz.
    pub line_freq: f64,
    /// RMS of the slow drift, µV.
    pub drift_rms: f64,
    /// Blinks per minute.
    pub blink_rate: f64,
    /// Blink peak at gain 1 of `blink_topography`, µV.
    pub blink_amplitude: f64,
    /// Blink gain per channel.
    pub blink_topography: Vec<f64>,
    pub seed: u64,
}

impl Default for SubjectParams {
    fn default() -> Self {
        Self::preset(SubjectPreset::Typical)
    }
}

impl SubjectParams {
    /// The preset's settings for [`STARSTIM_CHANNELS`] at [`STARSTIM_SFREQ`], seed 0.
    pub fn preset(preset: SubjectPreset) -> Self {
        let typical = Self {
            sfreq: STARSTIM_SFREQ,
            ch_names: STARSTIM_CHANNELS.iter().map(|s| s.to_string()).collect(),
            p300_amplitude: 9.0,
            p300_latency: 0.35,
            p300_width: 0.085,
            p300_jitter: 0.03,
            p300_variability: 0.3,
            p300_topography: P300_GAINS.to_vec(),
            vep_amplitude: 3.0,
            vep_topography: VEP_GAINS.to_vec(),
            pink_rms: 6.0,
            spatial_correlation: 0.4,
            alpha_rms: 9.0,
            alpha_freq: 10.0,
            alpha_bandwidth: 1.0,
            alpha_topography: ALPHA_GAINS.to_vec(),
            line_amplitude: 4.0,
            line_freq: 50.0,
            drift_rms: 10.0,
            blink_rate: 6.0,
            blink_amplitude: 90.0,
            blink_topography: BLINK_GAINS.to_vec(),
            seed: 0,
        };
        match preset {
            SubjectPreset::Typical => typical,
            SubjectPreset::Easy => Self {
                p300_amplitude: 10.0,
                p300_latency: 0.32,
                p300_width: 0.08,
                p300_jitter: 0.02,
                p300_variability: 0.2,
                pink_rms: 5.0,
                alpha_rms: 8.0,
                line_amplitude: 3.0,
                drift_rms: 8.0,
                blink_rate: 3.0,
                blink_amplitude: 80.0,
                ..typical
            },
            SubjectPreset::Hard => Self {
                p300_amplitude: 6.5,
                p300_latency: 0.40,
                p300_width: 0.09,
                p300_jitter: 0.06,
                p300_variability: 0.5,
                alpha_rms: 10.0,
                line_amplitude: 5.0,
                drift_rms: 12.0,
                blink_rate: 12.0,
                blink_amplitude: 100.0,
                ..typical
            },
        }
    }

    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    pub fn n_channels(&self) -> usize {
        self.ch_names.len()
    }

    /// Checks every setting; errors name the first one at fault.
    pub fn validate(&self) -> Result<(), SessionError> {
        let bad = |name: &'static str, value: String, reason: &str| {
            Err(SessionError::InvalidParameter {
                name,
                value,
                reason: reason.to_string(),
            })
        };
        if !(self.sfreq.is_finite() && self.sfreq > 0.0) {
            return bad("sfreq", self.sfreq.to_string(), "must be finite and > 0");
        }
        let n = self.ch_names.len();
        if n == 0 {
            return bad("ch_names", "[]".into(), "at least one channel");
        }
        for (i, name) in self.ch_names.iter().enumerate() {
            if name.trim().is_empty() {
                return bad("ch_names", format!("{:?}", self.ch_names), "empty name");
            }
            if self.ch_names[..i].contains(name) {
                return bad(
                    "ch_names",
                    format!("{:?}", self.ch_names),
                    &format!("{name} appears twice"),
                );
            }
        }
        for (name, gains) in [
            ("p300_topography", &self.p300_topography),
            ("vep_topography", &self.vep_topography),
            ("alpha_topography", &self.alpha_topography),
            ("blink_topography", &self.blink_topography),
        ] {
            if gains.len() != n {
                return bad(
                    name,
                    format!("{gains:?}"),
                    &format!("needs one gain per channel ({n})"),
                );
            }
            if gains.iter().any(|g| !g.is_finite()) {
                return bad(name, format!("{gains:?}"), "gains must be finite");
            }
        }
        for (name, v) in [
            ("p300_amplitude", self.p300_amplitude),
            ("p300_latency", self.p300_latency),
            ("p300_jitter", self.p300_jitter),
            ("p300_variability", self.p300_variability),
            ("vep_amplitude", self.vep_amplitude),
            ("pink_rms", self.pink_rms),
            ("alpha_rms", self.alpha_rms),
            ("line_amplitude", self.line_amplitude),
            ("drift_rms", self.drift_rms),
            ("blink_rate", self.blink_rate),
            ("blink_amplitude", self.blink_amplitude),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v.to_string(), "must be finite and >= 0");
            }
        }
        if !(self.p300_width.is_finite() && self.p300_width > 0.0) {
            return bad(
                "p300_width",
                self.p300_width.to_string(),
                "must be finite and > 0",
            );
        }
        // Responses must stay within a bounded window after their flash.
        let reach = self.p300_latency + 4.0 * self.p300_jitter + TAIL_SDS * self.p300_width;
        if reach > 10.0 {
            return bad(
                "p300_latency",
                self.p300_latency.to_string(),
                &format!("the P300 would last until {reach} s after the flash (at most 10 s)"),
            );
        }
        if !(0.0..=1.0).contains(&self.spatial_correlation) {
            return bad(
                "spatial_correlation",
                self.spatial_correlation.to_string(),
                "must be in 0..=1",
            );
        }
        let nyquist = self.sfreq / 2.0;
        let below_nyquist = |f: f64| f.is_finite() && f > 0.0 && f < nyquist;
        if self.alpha_rms > 0.0 {
            if !below_nyquist(self.alpha_freq) {
                return bad(
                    "alpha_freq",
                    self.alpha_freq.to_string(),
                    &format!("must be in (0, {nyquist}) Hz"),
                );
            }
            if !below_nyquist(self.alpha_bandwidth) {
                return bad(
                    "alpha_bandwidth",
                    self.alpha_bandwidth.to_string(),
                    &format!("must be in (0, {nyquist}) Hz"),
                );
            }
        }
        if self.line_amplitude > 0.0 && !below_nyquist(self.line_freq) {
            return bad(
                "line_freq",
                self.line_freq.to_string(),
                &format!("must be in (0, {nyquist}) Hz"),
            );
        }
        if self.blink_rate / 60.0 > self.sfreq {
            return bad(
                "blink_rate",
                self.blink_rate.to_string(),
                "more than one blink per sample",
            );
        }
        Ok(())
    }

    /// A subject at sample 0.
    pub fn build(&self) -> Result<SimulatedSubject, SessionError> {
        self.validate()?;
        Ok(SimulatedSubject::new(self.clone()))
    }
}

/// Standard normal numbers (Marsaglia's polar method) from one ChaCha stream.
#[derive(Debug, Clone)]
struct Gauss {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl Gauss {
    fn new(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self { rng, spare: None }
    }

    fn uniform(&mut self) -> f64 {
        self.rng.gen::<f64>()
    }

    /// Zero mean, unit variance, uniform: a cheap innovation for processes whose output averages
    /// hundreds of innovations (and so is Gaussian anyway).
    fn unit_uniform(&mut self) -> f64 {
        3f64.sqrt() * (2.0 * self.rng.gen::<f64>() - 1.0)
    }

    fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let u = 2.0 * self.rng.gen::<f64>() - 1.0;
            let v = 2.0 * self.rng.gen::<f64>() - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let k = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * k);
                return u * k;
            }
        }
    }
}

/// Weights of the shared and the own source for a shared variance fraction `rho`.
fn mix_weights(rho: f64) -> (f64, f64) {
    (rho.sqrt(), (1.0 - rho).sqrt())
}

/// Runs `step` (one innovation in, one sample out) for `n` samples from rest with a unit impulse
/// first, and returns the square root of the output energy: the RMS of the process driven by
/// unit-variance white noise.
fn impulse_rms(n: usize, mut step: impl FnMut(f64) -> f64) -> f64 {
    (0..n)
        .map(|i| step(if i == 0 { 1.0 } else { 0.0 }).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Samples to run a process before its first output, so it starts in its stationary state.
fn burn_in(sfreq: f64) -> usize {
    (BURN_IN_S * sfreq).ceil() as usize
}

/// The 1/f background. Each source (the shared one first, then one per channel) is white noise
/// through a cascade of first-order sections with poles at 0.5, 1.5, 4.5, … Hz and a zero
/// between each pair of poles (at √3 × the pole): every pole–zero pair turns the slope down by
/// half a decade per decade, which makes the power spectrum 1/f between the lowest pole and the
/// highest zero.
#[derive(Debug, Clone)]
struct Pink {
    gauss: Gauss,
    /// (pole, zero) of each section, z-plane.
    sections: Vec<(f64, f64)>,
    /// Per source and section: the previous input and output.
    state: Vec<(f64, f64)>,
    /// Output weight of the shared and own sources (0 = not simulated).
    shared: f64,
    own: f64,
}

impl Pink {
    fn new(p: &SubjectParams) -> Self {
        let z_plane = |f: f64| (-TAU * f / p.sfreq).exp();
        let mut sections = Vec::new();
        let mut pole = PINK_LOWEST_HZ;
        while pole * PINK_RATIO.sqrt() <= PINK_HIGHEST_FRACTION * p.sfreq || sections.is_empty() {
            sections.push((z_plane(pole), z_plane(pole * PINK_RATIO.sqrt())));
            pole *= PINK_RATIO;
        }
        let (shared, own) = mix_weights(p.spatial_correlation);
        let mut pink = Self {
            gauss: Gauss::new(p.seed, STREAM_PINK),
            state: vec![(0.0, 0.0); sections.len() * (p.n_channels() + 1)],
            sections,
            shared: 0.0,
            own: 0.0,
        };
        if p.pink_rms > 0.0 {
            // 20 time constants of the slowest pole: the rest of the energy is below 1e-17.
            let slowest = pink.sections.iter().fold(0f64, |m, s| m.max(s.0));
            let n = (20.0 / (1.0 - slowest)).ceil() as usize;
            let mut probe = pink.clone();
            let rms = impulse_rms(n, |e| probe.filter(0, e));
            pink.shared = shared * p.pink_rms / rms;
            pink.own = own * p.pink_rms / rms;
            let mut scratch = vec![0.0; p.n_channels()];
            for _ in 0..burn_in(p.sfreq) {
                pink.step(&mut scratch);
            }
        }
        pink
    }

    /// One sample of `source` for the innovation `e`.
    fn filter(&mut self, source: usize, e: f64) -> f64 {
        let k = self.sections.len();
        let mut x = e;
        for (st, &(pole, zero)) in self.state[source * k..(source + 1) * k]
            .iter_mut()
            .zip(&self.sections)
        {
            let y = x - zero * st.0 + pole * st.1;
            *st = (x, y);
            x = y;
        }
        x
    }

    /// This sample's background per channel.
    fn step(&mut self, out: &mut [f64]) {
        let shared = if self.shared > 0.0 {
            let e = self.gauss.normal();
            self.shared * self.filter(0, e)
        } else {
            0.0
        };
        for (c, o) in out.iter_mut().enumerate() {
            *o = shared;
            if self.own > 0.0 {
                let e = self.gauss.normal();
                *o += self.own * self.filter(c + 1, e);
            }
        }
    }
}

/// Alpha: per source (shared first, then one per channel) white noise through a two-pole
/// resonator at `alpha_freq`, poles at radius exp(−π · bandwidth / sfreq).
#[derive(Debug, Clone)]
struct Alpha {
    gauss: Gauss,
    /// AR(2) coefficients: x = a1·x₋₁ + a2·x₋₂ + e.
    a1: f64,
    a2: f64,
    /// Per source: the last two outputs.
    state: Vec<(f64, f64)>,
    shared: f64,
    own: f64,
    /// alpha_rms · gain per channel, over the unit-innovation RMS.
    gains: Vec<f64>,
    /// Simulated at all (`alpha_rms` > 0 and some gain not 0).
    on: bool,
}

impl Alpha {
    fn new(p: &SubjectParams) -> Self {
        let rho = (-PI * p.alpha_bandwidth / p.sfreq).exp();
        let a1 = 2.0 * rho * (TAU * p.alpha_freq / p.sfreq).cos();
        let a2 = -rho * rho;
        // Stationary variance of an AR(2) process with unit innovations.
        let var = (1.0 - a2) / ((1.0 + a2) * ((1.0 - a2).powi(2) - a1 * a1));
        let (shared, own) = mix_weights(p.spatial_correlation);
        let mut alpha = Self {
            gauss: Gauss::new(p.seed, STREAM_ALPHA),
            a1,
            a2,
            state: vec![(0.0, 0.0); p.n_channels() + 1],
            shared,
            own,
            gains: p
                .alpha_topography
                .iter()
                .map(|g| p.alpha_rms * g / var.sqrt())
                .collect(),
            on: p.alpha_rms > 0.0 && p.alpha_topography.iter().any(|&g| g != 0.0),
        };
        if alpha.on {
            let mut scratch = vec![0.0; p.n_channels()];
            for _ in 0..burn_in(p.sfreq) {
                alpha.step(&mut scratch);
            }
        }
        alpha
    }

    fn step_source(&mut self, source: usize) -> f64 {
        let (x1, x2) = self.state[source];
        let x = self.a1 * x1 + self.a2 * x2 + self.gauss.unit_uniform();
        self.state[source] = (x, x1);
        x
    }

    fn step(&mut self, out: &mut [f64]) {
        if !self.on {
            out.fill(0.0);
            return;
        }
        let shared = if self.shared > 0.0 {
            self.shared * self.step_source(0)
        } else {
            0.0
        };
        for (c, o) in out.iter_mut().enumerate() {
            let own = if self.own > 0.0 {
                self.own * self.step_source(c + 1)
            } else {
                0.0
            };
            *o = self.gains[c] * (shared + own);
        }
    }
}

/// Slow drift: per channel an AR(1) process with a very low corner.
#[derive(Debug, Clone)]
struct Drift {
    gauss: Gauss,
    pole: (f64, f64),
    state: Vec<f64>,
    rms: f64,
}

impl Drift {
    fn new(p: &SubjectParams) -> Self {
        let a = (-TAU * DRIFT_CORNER_HZ / p.sfreq).exp();
        let mut gauss = Gauss::new(p.seed, STREAM_DRIFT);
        let state = (0..p.n_channels()).map(|_| gauss.normal()).collect();
        Self {
            gauss,
            pole: (a, (1.0 - a * a).sqrt()),
            state,
            rms: p.drift_rms,
        }
    }

    fn step(&mut self, out: &mut [f64]) {
        if self.rms == 0.0 {
            out.fill(0.0);
            return;
        }
        let (a, b) = self.pole;
        for (s, o) in self.state.iter_mut().zip(out.iter_mut()) {
            *s = a * *s + b * self.gauss.unit_uniform();
            *o = self.rms * *s;
        }
    }
}

/// Eye blinks: a Poisson process of fixed-shape deflections.
#[derive(Debug, Clone)]
struct Blinks {
    gauss: Gauss,
    /// Probability of a blink starting at a sample.
    p_start: f64,
    amplitude: f64,
    rise: usize,
    fall: usize,
    /// (first sample, peak µV) of the blinks still under way, oldest first.
    active: VecDeque<(u64, f64)>,
}

impl Blinks {
    fn new(p: &SubjectParams) -> Self {
        Self {
            gauss: Gauss::new(p.seed, STREAM_BLINK),
            p_start: p.blink_rate / 60.0 / p.sfreq,
            amplitude: p.blink_amplitude,
            rise: ((BLINK_RISE_S * p.sfreq).round() as usize).max(1),
            fall: ((BLINK_FALL_S * p.sfreq).round() as usize).max(1),
            active: VecDeque::new(),
        }
    }

    /// Shape at sample `i` of a blink (0 at its start, 1 at its peak).
    fn shape(&self, i: usize) -> f64 {
        if i < self.rise {
            0.5 * (1.0 - (PI * i as f64 / self.rise as f64).cos())
        } else if i < self.rise + self.fall {
            0.5 * (1.0 + (PI * (i - self.rise) as f64 / self.fall as f64).cos())
        } else {
            0.0
        }
    }

    /// The blink signal at gain 1 at sample `n`.
    fn step(&mut self, n: u64) -> f64 {
        if self.p_start <= 0.0 || self.amplitude <= 0.0 {
            return 0.0;
        }
        if self.gauss.uniform() < self.p_start {
            let peak = self.amplitude * (1.0 + BLINK_SPREAD * (2.0 * self.gauss.uniform() - 1.0));
            self.active.push_back((n, peak));
        }
        let len = (self.rise + self.fall) as u64;
        while self.active.front().is_some_and(|&(s, _)| n >= s + len) {
            self.active.pop_front();
        }
        self.active
            .iter()
            .map(|&(s, peak)| peak * self.shape((n - s) as usize))
            .sum()
    }
}

/// The evoked responses of one registered flash, at gain 1.
#[derive(Debug, Clone)]
struct Evoked {
    onset: u64,
    /// One past the last sample with a response.
    end: u64,
    /// P300 time course from the onset (empty when not attended), µV.
    p300: Vec<f64>,
    /// Visual evoked time course from the onset, µV.
    vep: Vec<f64>,
}

/// Samples of a Gaussian bump of `peak` µV at `latency` s with sd `sd` s, from the onset until
/// `TAIL_SDS` sds after the peak.
fn gaussian_course(peak: f64, latency: f64, sd: f64, sfreq: f64) -> Vec<f64> {
    let n = ((latency + TAIL_SDS * sd) * sfreq).ceil().max(0.0) as usize + 1;
    (0..n)
        .map(|i| {
            let z = (i as f64 / sfreq - latency) / sd;
            peak * (-0.5 * z * z).exp()
        })
        .collect()
}

/// A simulated subject: registered flashes in, continuous EEG out.
#[derive(Debug, Clone)]
pub struct SimulatedSubject {
    params: SubjectParams,
    position: u64,
    pink: Pink,
    alpha: Alpha,
    drift: Drift,
    blinks: Blinks,
    /// Per-flash draws.
    flash_gauss: Gauss,
    /// Registered flashes not yet over, in onset order (registration order among equal onsets).
    flashes: VecDeque<Evoked>,
    /// Line amplitude per channel, µV.
    line: Vec<f64>,
    /// Scratch per channel: background, alpha, drift.
    scratch: [Vec<f64>; 3],
}

impl SimulatedSubject {
    fn new(params: SubjectParams) -> Self {
        let n = params.n_channels();
        let mut setup = Gauss::new(params.seed, STREAM_SETUP);
        let line = (0..n)
            .map(|_| params.line_amplitude * (0.8 + 0.4 * setup.uniform()))
            .collect();
        Self {
            position: 0,
            pink: Pink::new(&params),
            alpha: Alpha::new(&params),
            drift: Drift::new(&params),
            blinks: Blinks::new(&params),
            flash_gauss: Gauss::new(params.seed, STREAM_FLASH),
            flashes: VecDeque::new(),
            line,
            scratch: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            params,
        }
    }

    pub fn params(&self) -> &SubjectParams {
        &self.params
    }

    pub fn sfreq(&self) -> f64 {
        self.params.sfreq
    }

    pub fn ch_names(&self) -> &[String] {
        &self.params.ch_names
    }

    pub fn n_channels(&self) -> usize {
        self.params.ch_names.len()
    }

    /// Samples rendered so far (the index of the next sample).
    pub fn position(&self) -> u64 {
        self.position
    }

    /// Registered flashes whose responses are not yet over.
    pub fn n_pending_flashes(&self) -> usize {
        self.flashes.len()
    }

    /// A stimulus the subject sees at `onset` (absolute sample index); `attended` when it is the
    /// stimulus the person attends (it evokes a P300). Every flash evokes the visual N1/P2.
    /// Refused when `onset` is before [`Self::position`]: the past can't change.
    pub fn flash(&mut self, onset: u64, attended: bool) -> Result<(), SessionError> {
        if onset < self.position {
            return Err(SessionError::InvalidParameter {
                name: "onset",
                value: onset.to_string(),
                reason: format!(
                    "flash before the next sample to render ({}); the past can't change",
                    self.position
                ),
            });
        }
        let p = &self.params;
        // Always three draws, so the stream does not depend on which flashes are attended.
        let z_latency = self.flash_gauss.normal();
        let z_amplitude = self.flash_gauss.normal();
        let z_vep = self.flash_gauss.normal();
        let p300 = if attended && p.p300_amplitude > 0.0 {
            let latency = (p.p300_latency + p.p300_jitter * z_latency).max(0.0);
            let peak = p.p300_amplitude * (1.0 + p.p300_variability * z_amplitude).max(0.0);
            gaussian_course(peak, latency, p.p300_width, p.sfreq)
        } else {
            Vec::new()
        };
        let vep = if p.vep_amplitude > 0.0 {
            let a = p.vep_amplitude * (1.0 + VEP_VARIABILITY * z_vep).max(0.0);
            let n1 = gaussian_course(-a, VEP_N1.0, VEP_N1.1, p.sfreq);
            let mut p2 = gaussian_course(VEP_P2_GAIN * a, VEP_P2.0, VEP_P2.1, p.sfreq);
            for (x, y) in p2.iter_mut().zip(&n1) {
                *x += y;
            }
            p2
        } else {
            Vec::new()
        };
        let end = onset.saturating_add(p300.len().max(vep.len()) as u64);
        let at = self.flashes.partition_point(|f| f.onset <= onset);
        self.flashes.insert(
            at,
            Evoked {
                onset,
                end,
                p300,
                vep,
            },
        );
        Ok(())
    }

    /// The next `n` samples `(n_channels, n)`, µV.
    pub fn render(&mut self, n: usize) -> Array2<f64> {
        let mut out = Array2::zeros((self.n_channels(), n));
        self.render_into(out.view_mut());
        out
    }

    /// Writes the next `out.ncols()` samples into `out` `(n_channels, n)`, µV.
    ///
    /// # Panics
    /// When `out` does not have one row per channel.
    pub fn render_into(&mut self, mut out: ArrayViewMut2<'_, f64>) {
        let n_channels = self.n_channels();
        assert_eq!(out.nrows(), n_channels, "one row per channel");
        let sfreq = self.params.sfreq;
        let line_freq = self.params.line_freq;
        let line_on = self.params.line_amplitude > 0.0;
        let [mut pink, mut alpha, mut drift] = std::mem::take(&mut self.scratch);
        for i in 0..out.ncols() {
            let t = self.position;
            self.pink.step(&mut pink);
            self.alpha.step(&mut alpha);
            self.drift.step(&mut drift);
            let blink = self.blinks.step(t);
            let line = if line_on {
                (TAU * (line_freq * t as f64 / sfreq).fract()).sin()
            } else {
                0.0
            };
            while self.flashes.front().is_some_and(|f| f.end <= t) {
                self.flashes.pop_front();
            }
            let (mut p300, mut vep) = (0.0, 0.0);
            for f in &self.flashes {
                if f.onset > t {
                    break;
                }
                let k = (t - f.onset) as usize;
                p300 += f.p300.get(k).copied().unwrap_or(0.0);
                vep += f.vep.get(k).copied().unwrap_or(0.0);
            }
            let p = &self.params;
            for c in 0..n_channels {
                let x = pink[c]
                    + alpha[c]
                    + drift[c]
                    + self.line[c] * line
                    + p.blink_topography[c] * blink
                    + p.p300_topography[c] * p300
                    + p.vep_topography[c] * vep;
                out[[c, i]] = (x as f32) as f64;
            }
            self.position += 1;
        }
        self.scratch = [pink, alpha, drift];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn channel(params: &SubjectParams, name: &str) -> usize {
        params.ch_names.iter().position(|c| c == name).unwrap()
    }

    /// Nothing but the process under test.
    fn silent() -> SubjectParams {
        SubjectParams {
            p300_amplitude: 0.0,
            vep_amplitude: 0.0,
            pink_rms: 0.0,
            alpha_rms: 0.0,
            line_amplitude: 0.0,
            drift_rms: 0.0,
            blink_rate: 0.0,
            ..SubjectParams::preset(SubjectPreset::Typical)
        }
    }

    /// Welch power spectral density at `freq` (2 s Hann windows, half overlap), µV²/Hz.
    fn psd(x: &[f64], sfreq: f64, freq: f64) -> f64 {
        let len = (2.0 * sfreq) as usize;
        let window: Vec<f64> = (0..len)
            .map(|i| 0.5 - 0.5 * (TAU * i as f64 / len as f64).cos())
            .collect();
        let norm: f64 = window.iter().map(|w| w * w).sum::<f64>() * sfreq;
        let w = TAU * freq / sfreq;
        let (mut total, mut count) = (0.0, 0);
        for start in (0..=x.len() - len).step_by(len / 2) {
            let seg = &x[start..start + len];
            let mean = seg.iter().sum::<f64>() / len as f64;
            let (mut re, mut im) = (0.0, 0.0);
            for (i, (v, win)) in seg.iter().zip(&window).enumerate() {
                let a = (v - mean) * win;
                re += a * (w * i as f64).cos();
                im -= a * (w * i as f64).sin();
            }
            total += 2.0 * (re * re + im * im) / norm;
            count += 1;
        }
        total / count as f64
    }

    fn rms(x: &[f64]) -> f64 {
        (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
    }

    #[test]
    fn presets_parse_print_and_round_trip() {
        for p in SubjectPreset::ALL {
            assert_eq!(p.to_string().parse::<SubjectPreset>().unwrap(), p);
            let params = SubjectParams::preset(p).with_seed(9);
            params.validate().unwrap();
            assert_eq!(params.seed, 9);
            let json = serde_json::to_string(&params).unwrap();
            assert_eq!(
                serde_json::from_str::<SubjectParams>(&json).unwrap(),
                params
            );
        }
        assert_eq!(
            "typical".parse::<SubjectPreset>().unwrap(),
            SubjectPreset::Typical
        );
        assert!("Typical".parse::<SubjectPreset>().is_err());
        assert!("medium".parse::<SubjectPreset>().is_err());
        assert_eq!(
            serde_json::to_string(&SubjectPreset::Hard).unwrap(),
            "\"hard\""
        );
        let s = SubjectParams::default().build().unwrap();
        assert_eq!(s.sfreq(), 500.0);
        assert_eq!(s.n_channels(), 8);
        assert_eq!(s.ch_names()[3], "Pz");
        assert_eq!(s.position(), 0);
    }

    #[test]
    fn same_seed_same_samples_other_seed_differs() {
        let run = |seed| {
            let mut s = SubjectParams::preset(SubjectPreset::Typical)
                .with_seed(seed)
                .build()
                .unwrap();
            s.flash(100, true).unwrap();
            s.flash(225, false).unwrap();
            s.render(1000)
        };
        let a = run(1);
        assert_eq!(a.dim(), (8, 1000));
        assert_eq!(a, run(1));
        let b = run(2);
        assert!(a.iter().zip(&b).filter(|(x, y)| x != y).count() > 7900);
    }

    #[test]
    fn samples_are_float32_values() {
        let mut s = SubjectParams::preset(SubjectPreset::Hard).build().unwrap();
        s.flash(10, true).unwrap();
        let x = s.render(2000);
        assert!(x.iter().all(|&v| v.is_finite() && (v as f32) as f64 == v));
        assert_eq!(s.position(), 2000);
        assert_eq!(s.render(0).dim(), (8, 0));
    }

    #[test]
    fn a_flash_in_the_past_is_refused() {
        let mut s = SubjectParams::default().build().unwrap();
        s.render(100);
        assert!(matches!(
            s.flash(99, true),
            Err(SessionError::InvalidParameter { name: "onset", .. })
        ));
        s.flash(100, true).unwrap();
        s.flash(5000, false).unwrap();
        assert_eq!(s.n_pending_flashes(), 2);
    }

    #[test]
    fn finished_flashes_are_dropped() {
        let mut s = SubjectParams::default().build().unwrap();
        for k in 0..8 {
            s.flash(125 * k, k % 4 == 1).unwrap();
        }
        s.render(500);
        // Flashes up to 1 s old may still be under way; none older.
        assert!((1..=8).contains(&s.n_pending_flashes()));
        s.render(1000);
        assert_eq!(s.n_pending_flashes(), 0);
    }

    #[test]
    fn invalid_settings_are_refused() {
        type Edit = fn(&mut SubjectParams);
        let cases: [(&str, Edit); 14] = [
            ("sfreq", |p| p.sfreq = 0.0),
            ("sfreq", |p| p.sfreq = f64::NAN),
            ("ch_names", |p| p.ch_names.clear()),
            ("ch_names", |p| p.ch_names[1] = "Fz".into()),
            ("p300_topography", |p| {
                p.p300_topography.pop();
            }),
            ("blink_topography", |p| {
                p.blink_topography[0] = f64::INFINITY
            }),
            ("p300_amplitude", |p| p.p300_amplitude = -1.0),
            ("pink_rms", |p| p.pink_rms = f64::NAN),
            ("blink_rate", |p| p.blink_rate = -3.0),
            ("p300_width", |p| p.p300_width = 0.0),
            ("p300_latency", |p| p.p300_latency = 60.0),
            ("spatial_correlation", |p| p.spatial_correlation = 1.5),
            ("alpha_freq", |p| p.alpha_freq = 300.0),
            ("line_freq", |p| p.line_freq = 250.0),
        ];
        for (field, edit) in cases {
            let mut p = SubjectParams::default();
            edit(&mut p);
            match p.build() {
                Err(SessionError::InvalidParameter { name, .. }) => assert_eq!(name, field),
                other => panic!("{field}: expected an error, got {other:?}"),
            }
        }
        // A fewer-channel montage is fine with topographies to match.
        let mut p = SubjectParams::default();
        p.ch_names.truncate(2);
        for t in [
            &mut p.p300_topography,
            &mut p.vep_topography,
            &mut p.alpha_topography,
            &mut p.blink_topography,
        ] {
            t.truncate(2);
        }
        assert_eq!(p.build().unwrap().render(10).dim(), (2, 10));
    }

    #[test]
    fn evoked_responses_have_their_latencies_and_topographies() {
        let params = SubjectParams {
            p300_amplitude: 8.0,
            p300_jitter: 0.0,
            p300_variability: 0.0,
            vep_amplitude: 3.0,
            ..silent()
        };
        let (pz, oz, fz) = (
            channel(&params, "Pz"),
            channel(&params, "Oz"),
            channel(&params, "Fz"),
        );
        let mut s = params.build().unwrap();
        s.flash(100, true).unwrap();
        s.flash(1100, false).unwrap();
        let x = s.render(2100);
        let argmax = |c: usize, from: usize, sign: f64| {
            (from..from + 500)
                .max_by(|&a, &b| (sign * x[[c, a]]).total_cmp(&(sign * x[[c, b]])))
                .unwrap()
                - from
        };
        // Attended: the P300 dominates at Pz, peaking at the set latency with the set size.
        // (The visual P2 at Pz shifts the peak by a sample or two.)
        let peak = argmax(pz, 100, 1.0);
        assert!(peak.abs_diff((params.p300_latency * 500.0).round() as usize) <= 3);
        let at_peak = x[[pz, 100 + peak]];
        assert!((at_peak - 8.0).abs() < 1.0, "{at_peak}");
        assert!(x[[fz, 100 + peak]] < 0.5 * at_peak);
        // Not attended: only the visual N1 (160 ms) and P2, largest occipitally.
        assert!(argmax(oz, 1100, -1.0).abs_diff(80) <= 3);
        assert!(x[[oz, 1180]] < -2.0 && x[[oz, 1180]] < 3.0 * x[[fz, 1180]]);
        let late = x.slice(ndarray::s![pz, 1100 + 300..1100 + 450]);
        assert!(
            late.iter().all(|v| v.abs() < 0.5),
            "no P300 when not attended"
        );
    }

    #[test]
    fn background_has_a_falling_spectrum_an_alpha_peak_and_the_mains() {
        let params = SubjectParams::preset(SubjectPreset::Typical).with_seed(3);
        let sfreq = params.sfreq;
        let x = params.build().unwrap().render((120.0 * sfreq) as usize);
        for name in ["Pz", "Oz", "PO8"] {
            let row = x.row(channel(&params, name)).to_vec();
            let p = |f| psd(&row, sfreq, f);
            assert!(
                p(10.0) > 3.0 * p(6.0) && p(10.0) > 3.0 * p(14.0),
                "{name} alpha"
            );
            assert!(p(50.0) > 20.0 * (p(45.0) + p(55.0)), "{name} mains");
            assert!(p(2.0) > 5.0 * p(30.0), "{name} 1/f");
        }
        // Broadband RMS of realistic size.
        for c in 0..params.n_channels() {
            let r = rms(x.row(c).as_slice().unwrap());
            assert!(
                (8.0..25.0).contains(&r),
                "{}: {r} µV RMS",
                params.ch_names[c]
            );
        }
    }

    #[test]
    fn pink_background_is_one_over_f_and_correlated_across_channels() {
        let params = SubjectParams {
            pink_rms: 10.0,
            ..silent()
        };
        let sfreq = params.sfreq;
        let x = params.build().unwrap().render((200.0 * sfreq) as usize);
        let row = x.row(0).to_vec();
        assert!((rms(&row) - 10.0).abs() < 1.5, "{}", rms(&row));
        // f · PSD(f) flat within a factor 1.5 from 1 to 100 Hz.
        let fp: Vec<f64> = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 100.0]
            .iter()
            .map(|&f| f * psd(&row, sfreq, f))
            .collect();
        let (lo, hi) = fp
            .iter()
            .fold((f64::MAX, 0f64), |(l, h), &v| (l.min(v), h.max(v)));
        assert!(hi < 1.5 * lo, "f·PSD {fp:?}");
        let (a, b) = (x.row(0), x.row(5));
        let r = a.dot(&b) / (a.dot(&a) * b.dot(&b)).sqrt();
        assert!(
            (r - params.spatial_correlation).abs() < 0.1,
            "correlation {r}"
        );
    }

    #[test]
    fn blinks_are_largest_frontally() {
        let params = SubjectParams {
            blink_rate: 20.0,
            ..silent()
        };
        let x = params
            .build()
            .unwrap()
            .render((60.0 * params.sfreq) as usize);
        let peak = |name| {
            x.row(channel(&params, name))
                .iter()
                .fold(0f64, |m, v| m.max(v.abs()))
        };
        let (fz, cz, pz, oz) = (peak("Fz"), peak("Cz"), peak("Pz"), peak("Oz"));
        assert!(fz > 0.75 * params.blink_amplitude && fz <= 1.25 * params.blink_amplitude);
        assert!(fz > cz && cz > pz && pz > oz, "{fz} {cz} {pz} {oz}");
        assert!(fz > 4.0 * pz);
        // About 20 blinks: count the rising crossings of half the smallest peak.
        let fzrow = x.row(channel(&params, "Fz"));
        let half = 0.5 * 0.75 * params.blink_amplitude;
        let n = fzrow
            .windows(2)
            .into_iter()
            .filter(|w| w[0] < half && w[1] >= half)
            .count();
        assert!((8..=35).contains(&n), "{n} blinks in a minute");
    }

    #[test]
    fn switching_a_process_off_leaves_the_others_unchanged() {
        let all = SubjectParams::preset(SubjectPreset::Typical);
        let no_line = SubjectParams {
            line_amplitude: 0.0,
            ..all.clone()
        };
        let line_only = SubjectParams {
            line_amplitude: all.line_amplitude,
            ..silent()
        };
        let a = all.build().unwrap().render(3000);
        let b = no_line.build().unwrap().render(3000);
        let l = line_only.build().unwrap().render(3000);
        for ((x, y), z) in a.iter().zip(&b).zip(&l) {
            assert!((x - (y + z)).abs() < 1e-4, "{x} vs {y} + {z}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Chunks of any sizes, flashes registered at any time before their onset: the same
        /// samples, bit for bit.
        #[test]
        fn chunking_does_not_change_the_samples(
            seed in 0u64..1000,
            cuts in prop::collection::vec(0usize..1500, 0..12),
            flashes in prop::collection::vec((0u64..1500, any::<bool>()), 0..12),
            lead in 0u64..600,
        ) {
            let mut flashes = flashes;
            flashes.sort_by_key(|f| f.0);
            let params = SubjectParams::preset(SubjectPreset::Hard).with_seed(seed);
            let mut whole = params.build().unwrap();
            for &(onset, attended) in &flashes {
                whole.flash(onset, attended).unwrap();
            }
            let expected = whole.render(1500);

            let mut cuts = cuts;
            cuts.extend([0, 1500]);
            cuts.sort_unstable();
            let mut pieces = params.build().unwrap();
            let mut got = Array2::zeros((8, 1500));
            let mut pending = flashes.iter().peekable();
            for w in cuts.windows(2) {
                // Flashes are registered `lead` samples ahead of the chunk that shows them.
                while let Some(&(onset, attended)) =
                    pending.next_if(|f| f.0 < w[1] as u64 + lead)
                {
                    pieces.flash(onset, attended).unwrap();
                }
                pieces.render_into(got.slice_mut(ndarray::s![.., w[0]..w[1]]));
            }
            prop_assert_eq!(pieces.position(), 1500);
            prop_assert_eq!(got, expected);
        }
    }
}
