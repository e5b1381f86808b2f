//! The row/column P300 speller layout of a recording, and decoding spelled text from target events.
//!
//! Stimulus codes follow BCI2000's P3Speller by default ([`CodeOrder::RowsFirst`]): rows are
//! flashed with codes `1..=n_rows` (top to bottom), columns with `n_rows + 1..=n_rows + n_cols`
//! (left to right). For the BCI2000 sample files eeg3_* that is rows 1–6 and columns 7–12. BCI
//! Competition II/III files use the opposite order ([`CodeOrder::ColumnsFirst`]: columns 1–6,
//! rows 7–12).

use std::collections::BTreeMap;

use oddball_signal::{Event, Events};
use serde::{Deserialize, Serialize};

/// A spelled text that does not fit a recording ([`Speller::label_from_text`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TextLabelError {
    #[error("the text {text:?} has {symbols} symbols but the recording has {blocks} characters")]
    Length {
        blocks: usize,
        symbols: usize,
        text: String,
    },
    #[error("symbol {index} of the text, {symbol:?}, is not in the speller matrix")]
    NotInMatrix { symbol: String, index: usize },
}

/// The character written by [`Speller::decode`] for a block whose target row or column is unknown.
pub const UNDECIDED: char = '\u{FFFD}';

/// Which stimulus codes flash rows and which flash columns.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum CodeOrder {
    /// BCI2000's P3Speller: rows `1..=n_rows`, then columns `n_rows + 1..=n_rows + n_cols`.
    #[default]
    RowsFirst,
    /// BCI Competition II/III: columns `1..=n_cols`, then rows `n_cols + 1..=n_cols + n_rows`.
    ColumnsFirst,
}

/// A speller matrix (`n_rows × n_cols` symbols) and how a recording flashed it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Speller {
    matrix: Vec<Vec<String>>,
    /// The text the user was asked to copy (BCI2000 `TextToSpell`), if any.
    pub text_to_spell: Option<String>,
    /// Flashes (events) per character: BCI2000 `NumberOfSequences × (n_rows + n_cols)`.
    /// `None` when the recording does not say; [`Speller::decode`] then treats all events as
    /// one character.
    pub flashes_per_character: Option<usize>,
    /// Which codes are rows and which columns.
    #[serde(default)]
    pub code_order: CodeOrder,
}

impl Speller {
    /// A speller from its rows of symbols. `None` when there are no rows, no columns, or the
    /// rows differ in length.
    pub fn new(
        matrix: Vec<Vec<String>>,
        text_to_spell: Option<String>,
        flashes_per_character: Option<usize>,
    ) -> Option<Self> {
        let n_cols = matrix.first()?.len();
        if n_cols == 0 || matrix.iter().any(|r| r.len() != n_cols) {
            return None;
        }
        Some(Self {
            matrix,
            text_to_spell,
            flashes_per_character,
            code_order: CodeOrder::RowsFirst,
        })
    }

    /// A speller from `n_rows` strings of one-character symbols, e.g. `["ABCDEF", "GHIJKL", ...]`.
    pub fn from_rows<S: AsRef<str>>(rows: &[S]) -> Option<Self> {
        let matrix = rows
            .iter()
            .map(|r| r.as_ref().chars().map(String::from).collect())
            .collect();
        Self::new(matrix, None, None)
    }

    /// The symbols, `n_rows` rows of `n_cols`.
    pub fn matrix(&self) -> &[Vec<String>] {
        &self.matrix
    }

    pub fn n_rows(&self) -> usize {
        self.matrix.len()
    }

    pub fn n_cols(&self) -> usize {
        self.matrix[0].len()
    }

    /// The code of the first row and of the first column.
    fn first_codes(&self) -> (usize, usize) {
        match self.code_order {
            CodeOrder::RowsFirst => (1, self.n_rows() + 1),
            CodeOrder::ColumnsFirst => (self.n_cols() + 1, 1),
        }
    }

    /// The stimulus code that flashes row `row` (0-based): `row + 1` (rows first), or
    /// `n_cols + row + 1` (columns first).
    pub fn code_of_row(&self, row: usize) -> u32 {
        (self.first_codes().0 + row) as u32
    }

