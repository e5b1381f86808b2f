//! CSV bytes through `parse_csv` with the default options, the Muse preset, and the options
//! `CsvOptions::detect` guesses from the header (what `read_csv_auto` does).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::csv::parse_csv;
use oddball_io::CsvOptions;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.csv");
    let check = |options: &CsvOptions| {
        if let Err(e) = parse_csv(data, path, options) {
            assert!(e.to_string().contains("fuzz.csv"), "{e}");
        }
    };
    check(&CsvOptions::default());
    check(&CsvOptions::muse());
    check(&CsvOptions {
        require_final_newline: false,
        sfreq: Some(250.0),
        delimiter: b';',
        ..CsvOptions::default()
    });
    // `read_csv_auto`: the options detected from the header line.
    let header_end = data.iter().position(|&b| b == b'\n').unwrap_or(data.len());
    let header = &data[..header_end];
    let header = header.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(header);
    let header = header.strip_suffix(b"\r").unwrap_or(header);
    if let Ok(text) = std::str::from_utf8(header) {
        let names: Vec<&str> = text
            .split(',')
            .map(|s| {
                let s = s.trim();
                s.strip_prefix('"')
                    .and_then(|s| s.strip_suffix('"'))
                    .unwrap_or(s)
            })
            .collect();
        check(&CsvOptions::detect(&names));
    }
});
