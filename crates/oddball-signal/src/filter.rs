//! IIR filtering as cascaded second-order sections (SOS).
//!
//! * Design: Butterworth (and the Chebyshev type I low-pass that [`crate::decimate`] needs) as SOS.
//!   The Butterworth design is `sci-rs`'s port of scipy's `butter(..., output='sos')`; `sci-rs` has no
//!   Chebyshev prototype yet, so [`SosFilter::cheby1_lowpass`] writes the analog prototype
//!   (scipy's `cheb1ap`) here and hands it to `sci-rs`' bilinear transform and `zpk2sos`.
//! * Filtering: [`SosFilter::sosfilt`] (causal, transposed direct form II as scipy's `sosfilt`),
//!   [`SosFilter::sosfiltfilt`] (zero-phase, scipy's `sosfiltfilt` with its default odd padding of
//!   `3 × (2·n_sections + 1 − …)` samples and steady-state initial conditions) and the stateful
//!   [`StreamingFilter`] whose output on any chunking equals one causal pass.
//!
//! The filtering kernel is our own rather than `sci-rs`'s iterator version: it runs up to
//! [`LANES`] channels side by side in one interleaved buffer, so the recursions of different
//! channels overlap in the CPU and vectorise. It is checked against scipy (golden fixtures) and
//! against `sci-rs`' `sosfiltfilt_dyn` in the tests.

use nalgebra::Complex;
use ndarray::{Array2, ArrayView2, ArrayViewMut2};
use sci_rs::signal::filter::design::{
    bilinear_zpk_dyn, butter_dyn, lp2lp_zpk_dyn, zpk2sos_dyn, DigitalFilter, FilterBandType,
    FilterOutputType, Sos, ZpkFormatFilter,
};
use serde::{Deserialize, Serialize};

use crate::{Raw, SignalError};

/// Channels filtered side by side by the kernel.
pub const LANES: usize = 4;

/// Highest filter order accepted by the design functions.
pub const MAX_ORDER: usize = 24;

/// Which frequencies a filter keeps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Band {
    /// Keep below `h_freq` Hz.
    Lowpass { h_freq: f64 },
    /// Keep above `l_freq` Hz.
    Highpass { l_freq: f64 },
    /// Keep `l_freq`–`h_freq` Hz.
    Bandpass { l_freq: f64, h_freq: f64 },
    /// Remove `l_freq`–`h_freq` Hz (e.g. 48–52 Hz line noise).
    Bandstop { l_freq: f64, h_freq: f64 },
}

impl std::fmt::Display for Band {
    /// `0.5–20 Hz`, `below 40 Hz`, `above 1 Hz`, `without 48–52 Hz`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Band::Lowpass { h_freq } => write!(f, "below {h_freq} Hz"),
            Band::Highpass { l_freq } => write!(f, "above {l_freq} Hz"),
            Band::Bandpass { l_freq, h_freq } => write!(f, "{l_freq}–{h_freq} Hz"),
            Band::Bandstop { l_freq, h_freq } => write!(f, "without {l_freq}–{h_freq} Hz"),
        }
    }
}

impl Band {
    /// MNE's convention: `l_freq = None` is a low-pass, `h_freq = None` a high-pass, both a band-pass.
    pub fn from_l_h(l_freq: Option<f64>, h_freq: Option<f64>) -> Result<Band, SignalError> {
        match (l_freq, h_freq) {
            (Some(l_freq), Some(h_freq)) => Ok(Band::Bandpass { l_freq, h_freq }),
            (None, Some(h_freq)) => Ok(Band::Lowpass { h_freq }),
            (Some(l_freq), None) => Ok(Band::Highpass { l_freq }),
            (None, None) => Err(SignalError::InvalidBand {
                l_freq,
                h_freq,
                nyquist: f64::NAN,
            }),
        }
    }

