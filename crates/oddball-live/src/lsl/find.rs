//! Where liblsl is looked for (no unsafe code here; [`super::ffi`] opens what this finds).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A file to try as liblsl and why it is tried.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Candidate {
    /// A path, or a bare file name for the dynamic loader's search.
    pub file: PathBuf,
    /// Where the name came from (`ODDBALL_LIBLSL`, `the system`, `pylsl in $VIRTUAL_ENV`, …).
    pub origin: String,
}

impl Candidate {
    pub(super) fn new(file: impl Into<PathBuf>, origin: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            origin: origin.into(),
        }
    }
}

/// liblsl's names for the dynamic loader (its search path: `LD_LIBRARY_PATH`, ldconfig's cache,
/// `DYLD_*`, `PATH` on Windows), and the file name of pylsl's bundled copy.
#[cfg(target_os = "windows")]
const SYSTEM_NAMES: &[&str] = &["lsl.dll"];
#[cfg(target_os = "windows")]
const BUNDLED: &str = "lsl.dll";
#[cfg(target_os = "macos")]
const SYSTEM_NAMES: &[&str] = &[
    "liblsl.dylib",
    "liblsl.2.dylib",
    "/opt/homebrew/lib/liblsl.dylib",
    "/usr/local/lib/liblsl.dylib",
];
#[cfg(target_os = "macos")]
const BUNDLED: &str = "liblsl.dylib";
#[cfg(not(any(target_os = "windows", target_os = "macos")))]
const SYSTEM_NAMES: &[&str] = &["liblsl.so", "liblsl.so.2", "liblsl64.so"];
#[cfg(not(any(target_os = "windows", target_os = "macos")))]
const BUNDLED: &str = "liblsl.so";

/// The python asked for pylsl as a last resort.
#[cfg(target_os = "windows")]
pub(super) const PYTHON: &str = "python";
#[cfg(not(target_os = "windows"))]
pub(super) const PYTHON: &str = "python3";

/// The files to try, in order, from the environment `env` (a lookup of variables):
/// 1. `ODDBALL_LIBLSL`: when set, it alone (the user chose that file);
/// 2. `PYLSL_LIB` (pylsl's variable), when it names a file;
/// 3. the system's: liblsl's names for the dynamic loader;
/// 4. pylsl's bundled copy (`pylsl/lib/`) in the site-packages of `$VIRTUAL_ENV`,
///    `$CONDA_PREFIX` (and conda-forge's `liblsl` in `$CONDA_PREFIX/lib`) and the user's
///    (`~/.local`), those that exist.
///
/// [`super::library`] asks `python3` where pylsl is ([`liblsl_of_python`]) when none of them loads.
pub fn candidates(env: impl Fn(&str) -> Option<OsString>) -> Vec<Candidate> {
    let set = |name: &str| env(name).filter(|v| !v.is_empty());
    if let Some(file) = set("ODDBALL_LIBLSL") {
        return vec![Candidate::new(file, "ODDBALL_LIBLSL")];
    }
    let mut out = Vec::new();
    if let Some(file) = set("PYLSL_LIB").map(PathBuf::from) {
        if file.is_file() {
            out.push(Candidate::new(file, "PYLSL_LIB"));
        }
    }
    out.extend(
        SYSTEM_NAMES
            .iter()
            .map(|name| Candidate::new(*name, "the system")),
    );
    let mut prefixes = Vec::new();
    for var in ["VIRTUAL_ENV", "CONDA_PREFIX"] {
        if let Some(p) = set(var) {
            prefixes.push((PathBuf::from(p), format!("${var}")));
        }
    }
    let home = set("HOME")
        .or_else(|| set("USERPROFILE"))
        .map(PathBuf::from);
    if let Some(home) = home {
        prefixes.push((home.join(".local"), "~/.local".to_string()));
    }
    for (prefix, origin) in prefixes {
        for dir in site_packages(&prefix) {
            let file = dir.join("pylsl").join("lib").join(BUNDLED);
            if file.is_file() {
                out.push(Candidate::new(file, format!("pylsl in {origin}")));
            }
        }
        let conda = prefix.join("lib").join(BUNDLED);
        if origin == "$CONDA_PREFIX" && conda.is_file() {
            out.push(Candidate::new(conda, origin));
        }
    }
    out
}

/// The site-packages folders of a Python prefix: `lib/python3.*/site-packages` (and
/// `Lib/site-packages` on Windows).
fn site_packages(prefix: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(prefix.join("lib"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("python3"))
        .map(|e| e.path().join("site-packages"))
        .collect();
    out.sort();
    if cfg!(target_os = "windows") {
        out.push(prefix.join("Lib").join("site-packages"));
    }
    out
}

/// The liblsl file bundled with the pylsl that `python` imports (pylsl ≥ 1.16 wheels carry it
/// in `pylsl/lib/`), without importing pylsl; `None` when that python cannot be run within 10 s,
/// has no pylsl, or its pylsl carries no library.
pub fn liblsl_of_python(python: &Path) -> Option<PathBuf> {
    let code = "import importlib.util as u; s = u.find_spec('pylsl'); \
                print(s.submodule_search_locations[0] if s and s.submodule_search_locations else '')";
    let mut child = Command::new(python)
        .args(["-c", code])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(10)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
        }
    }
    let mut out = String::new();
    std::io::Read::read_to_string(&mut child.stdout.take()?, &mut out).ok()?;
    let dir = PathBuf::from(out.trim());
    if dir.as_os_str().is_empty() {
        return None;
    }
    // pylsl ≥ 1.16 keeps it in pylsl/lib, older ones beside the package's modules.
    [dir.join("lib").join(BUNDLED), dir.join(BUNDLED)]
        .into_iter()
        .find(|f| f.is_file())
}
