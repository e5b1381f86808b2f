//! BCI2000 `.dat` bytes through `parse_bci2000`, with both channel-naming options; a file that
//! parses also has every state decoded.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::bci2000::parse_bci2000;
use oddball_io::Bci2000Options;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.dat");
    for standard_64_names in [false, true] {
        let options = Bci2000Options { standard_64_names };
        match parse_bci2000(data, path, &options) {
            Ok(rec) => {
                let info = rec.bci2000().expect("BCI2000 details");
                let states = &info.states;
                let _ = states.all();
                for i in [0, states.n_samples().saturating_sub(1), states.n_samples()] {
                    let _ = states.vector(i);
                }
                assert_eq!(rec.raw.n_times(), states.n_samples());
                assert_eq!(rec.raw.ch_names().len(), info.header.source_ch);
            }
            Err(e) => {
                // Every error names the file.
                assert!(e.to_string().contains("fuzz.dat"), "{e}");
            }
        }
    }
});