    fn l_h(&self) -> (Option<f64>, Option<f64>) {
        match *self {
            Band::Lowpass { h_freq } => (None, Some(h_freq)),
            Band::Highpass { l_freq } => (Some(l_freq), None),
            Band::Bandpass { l_freq, h_freq } | Band::Bandstop { l_freq, h_freq } => {
                (Some(l_freq), Some(h_freq))
            }
        }
    }
}

/// Settings of a Butterworth filter, not yet designed for a sampling rate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ButterworthParams {
    /// Order of the low-pass prototype (a band-pass of order N has 2N poles, N sections).
    pub order: usize,
    pub band: Band,
}

impl ButterworthParams {
    /// The paper's pre-processing band: 4th-order Butterworth band-pass 1–15 Hz.
    pub fn paper() -> Self {
        Self {
            order: 4,
            band: Band::Bandpass {
                l_freq: 1.0,
                h_freq: 15.0,
            },
        }
    }

    /// Designs the filter for `sfreq` Hz.
    pub fn design(&self, sfreq: f64) -> Result<SosFilter, SignalError> {
        SosFilter::butter(self.order, self.band, sfreq)
    }
}

/// A digital filter as second-order sections `[b0, b1, b2, a0, a1, a2]` with `a0 = 1`
/// (scipy's `sos` array, one row per section).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SosFilter {
    sections: Vec<[f64; 6]>,
}

fn check_order(order: usize) -> Result<(), SignalError> {
    if (1..=MAX_ORDER).contains(&order) {
        Ok(())
    } else {
        Err(SignalError::InvalidOrder {
            order,
            max: MAX_ORDER,
        })
    }
}

fn to_rows(sos: &[Sos<f64>]) -> Vec<[f64; 6]> {
    sos.iter()
        .map(|s| {
            let a0 = s.a[0];
            [
                s.b[0] / a0,
                s.b[1] / a0,
                s.b[2] / a0,
                1.0,
                s.a[1] / a0,
                s.a[2] / a0,
            ]
        })
        .collect()
}

impl SosFilter {
    /// Wraps scipy-layout sections; each row is normalised so that `a0 = 1`. A row with
    /// `a0 = 0` or a non-finite coefficient is refused.
    pub fn from_sections(sections: Vec<[f64; 6]>) -> Result<Self, SignalError> {
        if let Some(index) = sections
            .iter()
            .position(|r| r[3] == 0.0 || r.iter().any(|v| !v.is_finite()))
        {
            return Err(SignalError::InvalidSection { index });
        }
        let sections = sections
            .into_iter()
            .map(|r| {
                [
                    r[0] / r[3],
                    r[1] / r[3],
                    r[2] / r[3],
                    1.0,
                    r[4] / r[3],
                    r[5] / r[3],
                ]
            })
            .collect();
        Ok(Self { sections })
    }

    /// Butterworth design, scipy's `butter(order, Wn, btype, fs=sfreq, output='sos')`.
    pub fn butter(order: usize, band: Band, sfreq: f64) -> Result<Self, SignalError> {
        check_order(order)?;
        crate::check_sfreq(sfreq)?;
        let nyquist = sfreq / 2.0;
        let (l_freq, h_freq) = band.l_h();
        let bad = || SignalError::InvalidBand {
            l_freq,
            h_freq,
            nyquist,
        };
        let inside = |f: f64| f.is_finite() && f > 0.0 && f < nyquist;
        let (wn, btype) = match band {
            Band::Lowpass { h_freq } if inside(h_freq) => (vec![h_freq], FilterBandType::Lowpass),
            Band::Highpass { l_freq } if inside(l_freq) => (vec![l_freq], FilterBandType::Highpass),
            Band::Bandpass { l_freq, h_freq }
                if inside(l_freq) && inside(h_freq) && l_freq < h_freq =>
            {
                (vec![l_freq, h_freq], FilterBandType::Bandpass)
            }
            Band::Bandstop { l_freq, h_freq }
                if inside(l_freq) && inside(h_freq) && l_freq < h_freq =>
            {
                (vec![l_freq, h_freq], FilterBandType::Bandstop)
            }
            _ => return Err(bad()),
        };
        match butter_dyn(
            order,
            wn,
            Some(btype),
            Some(false),
            Some(FilterOutputType::Sos),
            Some(sfreq),
        ) {
            DigitalFilter::Sos(sos) => Ok(Self {
                sections: to_rows(&sos.sos),
            }),
            _ => Err(bad()),
        }
    }

