//! The processes the simulated EEG is summed from: 1/f background, alpha, drift, blinks and
//! the evoked responses of registered flashes, each from its own seeded stream.

use std::collections::VecDeque;
use std::f64::consts::{PI, TAU};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::params::{SubjectParams, TAIL_SDS};

/// Lowest pole of the 1/f background's filter, Hz.
pub(super) const PINK_LOWEST_HZ: f64 = 0.5;
/// Ratio of successive poles (and zeros).
pub(super) const PINK_RATIO: f64 = 3.0;
/// Highest zero, as a fraction of `sfreq`.
pub(super) const PINK_HIGHEST_FRACTION: f64 = 0.45;
/// Processes run this long before the first sample, to start in their stationary state, s.
pub(super) const BURN_IN_S: f64 = 5.0;
/// Corner of the drift's AR(1) process, Hz.
pub(super) const DRIFT_CORNER_HZ: f64 = 0.05;
/// Blink rise and fall, seconds.
pub(super) const BLINK_RISE_S: f64 = 0.1;
pub(super) const BLINK_FALL_S: f64 = 0.2;
/// Blink amplitudes are uniform in (1 ± this) × `blink_amplitude`.
pub(super) const BLINK_SPREAD: f64 = 0.25;
/// Visual evoked response: N1 and P2 latency and sd, seconds; P2 relative amplitude.
pub(super) const VEP_N1: (f64, f64) = (0.16, 0.025);
pub(super) const VEP_P2: (f64, f64) = (0.24, 0.04);
pub(super) const VEP_P2_GAIN: f64 = 0.8;
/// Amplitude variability (sd of the factor) of the visual evoked response.
pub(super) const VEP_VARIABILITY: f64 = 0.25;

/// ChaCha streams of the processes.
pub(super) const STREAM_PINK: u64 = 1;
pub(super) const STREAM_ALPHA: u64 = 2;
pub(super) const STREAM_DRIFT: u64 = 3;
pub(super) const STREAM_BLINK: u64 = 4;
pub(super) const STREAM_FLASH: u64 = 5;
pub(super) const STREAM_SETUP: u64 = 6;

/// Standard normal numbers (Marsaglia's polar method) from one ChaCha stream.
#[derive(Debug, Clone)]
pub(super) struct Gauss {
    pub(super) rng: ChaCha8Rng,
    pub(super) spare: Option<f64>,
}

impl Gauss {
    pub(super) fn new(seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        Self { rng, spare: None }
    }

    pub(super) fn uniform(&mut self) -> f64 {
        self.rng.gen::<f64>()
    }

    /// Zero mean, unit variance, uniform: a cheap innovation for processes whose output averages
    /// hundreds of innovations (and so is Gaussian anyway).
    pub(super) fn unit_uniform(&mut self) -> f64 {
        3f64.sqrt() * (2.0 * self.rng.gen::<f64>() - 1.0)
    }

