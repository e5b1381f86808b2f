//! What the writers share: a temporary file renamed into place (a failure never leaves a
//! half-written file under the final name, and an old file under that name stays whole until
//! the new one is complete and synced; the `tempfile` crate's), and the check that every
//! sample can be stored.
//!
//! [`write_atomic`] and [`AtomicFile`] are the one way every output of oddball is written
//! (models, JSON, CSV, pictures, recordings' final files): the recording writers here, the
//! binary's reports and `oddball-plot`'s pictures all go through them.
//!
//! A target that exists and is not a regular file (`/dev/null`, `/dev/stdout`, a named pipe)
//! is written in place: renaming a temporary file over it would replace the device with a
//! regular file (as root, `-o /dev/null` once turned `/dev/null` into a file that every later
//! program read and wrote).

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use oddball_signal::Raw;

use crate::samples::{for_each_block, SampleBlocks};
use crate::IoError;

/// A temporary file beside the target (the `tempfile` crate's, named `.<name>.<random>.tmp`,
/// created with `O_EXCL`), removed on drop unless renamed into place with [`TempFile::persist`].
#[derive(Debug)]
pub(crate) struct TempFile {
    pub(crate) path: PathBuf,
    /// `None` when the target is a device or pipe written in place (see the module doc).
    temp: Option<tempfile::TempPath>,
}

impl TempFile {
    /// Creates the temporary file in the target's directory; its permissions are those of a
    /// file created with [`File::create`] (`0o666` less the umask), not `tempfile`'s `0o600`,
    /// since it becomes the written file.
    pub(crate) fn create(target: &Path) -> Result<(Self, File), IoError> {
        let err = |path: &Path, source| IoError::Io {
            path: path.to_path_buf(),
            action: "create",
            source,
        };
        if is_special(target) {
            let file = std::fs::OpenOptions::new()
                .write(true)
                .open(target)
                .map_err(|source| err(target, source))?;
            return Ok((
                Self {
                    path: target.to_path_buf(),
                    temp: None,
                },
                file,
            ));
        }
        let name = target.file_name().ok_or_else(|| {
            err(
                target,
                std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"),
            )
        })?;
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        let prefix = format!(".{}.", name.to_string_lossy());
        // The target's extension last, so writers that pick a format by extension (plotters'
        // PNG and SVG backends) write the temporary file in the target's format.
        let suffix = match target.extension() {
            Some(ext) => format!(".tmp.{}", ext.to_string_lossy()),
            None => ".tmp".to_string(),
        };
        builder.prefix(&prefix).suffix(&suffix);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let (file, temp) = builder
            .tempfile_in(dir)
            .map_err(|source| err(dir, source))?
            .into_parts();
        Ok((
            Self {
                path: temp.to_path_buf(),
                temp: Some(temp),
            },
            file,
        ))
    }

    /// Renames the (closed) file to `target` (nothing to do for a target written in place).
    pub(crate) fn persist(self, target: &Path) -> Result<(), IoError> {
        let Some(temp) = self.temp else {
            return Ok(());
        };
        temp.persist(target).map_err(|e| IoError::Io {
            path: target.to_path_buf(),
            action: "rename",
            source: e.error,
        })?;
        sync_dir(target);
        Ok(())
    }
}

/// A file being written under a temporary name beside `target` (same directory, same
/// extension); [`AtomicFile::commit`] syncs it to disk and renames it to `target`. Dropped
/// without a commit (an error on the way), the temporary file is removed and whatever was at
/// `target` before is untouched.
#[derive(Debug)]
pub struct AtomicFile {
    temp: TempFile,
    file: File,
    target: PathBuf,
}

impl AtomicFile {
    /// Creates the temporary file beside `target`.
    pub fn create(target: impl AsRef<Path>) -> Result<Self, IoError> {
        let target = target.as_ref();
        let (temp, file) = TempFile::create(target)?;
        Ok(Self {
            temp,
            file,
            target: target.to_path_buf(),
        })
    }

    /// The temporary file's path (for writers that open the file themselves by name; what they
    /// write there is what [`AtomicFile::commit`] syncs and renames).
    pub fn temp_path(&self) -> &Path {
        &self.temp.path
    }

    /// The path the file will have once committed.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The open temporary file.
    pub fn file(&mut self) -> &mut File {
        &mut self.file
    }

