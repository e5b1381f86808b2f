//! FIF tags: the 16-byte headers, the chain of tags through the file (`next`), the block tree
//! (`FIFF_BLOCK_START` / `FIFF_BLOCK_END`), and the typed reading of a tag's data.

use crate::IoError;

/// Tag kinds (`FIFF_*` in MNE's `_fiff/constants.py`).
pub(super) mod kind {
    pub const FILE_ID: i32 = 100;
    pub const DIR_POINTER: i32 = 101;
    pub const BLOCK_START: i32 = 104;
    pub const BLOCK_END: i32 = 105;
    pub const REF_ROLE: i32 = 115;
    pub const REF_FILE_NAME: i32 = 118;
    pub const NCHAN: i32 = 200;
    pub const SFREQ: i32 = 201;
    pub const CH_INFO: i32 = 203;
    pub const MEAS_DATE: i32 = 204;
    pub const COMMENT: i32 = 206;
    pub const FIRST_SAMPLE: i32 = 208;
    pub const CH_SCAN_NO: i32 = 250;
    pub const CH_LOGICAL_NO: i32 = 251;
    pub const CH_KIND: i32 = 252;
    pub const CH_RANGE: i32 = 253;
    pub const CH_CAL: i32 = 254;
    pub const CH_UNIT: i32 = 256;
    pub const CH_UNIT_MUL: i32 = 257;
    pub const CH_DACQ_NAME: i32 = 258;
    pub const DATA_BUFFER: i32 = 300;
    pub const DATA_SKIP: i32 = 301;
    pub const CH_COIL_TYPE: i32 = 350;
    pub const MNE_BASELINE_MIN: i32 = 3568;
    pub const MNE_BASELINE_MAX: i32 = 3569;
}

/// Block kinds (`FIFFB_*`).
pub(super) mod block {
    pub const ROOT: i32 = 999;
    pub const MEAS: i32 = 100;
    pub const MEAS_INFO: i32 = 101;
    pub const RAW_DATA: i32 = 102;
    pub const CONTINUOUS_DATA: i32 = 112;
    pub const CH_INFO: i32 = 113;
    pub const REF: i32 = 118;
    pub const IAS_RAW_DATA: i32 = 119;
    pub const MNE_ANNOTATIONS: i32 = 3810;
}

/// Data types (`FIFFT_*`).
pub(super) mod ty {
    pub const SHORT: u32 = 2;
    pub const INT: u32 = 3;
    pub const FLOAT: u32 = 4;
    pub const DOUBLE: u32 = 5;
    pub const STRING: u32 = 10;
    pub const DAU_PACK16: u32 = 16;
    pub const COMPLEX_FLOAT: u32 = 20;
    pub const COMPLEX_DOUBLE: u32 = 21;
    pub const CH_INFO_STRUCT: u32 = 30;
    pub const ID_STRUCT: u32 = 31;
}

/// Blocks nested deeper than this are refused (MNE's files nest four deep).
pub(super) const MAX_DEPTH: usize = 64;

/// A block kind as MNE names it, for messages.
pub(super) fn block_name(k: i32) -> String {
    let name = match k {
        block::ROOT => "root",
        block::MEAS => "FIFFB_MEAS",
        block::MEAS_INFO => "FIFFB_MEAS_INFO",
        block::RAW_DATA => "FIFFB_RAW_DATA",
        block::CONTINUOUS_DATA => "FIFFB_CONTINUOUS_DATA",
        block::CH_INFO => "FIFFB_CH_INFO",
        block::REF => "FIFFB_REF",
        block::IAS_RAW_DATA => "FIFFB_IAS_RAW_DATA",
        block::MNE_ANNOTATIONS => "FIFFB_MNE_ANNOTATIONS",
        _ => return format!("block {k}"),
    };
    format!("{name} ({k})")
}

/// One tag: its header at byte `pos`, its data at `pos + 16 .. pos + 16 + size`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Tag {
    pub kind: i32,
    pub ty: u32,
    pub size: usize,
    pub pos: usize,
}

impl Tag {
    pub fn data_pos(&self) -> usize {
        self.pos + 16
    }
}

/// A block: its kind, the byte of its `FIFF_BLOCK_START` tag, its own tags, its sub-blocks.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Node {
    pub kind: i32,
    pub start: usize,
    pub tags: Vec<Tag>,
    pub children: Vec<Node>,
}

impl Node {
    /// Every block of kind `k` at or below this one, depth first in file order.
    pub fn find(&self, k: i32) -> Vec<&Node> {
        let mut out = Vec::new();
        let mut stack = vec![self];
        while let Some(n) = stack.pop() {
            if n.kind == k {
                out.push(n);
            }
            stack.extend(n.children.iter().rev());
        }
        out
    }
}

/// The file's bytes and path ([`crate::bytes::FileBytes`]: its errors), with FIF's tag reads.
pub(super) type Ctx<'a> = crate::bytes::FileBytes<'a>;

