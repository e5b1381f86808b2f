//! MAT v5/v7 bytes through `parse_mat_file` (the container) and `parse_mat` (the BCI
//! Competition layout). Beyond "no panic": every error names the file; a truncation or invalid
//! field names a byte offset inside the input; a parsed file's arrays hold as many values as
//! their dimensions say; a recording's events lie inside it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_io::mat::{MatArray, MatValue};
use oddball_io::{parse_mat, parse_mat_file, IoError, MatOptions};

fn check(a: &MatArray) {
    let n: usize = a.dims.iter().product();
    match &a.value {
        MatValue::Numeric { real, imag, .. } => {
            assert_eq!(real.len(), n);
            if let Some(im) = imag {
                assert_eq!(im.len(), n);
            }
        }
        MatValue::Char(c) => assert_eq!(c.len(), n),
        MatValue::Cell(cells) => {
            assert_eq!(cells.len(), n);
            cells.iter().for_each(check);
        }
        MatValue::Struct { fields, values } => {
            assert_eq!(values.len(), n * fields.len());
            values.iter().for_each(check);
        }
        MatValue::Unsupported { .. } => {}
    }
}

fn check_err(e: &IoError, len: usize) {
    assert!(e.to_string().contains("fuzz.mat"), "{e}");
    if let IoError::Truncated { .. } | IoError::InvalidField { .. } = e {
        let offset = e.offset().expect("offset");
        assert!(offset <= len as u64, "{e}");
    }
}

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.mat");
    match parse_mat_file(data, path) {
        Ok(file) => file.variables.iter().for_each(|v| check(&v.array)),
        Err(e) => check_err(&e, data.len()),
    }
    match parse_mat(data, path, &MatOptions::default()) {
        Ok(rec) => {
            assert!(rec.mat().is_some());
            for e in rec.raw.events().iter() {
                assert!(e.onset < rec.raw.n_times());
            }
        }
        Err(e) => check_err(&e, data.len()),
    }
});
