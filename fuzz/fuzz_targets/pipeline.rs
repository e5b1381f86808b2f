//! Past parsing (issue #19): a fuzzed recording goes the way `oddball evaluate` takes it. The
//! first byte picks the format (BCI2000, CSV, EDF/BDF, XDF, MAT), the rest is the file; what
//! reads is preprocessed by the one path (non-finite held, detrend, zero-phase band-pass,
//! epochs, rejection) and, with both classes present, an `lda` pipeline is fitted and scores
//! it. Errors are fine; a panic, an abort (an allocation sized by a header) or a non-finite
//! score is a finding.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use oddball_decode::pipeline::{PipelineParams, Preprocess};
use oddball_io::{
    bci2000::parse_bci2000, csv::parse_csv, edf::parse_edf, parse_mat, parse_xdf, Bci2000Options,
    CsvOptions, EdfOptions, MatOptions,
};

fuzz_target!(|data: &[u8]| {
    let Some((&kind, bytes)) = data.split_first() else {
        return;
    };
    let rec = match kind % 5 {
        0 => parse_bci2000(bytes, Path::new("f.dat"), &Bci2000Options::default()),
        1 => {
            let text = String::from_utf8_lossy(bytes);
            let header: Vec<&str> = text.lines().next().unwrap_or("").split(',').collect();
            parse_csv(bytes, Path::new("f.csv"), &CsvOptions::detect(&header))
        }
        2 => parse_edf(bytes, Path::new("f.edf"), &EdfOptions::default()),
        3 => parse_xdf(bytes, Path::new("f.xdf")),
        _ => parse_mat(bytes, Path::new("f.mat"), &MatOptions::default()),
    };
    let Ok(rec) = rec else {
        return;
    };
    let Ok((epochs, _)) = Preprocess::peer().params().epochs_owned(rec.raw) else {
        return;
    };
    let y: Vec<Option<bool>> = epochs.targets();
    if epochs.n_epochs() < 6 || y.iter().any(Option::is_none) {
        return;
    }
    let y: Vec<bool> = y.into_iter().map(|t| t == Some(true)).collect();
    let Ok(params) = PipelineParams::preset("lda", epochs.sfreq()) else {
        return;
    };
    if let Ok(pipeline) = params.fit(epochs.data().view(), &y) {
        if let Ok(scores) = pipeline.decision_function(epochs.data().view()) {
            assert!(scores.iter().all(|s| s.is_finite()), "non-finite score");
        }
    }
});
