//! A file's bytes and its path, for the binary readers (EDF/BDF, GDF, FIF): the one
//! home of what their errors say — a field, its byte offset and, when the file ends early, the
//! byte it needed — and of bounds-checked little-endian reads.
//!
//! Each reader adds its own field readers to [`FileBytes`] in its own module (EDF's ASCII
//! header fields, GDF's NUL-cut texts, FIF's big-endian tags); what every format shares is here.

use std::path::Path;

use crate::IoError;

/// The bytes of a file and its path, with reads whose errors name the field and its offset.
pub(crate) struct FileBytes<'a> {
    pub(crate) path: &'a Path,
    pub(crate) bytes: &'a [u8],
}

impl FileBytes<'_> {
    /// The field at byte `offset` holds `found` where the format wants `expected`.
    pub(crate) fn invalid(
        &self,
        field: impl Into<String>,
        offset: usize,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> IoError {
        IoError::invalid_field(self.path, field, offset as u64, expected, found)
    }

    /// The field starting at byte `offset` needs the file to reach byte `needed`; it ends
    /// before.
    pub(crate) fn truncated(
        &self,
        field: impl Into<String>,
        offset: usize,
        needed: u64,
    ) -> IoError {
        IoError::Truncated {
            path: self.path.to_path_buf(),
            field: field.into(),
            offset: offset as u64,
            needed,
            file_len: self.bytes.len() as u64,
        }
    }

    /// `len` bytes at `off`, or a truncation error naming `field`.
    pub(crate) fn slice(&self, field: &str, off: usize, len: usize) -> Result<&[u8], IoError> {
        off.checked_add(len)
            .and_then(|end| self.bytes.get(off..end))
            .ok_or_else(|| self.truncated(field, off, (off as u64).saturating_add(len as u64)))
    }

    fn array<const N: usize>(&self, field: &str, off: usize) -> Result<[u8; N], IoError> {
        let s = self.slice(field, off, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    pub(crate) fn u8(&self, field: &str, off: usize) -> Result<u8, IoError> {
        Ok(self.array::<1>(field, off)?[0])
    }
    pub(crate) fn u16(&self, field: &str, off: usize) -> Result<u16, IoError> {
        Ok(u16::from_le_bytes(self.array(field, off)?))
    }
    pub(crate) fn u24(&self, field: &str, off: usize) -> Result<u32, IoError> {
        let [a, b, c] = self.array(field, off)?;
        Ok(u32::from_le_bytes([a, b, c, 0]))
    }
    pub(crate) fn u32(&self, field: &str, off: usize) -> Result<u32, IoError> {
        Ok(u32::from_le_bytes(self.array(field, off)?))
    }
    pub(crate) fn i64(&self, field: &str, off: usize) -> Result<i64, IoError> {
        Ok(i64::from_le_bytes(self.array(field, off)?))
    }
    pub(crate) fn u64(&self, field: &str, off: usize) -> Result<u64, IoError> {
        Ok(u64::from_le_bytes(self.array(field, off)?))
    }
    pub(crate) fn f32(&self, field: &str, off: usize) -> Result<f32, IoError> {
        Ok(f32::from_le_bytes(self.array(field, off)?))
    }
    pub(crate) fn f64(&self, field: &str, off: usize) -> Result<f64, IoError> {
        Ok(f64::from_le_bytes(self.array(field, off)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_name_the_field_and_the_byte_needed() {
        let bytes = [1u8, 2, 3, 4, 5];
        let f = FileBytes {
            path: Path::new("x.bin"),
            bytes: &bytes,
        };
        assert_eq!(f.u16("a", 0).unwrap(), 0x0201);
        assert_eq!(f.u24("b", 1).unwrap(), 0x040302);
        match f.u32("c", 2).unwrap_err() {
            IoError::Truncated {
                field,
                offset,
                needed,
                file_len,
                ..
            } => assert_eq!((field.as_str(), offset, needed, file_len), ("c", 2, 6, 5)),
            e => panic!("{e}"),
        }
        assert!(f.slice("d", usize::MAX, 2).is_err());
    }
}
