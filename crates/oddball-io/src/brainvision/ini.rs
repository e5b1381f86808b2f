//! The INI-like text of `.vhdr` and `.vmrk` files: the identification line, `[Section]`s,
//! `Key=Value` entries, `;` comments; the text encoding (`Codepage=`); every value kept with
//! the byte offset it starts at, so that errors can name it.

use std::path::Path;

use crate::IoError;

/// How the bytes of a header or marker file are turned into text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Encoding {
    Utf8,
    Latin1,
    /// Windows-1252, BrainVision Recorder's `Codepage=ANSI`.
    Cp1252,
}

/// Windows-1252 at 0x80..=0x9F (the five bytes it leaves undefined kept as Latin-1).
const CP1252_HIGH: [char; 32] = [
    '€', '\u{81}', '‚', 'ƒ', '„', '…', '†', '‡', 'ˆ', '‰', 'Š', '‹', 'Œ', '\u{8d}', 'Ž', '\u{8f}',
    '\u{90}', '‘', '’', '“', '”', '•', '–', '—', '˜', '™', 'š', '›', 'œ', '\u{9d}', 'ž', 'Ÿ',
];

impl Encoding {
    /// The encoding of `bytes`: the `Codepage=` line's (`UTF-8`, `ANSI`/`cp1252`,
    /// `Latin-1`/`ISO-8859-1`), UTF-8 without one; text that is not valid UTF-8 is read as
    /// Latin-1 (the older recorders' implicit encoding), as MNE does.
    fn detect(bytes: &[u8]) -> Self {
        let declared = bytes.split(|&b| b == b'\n').find_map(|line| {
            let eq = line.iter().position(|&b| b == b'=')?;
            let key = String::from_utf8_lossy(&line[..eq]);
            key.trim().eq_ignore_ascii_case("codepage").then(|| {
                String::from_utf8_lossy(&line[eq + 1..])
                    .trim()
                    .to_ascii_lowercase()
            })
        });
        match declared.as_deref() {
            Some("ansi" | "cp1252" | "windows-1252") => Self::Cp1252,
            Some("latin-1" | "latin1" | "iso-8859-1") => Self::Latin1,
            _ if std::str::from_utf8(bytes).is_ok() => Self::Utf8,
            _ => Self::Latin1,
        }
    }

    pub(super) fn decode(self, b: &[u8]) -> String {
        match self {
            Self::Utf8 => String::from_utf8_lossy(b).into_owned(),
            Self::Latin1 => b.iter().map(|&c| c as char).collect(),
            Self::Cp1252 => b
                .iter()
                .map(|&c| match c {
                    0x80..=0x9F => CP1252_HIGH[usize::from(c - 0x80)],
                    _ => c as char,
                })
                .collect(),
        }
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Self::Utf8 => "UTF-8",
            Self::Latin1 => "Latin-1",
            Self::Cp1252 => "cp1252",
        }
    }
}

/// One `Key=Value` line.
pub(super) struct Entry {
    /// The section it is in, as written.
    pub(super) section: String,
    pub(super) key: String,
    /// The value's bytes after `=`, the line end (`\r`) removed.
    pub(super) value: Vec<u8>,
    /// Byte offset of the value in the file.
    pub(super) value_at: usize,
}

/// One comma-separated field of a value: its text and its byte offset in the file.
pub(super) struct Field {
    pub(super) text: String,
    pub(super) at: usize,
}

/// A parsed `.vhdr` or `.vmrk` file.
pub(super) struct Ini<'a> {
    pub(super) path: &'a Path,
    pub(super) encoding: Encoding,
    pub(super) first_line: String,
    pub(super) entries: Vec<Entry>,
}

