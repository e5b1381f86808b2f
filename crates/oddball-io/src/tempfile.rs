//! Writing files so that a failure never leaves a half-written file under the final name.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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