    /// Chebyshev type I low-pass with `rp` dB pass-band ripple and normalised cutoff `wn`
    /// (fraction of Nyquist, 0 < wn < 1): scipy's `cheby1(order, rp, wn, output='sos')`.
    pub fn cheby1_lowpass(order: usize, rp: f64, wn: f64) -> Result<Self, SignalError> {
        check_order(order)?;
        if !(wn > 0.0 && wn < 1.0 && rp.is_finite() && rp > 0.0) {
            return Err(SignalError::InvalidBand {
                l_freq: None,
                h_freq: Some(wn),
                nyquist: 1.0,
            });
        }
        // scipy.signal.cheb1ap: analog prototype with cutoff 1 rad/s.
        let n = order as f64;
        let eps = (10f64.powf(0.1 * rp) - 1.0).sqrt();
        let mu = (1.0 / eps).asinh() / n;
        let poles: Vec<Complex<f64>> = (0..order)
            .map(|i| {
                let m = -(order as f64) + 1.0 + 2.0 * i as f64;
                let theta = std::f64::consts::PI * m / (2.0 * n);
                -Complex::new(mu, theta).sinh()
            })
            .collect();
        let mut k = poles
            .iter()
            .fold(Complex::new(1.0, 0.0), |acc, p| acc * (-p))
            .re;
        if order % 2 == 0 {
            k /= (1.0 + eps * eps).sqrt();
        }
        let proto = ZpkFormatFilter::new(Vec::new(), poles, k);
        // scipy.signal.iirfilter with fs = 2: pre-warp, scale the cutoff, bilinear transform.
        let fs = 2.0;
        let warped = 2.0 * fs * (std::f64::consts::PI * wn / fs).tan();
        let zpk = lp2lp_zpk_dyn(proto, Some(warped));
        let zpk = bilinear_zpk_dyn(zpk, fs);
        let sos = zpk2sos_dyn(order, zpk, None, Some(false));
        Ok(Self {
            sections: to_rows(&sos.sos),
        })
    }

    /// The sections, scipy layout, `a0 = 1`.
    pub fn sections(&self) -> &[[f64; 6]] {
        &self.sections
    }

    pub fn n_sections(&self) -> usize {
        self.sections.len()
    }

