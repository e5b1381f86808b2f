//! NIC `.easy` bytes (and optionally the `.info` text) through `parse_easy`.
//!
//! Input: the `.easy` bytes, then, if present, the separator `\0INFO\0` followed by the `.info`
//! bytes. Each input is parsed with the default options and with lenient ones (no final line
//! end required, no record-count check, a fixed rate and channel count).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::easy::parse_easy;
use oddball_io::EasyOptions;

const SEPARATOR: &[u8] = b"\0INFO\0";

fuzz_target!(|data: &[u8]| {
    let (easy, info) = match data.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) {
        Some(i) => (&data[..i], Some(&data[i + SEPARATOR.len()..])),
        None => (data, None),
    };
    let path = Path::new("fuzz.easy");
    let info_path = Path::new("fuzz.info");
    let lenient = EasyOptions {
        require_final_newline: false,
        check_record_count: false,
        ..EasyOptions::default()
    };
    let fixed = EasyOptions {
        sfreq: Some(500.0),
        n_channels: Some(8),
        target_codes: vec![2],
        nontarget_codes: vec![1],
        ..lenient.clone()
    };
    for options in [EasyOptions::default(), lenient, fixed] {
        match parse_easy(easy, path, info.map(|b| (b, info_path)), &options) {
            Ok(rec) => {
                let e = rec.easy().expect("easy details");
                assert_eq!(e.triggers.len(), rec.raw.n_times());
                assert_eq!(e.timestamps_ms.len(), rec.raw.n_times());
            }
            Err(e) => {
                let s = e.to_string();
                assert!(s.contains("fuzz.easy") || s.contains("fuzz.info"), "{s}");
            }
        }
    }
});
