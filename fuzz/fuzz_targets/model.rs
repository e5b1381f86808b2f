//! Arbitrary UTF-8 through `Model::from_json` (the saved-model reader of `oddball train`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use oddball_decode::pipeline::Model;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(model) = Model::from_json(text) {
            // A model that loads also saves, and loads again.
            let again = Model::from_json(&model.to_json());
            assert!(again.is_ok(), "{:?}", again.err());
        }
    }
});