    /// Steady-state of each section's two delays for a unit step input (scipy's `sosfilt_zi`).
    pub fn zi(&self) -> Vec<[f64; 2]> {
        let mut sos: Vec<Sos<f64>> = self
            .sections
            .iter()
            .map(|r| Sos::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]))
            .collect();
        sci_rs::signal::filter::sosfilt_zi_dyn::<f64, _, Sos<f64>>(sos.iter_mut());
        sos.iter().map(|s| [s.zi0, s.zi1]).collect()
    }

    /// scipy's default `padlen` for `sosfiltfilt`: `3 × (2·n_sections + 1 − min(#b2=0, #a2=0))`.
    pub fn padlen(&self) -> usize {
        let n = self.sections.len();
        let bz = self.sections.iter().filter(|r| r[2] == 0.0).count();
        let az = self.sections.iter().filter(|r| r[5] == 0.0).count();
        3 * (2 * n + 1 - bz.min(az))
    }

    /// Causal filtering of each row of `data` `(n_channels, n_times)`, as scipy's
    /// `sosfilt(sos, data, axis=-1)`. With `steady = true`, each channel starts in the steady
    /// state of its first sample (`zi = sosfilt_zi(sos) * x[0]`), so a constant input passes
    /// without a start-up transient; with `false` it starts from rest.
    pub fn sosfilt(&self, data: ArrayView2<'_, f64>, steady: bool) -> Array2<f64> {
        let mut stream = StreamingFilter::new(
            self.clone(),
            data.nrows(),
            if steady {
                StreamInit::Steady
            } else {
                StreamInit::Rest
            },
        );
        let mut out = data.to_owned();
        stream
            .process_inplace(out.view_mut())
            .expect("channel count matches by construction");
        out
    }

    /// Zero-phase forward–backward filtering of each row of `data` `(n_channels, n_times)`, equal
    /// to scipy's `sosfiltfilt(sos, data, axis=-1)` with its defaults (`padtype='odd'`,
    /// `padlen` = [`Self::padlen`]). Rows need more than `padlen` samples.
    pub fn sosfiltfilt(&self, data: ArrayView2<'_, f64>) -> Result<Array2<f64>, SignalError> {
        let mut out = data.to_owned();
        self.sosfiltfilt_inplace(out.view_mut())?;
        Ok(out)
    }

    /// In-place [`Self::sosfiltfilt`].
    pub fn sosfiltfilt_inplace(&self, mut data: ArrayViewMut2<'_, f64>) -> Result<(), SignalError> {
        let (n_channels, n_times) = data.dim();
        let padlen = self.padlen();
        if n_times <= padlen {
            return Err(SignalError::SignalTooShort { n_times, padlen });
        }
        if n_channels == 0 {
            return Ok(());
        }
        if !data.is_standard_layout() {
            let mut owned = data.to_owned();
            self.sosfiltfilt_inplace(owned.view_mut())?;
            data.assign(&owned);
            return Ok(());
        }
        let zi = self.zi();
        let n_ext = n_times + 2 * padlen;
        let flat = data
            .as_slice_mut()
            .expect("standard layout is one contiguous slice");
        let run = |block: &mut [f64]| {
            let mut rows: Vec<&mut [f64]> = block.chunks_exact_mut(n_times).collect();
            SCRATCH.with(|scratch| {
                let mut buf = scratch.borrow_mut();
                buf.clear();
                buf.resize(n_ext * LANES, 0.0);
                for (l, row) in rows.iter().enumerate() {
                    let (x0, xn) = (row[0], row[n_times - 1]);
                    // odd extension: 2·x[0] − x[padlen..0], x, 2·x[n−1] − x[n−2..n−2−padlen]
                    for i in 0..padlen {
                        buf[i * LANES + l] = 2.0 * x0 - row[padlen - i];
                        buf[(padlen + n_times + i) * LANES + l] = 2.0 * xn - row[n_times - 2 - i];
                    }
                }
                let body = &mut buf[padlen * LANES..(padlen + n_times) * LANES];
                let src: Vec<&[f64]> = rows.iter().map(|r| &**r).collect();
                gather(&src, body);
                let mut state = vec![[[0.0; LANES]; 2]; self.sections.len()];
                init_state(&mut state, &zi, &buf[..LANES]);
                run_kernel(&self.sections, &mut state, &mut buf, false);
                init_state(&mut state, &zi, &buf[(n_ext - 1) * LANES..]);
                run_kernel(&self.sections, &mut state, &mut buf, true);
                scatter(&buf[padlen * LANES..(padlen + n_times) * LANES], &mut rows);
                // A whole recording's buffer (four channels' worth, per thread) is not kept
                // after it is filtered: it would outlive the recording.
                if buf.len() > SCRATCH_KEPT {
                    *buf = Vec::new();
                }
            })
        };
        let block_len = LANES * n_times;
        if n_channels <= LANES {
            run(flat);
        } else {
            use rayon::prelude::*;
            flat.par_chunks_mut(block_len).for_each(run);
        }
        Ok(())
    }

    /// Zero-phase filtering of a [`Raw`] in place (see [`Self::sosfiltfilt`]).
    pub fn apply_raw(&self, raw: &mut Raw) -> Result<(), SignalError> {
        self.sosfiltfilt_inplace(raw.data_mut())
    }
}

