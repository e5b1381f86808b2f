//! What the tests of the oddball workspace share (a dev-dependency only, never published):
//!
//! * [`data_dir`] / [`data_file`]: the real EEG in `../shared/data` (or `$ODDBALL_DATA`);
//! * [`tool`]: an optional tool named by an environment variable (`ODDBALL_CHROMIUM`,
//!   `ODDBALL_PYXDF`, `ODDBALL_PYLSL`);
//! * [`TempDir`]: a temporary directory removed on drop (the `tempfile` crate's);
//! * [`synthetic_p300`]: deterministic synthetic P300 epochs.
//!
//! # Skip or fail
//! Locally a test whose data or tool is missing prints `skipping …` and returns. In CI it must
//! fail instead: with `ODDBALL_REQUIRE_DATA=1` a missing data folder or file panics, and so does
//! a missing tool, unless `ODDBALL_REQUIRE_TOOLS=0`; `ODDBALL_REQUIRE_TOOLS=1` alone requires the
//! tools only. [`on_missing`] is that rule as a pure function.
//!
//! ```
//! use oddball_testkit::{on_missing, Need, OnMissing};
//! assert_eq!(on_missing(Need::Data, None, None), OnMissing::Skip);
//! assert_eq!(on_missing(Need::Data, Some("1"), None), OnMissing::Fail);
//! assert_eq!(on_missing(Need::Tool, Some("1"), Some("0")), OnMissing::Skip);
//! ```

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use ndarray::{Array2, Array3};

/// What a test needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Need {
    /// The real EEG folder or a file in it.
    Data,
    /// A program named by an environment variable (browser, Python with a package).
    Tool,
}

/// What happens when a test's [`Need`] is missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnMissing {
    /// Print `skipping …` and pass.
    Skip,
    /// Panic: the test fails.
    Fail,
}

/// Whether an environment value switches a requirement on (`1`, `true`, `yes`, any case),
/// off (`0`, `false`, `no`, empty) or is not set (`None`).
fn switch(value: Option<&str>) -> Option<bool> {
    let v = value?.trim().to_ascii_lowercase();
    match v.as_str() {
        "1" | "true" | "yes" => Some(true),
        _ => Some(false),
    }
}

/// The rule of the module documentation, from the values of `ODDBALL_REQUIRE_DATA` and
/// `ODDBALL_REQUIRE_TOOLS` (`None`: not set).
pub fn on_missing(
    need: Need,
    require_data: Option<&str>,
    require_tools: Option<&str>,
) -> OnMissing {
    let data = switch(require_data).unwrap_or(false);
    let required = match need {
        Need::Data => data,
        Need::Tool => switch(require_tools).unwrap_or(data),
    };
    if required {
        OnMissing::Fail
    } else {
        OnMissing::Skip
    }
}

/// [`on_missing`] with this process's environment.
pub fn on_missing_here(need: Need) -> OnMissing {
    let var = |name: &str| std::env::var(name).ok();
    on_missing(
        need,
        var("ODDBALL_REQUIRE_DATA").as_deref(),
        var("ODDBALL_REQUIRE_TOOLS").as_deref(),
    )
}

/// Says that `test` cannot run because `why`: prints `skipping {test}: {why}` and returns, or
/// panics when the environment requires `need` (see the module documentation).
pub fn missing(need: Need, test: &str, why: &str) {
    match on_missing_here(need) {
        OnMissing::Skip => eprintln!("skipping {test}: {why}"),
        OnMissing::Fail => {
            let var = match need {
                Need::Data => "ODDBALL_REQUIRE_DATA",
                Need::Tool => "ODDBALL_REQUIRE_DATA/ODDBALL_REQUIRE_TOOLS",
            };
            panic!("{test}: {why}, and {var} requires it")
        }
    }
}