impl Ctx<'_> {
    fn be_i32(&self, at: usize) -> i32 {
        i32::from_be_bytes([
            self.bytes[at],
            self.bytes[at + 1],
            self.bytes[at + 2],
            self.bytes[at + 3],
        ])
    }

    /// The data of `tag` (in bounds: [`walk`] checked every tag against the file length).
    pub(super) fn data(&self, tag: &Tag) -> &[u8] {
        &self.bytes[tag.data_pos()..tag.data_pos() + tag.size]
    }

    fn expect_type(&self, tag: &Tag, field: &str, types: &[(u32, &str)]) -> Result<(), IoError> {
        if types.iter().any(|&(t, _)| t == tag.ty) {
            return Ok(());
        }
        let names: Vec<&str> = types.iter().map(|&(_, n)| n).collect();
        Err(self.invalid(
            field,
            tag.pos + 4,
            format!("data type {}", names.join(" or ")),
            format!("type {}", tag.ty),
        ))
    }

    /// The 32-bit integers of an `FIFFT_INT` tag.
    pub(super) fn ints(&self, tag: &Tag, field: &str) -> Result<Vec<i32>, IoError> {
        self.expect_type(tag, field, &[(ty::INT, "FIFFT_INT (3)")])?;
        if tag.size % 4 != 0 {
            return Err(self.invalid(
                field,
                tag.pos + 8,
                "a size that is a multiple of 4",
                tag.size.to_string(),
            ));
        }
        Ok(self
            .data(tag)
            .chunks_exact(4)
            .map(|c| i32::from_be_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    /// The one 32-bit integer of an `FIFFT_INT` tag.
    pub(super) fn int(&self, tag: &Tag, field: &str) -> Result<i32, IoError> {
        match self.ints(tag, field)?[..] {
            [v] => Ok(v),
            _ => Err(self.invalid(
                field,
                tag.pos + 8,
                "size 4 (one integer)",
                tag.size.to_string(),
            )),
        }
    }

    /// The numbers of an `FIFFT_FLOAT` or `FIFFT_DOUBLE` tag, and whether they are float32.
    pub(super) fn floats(&self, tag: &Tag, field: &str) -> Result<(Vec<f64>, bool), IoError> {
        self.expect_type(
            tag,
            field,
            &[
                (ty::FLOAT, "FIFFT_FLOAT (4)"),
                (ty::DOUBLE, "FIFFT_DOUBLE (5)"),
            ],
        )?;
        let w = if tag.ty == ty::FLOAT { 4 } else { 8 };
        if tag.size % w != 0 {
            return Err(self.invalid(
                field,
                tag.pos + 8,
                format!("a size that is a multiple of {w}"),
                tag.size.to_string(),
            ));
        }
        let d = self.data(tag);
        Ok(if w == 4 {
            let v = d
                .chunks_exact(4)
                .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect();
            (v, true)
        } else {
            let v = d
                .chunks_exact(8)
                .map(|c| f64::from_be_bytes(c.try_into().expect("8 bytes")))
                .collect();
            (v, false)
        })
    }

    /// The text of an `FIFFT_STRING` tag, decoded as MNE decodes it (see [`decode_string`]).
    pub(super) fn string(&self, tag: &Tag, field: &str) -> Result<String, IoError> {
        self.expect_type(tag, field, &[(ty::STRING, "FIFFT_STRING (10)")])?;
        Ok(decode_string(self.data(tag)))
    }
}

/// A FIF string: ISO 8859-1 (Latin-1), as the FIF standard and MNE read it; MNE writes other
/// characters as decimal references `&#NNNN;`, which are turned back into characters when the
/// text holds one with six digits (MNE's condition; named entities are left as they are).
pub(super) fn decode_string(bytes: &[u8]) -> String {
    let text: String = bytes.iter().map(|&b| b as char).collect();
    let has_six = text.match_indices("&#").any(|(i, _)| {
        let rest = &text.as_bytes()[i + 2..];
        rest.len() >= 7 && rest[..6].iter().all(u8::is_ascii_hexdigit) && rest[6] == b';'
    });
    if !has_six {
        return text;
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(i) = rest.find("&#") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let (digits, radix) = match after.strip_prefix(['x', 'X']) {
            Some(hex) => (hex, 16),
            None => (after, 10),
        };
        let n = digits
            .bytes()
            .take_while(|b| b.is_ascii_hexdigit() && (radix == 16 || b.is_ascii_digit()))
            .count();
        let decoded = (n > 0 && digits[n..].starts_with(';'))
            .then(|| u32::from_str_radix(&digits[..n], radix).ok())
            .flatten()
            .and_then(char::from_u32);
        match decoded {
            Some(c) => {
                out.push(c);
                rest = &digits[n + 1..];
            }
            None => {
                out.push_str("&#");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// Follows the tag chain from byte 0: `next` 0 = the tag right after this one, -1 = this is the
/// last tag, any other value = the byte of the next tag, which must lie after this tag's end (so
/// the chain only moves forward and cannot loop). The chain also ends at the end of the file when
/// that falls on a tag boundary (MNE reads such files; [`tree`] then refuses any block left open).
/// Every tag is checked against the file length.
pub(super) fn walk(ctx: &Ctx<'_>) -> Result<Vec<Tag>, IoError> {
    let len = ctx.bytes.len();
    let mut tags = Vec::new();
    let mut pos = 0usize;
    while pos < len {
        if len - pos < 16 {
            return Err(ctx.truncated(format!("tag header {}", tags.len()), pos, pos as u64 + 16));
        }
        let kind_v = ctx.be_i32(pos);
        let ty_v = ctx.be_i32(pos + 4) as u32;
        let size = ctx.be_i32(pos + 8);
        let next = ctx.be_i32(pos + 12);
        let index = tags.len();
        let field = || format!("tag {index} (kind {kind_v})");
        if size < 0 {
            return Err(ctx.invalid(
                format!("{} size", field()),
                pos + 8,
                "a size of 0 or more bytes",
                size.to_string(),
            ));
        }
        let size = size as usize;
        let end = pos + 16 + size;
        if end > len {
            return Err(ctx.truncated(format!("{} data ({size} bytes)", field()), pos, end as u64));
        }
        tags.push(Tag {
            kind: kind_v,
            ty: ty_v,
            size,
            pos,
        });
        pos = match next {
            0 => end,
            -1 => break,
            n if n > 0 && n as usize >= end => n as usize,
            n => {
                return Err(ctx.invalid(
                    format!("{} next", field()),
                    pos + 12,
                    format!("0 (the next tag follows), -1 (last tag) or a byte offset of at least {end} (after this tag)"),
                    n.to_string(),
                ))
            }
        };
    }
    let first_ok = tags
        .first()
        .is_some_and(|t| t.kind == kind::FILE_ID && t.ty == ty::ID_STRUCT && t.size == 20);
    if !first_ok {
        return Err(ctx.invalid(
            "file id tag",
            0,
            "a FIF file: a first tag of kind FIFF_FILE_ID (100), type FIFFT_ID_STRUCT (31), size 20",
            tags.first()
                .map(|t| format!("kind {}, type {}, size {}", t.kind, t.ty, t.size))
                .unwrap_or_else(|| "an empty file".into()),
        ));
    }
    match tags.get(1) {
        Some(t) if t.kind == kind::DIR_POINTER => {}
        other => {
            return Err(ctx.invalid(
                "directory pointer tag",
                other.map(|t| t.pos).unwrap_or(36),
                "a second tag of kind FIFF_DIR_POINTER (101)",
                other
                    .map(|t| format!("kind {}", t.kind))
                    .unwrap_or_else(|| "no second tag".into()),
            ))
        }
    }
    Ok(tags)
}

/// The block tree of the tags: every `FIFF_BLOCK_START` opens a block closed by the
/// `FIFF_BLOCK_END` of the same kind; a block left open at the end of the chain is an error (a
/// cut file).
pub(super) fn tree(ctx: &Ctx<'_>, tags: Vec<Tag>) -> Result<Node, IoError> {
    let mut stack = vec![Node {
        kind: block::ROOT,
        start: 0,
        tags: Vec::new(),
        children: Vec::new(),
    }];
    for t in tags {
        match t.kind {
            kind::BLOCK_START => {
                let k = ctx.int(&t, "FIFF_BLOCK_START")?;
                if stack.len() > MAX_DEPTH {
                    return Err(ctx.invalid(
                        "FIFF_BLOCK_START",
                        t.pos,
                        format!("blocks nested at most {MAX_DEPTH} deep"),
                        format!("{} open blocks", stack.len()),
                    ));
                }
                stack.push(Node {
                    kind: k,
                    start: t.pos,
                    tags: Vec::new(),
                    children: Vec::new(),
                });
            }
            kind::BLOCK_END => {
                let k = ctx.int(&t, "FIFF_BLOCK_END")?;
                let open = stack.last().map(|n| n.kind).unwrap_or(block::ROOT);
                if stack.len() < 2 || open != k {
                    return Err(ctx.invalid(
                        "FIFF_BLOCK_END",
                        t.data_pos(),
                        if stack.len() < 2 {
                            "no block end outside every block".to_string()
                        } else {
                            format!("the end of the open {}", block_name(open))
                        },
                        block_name(k),
                    ));
                }
                let done = stack.pop().expect("two or more");
                stack.last_mut().expect("the root").children.push(done);
            }
            _ => stack.last_mut().expect("the root").tags.push(t),
        }
    }
    if stack.len() > 1 {
        let open = stack.last().expect("open block");
        let len = ctx.bytes.len();
        return Err(ctx.truncated(
            format!(
                "{} started at byte {} (no FIFF_BLOCK_END: the file ends inside it)",
                block_name(open.kind),
                open.start
            ),
            open.start,
            len as u64 + 20,
        ));
    }
    Ok(stack.pop().expect("the root"))
}
