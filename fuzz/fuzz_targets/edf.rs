//! EDF, EDF+, BDF and BDF+ bytes through `parse_edf`, with default options and with the
//! lenient ones (mismatched rates dropped, a `Status` channel excluded).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::edf::parse_edf;
use oddball_io::EdfOptions;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.edf");
    let lenient = EdfOptions {
        drop_mismatched_rates: true,
        exclude: vec!["Status".into(), "EDF Annotations".into()],
    };
    for options in [EdfOptions::default(), lenient] {
        match parse_edf(data, path, &options) {
            Ok(rec) => {
                assert!(rec.edf().is_some());
                assert!(rec.raw.sfreq().is_finite() && rec.raw.sfreq() > 0.0);
            }
            Err(e) => assert!(e.to_string().contains("fuzz.edf"), "{e}"),
        }
    }
});