/// The shared data folder: `$ODDBALL_DATA`, else `../shared/data` beside the workspace.
/// `None` (after [`missing`]) when it is absent.
pub fn data_dir(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("ODDBALL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        });
    if dir.is_dir() {
        Some(dir)
    } else {
        missing(
            Need::Data,
            test,
            &format!("data folder {} not found (set ODDBALL_DATA)", dir.display()),
        );
        None
    }
}

/// A file below the data folder (`rel`, with `/`), or `None` (after [`missing`]) when absent.
pub fn data_file(test: &str, rel: &str) -> Option<PathBuf> {
    let p = data_dir(test)?.join(rel);
    if p.is_file() {
        Some(p)
    } else {
        missing(Need::Data, test, &format!("{} not found", p.display()));
        None
    }
}

/// The value of the environment variable `var` naming a tool (a browser, a Python), or `None`
/// (after [`missing`], with `hint` saying how to get it) when it is unset or empty.
pub fn tool(var: &str, test: &str, hint: &str) -> Option<OsString> {
    match std::env::var_os(var) {
        Some(v) if !v.is_empty() => Some(v),
        _ => {
            missing(Need::Tool, test, &format!("set {var} ({hint})"));
            None
        }
    }
}

/// A fresh directory under the system temporary directory (`oddball-{tag}-XXXXXX`), removed
/// with its contents on drop. It derefs to its [`Path`], so `dir.join("a.xdf")` works.
#[derive(Debug)]
pub struct TempDir(tempfile::TempDir);

impl TempDir {
    pub fn new(tag: &str) -> Self {
        let dir = tempfile::Builder::new()
            .prefix(&format!("oddball-{tag}-"))
            .tempdir()
            .expect("create a temporary directory");
        Self(dir)
    }

    pub fn path(&self) -> &Path {
        self.0.path()
    }

    /// `path()/name`.
    pub fn join(&self, name: impl AsRef<Path>) -> PathBuf {
        self.0.path().join(name)
    }

    /// Writes `bytes` to `name` inside the directory and returns the path.
    pub fn write(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.join(name);
        std::fs::write(&p, bytes).expect("write a temporary file");
        p
    }
}

impl std::ops::Deref for TempDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A continuous synthetic oddball recording at 256 Hz, `(n_channels, n_times)` µV and one marker
/// per sample: 240 flashes every 0.4 s from 1 s on, every fifth (`k % 5 == 2`) code 2 (a target,
/// with a 2 µV half-sine bump 300–500 ms later on every channel), the others code 1, 0 between
/// flashes; uniform noise of 10 µV peak-to-peak from an LCG seeded by `seed`, drawn sample by
/// sample. Returns `(data, markers, sfreq)`.
pub fn synthetic_oddball(n_channels: usize, seed: u64) -> (Array2<f64>, Vec<u32>, f64) {
    let sfreq = 256.0;
    let n_flash = 240;
    let step = (0.4 * sfreq) as usize;
    let n_times = 256 + n_flash * step + 256;
    let mut markers = vec![0u32; n_times];
    for k in 0..n_flash {
        markers[256 + k * step] = if k % 5 == 2 { 2 } else { 1 };
    }
    let mut state: u64 = seed;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10.0
    };
    let mut bump = vec![0.0f64; n_times];
    for (i, m) in markers.iter().enumerate() {
        if *m == 2 {
            let (a, b) = (i + (0.3 * sfreq) as usize, i + (0.5 * sfreq) as usize);
            for (j, v) in bump.iter_mut().enumerate().take(b.min(n_times)).skip(a) {
                let x = (j - a) as f64 / (b - a) as f64;
                *v += 2.0 * (std::f64::consts::PI * x).sin();
            }
        }
    }
    let mut data = Array2::zeros((n_channels, n_times));
    for i in 0..n_times {
        for c in 0..n_channels {
            data[[c, i]] = noise() + bump[i];
        }
    }
    (data, markers, sfreq)
}