/// Samples of the largest [`SCRATCH`] kept between calls (8 MB): chunks, epochs and short
/// recordings reuse it; a longer recording's is freed when it is filtered.
const SCRATCH_KEPT: usize = 1 << 20;

thread_local! {
    /// Interleaved work buffer of `sosfiltfilt`, kept between calls up to [`SCRATCH_KEPT`]
    /// samples: a fresh multi-megabyte allocation per call costs more in page faults than the
    /// filtering itself.
    static SCRATCH: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Interleaves up to [`LANES`] rows into frames: `dst[t * LANES + l] = rows[l][t]`.
fn gather(rows: &[&[f64]], dst: &mut [f64]) {
    if let [r0, r1, r2, r3] = rows {
        for (t, frame) in dst.chunks_exact_mut(LANES).enumerate() {
            frame.copy_from_slice(&[r0[t], r1[t], r2[t], r3[t]]);
        }
    } else {
        for (t, frame) in dst.chunks_exact_mut(LANES).enumerate() {
            for (l, r) in rows.iter().enumerate() {
                frame[l] = r[t];
            }
        }
    }
}

/// The inverse of [`gather`]: `rows[l][t] = src[t * LANES + l]`.
fn scatter(src: &[f64], rows: &mut [&mut [f64]]) {
    if let [r0, r1, r2, r3] = rows {
        for (t, frame) in src.chunks_exact(LANES).enumerate() {
            r0[t] = frame[0];
            r1[t] = frame[1];
            r2[t] = frame[2];
            r3[t] = frame[3];
        }
    } else {
        for (t, frame) in src.chunks_exact(LANES).enumerate() {
            for (l, r) in rows.iter_mut().enumerate() {
                r[t] = frame[l];
            }
        }
    }
}

fn init_state(state: &mut [[[f64; LANES]; 2]], zi: &[[f64; 2]], x0: &[f64]) {
    for (st, z) in state.iter_mut().zip(zi) {
        for l in 0..LANES {
            st[0][l] = z[0] * x0[l];
            st[1][l] = z[1] * x0[l];
        }
    }
}

/// Runs the cascade over an interleaved buffer `buf[t * LANES + lane]` in place, forwards or
/// backwards in time, transposed direct form II (scipy's `sosfilt`). On x86-64 CPUs with AVX2 and
/// FMA (checked at run time) the same code is compiled for those instructions.
fn run_kernel(
    sections: &[[f64; 6]],
    state: &mut [[[f64; LANES]; 2]],
    buf: &mut [f64],
    reverse: bool,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA, checked just above; that is the only
        // requirement of a `#[target_feature]` function.
        #[allow(unsafe_code)]
        unsafe {
            run_kernel_avx2_fma(sections, state, buf, reverse)
        };
        return;
    }
    run_kernel_impl::<false>(sections, state, buf, reverse);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn run_kernel_avx2_fma(
    sections: &[[f64; 6]],
    state: &mut [[[f64; LANES]; 2]],
    buf: &mut [f64],
    reverse: bool,
) {
    run_kernel_impl::<true>(sections, state, buf, reverse);
}

/// One section on one frame of lanes, transposed direct form II.
#[inline(always)]
fn section<const FMA: bool>(c: &[f64; 6], z: &mut [[f64; LANES]; 2], x: &mut [f64; LANES]) {
    let [b0, b1, b2, _, a1, a2] = *c;
    for l in 0..LANES {
        let xi = x[l];
        let y;
        if FMA {
            y = b0.mul_add(xi, z[0][l]);
            z[0][l] = (-a1).mul_add(y, b1.mul_add(xi, z[1][l]));
            z[1][l] = (-a2).mul_add(y, b2 * xi);
        } else {
            y = b0 * xi + z[0][l];
            z[0][l] = b1 * xi - a1 * y + z[1][l];
            z[1][l] = b2 * xi - a2 * y;
        }
        x[l] = y;
    }
}

#[inline(always)]
fn frame_fixed<const N: usize, const FMA: bool>(
    c: &[[f64; 6]; N],
    z: &mut [[[f64; LANES]; 2]; N],
    frame: &mut [f64],
) {
    let mut x = [0.0; LANES];
    x.copy_from_slice(frame);
    for s in 0..N {
        section::<FMA>(&c[s], &mut z[s], &mut x);
    }
    frame.copy_from_slice(&x);
}

#[inline(always)]
fn frame_dyn<const FMA: bool>(
    sections: &[[f64; 6]],
    state: &mut [[[f64; LANES]; 2]],
    frame: &mut [f64],
) {
    let mut x = [0.0; LANES];
    x.copy_from_slice(frame);
    for (c, z) in sections.iter().zip(state.iter_mut()) {
        section::<FMA>(c, z, &mut x);
    }
    frame.copy_from_slice(&x);
}

/// The cascade with a compile-time number of sections, so that the delays live in registers.
#[inline(always)]
fn cascade_fixed<const N: usize, const FMA: bool>(
    sections: &[[f64; 6]],
    state: &mut [[[f64; LANES]; 2]],
    buf: &mut [f64],
    reverse: bool,
) {
    let c: [[f64; 6]; N] = sections.try_into().expect("N sections");
    let mut z: [[[f64; LANES]; 2]; N] = (&*state).try_into().expect("N states");
    // Plain loops (no closures): a closure would not inherit the caller's target features.
    if reverse {
        for frame in buf.chunks_exact_mut(LANES).rev() {
            frame_fixed::<N, FMA>(&c, &mut z, frame);
        }
    } else {
        for frame in buf.chunks_exact_mut(LANES) {
            frame_fixed::<N, FMA>(&c, &mut z, frame);
        }
    }
    state.copy_from_slice(&z);
}

#[inline(always)]
fn run_kernel_impl<const FMA: bool>(
    sections: &[[f64; 6]],
    state: &mut [[[f64; LANES]; 2]],
    buf: &mut [f64],
    reverse: bool,
) {
    match sections.len() {
        1 => cascade_fixed::<1, FMA>(sections, state, buf, reverse),
        2 => cascade_fixed::<2, FMA>(sections, state, buf, reverse),
        3 => cascade_fixed::<3, FMA>(sections, state, buf, reverse),
        4 => cascade_fixed::<4, FMA>(sections, state, buf, reverse),
        5 => cascade_fixed::<5, FMA>(sections, state, buf, reverse),
        6 => cascade_fixed::<6, FMA>(sections, state, buf, reverse),
        _ => {
            if reverse {
                for frame in buf.chunks_exact_mut(LANES).rev() {
                    frame_dyn::<FMA>(sections, state, frame);
                }
            } else {
                for frame in buf.chunks_exact_mut(LANES) {
                    frame_dyn::<FMA>(sections, state, frame);
                }
            }
        }
    }
}

/// How a [`StreamingFilter`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StreamInit {
    /// All delays zero (scipy's `sosfilt` without `zi`).
    Rest,
    /// Each channel in the steady state of its first sample (`zi = sosfilt_zi(sos) * x[0]`),
    /// which avoids the start-up step response to the DC offset of EEG amplifiers.
    Steady,
}

