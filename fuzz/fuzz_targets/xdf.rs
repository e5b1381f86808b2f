//! Arbitrary bytes through the XDF reader (a recording cut anywhere must read, anything else
//! must be a clear error).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = oddball_io::xdf::parse_xdf(data, Path::new("fuzz.xdf"));
    let _ = oddball_io::xdf::parse_xdf_file(data, Path::new("fuzz.xdf"));
});
