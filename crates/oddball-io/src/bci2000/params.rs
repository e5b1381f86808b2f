//! BCI2000 parameter lines: `Section Type Name= value(s) ... // comment`.
//!
//! Values are URL-encoded (`%20` is a space, a lone `%` is the empty string). A list is a count
//! (or a `{ label ... }` block that gives both the count and the labels) followed by the items;
//! a matrix is a row count or row-label block, a column count or column-label block, then the
//! cells row by row. A cell can itself be a `{ ... }` block (a sub-matrix), which is kept as its
//! decoded tokens. Whatever follows the value (a default, a low and a high bound in most
//! parameters) is kept in [`Parameter::trailing`].

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

/// One value of a parameter, list item or matrix cell.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamCell {
    /// A plain (URL-decoded) value.
    Value(String),
    /// A nested `{ ... }` block: its decoded tokens, inner braces included, outer braces not.
    Block(Vec<String>),
}

impl ParamCell {
    /// The text of a plain value; `None` for a nested block.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            ParamCell::Value(s) => Some(s),
            ParamCell::Block(_) => None,
        }
    }
}

/// The value of a parameter, by shape.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum ParamValue {
    /// `int`, `float`, `string`, `variant`, ...: one value (empty string when the line has none).
    Single(ParamCell),
    /// `list`, `intlist`, `floatlist`, `stringlist`, ...
    List {
        labels: Option<Vec<String>>,
        items: Vec<ParamCell>,
    },
    /// `matrix`: `rows.len()` rows of equal length.
    Matrix {
        row_labels: Option<Vec<String>>,
        col_labels: Option<Vec<String>>,
        n_cols: usize,
        rows: Vec<Vec<ParamCell>>,
    },
}

/// One parameter line of a BCI2000 header.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Parameter {
    /// URL-decoded section path, e.g. `Source:Signal Properties:DataIOFilter`.
    pub section: String,
    /// The type word: `int`, `float`, `string`, `list`, `intlist`, `floatlist`, `matrix`, ...
    pub kind: String,
    pub name: String,
    pub value: ParamValue,
    /// Decoded tokens after the value (usually default, low and high bounds).
    pub trailing: Vec<String>,
    /// The text after `//`, trimmed.
    pub comment: String,
    /// Byte offset of the line in the file.
    pub offset: u64,
}

impl Parameter {
    /// The single value's text (for `Single` parameters with a plain value).
    pub fn as_str(&self) -> Option<&str> {
        match &self.value {
            ParamValue::Single(c) => c.as_str(),
            _ => None,
        }
    }

    /// The items of a list as text (nested blocks are skipped).
    pub fn list_items(&self) -> Option<Vec<&str>> {
        match &self.value {
            ParamValue::List { items, .. } => {
                Some(items.iter().filter_map(|c| c.as_str()).collect())
            }
            _ => None,
        }
    }

    /// The cells of a matrix, row by row.
    pub fn matrix_rows(&self) -> Option<&[Vec<ParamCell>]> {
        match &self.value {
            ParamValue::Matrix { rows, .. } => Some(rows),
            _ => None,
        }
    }

    /// Every plain value as text: the single value, the list items, or the matrix cells row by row.
    pub fn values(&self) -> Vec<&str> {
        match &self.value {
            ParamValue::Single(c) => c.as_str().into_iter().collect(),
            ParamValue::List { items, .. } => items.iter().filter_map(|c| c.as_str()).collect(),
            ParamValue::Matrix { rows, .. } => rows
                .iter()
                .flat_map(|r| r.iter().filter_map(|c| c.as_str()))
                .collect(),
        }
    }
}

/// All parameters of a file, in file order, looked up by name (a later duplicate wins).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Parameters {
    list: Vec<Parameter>,
    by_name: HashMap<String, usize>,
}

impl Parameters {
    pub(crate) fn push(&mut self, p: Parameter) {
        self.by_name.insert(p.name.clone(), self.list.len());
        self.list.push(p);
    }

    /// The parameter called `name` (exact, case-sensitive, as BCI2000 does).
    pub fn get(&self, name: &str) -> Option<&Parameter> {
        self.by_name.get(name).map(|&i| &self.list[i])
    }

    /// All parameter lines in file order (duplicates included).
    pub fn iter(&self) -> std::slice::Iter<'_, Parameter> {
        self.list.iter()
    }

    pub fn len(&self) -> usize {
        self.list.len()
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The names, in file order.
    pub fn names(&self) -> Vec<&str> {
        self.list.iter().map(|p| p.name.as_str()).collect()
    }
}

