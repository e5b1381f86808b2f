//! What the XDF reader keeps while it reads (one accumulator per stream) and the context its
//! errors are made in: shared by the chunk reader ([`super::read`]) and the check of a chunk cut
//! by the file's end ([`super::cut`]), so neither imports the other's.

use std::path::Path;

use crate::IoError;

use super::types::*;
use super::xml::*;

pub(super) struct Acc {
    pub(super) info: XdfStreamInfo,
    pub(super) timestamps: Vec<f64>,
    pub(super) numeric: Vec<f64>,
    pub(super) strings: Vec<Vec<String>>,
    pub(super) last_ts: f64,
    pub(super) tdiff: f64,
    /// File offset of the StreamFooter's `sample_count` text, when it has one.
    pub(super) footer_count_at: Option<usize>,
}

pub(super) struct Ctx<'a> {
    pub(super) path: &'a Path,
}

impl Ctx<'_> {
    pub(super) fn invalid(
        &self,
        offset: usize,
        field: impl Into<String>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> IoError {
        IoError::invalid_field(self.path, field, offset as u64, expected, found)
    }
}

// The XML of StreamHeaders and StreamFooters.

impl Ctx<'_> {
    /// Parses XML `bytes` starting at file offset `base`.
    pub(super) fn xml(
        &self,
        bytes: &[u8],
        base: usize,
        what: &str,
    ) -> Result<(String, XmlNode), IoError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            self.invalid(
                base + e.valid_up_to(),
                format!("{what} XML"),
                "UTF-8 text",
                format!("byte {:#04x}", bytes[e.valid_up_to()]),
            )
        })?;
        let root = parse_xml(text).map_err(|e| {
            self.invalid(base + e.offset, format!("{what} XML"), e.expected, e.found)
        })?;
        Ok((text.to_string(), root))
    }
}