/// A causal filter that keeps its state between chunks, for online processing.
///
/// Feeding a recording in chunks of any sizes gives exactly the output of one
/// [`SosFilter::sosfilt`] pass over the whole recording with the same [`StreamInit`].
#[derive(Debug, Clone)]
pub struct StreamingFilter {
    filter: SosFilter,
    zi: Vec<[f64; 2]>,
    n_channels: usize,
    init: StreamInit,
    started: bool,
    /// One state per block of [`LANES`] channels: `[section][delay][lane]`.
    state: Vec<Vec<[[f64; LANES]; 2]>>,
    buf: Vec<f64>,
}

impl StreamingFilter {
    pub fn new(filter: SosFilter, n_channels: usize, init: StreamInit) -> Self {
        let n_blocks = n_channels.div_ceil(LANES);
        let zi = filter.zi();
        let state = vec![vec![[[0.0; LANES]; 2]; filter.n_sections()]; n_blocks];
        Self {
            filter,
            zi,
            n_channels,
            init,
            started: false,
            state,
            buf: Vec::new(),
        }
    }

    pub fn n_channels(&self) -> usize {
        self.n_channels
    }

    pub fn filter(&self) -> &SosFilter {
        &self.filter
    }

    /// Forgets the past: the next chunk starts the filter afresh.
    pub fn reset(&mut self) {
        self.started = false;
        for block in &mut self.state {
            for st in block.iter_mut() {
                *st = [[0.0; LANES]; 2];
            }
        }
    }