    /// The stimulus code that flashes column `col` (0-based): `n_rows + col + 1` (rows first),
    /// or `col + 1` (columns first).
    pub fn code_of_col(&self, col: usize) -> u32 {
        (self.first_codes().1 + col) as u32
    }

    /// The row (0-based) a stimulus code flashes, if it is a row code.
    pub fn row_of_code(&self, code: u32) -> Option<usize> {
        let c = code as usize;
        let first = self.first_codes().0;
        (first..first + self.n_rows())
            .contains(&c)
            .then(|| c - first)
    }

    /// The column (0-based) a stimulus code flashes, if it is a column code.
    pub fn col_of_code(&self, code: u32) -> Option<usize> {
        let c = code as usize;
        let first = self.first_codes().1;
        (first..first + self.n_cols())
            .contains(&c)
            .then(|| c - first)
    }

    /// The symbol at `(row, col)`, 0-based.
    pub fn symbol(&self, row: usize, col: usize) -> Option<&str> {
        self.matrix.get(row)?.get(col).map(String::as_str)
    }

    /// Where `symbol` is in the matrix, `(row, col)`.
    pub fn position(&self, symbol: &str) -> Option<(usize, usize)> {
        self.matrix
            .iter()
            .enumerate()
            .find_map(|(r, row)| row.iter().position(|s| s == symbol).map(|c| (r, c)))
    }