/// Parses a header (`kind` = `"Header"`) or marker (`"Marker"`) file. The first line must
/// identify it: `Brain Vision Data Exchange Header File Version 1.0` and the spellings MNE
/// accepts (`BrainVision`, `Core`, `V-Amp`, no `Exchange`, a comma, version 2.0).
pub(super) fn parse<'a>(bytes: &[u8], path: &'a Path, kind: &str) -> Result<Ini<'a>, IoError> {
    let encoding = Encoding::detect(bytes);
    let start = if bytes.starts_with(b"\xEF\xBB\xBF") {
        3
    } else {
        0
    };
    let mut lines = Lines { bytes, at: start };
    let (first_at, first) = lines.next().unwrap_or((start, &[]));
    let first_line = encoding.decode(first).trim().to_string();
    let squeezed: String = first_line
        .chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect();
    let wanted = format!("{}file", kind.to_ascii_lowercase());
    if !squeezed.starts_with("brainvision") || !squeezed.contains(&wanted) {
        return Err(IoError::invalid_field(
            path,
            "identification line",
            first_at as u64,
            format!("`Brain Vision Data Exchange {kind} File Version 1.0`"),
            first_line,
        ));
    }
    let mut section = String::new();
    let mut entries = Vec::new();
    for (at, line) in lines {
        let trimmed = trim(line);
        if trimmed.is_empty() || trimmed[0] == b';' {
            continue;
        }
        if trimmed[0] == b'[' {
            if trimmed.last() != Some(&b']') {
                return Err(IoError::invalid_field(
                    path,
                    "section name",
                    at as u64,
                    "`[Name]`",
                    encoding.decode(trimmed),
                ));
            }
            section = encoding
                .decode(&trimmed[1..trimmed.len() - 1])
                .trim()
                .to_string();
            continue;
        }
        // Lines without `=` (the free text of `[Comment]`) are no settings.
        let Some(eq) = line.iter().position(|&b| b == b'=') else {
            continue;
        };
        let mut value = &line[eq + 1..];
        while let [rest @ .., b'\r'] = value {
            value = rest;
        }
        entries.push(Entry {
            section: section.clone(),
            key: encoding.decode(trim(&line[..eq])),
            value: value.to_vec(),
            value_at: at + eq + 1,
        });
    }
    Ok(Ini {
        path,
        encoding,
        first_line,
        entries,
    })
}

fn trim(mut b: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = b {
        if !first.is_ascii_whitespace() {
            break;
        }
        b = rest;
    }
    while let [rest @ .., last] = b {
        if !last.is_ascii_whitespace() {
            break;
        }
        b = rest;
    }
    b
}

/// Lines of a byte buffer with their byte offsets (`\n` ends a line).
struct Lines<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.at >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.at..];
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let start = self.at;
        self.at += len + 1;
        let mut line = &rest[..len];
        while let [head @ .., b'\r'] = line {
            line = head;
        }
        Some((start, line))
    }
}

impl Ini<'_> {
    /// The entries of `section` (any letter case), in file order.
    pub(super) fn section<'s>(&'s self, section: &'s str) -> impl Iterator<Item = &'s Entry> {
        self.entries
            .iter()
            .filter(move |e| e.section.eq_ignore_ascii_case(section))
    }

    /// The first entry `key` of `section` (any letter case).
    pub(super) fn get(&self, section: &str, key: &str) -> Option<&Entry> {
        self.entries
            .iter()
            .find(|e| e.section.eq_ignore_ascii_case(section) && e.key.eq_ignore_ascii_case(key))
    }

    /// The trimmed text of `key` in `section`, or an error naming both.
    pub(super) fn require(&self, section: &str, key: &str) -> Result<(String, usize), IoError> {
        match self.get(section, key) {
            Some(e) => Ok((self.text(e), e.value_at)),
            None => Err(self.missing(section, key)),
        }
    }

    /// The error of a missing `key` in `section`, listing the keys there are.
    pub(super) fn missing(&self, section: &str, key: &str) -> IoError {
        IoError::Missing {
            path: self.path.to_path_buf(),
            what: "BrainVision setting",
            name: format!("[{section}] {key}"),
            available: self
                .section(section)
                .map(|e| e.key.clone())
                .take(20)
                .collect(),
        }
    }

    /// An entry's value as trimmed text.
    pub(super) fn text(&self, e: &Entry) -> String {
        self.encoding.decode(trim(&e.value))
    }

    /// An entry's comma-separated fields, `\1` turned back into commas, each with its offset.
    /// The value is trimmed first (as Python's `configparser` trims it for MNE).
    pub(super) fn fields(&self, e: &Entry) -> Vec<Field> {
        let lead = e
            .value
            .iter()
            .take_while(|b| b.is_ascii_whitespace())
            .count();
        let value = trim(&e.value);
        let mut out = Vec::new();
        let mut start = lead;
        for (i, part) in value.split(|&b| b == b',').enumerate() {
            if i > 0 {
                start += 1;
            }
            out.push(Field {
                text: self.encoding.decode(part).replace("\\1", ","),
                at: e.value_at + start,
            });
            start += part.len();
        }
        out
    }

    pub(super) fn invalid(
        &self,
        field: impl Into<String>,
        at: usize,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> IoError {
        IoError::invalid_field(self.path, field, at as u64, expected, found)
    }
}
