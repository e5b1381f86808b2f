//! FIF raw bytes through `parse_fif` (one file from memory; split parts are refused there).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::parse_fif;

fuzz_target!(|data: &[u8]| {
    match parse_fif(data, Path::new("fuzz_raw.fif")) {
        Ok(rec) => {
            let info = rec.fif().expect("FIF details");
            assert!(rec.raw.sfreq().is_finite() && rec.raw.sfreq() > 0.0);
            assert!(rec.raw.n_times() > 0 && rec.raw.n_channels() > 0);
            assert_eq!(info.parts.len(), 1);
        }
        Err(e) => assert!(e.to_string().contains("fuzz_raw.fif"), "{e}"),
    }
});
