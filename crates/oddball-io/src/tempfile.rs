//! What the writers share: a temporary file renamed into place (a failure never leaves a
//! half-written file under the final name), and the check that every sample can be stored.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use oddball_signal::Raw;

use crate::IoError;

/// A temporary file beside the target, removed on drop unless renamed into place.
pub(crate) struct TempFile {
    pub(crate) path: PathBuf,
    persisted: bool,
}

impl TempFile {
    /// Creates `.<name>.<pid>-<n>.tmp` in the target's directory.
    pub(crate) fn create(target: &Path) -> Result<(Self, File), IoError> {
        static N: AtomicUsize = AtomicUsize::new(0);
        let name = target.file_name().ok_or_else(|| IoError::Io {
            path: target.to_path_buf(),
            action: "create",
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file path"),
        })?;
        let path = target.with_file_name(format!(
            ".{}.{}-{}.tmp",
            name.to_string_lossy(),
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|source| IoError::Io {
                path: path.clone(),
                action: "create",
                source,
            })?;
        Ok((
            Self {
                path,
                persisted: false,
            },
            file,
        ))
    }

    /// Renames the (closed) file to `target`.
    pub(crate) fn persist(mut self, target: &Path) -> Result<(), IoError> {
        std::fs::rename(&self.path, target).map_err(|source| IoError::Io {
            path: target.to_path_buf(),
            action: "rename",
            source,
        })?;
        self.persisted = true;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.persisted {
            let _ = std::fs::remove_file(&self.path);
        }
    }
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
    let mut max_rounding = 0.0f64;
    for (c, row) in raw.data().rows().into_iter().enumerate() {
        for (t, &x) in row.iter().enumerate() {
            let back = if x.is_finite() { round_trip(x) } else { None };
            match back {
                Some(b) => max_rounding = max_rounding.max((b - x).abs()),
                None => {
                    return Err(IoError::UnwritableSample {
                        path: path.to_path_buf(),
                        channel: raw.ch_names()[c].clone(),
                        channel_index: c,
                        sample: t,
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
    Ok(max_rounding)
}

/// Refuses an empty recording (no channel or no sample): no format can be read back from it.
pub(crate) fn check_not_empty(path: &Path, raw: &Raw, format: &str) -> Result<(), IoError> {
    let (n_ch, n_times) = (raw.n_channels(), raw.n_times());
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
