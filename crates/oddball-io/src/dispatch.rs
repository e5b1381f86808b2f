//! Reading a recording whatever its format: [`read`] chooses the reader by the file's extension.

use std::path::Path;

use crate::bci2000::read_bci2000;
use crate::csv::read_csv_auto;
use crate::easy::read_easy;
use crate::edf::read_edf;
use crate::mat::read_mat;
use crate::xdf::{self, read_xdf};
use crate::{IoError, Recording};

/// The extensions [`read`] dispatches on (any case), as `IoError::UnknownFormat` lists them.
pub const RECORDING_EXTENSIONS: [&str; 7] = ["dat", "csv", "edf", "bdf", "easy", "xdf", "mat"];

/// Refuses, before any reading, a path that does not exist, is a directory (naming the
/// recordings inside it), or is not a regular file (a device such as `/dev/zero`, a pipe, a
/// socket, or a link to one: reading it could cost without end). Every path oddball reads
/// passes here.
pub fn check_file(path: &Path) -> Result<(), IoError> {
    let meta = std::fs::metadata(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => IoError::NotFound {
            path: path.to_path_buf(),
        },
        _ => IoError::Io {
            path: path.to_path_buf(),
            action: "read",
            source,
        },
    })?;
    if meta.is_dir() {
        let mut recordings: Vec<String> = std::fs::read_dir(path)
            .map(|entries| {
                entries
                    .filter_map(|e| e.ok())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|name| {
                        std::path::Path::new(name)
                            .extension()
                            .and_then(|e| e.to_str())
                            .is_some_and(|e| {
                                RECORDING_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                            })
                    })
                    .collect()
            })
            .unwrap_or_default();
        recordings.sort();
        recordings.truncate(3);
        return Err(IoError::IsDirectory {
            path: path.to_path_buf(),
            recordings,
        });
    }
    if !meta.is_file() {
        return Err(IoError::NotRegular {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

/// Reads a recording, choosing the reader by extension (case-insensitive): `.dat` → BCI2000,
/// `.csv` → CSV with [`CsvOptions::detect`](crate::CsvOptions::detect), `.edf`/`.bdf` → EDF/BDF (the header decides which),
/// `.easy` → NIC with the `.info` beside it ([`read_easy`]), `.xdf` → XDF ([`read_xdf`]),
/// `.mat` → MAT in the BCI Competition layout ([`read_mat`], 240 Hz); a file
/// with another extension that starts with the XDF magic code `XDF:` is read as XDF.
pub fn read(path: impl AsRef<Path>) -> Result<Recording, IoError> {
    let path = path.as_ref();
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