    /// Filters a chunk `(n_channels, n_chunk)` in place, continuing from the previous chunk.
    pub fn process_inplace(
        &mut self,
        mut chunk: ArrayViewMut2<'_, f64>,
    ) -> Result<(), SignalError> {
        let (n_channels, n_times) = chunk.dim();
        if n_channels != self.n_channels {
            return Err(SignalError::ChunkChannels {
                got: n_channels,
                expected: self.n_channels,
            });
        }
        if n_times == 0 {
            return Ok(());
        }
        if !chunk.is_standard_layout() {
            let mut owned = chunk.to_owned();
            self.process_inplace(owned.view_mut())?;
            chunk.assign(&owned);
            return Ok(());
        }
        self.buf.clear();
        self.buf.resize(n_times * LANES, 0.0);
        let flat = chunk
            .as_slice_mut()
            .expect("standard layout is one contiguous slice");
        for (block, state) in flat.chunks_mut(LANES * n_times).zip(self.state.iter_mut()) {
            let mut rows: Vec<&mut [f64]> = block.chunks_exact_mut(n_times).collect();
            let src: Vec<&[f64]> = rows.iter().map(|r| &**r).collect();
            gather(&src, &mut self.buf);
            if !self.started && self.init == StreamInit::Steady {
                init_state(state, &self.zi, &self.buf[..LANES]);
            }
            run_kernel(&self.filter.sections, state, &mut self.buf, false);
            scatter(&self.buf, &mut rows);
        }
        self.started = true;
        Ok(())
    }

