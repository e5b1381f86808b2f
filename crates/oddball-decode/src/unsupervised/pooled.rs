//! A start for EM from other people's data: the target-vs-non-target effect size of every
//! channel (by name) and time after the flash, pooled over labelled recordings of other
//! subjects and data sets ([`PooledStart`]), turned into a diagonal LDA on a new session's own
//! features ([`PooledScorer`]).
//!
//! Montages and rates differ, so the pattern is kept per channel name (matched case aside) on a
//! fixed grid of times ([`GRID_STEP_S`] from 0 to [`GRID_END_S`]): a recording of any rate and
//! any subset or superset of the channels takes the values of the channels it shares, linearly
//! interpolated to its feature bins' centres, and 0 for the others. The effect size `d` (mean
//! difference over the pooled within-class standard deviation) is unit-free, so recordings in
//! different units and references pool; the session divides it by its own features' standard
//! deviation (label-free), which makes the score `Σ_j d_j x_j / sd_j` a diagonal LDA in the
//! session's units.
//!
//! A start only chooses where EM begins: the fit it leads to is kept when its likelihood beats
//! the template's, the warm start's and the random starts'
//! ([`super::UnsupervisedParams::fit_features_starts`]), so a start that does not fit the
//! session is outvoted by the session's own evidence, the more so the more trials there are.
//!
//! The shipped start ([`pooled_start`]) is `pooled.json` beside this file, built from the public
//! recordings of `datasets/` by `oddball benchmark datasets/*.toml --write-pooled FILE`; a
//! pooled start read from elsewhere is outside input and checked where it enters
//! ([`PooledStart::from_json`]).

use ndarray::{Array1, ArrayView2};
use serde::{Deserialize, Serialize};

use super::error::{Result, UnsupervisedError};
use crate::features::amplitude::{AmplitudeFeatures, Reduction};

/// The format version this build reads and writes.
pub const POOLED_VERSION: u32 = 1;
/// Spacing of the pattern's time grid, s.
pub const GRID_STEP_S: f64 = 0.025;
/// Last time of the grid, s (the grid starts at 0, the flash).
pub const GRID_END_S: f64 = 0.8;
/// Most channels a pattern may name (a check on outside input).
const MAX_CHANNELS: usize = 512;

/// The grid's times, s.
pub fn grid() -> Vec<f64> {
    let n = (GRID_END_S / GRID_STEP_S).round() as usize;
    (0..=n).map(|k| k as f64 * GRID_STEP_S).collect()
}

/// One pre-processing's pattern: effect size per channel on the grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PooledPattern {
    /// Whether the EEG was band-passed causally (as a live session) or zero-phase.
    pub causal: bool,
    /// Channel names, in the order of `effect`.
    pub channels: Vec<String>,
    /// Per channel, the effect size at each [`grid`] time.
    pub effect: Vec<Vec<f64>>,
    /// Per channel, how many recording sets were pooled into it.
    pub n_sets: Vec<usize>,
    /// What it was built from (data set/subject names).
    pub sources: Vec<String>,
}

/// Every pre-processing's pattern, as shipped or written by the builder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PooledStart {
    pub version: u32,
    pub patterns: Vec<PooledPattern>,
}

/// The shipped pooled start (`pooled.json`, built from the public recordings; module doc).
pub fn pooled_start() -> PooledStart {
    PooledStart::from_json(include_str!("pooled.json")).expect("the shipped pooled start is valid")
}

impl PooledStart {
    /// Reads and checks a pooled start: its version, every pattern's shape, finite values,
    /// distinct channel names.
    pub fn from_json(text: &str) -> Result<Self> {
        let s: Self = serde_json::from_str(text).map_err(|e| invalid(e.to_string()))?;
        s.check()?;
        Ok(s)
    }

    /// As JSON (effect sizes to 4 significant digits: the file stays small).
    pub fn to_json(&self) -> String {
        let mut s = self.clone();
        for p in &mut s.patterns {
            for row in &mut p.effect {
                for v in row.iter_mut() {
                    *v = round_sig(*v, 4);
                }
            }
        }
        serde_json::to_string(&s).expect("a pooled start serialises")
    }

    /// The checks [`Self::from_json`] makes.
    pub fn check(&self) -> Result<()> {
        if self.version != POOLED_VERSION {
            return Err(invalid(format!(
                "version {} (this build reads {POOLED_VERSION})",
                self.version
            )));
        }
        if self.patterns.is_empty() {
            return Err(invalid("no pattern".into()));
        }
        for p in &self.patterns {
            p.check()?;
        }
        Ok(())
    }

