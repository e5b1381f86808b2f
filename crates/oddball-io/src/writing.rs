//! What the writers share: a temporary file renamed into place (a failure never leaves a
//! half-written file under the final name; the `tempfile` crate's), and the check that every
//! sample can be stored.

use std::fs::File;
use std::path::{Path, PathBuf};

use oddball_signal::Raw;

use crate::IoError;

/// A temporary file beside the target (the `tempfile` crate's, named `.<name>.<random>.tmp`,
/// created with `O_EXCL`), removed on drop unless renamed into place with [`TempFile::persist`].
#[derive(Debug)]
pub(crate) struct TempFile {
    pub(crate) path: PathBuf,
    temp: tempfile::TempPath,
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
        builder.prefix(&prefix).suffix(".tmp");
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
                temp,
            },
            file,
        ))
    }

    /// Renames the (closed) file to `target`.
    pub(crate) fn persist(self, target: &Path) -> Result<(), IoError> {
        self.temp.persist(target).map_err(|e| IoError::Io {
            path: target.to_path_buf(),
            action: "rename",
            source: e.error,
        })
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
