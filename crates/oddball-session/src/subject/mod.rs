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
//! * **P300 refractoriness (target-to-target interval)**: the P300 of an attended flash `TTI` s
//!   after the previous attended one is further scaled by
//!   `(1 − e^(−TTI/τ)) / (1 − e^(−ref/τ))` ([`SubjectParams::tti_factor`]; τ = `p300_recovery`,
//!   ref = `p300_reference_tti`; the first attended flash counts as a long interval).
//!   Sources: that P300 amplitude grows with the target-to-target interval, and that TTI rather
//!   than probability or ISI sets it, is Gonsalvez & Polich (2002, Psychophysiology 39:388–396;
//!   visual and auditory oddballs with TTIs of about 1 to 16 s); that the target ERPs of a
//!   P300 speller shrink when targets follow each other closely is Martens et al. (2009,
//!   J. Neural Eng. 6:026003). The numbers are ours, not fitted to either paper: the
//!   saturating-exponential form is the simplest recovery that keeps growing over seconds as
//!   Gonsalvez & Polich's amplitudes did; τ = [`P300_RECOVERY_S`] = 2 s is an assumption (it
//!   halves the P300 at a 0.45 s TTI, about 0.35–0.5 s being where Martens et al. saw the
//!   target ERP clearly reduced); ref = [`P300_REFERENCE_TTI_S`] = 1 s is the paper timing's
//!   mean TTI (a target once per 1 s round), so the presets' amplitudes, set at that timing,
//!   keep their meaning there. At the `fast` timing (a flash every 175 ms, mean TTI 0.7 s,
//!   shortest 0.35 s) the mean factor is about 0.75, at the paper's about 1.
//! * **overlap of successive responses**: every flash's visual response and P300 are added to
//!   the EEG from their onset on (linear superposition of evoked responses, the model behind
//!   the overlap correction of Woldorff 1993, Psychophysiology 30:98–119, and of the
//!   regression ERPs of Smith & Kutas 2015). At 175 ms onset-to-onset the P300 of a target
//!   (350 ms latency, ~200 ms wide) lies under the epochs of the two or three flashes after
//!   it, and their visual responses under its epoch; nothing is corrected for it.
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

mod params;
mod processes;

use std::collections::VecDeque;
use std::f64::consts::TAU;

use ndarray::{Array2, ArrayViewMut2};

use crate::SessionError;

pub use params::{
    SubjectParams, SubjectPreset, P300_RECOVERY_S, P300_REFERENCE_TTI_S, STARSTIM_CHANNELS,
    STARSTIM_SFREQ,
};
use processes::*;

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
    /// Onset of the last attended flash (the target-to-target interval starts there).
    last_target: Option<u64>,
    /// Registered flashes not yet over, in onset order (registration order among equal onsets).
    flashes: VecDeque<Evoked>,
    /// Line amplitude per channel, µV.
    line: Vec<f64>,
    /// Scratch per channel: background, alpha, drift.
    scratch: [Vec<f64>; 3],
}

impl SubjectParams {
    /// A subject at sample 0.
    pub fn build(&self) -> Result<SimulatedSubject, SessionError> {
        self.validate()?;
        Ok(SimulatedSubject::new(self.clone()))
    }
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
            last_target: None,
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
            let tti = self
                .last_target
                .map(|last| onset.saturating_sub(last) as f64 / p.sfreq);
            let latency = (p.p300_latency + p.p300_jitter * z_latency).max(0.0);
            let peak = p.p300_amplitude
                * p.tti_factor(tti)
                * (1.0 + p.p300_variability * z_amplitude).max(0.0);
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
        if attended {
            self.last_target = Some(onset);
        }
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
            p300_recovery: 0.0,
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

    /// Pz of a silent subject (evoked responses only, no variability) after `flashes`.
    fn evoked_pz(params: &SubjectParams, flashes: &[(u64, bool)], n: usize) -> Vec<f64> {
        let pz = channel(params, "Pz");
        let mut s = params.clone().build().unwrap();
        for &(onset, attended) in flashes {
            s.flash(onset, attended).unwrap();
        }
        s.render(n).row(pz).to_vec()
    }