    /// Filters a chunk `(n_channels, n_chunk)`, returning the output.
    pub fn process(&mut self, chunk: ArrayView2<'_, f64>) -> Result<Array2<f64>, SignalError> {
        let mut out = chunk.to_owned();
        self.process_inplace(out.view_mut())?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    #[test]
    fn bands_print_as_a_person_reads_them() {
        let shown: Vec<String> = [
            Band::Bandpass {
                l_freq: 0.5,
                h_freq: 20.0,
            },
            Band::Lowpass { h_freq: 40.0 },
            Band::Highpass { l_freq: 1.0 },
            Band::Bandstop {
                l_freq: 48.0,
                h_freq: 52.0,
            },
        ]
        .iter()
        .map(ToString::to_string)
        .collect();
        assert_eq!(
            shown,
            ["0.5–20 Hz", "below 40 Hz", "above 1 Hz", "without 48–52 Hz"]
        );
    }

    /// 4th-order Butterworth band-pass, 1–15 Hz at 256 Hz.
    fn bandpass_1_15() -> SosFilter {
        SosFilter::butter(
            4,
            Band::Bandpass {
                l_freq: 1.0,
                h_freq: 15.0,
            },
            256.0,
        )
        .unwrap()
    }

    fn test_signal(n_channels: usize, n_times: usize) -> Array2<f64> {
        Array2::from_shape_fn((n_channels, n_times), |(c, t)| {
            let t = t as f64 / 256.0;
            10.0 * (2.0 * std::f64::consts::PI * (3.0 + c as f64) * t).sin()
                + 5.0 * (2.0 * std::f64::consts::PI * 40.0 * t).cos()
                + 20.0
                + c as f64 * t
        })
    }

    #[test]
    fn sosfiltfilt_matches_sci_rs() {
        let f = bandpass_1_15();
        let x = test_signal(11, 2000);
        let ours = f.sosfiltfilt(x.view()).unwrap();
        let sos: Vec<Sos<f64>> = f
            .sections()
            .iter()
            .map(|r| Sos::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]))
            .collect();
        for c in 0..x.nrows() {
            let theirs = sci_rs::signal::filter::sosfiltfilt_dyn(x.row(c).iter(), &sos);
            for (a, b) in ours.row(c).iter().zip(&theirs) {
                assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }

    #[test]
    fn steady_start_passes_a_constant_through_a_lowpass() {
        let f = SosFilter::butter(4, Band::Lowpass { h_freq: 10.0 }, 256.0).unwrap();
        let x = Array2::from_elem((3, 100), 42.0);
        let y = f.sosfilt(x.view(), true);
        for v in y.iter() {
            assert!((v - 42.0).abs() < 1e-9, "{v}");
        }
        let y0 = f.sosfilt(x.view(), false);
        assert!(
            (y0[[0, 0]] - 42.0).abs() > 1.0,
            "from rest the step must show a transient"
        );
    }

    #[test]
    fn bad_designs_are_errors() {
        assert!(matches!(
            SosFilter::butter(
                4,
                Band::Bandpass {
                    l_freq: 15.0,
                    h_freq: 1.0
                },
                256.0
            ),
            Err(SignalError::InvalidBand { .. })
        ));
        assert!(matches!(
            SosFilter::butter(4, Band::Lowpass { h_freq: 200.0 }, 256.0),
            Err(SignalError::InvalidBand { .. })
        ));
        assert!(matches!(
            SosFilter::butter(0, Band::Lowpass { h_freq: 20.0 }, 256.0),
            Err(SignalError::InvalidOrder { .. })
        ));
        assert!(matches!(
            SosFilter::butter(4, Band::Lowpass { h_freq: 20.0 }, 0.0),
            Err(SignalError::InvalidSfreq { .. })
        ));
        let f = bandpass_1_15();
        let short = Array2::zeros((2, f.padlen()));
        assert!(matches!(
            f.sosfiltfilt(short.view()),
            Err(SignalError::SignalTooShort { .. })
        ));
    }

    #[test]
    fn sections_with_a0_zero_or_nan_are_refused() {
        let ok = SosFilter::from_sections(vec![[2.0, 0.0, 0.0, 2.0, -1.0, 0.0]]).unwrap();
        assert_eq!(ok.sections()[0], [1.0, 0.0, 0.0, 1.0, -0.5, 0.0]);
        assert_eq!(
            SosFilter::from_sections(vec![[1.0; 6], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]),
            Err(SignalError::InvalidSection { index: 1 })
        );
        assert_eq!(
            SosFilter::from_sections(vec![[f64::NAN, 0.0, 0.0, 1.0, 0.0, 0.0]]),
            Err(SignalError::InvalidSection { index: 0 })
        );
    }

    #[test]
    fn streaming_rejects_wrong_channel_count() {
        let f = SosFilter::butter(2, Band::Lowpass { h_freq: 20.0 }, 256.0).unwrap();
        let mut s = StreamingFilter::new(f, 4, StreamInit::Rest);
        let chunk = Array2::zeros((3, 10));
        assert!(matches!(
            s.process(chunk.view()),
            Err(SignalError::ChunkChannels {
                got: 3,
                expected: 4
            })
        ));
    }
}