    pub(super) fn normal(&mut self) -> f64 {
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
pub(super) fn mix_weights(rho: f64) -> (f64, f64) {
    (rho.sqrt(), (1.0 - rho).sqrt())
}

/// Runs `step` (one innovation in, one sample out) for `n` samples from rest with a unit impulse
/// first, and returns the square root of the output energy: the RMS of the process driven by
/// unit-variance white noise.
pub(super) fn impulse_rms(n: usize, mut step: impl FnMut(f64) -> f64) -> f64 {
    (0..n)
        .map(|i| step(if i == 0 { 1.0 } else { 0.0 }).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Samples to run a process before its first output, so it starts in its stationary state.
pub(super) fn burn_in(sfreq: f64) -> usize {
    (BURN_IN_S * sfreq).ceil() as usize
}

/// The 1/f background. Each source (the shared one first, then one per channel) is white noise
/// through a cascade of first-order sections with poles at 0.5, 1.5, 4.5, … Hz and a zero
/// between each pair of poles (at √3 × the pole): every pole–zero pair turns the slope down by
/// half a decade per decade, which makes the power spectrum 1/f between the lowest pole and the
/// highest zero.
#[derive(Debug, Clone)]
pub(super) struct Pink {
    pub(super) gauss: Gauss,
    /// (pole, zero) of each section, z-plane.
    pub(super) sections: Vec<(f64, f64)>,
    /// Per source and section: the previous input and output.
    pub(super) state: Vec<(f64, f64)>,
    /// Output weight of the shared and own sources (0 = not simulated).
    pub(super) shared: f64,
    pub(super) own: f64,
}

impl Pink {
    pub(super) fn new(p: &SubjectParams) -> Self {
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
    pub(super) fn filter(&mut self, source: usize, e: f64) -> f64 {
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
    pub(super) fn step(&mut self, out: &mut [f64]) {
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
pub(super) struct Alpha {
    pub(super) gauss: Gauss,
    /// AR(2) coefficients: x = a1·x₋₁ + a2·x₋₂ + e.
    pub(super) a1: f64,
    pub(super) a2: f64,
    /// Per source: the last two outputs.
    pub(super) state: Vec<(f64, f64)>,
    pub(super) shared: f64,
    pub(super) own: f64,
    /// alpha_rms · gain per channel, over the unit-innovation RMS.
    pub(super) gains: Vec<f64>,
    /// Simulated at all (`alpha_rms` > 0 and some gain not 0).
    pub(super) on: bool,
}

impl Alpha {
    pub(super) fn new(p: &SubjectParams) -> Self {
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

    pub(super) fn step_source(&mut self, source: usize) -> f64 {
        let (x1, x2) = self.state[source];
        let x = self.a1 * x1 + self.a2 * x2 + self.gauss.unit_uniform();
        self.state[source] = (x, x1);
        x
    }

    pub(super) fn step(&mut self, out: &mut [f64]) {
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
pub(super) struct Drift {
    pub(super) gauss: Gauss,
    pub(super) pole: (f64, f64),
    pub(super) state: Vec<f64>,
    pub(super) rms: f64,
}

impl Drift {
    pub(super) fn new(p: &SubjectParams) -> Self {
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

    pub(super) fn step(&mut self, out: &mut [f64]) {
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
pub(super) struct Blinks {
    pub(super) gauss: Gauss,
    /// Probability of a blink starting at a sample.
    pub(super) p_start: f64,
    pub(super) amplitude: f64,
    pub(super) rise: usize,
    pub(super) fall: usize,
    /// (first sample, peak µV) of the blinks still under way, oldest first.
    pub(super) active: VecDeque<(u64, f64)>,
}

impl Blinks {
    pub(super) fn new(p: &SubjectParams) -> Self {
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
    pub(super) fn shape(&self, i: usize) -> f64 {
        if i < self.rise {
            0.5 * (1.0 - (PI * i as f64 / self.rise as f64).cos())
        } else if i < self.rise + self.fall {
            0.5 * (1.0 + (PI * (i - self.rise) as f64 / self.fall as f64).cos())
        } else {
            0.0
        }
    }

    /// The blink signal at gain 1 at sample `n`.
    pub(super) fn step(&mut self, n: u64) -> f64 {
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
pub(super) struct Evoked {
    pub(super) onset: u64,
    /// One past the last sample with a response.
    pub(super) end: u64,
    /// P300 time course from the onset (empty when not attended), µV.
    pub(super) p300: Vec<f64>,
    /// Visual evoked time course from the onset, µV.
    pub(super) vep: Vec<f64>,
}

/// Samples of a Gaussian bump of `peak` µV at `latency` s with sd `sd` s, from the onset until
/// `TAIL_SDS` sds after the peak.
pub(super) fn gaussian_course(peak: f64, latency: f64, sd: f64, sfreq: f64) -> Vec<f64> {
    let n = ((latency + TAIL_SDS * sd) * sfreq).ceil().max(0.0) as usize + 1;
    (0..n)
        .map(|i| {
            let z = (i as f64 / sfreq - latency) / sd;
            peak * (-0.5 * z * z).exp()
        })
        .collect()
}
