//! The eeg3 speller recordings as the peer pre-processes them, shared by the benchmarks.

use std::path::PathBuf;

use oddball_decode::pipeline::Preprocess;
use oddball_signal::Epochs;

/// Epochs of `name` (in `bci2000-samplefiles-p300` under `../shared/data` or `ODDBALL_DATA`) cut
/// by `pre`'s preprocessing, as `oddball train` cuts them; `None`, said on stderr, without the
/// file.
pub fn speller_epochs(name: &str, pre: &Preprocess) -> Option<Epochs> {
    let dir = std::env::var_os("ODDBALL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        });
    let path = dir.join("bci2000-samplefiles-p300").join(name);
    if !path.is_file() {
        eprintln!(
            "skipping the {name} benchmarks: {} not found",
            path.display()
        );
        return None;
    }
    let rec = oddball_io::read(&path).expect("the speller file reads");
    Some(pre.params().epochs(&rec.raw).unwrap().0)
}