/// Why a parameter line could not be parsed (turned into an [`crate::IoError`] by the caller).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ParamLineError {
    pub name: Option<String>,
    pub expected: String,
    pub found: String,
}

/// URL-decodes one token the way BCI2000 (and Python's `urllib.parse.unquote`) does: a lone
/// `%` is the empty string, `%XX` runs are bytes decoded as UTF-8 (invalid sequences become
/// U+FFFD), and a `%` not followed by two hex digits is kept as it is.
pub(crate) fn url_decode(tok: &str) -> String {
    if tok == "%" {
        return String::new();
    }
    if !tok.contains('%') {
        return tok.to_string();
    }
    let b = tok.as_bytes();
    let mut out = String::with_capacity(tok.len());
    let mut pending: Vec<u8> = Vec::new();
    let mut i = 0;
    let mut plain_start = 0;
    while i < b.len() {
        let escaped = if b[i] == b'%' && i + 2 < b.len() {
            hex(b[i + 1]).zip(hex(b[i + 2]))
        } else {
            None
        };
        match escaped {
            Some((hi, lo)) => {
                if plain_start < i {
                    flush(&mut out, &mut pending);
                    out.push_str(&tok[plain_start..i]);
                }
                pending.push(hi * 16 + lo);
                i += 3;
                plain_start = i;
            }
            None => i += 1,
        }
    }
    if plain_start < b.len() {
        flush(&mut out, &mut pending);
        out.push_str(&tok[plain_start..]);
    }
    flush(&mut out, &mut pending);
    out
}

fn flush(out: &mut String, pending: &mut Vec<u8>) {
    if !pending.is_empty() {
        out.push_str(&String::from_utf8_lossy(pending));
        pending.clear();
    }
}

fn hex(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Splits a value string into tokens; `{` and `}` become tokens of their own.
fn tokenize(s: &str) -> Vec<&str> {
    let mut toks = Vec::new();
    for word in s.split_whitespace() {
        let mut start = 0;
        for (i, ch) in word.char_indices() {
            if ch == '{' || ch == '}' {
                if start < i {
                    toks.push(&word[start..i]);
                }
                toks.push(&word[i..i + 1]);
                start = i + 1;
            }
        }
        if start < word.len() {
            toks.push(&word[start..]);
        }
    }
    toks
}

struct Cursor<'a> {
    toks: Vec<&'a str>,
    i: usize,
    name: String,
}

impl<'a> Cursor<'a> {
    fn err(&self, expected: impl Into<String>, found: impl Into<String>) -> ParamLineError {
        ParamLineError {
            name: Some(self.name.clone()),
            expected: expected.into(),
            found: crate::error::bounded(&found.into()),
        }
    }

    fn peek(&self) -> Option<&'a str> {
        self.toks.get(self.i).copied()
    }

    fn remaining(&self) -> usize {
        self.toks.len() - self.i
    }

    /// A dimension: a non-negative integer count, or a `{ label ... }` block.
    fn dimension(&mut self, what: &str) -> Result<(usize, Option<Vec<String>>), ParamLineError> {
        match self.peek() {
            None => Err(self.err(
                format!("{what} (a count or a {{ label }} list)"),
                "end of line",
            )),
            Some("{") => {
                let close = self.toks[self.i..]
                    .iter()
                    .position(|t| *t == "}")
                    .map(|p| self.i + p)
                    .ok_or_else(|| {
                        self.err(format!("`}}` closing the {what} labels"), "end of line")
                    })?;
                let labels: Vec<String> = self.toks[self.i + 1..close]
                    .iter()
                    .map(|t| url_decode(t))
                    .collect();
                self.i = close + 1;
                Ok((labels.len(), Some(labels)))
            }
            Some(t) => {
                let n: usize = t
                    .parse()
                    .map_err(|_| self.err(format!("{what} as a non-negative integer"), t))?;
                self.i += 1;
                Ok((n, None))
            }
        }
    }

    /// One value; a `{ ... }` here is a nested block, kept with its inner braces.
    fn cell(&mut self) -> Result<ParamCell, ParamLineError> {
        match self.peek() {
            None => Err(self.err("a value", "end of line")),
            Some("{") => {
                let mut depth = 0usize;
                let mut j = self.i;
                loop {
                    match self.toks.get(j) {
                        None => return Err(self.err("`}` closing a nested block", "end of line")),
                        Some(&"{") => depth += 1,
                        Some(&"}") => {
                            depth -= 1;
                            if depth == 0 {
                                break;
                            }
                        }
                        Some(_) => {}
                    }
                    j += 1;
                }
                let inner = self.toks[self.i + 1..j]
                    .iter()
                    .map(|t| url_decode(t))
                    .collect();
                self.i = j + 1;
                Ok(ParamCell::Block(inner))
            }
            Some("}") => Err(self.err("a value", "`}` without a matching `{`")),
            Some(t) => {
                self.i += 1;
                Ok(ParamCell::Value(url_decode(t)))
            }
        }
    }

    fn cells(&mut self, n: usize, what: &str) -> Result<Vec<ParamCell>, ParamLineError> {
        // A value takes at least one token: refuse absurd counts before allocating.
        if n > self.remaining() {
            return Err(self.err(
                format!("{n} {what}"),
                format!("only {} tokens left on the line", self.remaining()),
            ));
        }
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            out.push(self.cell()?);
        }
        Ok(out)
    }
}