    /// The pattern of a causal or zero-phase band-pass (the other one when it has only that).
    pub fn pattern(&self, causal: bool) -> &PooledPattern {
        self.patterns
            .iter()
            .find(|p| p.causal == causal)
            .unwrap_or(&self.patterns[0])
    }
}

fn invalid(what: String) -> UnsupervisedError {
    UnsupervisedError::InvalidPooled { what }
}

fn round_sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// The centre (s after the flash) of each feature point of one channel: epochs of `n_times`
/// samples starting `tmin` s after the flash at `sfreq`.
pub fn feature_times(
    features: AmplitudeFeatures,
    sfreq: f64,
    tmin: f64,
    n_times: usize,
) -> Vec<f64> {
    let n = features.n_points(n_times);
    (0..n)
        .map(|k| {
            let centre = match features.reduction {
                Reduction::BinMean { bin } => (k * bin) as f64 + (bin as f64 - 1.0) / 2.0,
                Reduction::Decimate { step } => (k * step) as f64,
            };
            tmin + centre / sfreq
        })
        .collect()
}

/// A name that numbers a channel instead of placing it (`Channel 3`, `ch12`, `EEG 5`, `7`; a
/// net's own sensor names such as `E101` are kept).
pub fn is_placeholder(name: &str) -> bool {
    let lower = name.trim().to_ascii_lowercase();
    let stem = lower.trim_end_matches(|c: char| c.is_ascii_digit());
    if stem.len() == lower.len() {
        return false;
    }
    matches!(
        stem.trim_end_matches([' ', '_', '-']),
        "" | "ch" | "chan" | "channel" | "eeg"
    )
}

/// `values` on `times` linearly interpolated at `at` (held at the ends).
fn interpolate(times: &[f64], values: &[f64], at: f64) -> f64 {
    if at <= times[0] {
        return values[0];
    }
    for k in 1..times.len() {
        if at <= times[k] {
            let f = (at - times[k - 1]) / (times[k] - times[k - 1]);
            return values[k - 1] + f * (values[k] - values[k - 1]);
        }
    }
    values[values.len() - 1]
}

impl PooledPattern {
    /// The pattern of one set of labelled recordings: feature rows `x` `(n_epochs, n_channels ×
    /// n_points)` (channel-major, the amplitude features' layout) at point times `times`, with
    /// `target` per row. The labels are the other recordings' own: a pattern is built from data
    /// the session it starts is not part of.
    pub fn from_labelled(
        x: ArrayView2<f64>,
        target: &[bool],
        channels: &[String],
        times: &[f64],
        causal: bool,
        source: &str,
    ) -> Result<Self> {
        let (n, p) = x.dim();
        let n_pts = times.len();
        if target.len() != n || channels.len() * n_pts != p || n_pts == 0 {
            return Err(invalid(format!(
                "{n} rows × {p} features, {} labels, {} channels × {n_pts} times",
                target.len(),
                channels.len()
            )));
        }
        let n_t = target.iter().filter(|&&t| t).count();
        if n_t < 2 || n - n_t < 2 {
            return Err(invalid(format!(
                "{source}: {n_t} targets of {n} epochs: two of each class at least"
            )));
        }
        let mut d = vec![0.0; p];
        for (j, dj) in d.iter_mut().enumerate() {
            let col = x.column(j);
            let (mut st, mut sn) = (0.0, 0.0);
            for (v, &t) in col.iter().zip(target) {
                if t {
                    st += v;
                } else {
                    sn += v;
                }
            }
            let (mt, mn) = (st / n_t as f64, sn / (n - n_t) as f64);
            let ss: f64 = col
                .iter()
                .zip(target)
                .map(|(v, &t)| (v - if t { mt } else { mn }).powi(2))
                .sum();
            let sd = (ss / (n - 2) as f64).sqrt();
            *dj = if sd > 0.0 { (mt - mn) / sd } else { 0.0 };
        }
        let g = grid();
        // Only channels named by position transfer: `Channel 3` or `ch12` says nothing.
        let kept: Vec<usize> = (0..channels.len())
            .filter(|&c| !is_placeholder(&channels[c]))
            .collect();
        if kept.is_empty() {
            return Err(UnsupervisedError::NoNamedChannels {
                recordings: source.to_string(),
                channels: channels.to_vec(),
            });
        }
        let effect = kept
            .iter()
            .map(|&c| {
                let row = &d[c * n_pts..(c + 1) * n_pts];
                g.iter().map(|&t| interpolate(times, row, t)).collect()
            })
            .collect();
        let p = Self {
            causal,
            channels: kept.iter().map(|&c| channels[c].clone()).collect(),
            effect,
            n_sets: vec![1; kept.len()],
            sources: vec![source.to_string()],
        };
        p.check()?;
        Ok(p)
    }

