//! EEGLAB `.set` bytes (a MAT v5/v7 file) through `parse_eeglab`, with and without a `.fdt`:
//! the input's first little-endian u16 is the length of the `.fdt` bytes at its end. Beyond
//! "no panic": every error names the `.set` or the `.fdt`; a recording's events lie inside it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::parse_eeglab;

fuzz_target!(|input: &[u8]| {
    if input.len() < 2 {
        return;
    }
    let fl = usize::from(u16::from_le_bytes([input[0], input[1]]));
    let rest = &input[2..];
    let (set, fdt) = rest.split_at(rest.len() - fl.min(rest.len()));
    let path = Path::new("fuzz.set");
    for f in [Some(fdt), None] {
        match parse_eeglab(set, path, f) {
            Ok(rec) => {
                assert!(rec.eeglab().is_some());
                for e in rec.raw.events().iter() {
                    assert!(e.onset < rec.raw.n_times());
                }
            }
            Err(e) => {
                let s = e.to_string();
                assert!(s.contains("fuzz.set") || s.contains(".fdt") || s.contains("fdt"), "{s}");
            }
        }
    }
});
