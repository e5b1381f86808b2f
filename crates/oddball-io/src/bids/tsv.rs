//! BIDS TSV files (`*_events.tsv`, `*_channels.tsv`, `participants.tsv`) read as outside input:
//! size bounded, UTF-8, a header of unique column names, every row as wide as the header; each
//! fault names the file, line and column. Writing escapes nothing (cells are checked instead).

use std::path::{Path, PathBuf};

use super::{BidsError, MAX_SIDECAR_BYTES};

/// A TSV table read from a file.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Table {
    pub path: PathBuf,
    pub header: Vec<String>,
    /// Each row's cells with its 1-based line number.
    pub rows: Vec<(usize, Vec<String>)>,
}

/// Reads a file of at most [`MAX_SIDECAR_BYTES`] as UTF-8 text.
pub(crate) fn read_text(path: &Path) -> Result<String, crate::IoError> {
    crate::check_file(path)?;
    let io = |source| crate::IoError::Io {
        path: path.to_path_buf(),
        action: "read",
        source,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > MAX_SIDECAR_BYTES {
        return Err(BidsError::TooLarge {
            path: path.to_path_buf(),
            len,
            limit: MAX_SIDECAR_BYTES,
        }
        .into());
    }
    let bytes = std::fs::read(path).map_err(io)?;
    String::from_utf8(bytes).map_err(|e| {
        let before = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        BidsError::Table {
            path: path.to_path_buf(),
            line,
            column: String::new(),
            what: format!("not UTF-8 (byte offset {})", e.utf8_error().valid_up_to()),
        }
        .into()
    })
}

impl Table {
    /// Reads and checks a TSV file.
    pub fn read(path: &Path) -> Result<Self, crate::IoError> {
        let text = read_text(path)?;
        Ok(Self::parse(&text, path)?)
    }

    /// Parses TSV text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, BidsError> {
        let fault = |line: usize, column: &str, what: String| BidsError::Table {
            path: path.to_path_buf(),
            line,
            column: crate::error::bounded(column),
            what,
        };
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text.lines().enumerate();
        let Some((_, head)) = lines.next() else {
            return Err(fault(1, "", "empty file: no header line".into()));
        };
        let header: Vec<String> = head.split('\t').map(|s| s.trim().to_string()).collect();
        for (i, h) in header.iter().enumerate() {
            if h.is_empty() {
                return Err(fault(1, "", format!("header cell {} is empty", i + 1)));
            }
            if header[..i].contains(h) {
                return Err(fault(1, h, "column named twice".into()));
            }
        }
        let mut rows = Vec::new();
        for (i, line) in lines {
            if line.trim().is_empty() {
                continue;
            }
            let cells: Vec<String> = line.split('\t').map(|s| s.trim().to_string()).collect();
            if cells.len() != header.len() {
                return Err(fault(
                    i + 1,
                    "",
                    format!(
                        "{} cells in a table of {} columns",
                        cells.len(),
                        header.len()
                    ),
                ));
            }
            rows.push((i + 1, cells));
        }
        Ok(Self {
            path: path.to_path_buf(),
            header,
            rows,
        })
    }

    /// The index of `name`'s column, if the table has it.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The index of `name`'s column, or an error naming it.
    pub fn required(&self, name: &str) -> Result<usize, BidsError> {
        self.column(name).ok_or_else(|| BidsError::Table {
            path: self.path.clone(),
            line: 1,
            column: name.to_string(),
            what: format!(
                "required column missing (columns: {})",
                self.header.join(", ")
            ),
        })
    }

    /// An error at a row's cell.
    pub fn fault(&self, line: usize, column: usize, what: impl Into<String>) -> BidsError {
        BidsError::Table {
            path: self.path.clone(),
            line,
            column: self.header[column].clone(),
            what: what.into(),
        }
    }
}

/// TSV text from a header and rows; a cell may not hold a tab or a line break (the caller
/// replaces them).
pub(crate) fn format(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = header.join("\t");
    s.push('\n');
    for r in rows {
        s.push_str(&r.join("\t"));
        s.push('\n');
    }
    s
}

/// A text made safe for one TSV cell: control characters (tabs, line breaks) become spaces,
/// and an empty text `n/a`.
pub(crate) fn cell(text: &str) -> String {
    let t: String = text
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    let t = t.trim();
    if t.is_empty() {
        "n/a".into()
    } else {
        t.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_faults() {
        let p = Path::new("x.tsv");
        let t = Table::parse("onset\tvalue\n0.5\t3\n\n1.0\tn/a\n", p).unwrap();
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.rows[1].0, 4);
        assert_eq!(t.required("value").unwrap(), 1);
        let e = t.required("sample").unwrap_err().to_string();
        assert!(e.contains("x.tsv: line 1, column \"sample\""), "{e}");
        let e = Table::parse("a\tb\n1\n", p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("1 cells"), "{e}");
        assert!(Table::parse("a\ta\n", p).is_err());
        assert!(Table::parse("", p).is_err());
        assert_eq!(cell("a\tb\n"), "a b");
        assert_eq!(cell(" "), "n/a");
    }
}
