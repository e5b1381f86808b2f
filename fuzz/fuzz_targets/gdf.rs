//! GDF 1.x / 2.x bytes through `parse_gdf`, with default options and with the lenient ones
//! (mismatched rates dropped, a channel excluded).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::gdf::parse_gdf;
use oddball_io::GdfOptions;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.gdf");
    let lenient = GdfOptions {
        drop_mismatched_rates: true,
        exclude: vec!["Status".into()],
    };
    for options in [GdfOptions::default(), lenient] {
        match parse_gdf(data, path, &options) {
            Ok(rec) => {
                assert!(rec.gdf().is_some());
                assert!(rec.raw.sfreq().is_finite() && rec.raw.sfreq() > 0.0);
                let n = rec.raw.n_times();
                assert!(rec.raw.events().iter().all(|e| e.onset < n));
            }
            Err(e) => assert!(e.to_string().contains("fuzz.gdf"), "{e}"),
        }
    }
});
