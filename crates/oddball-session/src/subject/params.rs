//! The simulated subject's settings: presets and parameters, and the default montage.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::SessionError;

/// Gaussians are cut this many sds after their peak.
pub(super) const TAIL_SDS: f64 = 5.0;

/// The default montage: eight channels of a Neuroelectrics Starstim-like cap.
pub const STARSTIM_CHANNELS: [&str; 8] = ["Fz", "Cz", "P3", "Pz", "P4", "PO7", "Oz", "PO8"];

/// The default sampling rate (Starstim), Hz.
pub const STARSTIM_SFREQ: f64 = 500.0;

/// P300 gain per channel of [`STARSTIM_CHANNELS`]: parietal maximum, smaller frontally.
pub(super) const P300_GAINS: [f64; 8] = [0.35, 0.7, 0.8, 1.0, 0.8, 0.55, 0.45, 0.55];
/// Visual evoked response gain: occipital.
pub(super) const VEP_GAINS: [f64; 8] = [0.1, 0.25, 0.55, 0.5, 0.55, 0.95, 1.0, 0.95];
/// Alpha gain: posterior.
pub(super) const ALPHA_GAINS: [f64; 8] = [0.3, 0.5, 0.8, 0.85, 0.8, 0.95, 1.0, 0.95];
/// Blink gain: frontal, decaying backwards.
pub(super) const BLINK_GAINS: [f64; 8] = [1.0, 0.45, 0.15, 0.15, 0.15, 0.06, 0.05, 0.06];

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

/// Time constant of the P300's recovery with the target-to-target interval, s (module doc).
pub const P300_RECOVERY_S: f64 = 2.0;
/// The target-to-target interval the presets' P300 amplitudes hold at: the mean of the paper's
/// timing (a target once per 1 s round), s.
pub const P300_REFERENCE_TTI_S: f64 = 1.0;

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
    /// Time constant of the P300's recovery after the previous attended flash, s: a target
    /// `TTI` s after the last one evokes `(1 − e^(−TTI/τ)) / (1 − e^(−ref/τ))` of
    /// `p300_amplitude` (ref = `p300_reference_tti`). 0 switches the effect off (and is what a
    /// file written before it existed reads as). See the module doc for the sources.
    #[serde(default)]
    pub p300_recovery: f64,
    /// Target-to-target interval at which the P300 has `p300_amplitude`, s.
    #[serde(default)]
    pub p300_reference_tti: f64,
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
    /// The P300's amplitude factor for a target `tti` s after the previous attended flash
    /// (`None`: no attended flash before): 1 at `p300_reference_tti`, growing towards
    /// `1 / (1 − e^(−ref/τ))` for long intervals, towards 0 for short ones.
    pub fn tti_factor(&self, tti: Option<f64>) -> f64 {
        let tau = self.p300_recovery;
        if tau <= 0.0 {
            return 1.0;
        }
        let recovered = |t: f64| 1.0 - (-t.max(0.0) / tau).exp();
        tti.map_or(1.0, recovered) / recovered(self.p300_reference_tti)
    }

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
            p300_recovery: P300_RECOVERY_S,
            p300_reference_tti: P300_REFERENCE_TTI_S,
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
            ("p300_recovery", self.p300_recovery),
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
        if self.p300_recovery > 0.0
            && !(self.p300_reference_tti.is_finite() && self.p300_reference_tti > 0.0)
        {
            return bad(
                "p300_reference_tti",
                self.p300_reference_tti.to_string(),
                "must be > 0 when p300_recovery is",
            );
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
}
