//! Reading a recording whatever its format: [`read`] chooses the reader by the file's extension.

use std::path::Path;

use crate::bci2000::read_bci2000;
use crate::brainvision::read_brainvision;
use crate::csv::read_csv_auto;
use crate::easy::read_easy;
use crate::edf::read_edf;
use crate::eeglab::read_eeglab;
use crate::fif::read_fif;
use crate::files::check_file;
use crate::gdf::read_gdf;
use crate::mat::read_mat;
use crate::xdf::{self, read_xdf};
use crate::{IoError, Recording};

/// Reads a recording, choosing the reader by extension (case-insensitive): `.dat` → BCI2000,
/// `.csv` → CSV with [`CsvOptions::detect`](crate::CsvOptions::detect), `.edf`/`.bdf` → EDF/BDF (the header decides which),
/// `.easy` → NIC with the `.info` beside it ([`read_easy`]), `.xdf` → XDF ([`read_xdf`]),
/// `.mat` → MAT in the BCI Competition layout ([`read_mat`], 240 Hz), `.vhdr` → BrainVision
/// ([`read_brainvision`]), `.set` → EEGLAB ([`read_eeglab`]), `.fif` → FIF raw ([`read_fif`], its
/// split parts too; `.fif.gz` refused: decompress it first), `.gdf` → GDF 1.x/2.x ([`read_gdf`]); a file
/// with another extension that starts with the XDF magic code `XDF:` is read as XDF.
///
/// A run of a BIDS-EEG data set (`sub-…_eeg.<edf|bdf|vhdr|set>` with its `_events.tsv` beside
/// it) is read by [`crate::bids::read_bids_run`]: its events and channels come from the data
/// set's sidecars, not from the data file.
pub fn read(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
    check_file(path)?;
    if crate::bids::is_bids_run(path) {
        return crate::bids::read_bids_run(path);
    }
    read_format(path)
}

/// [`read`] by the extension alone (a BIDS run's data file as its format's reader reads it).
pub(crate) fn read_format(path: &Path) -> Result<Recording, IoError> {
    check_file(path)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("dat") => read_bci2000(path),
        Some("csv") => read_csv_auto(path),
        Some("edf") | Some("bdf") => read_edf(path),
        Some("easy") => read_easy(path),
        Some("xdf") => read_xdf(path),
        Some("mat") => read_mat(path),
        Some("vhdr") => read_brainvision(path),
        Some("set") => read_eeglab(path),
        Some("fif") => read_fif(path),
        Some("gz")
            if path
                .to_string_lossy()
                .to_ascii_lowercase()
                .ends_with(".fif.gz") =>
        {
            read_fif(path)
        }
        Some("gdf") => read_gdf(path),
        Some("xdfz") => Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "gzip-compressed XDF (.xdfz); decompress it to .xdf first".into(),
        }),
        _ if xdf::has_magic(path) => read_xdf(path),
        _ => Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
            extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
        }),
    }
}