/// A long synthetic flash train at `sfreq`, `(n_channels, n_times)` µV: uniform noise of 20 µV
/// peak-to-peak from an LCG seeded by `seed` (drawn channel by channel), and a flash every
/// `every` s from 1 s on until 1 s before the end, every fifth (`k % 5 == 2`) a target with a
/// 3 µV step 300–500 ms later on every channel. Returns the data and each flash's `(onset sample,
/// target)` (for measuring memory and speed on recordings of any length; `synthetic_oddball` is
/// the short one with a shaped bump).
pub fn flash_train(
    n_channels: usize,
    n_times: usize,
    sfreq: f64,
    every: f64,
    seed: u64,
) -> (Array2<f64>, Vec<(usize, bool)>) {
    let mut state = seed;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 20.0
    };
    let mut data = Array2::from_shape_fn((n_channels, n_times), |_| noise());
    let second = sfreq as usize;
    let (from, to) = (
        (0.3 * sfreq).round() as usize,
        (0.5 * sfreq).round() as usize,
    );
    let mut flashes = Vec::new();
    let step = ((every * sfreq) as usize).max(1);
    for (k, onset) in (second..n_times.saturating_sub(second))
        .step_by(step)
        .enumerate()
    {
        let target = k % 5 == 2;
        if target {
            for c in 0..n_channels {
                for t in onset + from..onset + to {
                    data[[c, t]] += 3.0;
                }
            }
        }
        flashes.push((onset, target));
    }
    (data, flashes)
}

/// Writes a recording as CSV: a `time` column (s, 6 decimals), `ch0..chN` (µV, 4 decimals) and a
/// `stim` column of markers (0 = none).
pub fn write_codes_csv(path: &Path, data: &Array2<f64>, markers: &[u32], sfreq: f64) {
    use std::fmt::Write as _;
    let (n_ch, n_times) = data.dim();
    let mut text = String::from("time");
    for c in 0..n_ch {
        let _ = write!(text, ",ch{c}");
    }
    text.push_str(",stim\n");
    for i in 0..n_times {
        let _ = write!(text, "{:.6}", i as f64 / sfreq);
        for c in 0..n_ch {
            let _ = write!(text, ",{:.4}", data[[c, i]]);
        }
        let _ = writeln!(text, ",{}", markers[i]);
    }
    std::fs::write(path, text).expect("the CSV is written");
}

/// Writes a minimal uncompressed little-endian MAT v5 file of real double matrices, each
/// `(name, n_rows, n_cols, values column-major)` (MATLAB's layout: element `(i, j)` at
/// `i + j·n_rows`), for tests of the MAT reader's users.
pub fn write_mat_v5(path: &Path, vars: &[(&str, usize, usize, &[f64])]) {
    fn tag(out: &mut Vec<u8>, ty: u32, len: usize) {
        out.extend_from_slice(&ty.to_le_bytes());
        out.extend_from_slice(&(len as u32).to_le_bytes());
    }
    fn pad8(out: &mut Vec<u8>) {
        while out.len() % 8 != 0 {
            out.push(0);
        }
    }
    let mut out = Vec::new();
    let mut text = b"MATLAB 5.0 MAT-file, written by oddball-testkit".to_vec();
    text.resize(116, b' ');
    out.extend_from_slice(&text);
    out.extend_from_slice(&[0u8; 8]);
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    for (name, rows, cols, values) in vars {
        assert_eq!(
            rows * cols,
            values.len(),
            "{name}: dimensions and values disagree"
        );
        let mut body = Vec::new();
        // Array flags: class double (6).
        tag(&mut body, 6, 8);
        body.extend_from_slice(&6u32.to_le_bytes());
        body.extend_from_slice(&0u32.to_le_bytes());
        // Dimensions.
        tag(&mut body, 5, 8);
        body.extend_from_slice(&(*rows as i32).to_le_bytes());
        body.extend_from_slice(&(*cols as i32).to_le_bytes());
        // Name (miINT8).
        tag(&mut body, 1, name.len());
        body.extend_from_slice(name.as_bytes());
        pad8(&mut body);
        // Real part (miDOUBLE).
        tag(&mut body, 9, values.len() * 8);
        for v in *values {
            body.extend_from_slice(&v.to_le_bytes());
        }
        pad8(&mut body);
        tag(&mut out, 14, body.len());
        out.extend_from_slice(&body);
    }
    std::fs::write(path, out).expect("the MAT file is written");
}

