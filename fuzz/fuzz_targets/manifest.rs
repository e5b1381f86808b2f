//! Dataset manifests (TOML) through `Manifest::parse`: every check runs before any EEG is read,
//! so arbitrary text must give a manifest or an error, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::Manifest;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(m) = Manifest::parse(text, Path::new("/nonexistent/fuzz.toml")) {
            let _ = m.subjects.iter().map(|s| s.runs().count()).sum::<usize>();
        }
    }
});