    /// The events of each character: consecutive blocks of `flashes_per_character` events
    /// (the last may be shorter), or one block of all events when that is unknown.
    pub fn character_blocks<'a>(&self, events: &'a Events) -> Vec<&'a [Event]> {
        let all = events.as_slice();
        match self.flashes_per_character {
            Some(n) if n > 0 => all.chunks(n).collect(),
            _ if all.is_empty() => Vec::new(),
            _ => vec![all],
        }
    }

    /// The symbol of each character block: the row and column whose codes occur most often
    /// among the block's target events (`target == Some(true)`); ties go to the lower code.
    /// `None` for a block with no target row or no target column.
    pub fn decode_blocks(&self, events: &Events) -> Vec<Option<String>> {
        self.character_blocks(events)
            .into_iter()
            .map(|block| {
                let mut rows: BTreeMap<usize, usize> = BTreeMap::new();
                let mut cols: BTreeMap<usize, usize> = BTreeMap::new();
                for e in block.iter().filter(|e| e.target == Some(true)) {
                    if let Some(r) = self.row_of_code(e.code) {
                        *rows.entry(r).or_default() += 1;
                    } else if let Some(c) = self.col_of_code(e.code) {
                        *cols.entry(c).or_default() += 1;
                    }
                }
                let best = |m: &BTreeMap<usize, usize>| {
                    m.iter()
                        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                        .map(|(&k, _)| k)
                };
                let (r, c) = (best(&rows)?, best(&cols)?);
                self.symbol(r, c).map(str::to_string)
            })
            .collect()
    }

    /// The events with target flags from the text that was spelled (for runs recorded without
    /// labels, e.g. a competition's test runs): in character block `k`, a flash is a target when
    /// its row or column holds the `k`-th symbol of `text`. Events that flash no row or column
    /// keep their flag.
    pub fn label_from_text(&self, events: &Events, text: &str) -> Result<Events, TextLabelError> {
        let symbols: Vec<String> = text.chars().map(String::from).collect();
        let blocks = self.character_blocks(events);
        if blocks.len() != symbols.len() {
            return Err(TextLabelError::Length {
                blocks: blocks.len(),
                symbols: symbols.len(),
                text: text.chars().take(80).collect(),
            });
        }
        let mut out = Vec::with_capacity(events.len());
        for (k, (block, sym)) in blocks.iter().zip(&symbols).enumerate() {
            let (r, c) = self
                .position(sym)
                .ok_or_else(|| TextLabelError::NotInMatrix {
                    symbol: sym.clone(),
                    index: k,
                })?;
            for e in block.iter() {
                let target = if let Some(row) = self.row_of_code(e.code) {
                    Some(row == r)
                } else {
                    self.col_of_code(e.code).map(|col| col == c).or(e.target)
                };
                let mut e = e.clone();
                e.target = target;
                out.push(e);
            }
        }
        Ok(Events::new(out))
    }

    /// The spelled text: the symbols of [`Speller::decode_blocks`] joined, with [`UNDECIDED`]
    /// for a block that has no target row or column.
    pub fn decode(&self, events: &Events) -> String {
        self.decode_blocks(events)
            .into_iter()
            .map(|s| s.unwrap_or_else(|| UNDECIDED.to_string()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_from_the_spelled_text_decode_back_to_it() {
        let s = speller();
        let labelled = events_for(&s, "Q7");
        let bare = Events::new(
            labelled
                .iter()
                .map(|e| Event::new(e.onset, e.code))
                .collect(),
        );
        let relabelled = s.label_from_text(&bare, "Q7").unwrap();
        assert_eq!(relabelled, labelled);
        assert_eq!(s.decode(&relabelled), "Q7");
        assert!(matches!(
            s.label_from_text(&bare, "Q"),
            Err(TextLabelError::Length {
                blocks: 2,
                symbols: 1,
                ..
            })
        ));
        assert!(matches!(
            s.label_from_text(&bare, "Q!"),
            Err(TextLabelError::NotInMatrix { index: 1, .. })
        ));
    }

    fn speller() -> Speller {
        let mut s =
            Speller::from_rows(&["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789?"])
                .unwrap();
        s.flashes_per_character = Some(24);
        s
    }

    /// Two sequences of 12 flashes for each character, targets flagged.
    fn events_for(s: &Speller, text: &str) -> Events {
        let mut ev = Vec::new();
        let mut t = 0;
        for ch in text.chars() {
            let (r, c) = s.position(&ch.to_string()).unwrap();
            for _seq in 0..2 {
                for code in 1..=12u32 {
                    let target = code == s.code_of_row(r) || code == s.code_of_col(c);
                    ev.push(Event::new(t, code).with_target(target));
                    t += 10;
                }
            }
        }
        Events::new(ev)
    }

    #[test]
    fn codes_and_symbols() {
        let s = speller();
        assert_eq!((s.n_rows(), s.n_cols()), (6, 6));
        assert_eq!(s.code_of_row(0), 1);
        assert_eq!(s.code_of_col(0), 7);
        assert_eq!(s.code_of_col(5), 12);
        assert_eq!(s.row_of_code(6), Some(5));
        assert_eq!(s.row_of_code(7), None);
        assert_eq!(s.col_of_code(7), Some(0));
        assert_eq!(s.col_of_code(13), None);
        assert_eq!(s.col_of_code(0), None);
        assert_eq!(s.symbol(3, 1), Some("T"));
        assert_eq!(s.symbol(5, 5), Some("?"));
        assert_eq!(s.symbol(6, 0), None);
        assert_eq!(s.position("?"), Some((5, 5)));
    }

    #[test]
    fn decodes_text() {
        let s = speller();
        for text in ["T3OF", "6MK?", "AA", "AB"] {
            assert_eq!(s.decode(&events_for(&s, text)), text);
        }
    }

    #[test]
    fn undecided_blocks() {
        let s = speller();
        let ev: Events = events_for(&s, "HI")
            .iter()
            .map(|e| Event::new(e.onset, e.code))
            .collect();
        assert_eq!(s.decode(&ev), format!("{UNDECIDED}{UNDECIDED}"));
        assert_eq!(s.decode(&Events::default()), "");
    }

    #[test]
    fn columns_first_codes() {
        let mut s = speller();
        s.code_order = CodeOrder::ColumnsFirst;
        assert_eq!(s.code_of_col(0), 1);
        assert_eq!(s.code_of_col(5), 6);
        assert_eq!(s.code_of_row(0), 7);
        assert_eq!(s.code_of_row(5), 12);
        assert_eq!(s.col_of_code(6), Some(5));
        assert_eq!(s.col_of_code(7), None);
        assert_eq!(s.row_of_code(7), Some(0));
        assert_eq!(s.row_of_code(13), None);
        assert_eq!(s.row_of_code(0), None);
        for text in ["T3OF", "6MK?", "AB"] {
            assert_eq!(s.decode(&events_for(&s, text)), text);
        }
    }

    #[test]
    fn rejects_ragged_matrices() {
        assert!(Speller::from_rows(&["AB", "C"]).is_none());
        assert!(Speller::from_rows::<&str>(&[]).is_none());
        assert!(Speller::from_rows(&[""]).is_none());
    }
}