    /// Syncs the temporary file and renames it to the target.
    pub fn commit(self) -> Result<(), IoError> {
        sync(&self.file).map_err(|source| IoError::Io {
            path: self.temp.path.clone(),
            action: "write",
            source,
        })?;
        drop(self.file);
        self.temp.persist(&self.target)
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

/// Writes `bytes` to `path` through an [`AtomicFile`]: either the whole new content is at
/// `path` (synced) or, on any error, the old file is.
pub fn write_atomic(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> Result<(), IoError> {
    let path = path.as_ref();
    let mut f = AtomicFile::create(path)?;
    f.file()
        .write_all(bytes.as_ref())
        .map_err(|source| IoError::Io {
            path: f.temp_path().to_path_buf(),
            action: "write",
            source,
        })?;
    f.commit()
}

/// `fsync` for a regular file; nothing for a device or pipe written in place (`fsync` on one
/// fails with `EINVAL`).
pub(crate) fn sync(file: &File) -> std::io::Result<()> {
    if file.metadata()?.is_file() {
        file.sync_all()
    } else {
        Ok(())
    }
}

/// Whether `target` exists and is not a regular file or a directory (a device, pipe or socket;
/// symbolic links followed).
fn is_special(target: &Path) -> bool {
    std::fs::metadata(target).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Makes a rename inside `target`'s directory durable (best effort: not every file system lets
/// a directory be opened and synced).
fn sync_dir(target: &Path) {
    #[cfg(unix)]
    {
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = target;
}

/// Checks that every sample of `raw` survives a writer whose stored-and-read-back value is
/// `round_trip(x)` (`None`: out of the format's range, said by `range_reason`). Returns the
/// largest `|round_trip(x) − x|`; the first non-finite or out-of-range sample is an error naming
/// its channel and sample.
pub(crate) fn check_writable(
    path: &Path,
    raw: &Raw,
    range_reason: &'static str,
    round_trip: impl Fn(f64) -> Option<f64>,
) -> Result<f64, IoError> {
    check_writable_blocks(
        path,
        &raw.data().view(),
        raw.ch_names(),
        range_reason,
        round_trip,
    )
}

/// [`check_writable`] over samples read a block at a time (the first bad sample of the first
/// block that has one, channel by channel).
pub(crate) fn check_writable_blocks(
    path: &Path,
    samples: &dyn SampleBlocks,
    ch_names: &[String],
    range_reason: &'static str,
    round_trip: impl Fn(f64) -> Option<f64>,
) -> Result<f64, IoError> {
    let mut max_rounding = 0.0f64;
    for_each_block(
        samples,
        |start, block| {
            for (c, row) in block.rows().into_iter().enumerate() {
                for (t, &x) in row.iter().enumerate() {
                    let back = if x.is_finite() { round_trip(x) } else { None };
                    match back {
                        Some(b) => max_rounding = max_rounding.max((b - x).abs()),
                        None => {
                            return Err(IoError::UnwritableSample {
                                path: path.to_path_buf(),
                                channel: ch_names[c].clone(),
                                channel_index: c,
                                sample: start + t,
                                value: x,
                                reason: if x.is_finite() {
                                    range_reason
                                } else {
                                    "not a finite number"
                                },
                            })
                        }
                    }
                }
            }
            Ok(())
        },
        |source| read_error(path, source),
    )?;
    Ok(max_rounding)
}

/// A failed read of the samples being written (a spilled session's temporary file).
pub(crate) fn read_error(path: &Path, source: std::io::Error) -> IoError {
    IoError::Io {
        path: path.to_path_buf(),
        action: "read the samples to write to",
        source,
    }
}

/// Refuses an empty recording (no channel or no sample): no format can be read back from it.
pub(crate) fn check_not_empty(path: &Path, raw: &Raw, format: &str) -> Result<(), IoError> {
    check_not_empty_counts(path, raw.n_channels(), raw.n_times(), format)
}

/// [`check_not_empty`] for samples given by their counts.
pub(crate) fn check_not_empty_counts(
    path: &Path,
    n_ch: usize,
    n_times: usize,
    format: &str,
) -> Result<(), IoError> {
    if n_ch == 0 || n_times == 0 {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "writing an empty recording ({n_ch} channels, {n_times} samples) to {format}"
            ),
        });
    }
    Ok(())
}