/// Finds the `//` that starts the comment: the first one at the start of the value text or
/// after whitespace (so a value like `http://host` keeps its slashes).
fn comment_start(s: &str) -> Option<usize> {
    let b = s.as_bytes();
    (0..b.len().saturating_sub(1))
        .find(|&i| b[i] == b'/' && b[i + 1] == b'/' && (i == 0 || b[i - 1].is_ascii_whitespace()))
}

/// Parses one parameter line. `offset` is the line's byte offset in the file.
pub(crate) fn parse_parameter_line(line: &str, offset: u64) -> Result<Parameter, ParamLineError> {
    let bad = |expected: &str| ParamLineError {
        name: None,
        expected: expected.to_string(),
        found: line.chars().take(120).collect(),
    };
    let line = line.trim();
    let (section, rest) = line
        .split_once(char::is_whitespace)
        .ok_or_else(|| bad("`Section Type Name= value`"))?;
    let rest = rest.trim_start();
    let (kind, rest) = rest
        .split_once(char::is_whitespace)
        .ok_or_else(|| bad("`Section Type Name= value`"))?;
    let rest = rest.trim_start();
    let eq = rest
        .find('=')
        .ok_or_else(|| bad("`Name=` after the section and type"))?;
    let name = rest[..eq].trim();
    if name.is_empty() || name.contains(char::is_whitespace) {
        return Err(bad("a parameter name without spaces before `=`"));
    }
    let rest = &rest[eq + 1..];
    let (value_text, comment) = match comment_start(rest) {
        Some(i) => (&rest[..i], rest[i + 2..].trim()),
        None => (rest, ""),
    };
    let mut cur = Cursor {
        toks: tokenize(value_text),
        i: 0,
        name: name.to_string(),
    };
    let value = if kind.ends_with("list") {
        let (n, labels) = cur.dimension("item count")?;
        let items = cur.cells(n, "list items")?;
        ParamValue::List { labels, items }
    } else if kind == "matrix" {
        let (nr, row_labels) = cur.dimension("row count")?;
        let (nc, col_labels) = cur.dimension("column count")?;
        let total = nr
            .checked_mul(nc)
            .ok_or_else(|| cur.err("a matrix size that fits in memory", format!("{nr} x {nc}")))?;
        if total > cur.remaining() {
            return Err(cur.err(
                format!("{nr} x {nc} = {total} matrix cells"),
                format!("only {} tokens left on the line", cur.remaining()),
            ));
        }
        let mut rows = Vec::with_capacity(nr);
        for _ in 0..nr {
            rows.push(cur.cells(nc, "matrix cells")?);
        }
        ParamValue::Matrix {
            row_labels,
            col_labels,
            n_cols: nc,
            rows,
        }
    } else if cur.peek().is_none() {
        ParamValue::Single(ParamCell::Value(String::new()))
    } else {
        ParamValue::Single(cur.cell()?)
    };
    let trailing = cur.toks[cur.i..].iter().map(|t| url_decode(t)).collect();
    Ok(Parameter {
        section: url_decode(section),
        kind: kind.to_string(),
        name: name.to_string(),
        value,
        trailing,
        comment: comment.to_string(),
        offset,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(line: &str) -> Parameter {
        parse_parameter_line(line, 0).unwrap()
    }

    #[test]
    fn decodes_url_escapes() {
        assert_eq!(url_decode("%"), "");
        assert_eq!(url_decode("Thu%20Mar%2005"), "Thu Mar 05");
        assert_eq!(url_decode("100%"), "100%");
        assert_eq!(url_decode("%zz1"), "%zz1");
        assert_eq!(url_decode("%C3%A9t%C3%A9"), "été");
        assert_eq!(url_decode("a%2"), "a%2");
    }

    #[test]
    fn single_values() {
        let q = p("Source:Signal%20Properties:DataIOFilter int SamplingRate= 256 256Hz 1 % // sample rate");
        assert_eq!(q.section, "Source:Signal Properties:DataIOFilter");
        assert_eq!(q.kind, "int");
        assert_eq!(q.name, "SamplingRate");
        assert_eq!(q.as_str(), Some("256"));
        assert_eq!(q.trailing, vec!["256Hz", "1", ""]);
        assert_eq!(q.comment, "sample rate");
        let q = p("Application:Speller:P3SpellerTask string TextResult= % // user spelling result");
        assert_eq!(q.as_str(), Some(""));
        let q = p("Storage string StorageTime= Thu%20Mar%2005%2011:56:24%202009 // time");
        assert_eq!(q.as_str(), Some("Thu Mar 05 11:56:24 2009"));
        let q = p("X string Url= http://host/a // where");
        assert_eq!(q.as_str(), Some("http://host/a"));
        assert_eq!(q.comment, "where");
        let q = p("X string Empty=");
        assert_eq!(q.as_str(), Some(""));
    }

    #[test]
    fn lists() {
        let q = p("S list ChannelNames= 3 Fz Cz P%203 // names");
        assert_eq!(q.list_items().unwrap(), vec!["Fz", "Cz", "P 3"]);
        let q = p("S floatlist SourceChOffset= 2 0 1.5 0 % % // x");
        assert_eq!(q.list_items().unwrap(), vec!["0", "1.5"]);
        assert_eq!(q.trailing, vec!["0", "", ""]);
        let q = p("S intlist L= { a b } 1 2 //");
        match &q.value {
            ParamValue::List { labels, items } => {
                assert_eq!(
                    labels.as_deref(),
                    Some(&["a".to_string(), "b".to_string()][..])
                );
                assert_eq!(items.len(), 2);
            }
            v => panic!("not a list: {v:?}"),
        }
        let q = p("Connector:ConnectorInput list ConnectorInputFilter= 0 // list");
        assert_eq!(q.list_items().unwrap(), Vec::<&str>::new());
    }

    #[test]
    fn matrices() {
        let q = p("System:Configuration matrix SignalSourceVersion= { Framework Revision Build } 1 2.x % Feb%2017%202009 // v");
        match &q.value {
            ParamValue::Matrix {
                row_labels,
                col_labels,
                n_cols,
                rows,
            } => {
                assert_eq!(row_labels.as_ref().unwrap().len(), 3);
                assert!(col_labels.is_none());
                assert_eq!(*n_cols, 1);
                assert_eq!(rows.len(), 3);
                assert_eq!(rows[2][0].as_str(), Some("Feb 17 2009"));
                assert_eq!(rows[1][0].as_str(), Some(""));
            }
            v => panic!("not a matrix: {v:?}"),
        }
        let q = p("L matrix LocalizedStrings= { German } { TIME%20OUT%20!!! Waiting%20to%20start%20... } Zeit%20abgelaufen! Warte%20... // m");
        let rows = q.matrix_rows().unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0][1].as_str(), Some("Warte ..."));
        let q = p("A matrix M= 2 2 a { matrix 1 1 { x } } c d // nested");
        let rows = q.matrix_rows().unwrap();
        assert_eq!(
            rows[0][1],
            ParamCell::Block(vec![
                "matrix".into(),
                "1".into(),
                "1".into(),
                "{".into(),
                "x".into(),
                "}".into()
            ])
        );
        assert_eq!(rows[1][1].as_str(), Some("d"));
    }

    #[test]
    fn malformed_lines() {
        assert!(parse_parameter_line("justone", 0).is_err());
        assert!(parse_parameter_line("S int NoEquals 5", 0).is_err());
        let e = parse_parameter_line("S list L= 5 a b // short", 0).unwrap_err();
        assert_eq!(e.name.as_deref(), Some("L"));
        assert!(e.expected.contains("5 list items"), "{e:?}");
        let e = parse_parameter_line("S list L= x a b", 0).unwrap_err();
        assert!(e.expected.contains("non-negative integer"), "{e:?}");
        let e = parse_parameter_line("S matrix M= 1000000 1000000 a", 0).unwrap_err();
        assert!(e.expected.contains("matrix cells"), "{e:?}");
        let e = parse_parameter_line("S matrix M= { a b 1 x", 0).unwrap_err();
        assert!(e.expected.contains("`}`"), "{e:?}");
        let e = parse_parameter_line("S matrix M= 1 1 { a", 0).unwrap_err();
        assert!(e.expected.contains("`}`"), "{e:?}");
        let e = parse_parameter_line("S list L= 18446744073709551616 a", 0).unwrap_err();
        assert!(e.expected.contains("integer"), "{e:?}");
    }
}
