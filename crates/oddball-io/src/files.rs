//! The one gate every path oddball reads passes: [`check_file`] (exists, not a folder, a regular
//! file: no device, pipe or socket, whose content has no end) and [`read_file`] behind it.

use std::path::Path;

use crate::IoError;

/// The extensions [`crate::read`] dispatches on (any case), as `IoError::UnknownFormat` lists
/// them.
pub const RECORDING_EXTENSIONS: [&str; 11] = [
    "dat", "csv", "edf", "bdf", "easy", "xdf", "mat", "vhdr", "set", "fif", "gdf",
];

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

/// Reads a whole regular file ([`check_file`] first: devices and pipes refused), mapping
/// the OS error to [`IoError::Io`].
pub(crate) fn read_file(path: &std::path::Path) -> Result<Vec<u8>, IoError> {
    check_file(path)?;
    std::fs::read(path).map_err(|source| IoError::Io {
        path: path.to_path_buf(),
        action: "read",
        source,
    })
}