    #[test]
    fn the_p300_shrinks_when_targets_come_close_together() {
        let params = SubjectParams {
            p300_amplitude: 8.0,
            p300_jitter: 0.0,
            p300_variability: 0.0,
            ..silent()
        };
        assert_eq!(params.p300_recovery, P300_RECOVERY_S);
        let f = |t| params.tti_factor(Some(t));
        assert!((f(1.0) - 1.0).abs() < 1e-12);
        assert!(f(0.35) < 0.5 && f(0.7) < 0.8 && f(2.0) > 1.5);
        assert!(f(0.0) == 0.0 && f(0.5) < f(0.6));
        // The hand formula at 0.35 s.
        let hand = (1.0 - (-0.35f64 / 2.0).exp()) / (1.0 - (-0.5f64).exp());
        assert!((f(0.35) - hand).abs() < 1e-12);
        // Two targets 0.35 s apart against two 1 s apart: the second P300 (the first's
        // response subtracted) peaks at f(0.35) and f(1.0) of the amplitude.
        let n = 2000;
        let alone = evoked_pz(&params, &[(100, true)], n);
        let lat = (params.p300_latency * 500.0).round() as usize;
        for (gap, expected) in [(175usize, f(0.35)), (500, 1.0)] {
            let both = evoked_pz(&params, &[(100, true), (100 + gap as u64, true)], n);
            let second = both[100 + gap + lat] - alone[100 + gap + lat];
            assert!(
                (second - 8.0 * expected).abs() < 0.05,
                "gap {gap}: {second} vs {}",
                8.0 * expected
            );
        }
        // Switched off: every target has the full amplitude.
        let off = SubjectParams {
            p300_recovery: 0.0,
            ..params.clone()
        };
        assert_eq!(off.tti_factor(Some(0.1)), 1.0);
        // Non-attended flashes in between do not reset the interval.
        let with_nontarget = evoked_pz(&params, &[(100, true), (187, false), (275, true)], n);
        let nontarget = evoked_pz(&params, &[(100, true), (187, false)], n);
        let second = with_nontarget[275 + lat] - nontarget[275 + lat];
        assert!((second - 8.0 * f(0.35)).abs() < 0.05, "{second}");
    }

    #[test]
    fn responses_of_successive_flashes_add_up() {
        // Flashes every 175 ms (the fast timing): the EEG is the sum of each flash's response.
        let params = SubjectParams {
            p300_amplitude: 8.0,
            p300_jitter: 0.0,
            p300_variability: 0.0,
            p300_recovery: 0.0,
            vep_amplitude: 3.0,
            ..silent()
        };
        let flashes: Vec<(u64, bool)> = (0..6).map(|k| (50 + 88 * k, k % 3 == 1)).collect();
        let together = evoked_pz(&params, &flashes, 1200);
        // Each flash alone, with the draws it had among the others: the flashes before it are
        // registered far beyond the rendered samples (they draw, but show nothing).
        let pz = channel(&params, "Pz");
        let mut sum = vec![0.0; 1200];
        for (k, &(onset, attended)) in flashes.iter().enumerate() {
            let mut s = params.clone().build().unwrap();
            for _ in 0..k {
                s.flash(1_000_000, false).unwrap();
            }
            s.flash(onset, attended).unwrap();
            for (t, v) in sum.iter_mut().zip(s.render(1200).row(pz)) {
                *t += v;
            }
        }
        let peak = together.iter().fold(0f64, |m, v| m.max(v.abs()));
        assert!(peak > 5.0, "{peak}");
        for (i, (a, b)) in together.iter().zip(&sum).enumerate() {
            // Each render rounds to f32 once; the sum of six rounded renders differs by ulps.
            assert!((a - b).abs() < 1e-5, "sample {i}: {a} vs {b}");
        }
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