/// Synthetic epochs `(n_epochs, 4, 64)` at 64 Hz: uniform noise of `noise` µV peak-to-peak, a
/// 10 Hz sine, and on targets (`i % every == phase`) a Gaussian bump of `bump` × (channel + 1)
/// µV at 300 ms. Deterministic in `seed` (an LCG).
pub fn synthetic_p300(
    n_epochs: usize,
    seed: u64,
    every: usize,
    phase: usize,
    bump: f64,
    noise: f64,
) -> (Array3<f64>, Vec<bool>) {
    let (n_ch, n_t, sfreq) = (4, 64, 64.0);
    let mut state = seed;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let y: Vec<bool> = (0..n_epochs).map(|i| i % every == phase).collect();
    let x = Array3::from_shape_fn((n_epochs, n_ch, n_t), |(e, c, t)| {
        let tt = t as f64 / sfreq;
        let b = if y[e] {
            bump * (c as f64 + 1.0) * (-((tt - 0.3) / 0.05).powi(2)).exp()
        } else {
            0.0
        };
        b + noise * uniform() + (2.0 * std::f64::consts::PI * 10.0 * tt + c as f64).sin()
    });
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_switch_skips_locally_and_fails_when_required() {
        use Need::*;
        use OnMissing::*;
        for need in [Data, Tool] {
            assert_eq!(on_missing(need, None, None), Skip);
            assert_eq!(on_missing(need, Some("0"), None), Skip);
            assert_eq!(on_missing(need, Some(""), None), Skip);
            assert_eq!(on_missing(need, Some("1"), None), Fail);
            assert_eq!(on_missing(need, Some("TRUE"), None), Fail);
            assert_eq!(on_missing(need, Some(" yes "), None), Fail);
        }
        // Tools follow ODDBALL_REQUIRE_DATA unless ODDBALL_REQUIRE_TOOLS says otherwise.
        assert_eq!(on_missing(Tool, Some("1"), Some("0")), Skip);
        assert_eq!(on_missing(Tool, None, Some("1")), Fail);
        assert_eq!(on_missing(Tool, Some("0"), Some("1")), Fail);
        // ODDBALL_REQUIRE_TOOLS never requires the data.
        assert_eq!(on_missing(Data, None, Some("1")), Skip);
        assert_eq!(on_missing(Data, Some("1"), Some("0")), Fail);
    }

    #[test]
    fn temp_dirs_are_removed_on_drop() {
        let d = TempDir::new("testkit");
        let f = d.write("a.txt", b"x");
        assert_eq!(std::fs::read(&f).unwrap(), b"x");
        let p = d.path().to_path_buf();
        drop(d);
        assert!(!p.exists());
    }

    #[test]
    fn synthetic_targets_carry_the_bump() {
        let (x, y) = synthetic_p300(10, 1, 5, 0, 4.0, 0.0);
        assert_eq!(x.dim(), (10, 4, 64));
        assert_eq!(y.iter().filter(|&&t| t).count(), 2);
        // At 300 ms (sample 19.2 → 19) the target's channel 3 is ~16 µV above the non-target's.
        let d = x[[0, 3, 19]] - x[[1, 3, 19]];
        assert!((d - 16.0 * (-((19.0 / 64.0 - 0.3) / 0.05f64).powi(2)).exp()).abs() < 1e-12);
    }
}
