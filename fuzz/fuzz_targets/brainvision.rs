//! BrainVision header, marker and data bytes through `parse_brainvision`. The input is split
//! in three: two little-endian u16 lengths, then the header, the marker file and the data.
//! Beyond "no panic": every error names a file and an offset inside the input; a recording's
//! events lie inside it and its shape is the data's length over the channels.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::{parse_brainvision, IoError};

fuzz_target!(|input: &[u8]| {
    if input.len() < 4 {
        return;
    }
    let hl = usize::from(u16::from_le_bytes([input[0], input[1]]));
    let ml = usize::from(u16::from_le_bytes([input[2], input[3]]));
    let rest = &input[4..];
    let (header, rest) = rest.split_at(hl.min(rest.len()));
    let (markers, data) = rest.split_at(ml.min(rest.len()));
    let path = Path::new("fuzz.vhdr");
    for m in [Some(markers), None] {
        match parse_brainvision(header, path, data, m) {
            Ok(rec) => {
                let info = rec.brainvision().expect("details");
                let n = rec.raw.n_channels() * rec.raw.n_times() * info.binary_format.size();
                assert_eq!(n, data.len());
                for e in rec.raw.events().iter() {
                    assert!(e.onset < rec.raw.n_times());
                }
            }
            Err(e) => {
                if let IoError::Truncated { .. } | IoError::InvalidField { .. } = e {
                    let offset = e.offset().expect("offset");
                    assert!(offset <= input.len() as u64, "{e}");
                }
            }
        }
    }
});