    /// The mean of `parts` (of one pre-processing) per channel name, case aside, each part
    /// counted by its [`Self::n_sets`]: a channel is the mean of the sets that have it.
    pub fn pool(parts: &[PooledPattern]) -> Result<Self> {
        let first = parts
            .first()
            .ok_or_else(|| invalid("nothing to pool".into()))?;
        let n_grid = grid().len();
        let mut channels: Vec<String> = Vec::new();
        let mut sums: Vec<Vec<f64>> = Vec::new();
        let mut counts: Vec<usize> = Vec::new();
        let mut sources = Vec::new();
        for part in parts {
            part.check()?;
            if part.causal != first.causal {
                return Err(invalid(
                    "causal and zero-phase patterns pooled together".into(),
                ));
            }
            sources.extend(part.sources.iter().cloned());
            for ((name, row), &k) in part.channels.iter().zip(&part.effect).zip(&part.n_sets) {
                let i = match channels.iter().position(|c| c.eq_ignore_ascii_case(name)) {
                    Some(i) => i,
                    None => {
                        channels.push(name.clone());
                        sums.push(vec![0.0; n_grid]);
                        counts.push(0);
                        channels.len() - 1
                    }
                };
                for (s, v) in sums[i].iter_mut().zip(row) {
                    *s += k as f64 * v;
                }
                counts[i] += k;
            }
        }
        let effect = sums
            .into_iter()
            .zip(&counts)
            .map(|(s, &k)| s.into_iter().map(|v| v / k as f64).collect())
            .collect();
        Ok(Self {
            causal: first.causal,
            channels,
            effect,
            n_sets: counts,
            sources,
        })
    }

    fn check(&self) -> Result<()> {
        let n_grid = grid().len();
        if self.channels.is_empty() || self.channels.len() > MAX_CHANNELS {
            return Err(invalid(format!(
                "{} channels (1..={MAX_CHANNELS})",
                self.channels.len()
            )));
        }
        if self.effect.len() != self.channels.len() || self.n_sets.len() != self.channels.len() {
            return Err(invalid(format!(
                "{} channels, {} rows of effect sizes, {} counts",
                self.channels.len(),
                self.effect.len(),
                self.n_sets.len()
            )));
        }
        for (c, (name, row)) in self.channels.iter().zip(&self.effect).enumerate() {
            if row.len() != n_grid {
                return Err(invalid(format!(
                    "channel {name}: {} values for {n_grid} grid times",
                    row.len()
                )));
            }
            if let Some(v) = row.iter().find(|v| !v.is_finite()) {
                return Err(invalid(format!("channel {name}: value {v}")));
            }
            if name.trim().is_empty()
                || self.channels[..c]
                    .iter()
                    .any(|o| o.eq_ignore_ascii_case(name))
            {
                return Err(invalid(format!("channel name {name:?} empty or repeated")));
            }
        }
        Ok(())
    }

    /// The pattern on a session's features: channels `ch_names` (matched by name, case aside:
    /// a subset or superset of the pattern's), each point at `times` (s after the flash,
    /// [`feature_times`]). Channels the pattern does not name weigh 0; none shared is an error.
    pub fn scorer(&self, ch_names: &[String], times: &[f64]) -> Result<PooledScorer> {
        let g = grid();
        let mut weights = Vec::with_capacity(ch_names.len() * times.len());
        let mut shared = 0;
        for name in ch_names {
            match self
                .channels
                .iter()
                .position(|c| c.eq_ignore_ascii_case(name))
            {
                Some(i) => {
                    shared += 1;
                    weights.extend(times.iter().map(|&t| interpolate(&g, &self.effect[i], t)));
                }
                None => weights.extend(std::iter::repeat_n(0.0, times.len())),
            }
        }
        if shared == 0 {
            return Err(UnsupervisedError::NoSharedChannels {
                session: ch_names.to_vec(),
                pattern: self.channels.clone(),
            });
        }
        Ok(PooledScorer {
            effect: Array1::from(weights),
            n_shared: shared,
        })
    }
}

/// A [`PooledPattern`] on one session's feature layout.
#[derive(Debug, Clone, PartialEq)]
pub struct PooledScorer {
    effect: Array1<f64>,
    n_shared: usize,
}

impl PooledScorer {
    /// The effect size of each feature (0 for channels the pattern does not name).
    pub fn effect(&self) -> ndarray::ArrayView1<'_, f64> {
        self.effect.view()
    }

    /// How many of the session's channels the pattern names.
    pub fn n_shared(&self) -> usize {
        self.n_shared
    }

    /// Each row's score `Σ_j d_j x_j / sd_j`, `sd_j` the standard deviation of feature `j` over
    /// the rows `x` themselves (label-free): a diagonal LDA in the session's units.
    pub fn scores(&self, x: ArrayView2<f64>) -> Result<Vec<f64>> {
        if x.ncols() != self.effect.len() {
            return Err(crate::DecodeError::ShapeMismatch {
                what: "features for the pooled start".into(),
                expected: format!("{} features", self.effect.len()),
                got: x.ncols().to_string(),
            }
            .into());
        }
        let n = x.nrows().max(1) as f64;
        let mean = x.sum_axis(ndarray::Axis(0)) / n;
        let w: Array1<f64> = self
            .effect
            .iter()
            .zip(x.columns())
            .zip(&mean)
            .map(|((&d, col), &m)| {
                let sd = (col.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n).sqrt();
                if sd > 0.0 {
                    d / sd
                } else {
                    0.0
                }
            })
            .collect();
        Ok(x.dot(&w).to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::Array2;

    fn pattern(channels: &[&str], value: f64) -> PooledPattern {
        PooledPattern {
            causal: false,
            channels: channels.iter().map(|s| s.to_string()).collect(),
            effect: channels.iter().map(|_| vec![value; grid().len()]).collect(),
            n_sets: vec![1; channels.len()],
            sources: vec!["t".into()],
        }
    }

    #[test]
    fn pooling_averages_by_name_case_aside() {
        let a = pattern(&["Cz", "Pz"], 1.0);
        let b = pattern(&["PZ", "Oz"], 3.0);
        let p = PooledPattern::pool(&[a, b]).unwrap();
        assert_eq!(p.channels, ["Cz", "Pz", "Oz"]);
        assert_eq!(p.n_sets, [1, 2, 1]);
        assert_eq!(
            (p.effect[0][0], p.effect[1][0], p.effect[2][0]),
            (1.0, 2.0, 3.0)
        );
    }

    #[test]
    fn a_subset_or_superset_of_channels_is_scored_and_none_shared_is_an_error() {
        let p = pattern(&["Cz", "Pz"], 1.0);
        let names: Vec<String> = ["pz", "T7"].iter().map(|s| s.to_string()).collect();
        let s = p.scorer(&names, &[0.1, 0.3]).unwrap();
        assert_eq!(s.n_shared(), 1);
        assert_eq!(s.effect().to_vec(), [1.0, 1.0, 0.0, 0.0]);
        let x = Array2::from_shape_fn((4, 4), |(i, j)| (i * j) as f64);
        assert_eq!(s.scores(x.view()).unwrap().len(), 4);
        let none = p.scorer(&["T7".to_string()], &[0.1]).unwrap_err();
        assert!(matches!(none, UnsupervisedError::NoSharedChannels { .. }));
    }

    #[test]
    fn outside_input_is_checked() {
        let good = PooledStart {
            version: POOLED_VERSION,
            patterns: vec![pattern(&["Cz"], 0.5)],
        };
        assert_eq!(PooledStart::from_json(&good.to_json()).unwrap(), good);
        let mut bad = good.clone();
        bad.version = 99;
        assert!(PooledStart::from_json(&serde_json::to_string(&bad).unwrap()).is_err());
        let mut bad = good.clone();
        bad.patterns[0].effect[0].pop();
        assert!(PooledStart::from_json(&serde_json::to_string(&bad).unwrap()).is_err());
        let mut bad = good.clone();
        bad.patterns[0].channels.push("cz".into());
        bad.patterns[0].effect.push(vec![0.0; grid().len()]);
        bad.patterns[0].n_sets.push(1);
        assert!(PooledStart::from_json(&serde_json::to_string(&bad).unwrap()).is_err());
        let text = good.to_json().replace("0.5", "NaN");
        assert!(PooledStart::from_json(&text).is_err());
    }

    #[test]
    fn the_shipped_start_is_valid_and_small() {
        let text = include_str!("pooled.json");
        assert!(text.len() < 150_000, "{} bytes", text.len());
        let s = pooled_start();
        assert!(s.patterns.iter().any(|p| p.causal) && s.patterns.iter().any(|p| !p.causal));
    }

    #[test]
    fn numbered_channels_are_placeholders() {
        for n in ["Channel 3", "ch12", "EEG 5", "7"] {
            assert!(is_placeholder(n), "{n}");
        }
        for n in ["Cz", "PO7", "TP10", "Fp1", "Iz", "E101"] {
            assert!(!is_placeholder(n), "{n}");
        }
    }

    #[test]
    fn feature_times_are_bin_centres() {
        let f = AmplitudeFeatures::bin_mean(10).unwrap();
        let t = feature_times(f, 250.0, 0.0, 200);
        assert_eq!(t.len(), 20);
        assert!((t[0] - 4.5 / 250.0).abs() < 1e-12 && (t[1] - 14.5 / 250.0).abs() < 1e-12);
    }
}
