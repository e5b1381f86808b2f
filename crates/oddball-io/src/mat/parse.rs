//! The MAT v5/v7 container: the 128-byte header, data elements (normal and small), `miMATRIX`
//! arrays (numeric, logical, char, cell, struct) and `miCOMPRESSED` (zlib) elements.
//!
//! Every length read from the file is checked against the bytes that follow it before anything
//! is allocated; an error names the byte offset and the element at fault. Inside a compressed
//! element the offset is the element's own offset in the file, and the field text gives the
//! byte within the decompressed data.
//!
//! The layout is read as `scipy.io.loadmat` reads it (checked on the fixtures of
//! `tools/golden/mat/make_padding.py`): an element's data is padded to a multiple of 8 bytes
//! counted from the data's own start; a small data element (1 to 4 bytes, its byte count in the
//! upper half of the tag's first word) holds its data in the tag, 8 bytes in all; a top-level
//! variable ends where its byte count ends, with no padding after it (none follows compressed
//! data, so the variable after a compressed one may start at any offset). Bytes where scipy
//! expects the next variable's tag and finds padding are an error here too, at that byte.

use std::io::Read;
use std::path::Path;

use super::file::{
    MatArray, MatClass, MatFile, MatHeader, MatNumbers, MatType, MatValue, MatVariable,
};
use crate::files::read_file;
use crate::IoError;

/// The header: 116 bytes of text, 8 of subsystem offset, 2 of version, 2 of endian indicator.
pub(crate) const HEADER_LEN: usize = 128;

/// Nesting deeper than this (cells in structs in cells …) is refused rather than risking the
/// stack on a crafted file.
const MAX_DEPTH: usize = 32;

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;
const MI_UTF16: u32 = 17;
const MI_UTF32: u32 = 18;

/// The name MATLAB's documentation gives a data type number.
fn mi_name(t: u32) -> String {
    match t {
        MI_INT8 => "miINT8".into(),
        MI_UINT8 => "miUINT8".into(),
        MI_INT16 => "miINT16".into(),
        MI_UINT16 => "miUINT16".into(),
        MI_INT32 => "miINT32".into(),
        MI_UINT32 => "miUINT32".into(),
        MI_SINGLE => "miSINGLE".into(),
        MI_DOUBLE => "miDOUBLE".into(),
        MI_INT64 => "miINT64".into(),
        MI_UINT64 => "miUINT64".into(),
        MI_MATRIX => "miMATRIX".into(),
        MI_COMPRESSED => "miCOMPRESSED".into(),
        MI_UTF8 => "miUTF8".into(),
        MI_UTF16 => "miUTF16".into(),
        MI_UTF32 => "miUTF32".into(),
        other => format!("data type {other}"),
    }
}

fn mat_type(t: u32) -> Option<MatType> {
    Some(match t {
        MI_INT8 => MatType::Int8,
        MI_UINT8 => MatType::UInt8,
        MI_INT16 => MatType::Int16,
        MI_UINT16 => MatType::UInt16,
        MI_INT32 => MatType::Int32,
        MI_UINT32 => MatType::UInt32,
        MI_SINGLE => MatType::Single,
        MI_DOUBLE => MatType::Double,
        MI_INT64 => MatType::Int64,
        MI_UINT64 => MatType::UInt64,
        _ => return None,
    })
}

/// Where the bytes being parsed come from, to name offsets in errors.
#[derive(Clone, Copy)]
enum Origin {
    File,
    /// The decompressed contents of the `miCOMPRESSED` element whose tag is at `at` in the file.
    Compressed {
        at: u64,
    },
}

/// A byte buffer (the file or one decompressed element) with its byte order and origin.
struct Buf<'a> {
    bytes: &'a [u8],
    big_endian: bool,
    origin: Origin,
    path: &'a Path,
    file_len: u64,
    /// The tag offset of the `miMATRIX` element these bytes are the contents of (they end
    /// where it ends), `None` at the top level.
    parent: Option<usize>,
}

/// One data element: its type, where its tag starts, and its data bytes `start..start + len`.
struct Element {
    mi: u32,
    tag_at: usize,
    start: usize,
    len: usize,
    /// Where the next element starts (after padding).
    next: usize,
}

impl<'a> Buf<'a> {
    fn u32_at(&self, at: usize) -> u32 {
        let b: [u8; 4] = self.bytes[at..at + 4].try_into().unwrap_or([0; 4]);
        if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        }
    }

    fn invalid(&self, at: usize, field: &str, expected: &str, found: String) -> IoError {
        let (offset, field) = match self.origin {
            Origin::File => (at as u64, field.to_string()),
            Origin::Compressed { at: c } => (
                c,
                format!("{field} (byte {at} of the decompressed miCOMPRESSED element)"),
            ),
        };
        IoError::InvalidField {
            path: self.path.to_path_buf(),
            field,
            offset,
            expected: expected.to_string(),
            found: crate::error::bounded(&found),
        }
    }

    fn truncated(&self, at: usize, field: &str, needed: usize) -> IoError {
        if let Some(p) = self.parent {
            return self.invalid(
                at,
                field,
                &format!(
                    "to end within its miMATRIX element (tag at byte {p}, ending at byte {})",
                    self.bytes.len()
                ),
                format!("an element reaching byte {needed}"),
            );
        }
        match self.origin {
            Origin::File => IoError::Truncated {
                path: self.path.to_path_buf(),
                field: field.to_string(),
                offset: at as u64,
                needed: needed as u64,
                file_len: self.file_len,
            },
            Origin::Compressed { .. } => self.invalid(
                at,
                field,
                &format!("data up to decompressed byte {needed}"),
                format!("the element decompresses to {} bytes", self.bytes.len()),
            ),
        }
    }

    /// The data element whose tag starts at `at`; `what` names it in errors.
    fn element(&self, at: usize, what: &str) -> Result<Element, IoError> {
        if self.bytes.len().saturating_sub(at) < 4 {
            return Err(self.truncated(at, &format!("{what}: tag"), at + 8));
        }
        let first = self.u32_at(at);
        if first >> 16 != 0 {
            // Small data element: 2 bytes of length, 2 of type, then up to 4 bytes of data.
            let len = (first >> 16) as usize;
            let mi = first & 0xffff;
            if len > 4 {
                return Err(self.invalid(
                    at,
                    &format!("{what}: small data element length"),
                    "at most 4 bytes",
                    format!("{len} bytes ({})", mi_name(mi)),
                ));
            }
            if self.bytes.len() - at < 8 {
                return Err(self.truncated(at, &format!("{what}: small data element"), at + 8));
            }
            return Ok(Element {
                mi,
                tag_at: at,
                start: at + 4,
                len,
                next: at + 8,
            });
        }
        if self.bytes.len() - at < 8 {
            return Err(self.truncated(at, &format!("{what}: tag"), at + 8));
        }
        let mi = first;
        let len = self.u32_at(at + 4) as usize;
        let start = at + 8;
        let end = start.saturating_add(len);
        if end > self.bytes.len() {
            return Err(self.truncated(at, &format!("{what} ({}, {len} bytes)", mi_name(mi)), end));
        }
        // Data is padded to a multiple of 8 bytes counted from its own start (scipy's
        // `seek(8 - byte_count % 8)`): after an unpadded miCOMPRESSED element a variable starts
        // at any offset, and its elements keep that offset's alignment. Compressed data is not
        // padded (MATLAB and scipy write none). The padding of a matrix's last element may lie
        // beyond the matrix's byte count; nothing is read there.
        let next = if mi == MI_COMPRESSED {
            end
        } else {
            end.saturating_add((8 - len % 8) % 8).min(self.bytes.len())
        };
        Ok(Element {
            mi,
            tag_at: at,
            start,
            len,
            next,
        })
    }

    fn data(&self, e: &Element) -> &'a [u8] {
        &self.bytes[e.start..e.start + e.len]
    }

    /// The values of an integer element (dimensions, field name length) as `i64`.
    fn i32s(&self, e: &Element, what: &str) -> Result<Vec<i64>, IoError> {
        let values = match e.mi {
            MI_INT32 | MI_UINT32 | MI_INT8 | MI_UINT8 | MI_INT16 | MI_UINT16 => {
                self.numbers(e, what)?.to_i64()
            }
            other => {
                return Err(self.invalid(
                    e.tag_at,
                    &format!("{what}: data type"),
                    "miINT32",
                    mi_name(other),
                ))
            }
        };
        Ok(values)
    }

    /// The numbers of a numeric data element, in the type they are stored in.
    fn numbers(&self, e: &Element, what: &str) -> Result<MatNumbers, IoError> {
        let Some(t) = mat_type(e.mi) else {
            return Err(self.invalid(
                e.tag_at,
                &format!("{what}: data type"),
                "a numeric type (miINT8 … miUINT64, miSINGLE, miDOUBLE)",
                mi_name(e.mi),
            ));
        };
        let size = t.size();
        let d = self.data(e);
        if d.len() % size != 0 {
            return Err(self.invalid(
                e.tag_at,
                &format!("{what}: byte count"),
                &format!("a multiple of {size} ({})", mi_name(e.mi)),
                format!("{} bytes", d.len()),
            ));
        }
        Ok(MatNumbers::decode(t, d, self.big_endian))
    }
}

/// Parses a whole MAT file (its bytes `b`); `path` names it in errors.
pub(crate) fn parse(b: &[u8], path: &Path) -> Result<MatFile, IoError> {
    let header = parse_header(b, path)?;
    let buf = Buf {
        bytes: b,
        big_endian: header.big_endian,
        origin: Origin::File,
        path,
        file_len: b.len() as u64,
        parent: None,
    };
    // A subsystem offset (MATLAB objects) points past the variables; those bytes are not
    // variables. 0 and all-spaces/all-ones mean "none".
    let end = match header.subsys_offset {
        o if o >= HEADER_LEN as u64 && o < b.len() as u64 => o as usize,
        _ => b.len(),
    };
    let buf = Buf {
        bytes: &b[..end],
        ..buf
    };
    let mut variables = Vec::new();
    let mut at = HEADER_LEN;
    let mut inflated = 0u64;
    while at < end {
        let what = match peek_name(&buf, at) {
            Some(name) => format!("variable {} ({name:?})", variables.len() + 1),
            None => format!("variable {}", variables.len() + 1),
        };
        let e = buf.element(at, &what)?;
        let var = match e.mi {
            MI_MATRIX => {
                let (name, array, global) = parse_matrix(&buf, &e, &what, 0)?;
                MatVariable {
                    name,
                    array,
                    offset: at as u64,
                    compressed: false,
                    global,
                }
            }
            MI_COMPRESSED => {
                let budget = inflate_budget(buf.file_len).saturating_sub(inflated);
                let inner = inflate(&buf, &e, &what, budget)?;
                inflated += inner.len() as u64;
                let ibuf = Buf {
                    bytes: &inner,
                    big_endian: buf.big_endian,
                    origin: Origin::Compressed { at: at as u64 },
                    path,
                    file_len: buf.file_len,
                    parent: None,
                };
                let ie = ibuf.element(0, &what)?;
                if ie.mi != MI_MATRIX {
                    return Err(ibuf.invalid(
                        0,
                        &format!("{what}: data type"),
                        "miMATRIX",
                        mi_name(ie.mi),
                    ));
                }
                let (name, array, global) = parse_matrix(&ibuf, &ie, &what, 0)?;
                MatVariable {
                    name,
                    array,
                    offset: at as u64,
                    compressed: true,
                    global,
                }
            }
            other => {
                return Err(buf.invalid(
                    at,
                    &format!("{what}: data type"),
                    "miMATRIX or miCOMPRESSED",
                    mi_name(other),
                ))
            }
        };
        variables.push(var);
        // The next variable starts where this one's byte count ends, padded or not (scipy's
        // `next_position`): a count that leaves out padding written after it is an error at the
        // padding, as in scipy.
        at = e.start + e.len;
    }
    Ok(MatFile { header, variables })
}

/// The name of the uncompressed `miMATRIX` variable whose tag is at `at`, read from whatever
/// bytes of it the buffer holds (for error messages about a variable cut short).
fn peek_name(buf: &Buf<'_>, at: usize) -> Option<String> {
    if buf.bytes.len().checked_sub(at)? < 8 || buf.u32_at(at) != MI_MATRIX {
        return None;
    }
    let flags = buf.element(at + 8, "").ok()?;
    let dims = buf.element(flags.next, "").ok()?;
    let name = buf.element(dims.next, "").ok()?;
    (name.mi == MI_INT8).then(|| String::from_utf8_lossy(buf.data(&name)).into_owned())
}

fn parse_header(b: &[u8], path: &Path) -> Result<MatHeader, IoError> {
    let invalid = |offset: u64, field: &str, expected: &str, found: String| IoError::InvalidField {
        path: path.to_path_buf(),
        field: field.into(),
        offset,
        expected: expected.into(),
        found: crate::error::bounded(&found),
    };
    // HDF5-based v7.3 files carry a 512-byte user block starting with the same text header.
    if b.len() >= 128 && &b[126..128] == b"IM" && b[124..126] == [0x00, 0x02]
        || b.len() >= 8 && b.starts_with(b"\x89HDF\r\n\x1a\n")
        || b.len() >= 520 && &b[512..520] == b"\x89HDF\r\n\x1a\n"
    {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "MAT-file version 7.3 (HDF5-based, header version 0x0200); \
                   save it with `save -v7` in MATLAB, or convert it with h5py"
                .into(),
        });
    }
    if b.len() < HEADER_LEN {
        return Err(IoError::Truncated {
            path: path.to_path_buf(),
            field: "MAT-file header".into(),
            offset: 0,
            needed: HEADER_LEN as u64,
            file_len: b.len() as u64,
        });
    }
    let text_end = b[..116].iter().position(|&c| c == 0).unwrap_or(116);
    let text = String::from_utf8_lossy(&b[..text_end])
        .trim_end()
        .to_string();
    let big_endian = match &b[126..128] {
        b"IM" => false,
        b"MI" => true,
        other => {
            let v4 = !text.starts_with("MATLAB");
            return Err(invalid(
                126,
                "MAT-file header: endian indicator",
                "\"IM\" or \"MI\" (MAT v5/v7)",
                if v4 {
                    format!("{other:?}; no \"MATLAB 5.0 MAT-file\" text either: a MAT v4 file or not a MAT file")
                } else {
                    format!("{other:?}")
                },
            ));
        }
    };
    let version = if big_endian {
        u16::from_be_bytes([b[124], b[125]])
    } else {
        u16::from_le_bytes([b[124], b[125]])
    };
    if version == 0x0200 {
        return Err(IoError::Unsupported {
            path: path.to_path_buf(),
            what: "MAT-file version 7.3 (HDF5-based, header version 0x0200); \
                   save it with `save -v7` in MATLAB, or convert it with h5py"
                .into(),
        });
    }
    if version != 0x0100 {
        return Err(invalid(
            124,
            "MAT-file header: version",
            "0x0100 (MAT v5/v7)",
            format!("{version:#06x}"),
        ));
    }
    let so: [u8; 8] = b[116..124].try_into().unwrap_or([0; 8]);
    let subsys_offset = if big_endian {
        u64::from_be_bytes(so)
    } else {
        u64::from_le_bytes(so)
    };
    Ok(MatHeader {
        text,
        version,
        big_endian,
        subsys_offset,
    })
}

/// What all the compressed variables of one file may decompress to together: this allowance
/// plus [`INFLATE_RATIO`] bytes per byte of the file. EEG compresses a few times at most; a
/// file that inflates further is a zip bomb (the probe's: 522 KB that took `inspect` to 4.6 GB),
/// refused before anything is inflated.
pub const INFLATE_ALLOWANCE: u64 = 16 << 20;
/// See [`INFLATE_ALLOWANCE`].
pub const INFLATE_RATIO: u64 = 40;

/// What a file of `file_len` bytes may decompress to in all (see [`INFLATE_ALLOWANCE`]).
pub fn inflate_budget(file_len: u64) -> u64 {
    INFLATE_ALLOWANCE.saturating_add(INFLATE_RATIO.saturating_mul(file_len))
}

/// Decompresses a `miCOMPRESSED` element: at most as many bytes as the `miMATRIX` tag at the
/// start of the stream announces (plus its tag), never more than the stream holds, and refused
/// before inflating when that is more than the file's remaining budget (`budget` bytes).
fn inflate(buf: &Buf<'_>, e: &Element, what: &str, budget: u64) -> Result<Vec<u8>, IoError> {
    let err = |msg: String| {
        buf.invalid(
            e.tag_at,
            &format!("{what}: zlib stream of the miCOMPRESSED element"),
            "a valid zlib stream",
            msg,
        )
    };
    let mut dec = flate2::read::ZlibDecoder::new(buf.data(e));
    let mut tag = [0u8; 8];
    dec.read_exact(&mut tag)
        .map_err(|x| err(format!("cannot decompress its first 8 bytes: {x}")))?;
    let word = |b: &[u8]| {
        let a: [u8; 4] = b.try_into().unwrap_or([0; 4]);
        if buf.big_endian {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        }
    };
    let declared = u64::from(word(&tag[4..8]));
    if declared.saturating_add(8) > budget {
        return Err(buf.invalid(
            e.tag_at,
            &format!("{what}: decompressed size"),
            &format!(
                "at most {budget} bytes left of what the file's {} bytes may decompress to \
                 ({} MiB + {INFLATE_RATIO} × its size, for all its variables)",
                buf.file_len,
                INFLATE_ALLOWANCE >> 20
            ),
            format!("{declared} bytes: a zip bomb, not a recording"),
        ));
    }
    let mut out = tag.to_vec();
    dec.take(declared)
        .read_to_end(&mut out)
        .map_err(|x| err(format!("{x}")))?;
    Ok(out)
}

/// Parses a `miMATRIX` element: returns its name, the array and its global flag.
fn parse_matrix(
    buf: &Buf<'_>,
    e: &Element,
    what: &str,
    depth: usize,
) -> Result<(String, MatArray, bool), IoError> {
    if depth > MAX_DEPTH {
        return Err(buf.invalid(
            e.tag_at,
            &format!("{what}: nesting"),
            &format!("cells/structs nested at most {MAX_DEPTH} deep"),
            format!("{depth} levels"),
        ));
    }
    if e.len == 0 {
        // MATLAB writes an empty array (e.g. an empty cell or field) as a bare tag.
        let array = MatArray {
            dims: vec![0, 0],
            value: MatValue::Numeric {
                class: MatClass::Double,
                real: MatNumbers::F64(Vec::new()),
                imag: None,
            },
        };
        return Ok((String::new(), array, false));
    }
    let end = e.start + e.len;
    let sub = Buf {
        bytes: &buf.bytes[..end],
        parent: Some(e.tag_at),
        ..*buf
    };
    // Array flags.
    let fe = sub.element(e.start, &format!("{what}: array flags"))?;
    if fe.mi != MI_UINT32 || fe.len < 8 {
        return Err(sub.invalid(
            fe.tag_at,
            &format!("{what}: array flags"),
            "miUINT32 of 8 bytes",
            format!("{} of {} bytes", mi_name(fe.mi), fe.len),
        ));
    }
    let flags = sub.u32_at(fe.start);
    let class_byte = (flags & 0xff) as u8;
    let complex = flags & 0x0800 != 0;
    let global = flags & 0x0400 != 0;
    let logical = flags & 0x0200 != 0;
    // Dimensions.
    let de = sub.element(fe.next, &format!("{what}: dimensions"))?;
    let dims_i = sub.i32s(&de, &format!("{what}: dimensions"))?;
    if dims_i.len() < 2 || dims_i.iter().any(|&d| d < 0) {
        return Err(sub.invalid(
            de.tag_at,
            &format!("{what}: dimensions"),
            "at least 2 non-negative sizes",
            format!("{dims_i:?}"),
        ));
    }
    let dims: Vec<usize> = dims_i.iter().map(|&d| d as usize).collect();
    let n = dims
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or_else(|| {
            sub.invalid(
                de.tag_at,
                &format!("{what}: dimensions"),
                "a product that fits in memory",
                format!("{dims:?}"),
            )
        })?;
    // Name.
    let ne = sub.element(de.next, &format!("{what}: array name"))?;
    if ne.mi != MI_INT8 && ne.mi != MI_UINT8 {
        return Err(sub.invalid(
            ne.tag_at,
            &format!("{what}: array name"),
            "miINT8",
            mi_name(ne.mi),
        ));
    }
    let name = String::from_utf8_lossy(sub.data(&ne)).into_owned();
    let what = if name.is_empty() {
        what.to_string()
    } else {
        format!("{what} ({name:?})")
    };
    let mut at = ne.next;
    let class = MatClass::from_byte(class_byte);
    let value = match class {
        Some(c) if c.is_numeric() => {
            let re = sub.element(at, &format!("{what}: real part"))?;
            let real = sub.numbers(&re, &format!("{what}: real part"))?;
            check_count(&sub, &re, &format!("{what}: real part"), real.len(), n)?;
            at = re.next;
            let imag = if complex {
                let ie = sub.element(at, &format!("{what}: imaginary part"))?;
                let imag = sub.numbers(&ie, &format!("{what}: imaginary part"))?;
                check_count(&sub, &ie, &format!("{what}: imaginary part"), imag.len(), n)?;
                Some(imag)
            } else {
                None
            };
            let class = if logical { MatClass::Logical } else { c };
            MatValue::Numeric { class, real, imag }
        }
        Some(MatClass::Char) => {
            let ce = sub.element(at, &format!("{what}: characters"))?;
            let chars = parse_chars(&sub, &ce, &format!("{what}: characters"))?;
            check_count(&sub, &ce, &format!("{what}: characters"), chars.len(), n)?;
            MatValue::Char(chars)
        }
        Some(MatClass::Cell) => {
            let mut cells = Vec::new();
            for i in 0..n {
                let cw = format!("{what}: cell {}", i + 1);
                let ce = sub.element(at, &cw)?;
                expect_matrix(&sub, &ce, &cw)?;
                cells.push(parse_matrix(&sub, &ce, &cw, depth + 1)?.1);
                at = ce.next;
            }
            MatValue::Cell(cells)
        }
        Some(MatClass::Struct) => {
            let le = sub.element(at, &format!("{what}: field name length"))?;
            let l = sub.i32s(&le, &format!("{what}: field name length"))?;
            let flen = match l.as_slice() {
                [x] if *x > 0 => *x as usize,
                _ => {
                    return Err(sub.invalid(
                        le.tag_at,
                        &format!("{what}: field name length"),
                        "one positive number",
                        format!("{l:?}"),
                    ))
                }
            };
            let fe = sub.element(le.next, &format!("{what}: field names"))?;
            let raw = sub.data(&fe);
            if raw.len() % flen != 0 {
                return Err(sub.invalid(
                    fe.tag_at,
                    &format!("{what}: field names"),
                    &format!("a multiple of the name length {flen}"),
                    format!("{} bytes", raw.len()),
                ));
            }
            let fields: Vec<String> = raw
                .chunks(flen)
                .map(|c| {
                    let z = c.iter().position(|&b| b == 0).unwrap_or(c.len());
                    String::from_utf8_lossy(&c[..z]).into_owned()
                })
                .collect();
            at = fe.next;
            let mut values = Vec::new();
            // A struct without fields has no values, whatever its (possibly absurd) size.
            let n_with_values = if fields.is_empty() { 0 } else { n };
            for i in 0..n_with_values {
                for f in &fields {
                    let fw = format!("{what}: element {}, field {f:?}", i + 1);
                    let ve = sub.element(at, &fw)?;
                    expect_matrix(&sub, &ve, &fw)?;
                    values.push(parse_matrix(&sub, &ve, &fw, depth + 1)?.1);
                    at = ve.next;
                }
            }
            MatValue::Struct { fields, values }
        }
        _ => MatValue::Unsupported { class: class_byte },
    };
    Ok((name, MatArray { dims, value }, global))
}

fn expect_matrix(buf: &Buf<'_>, e: &Element, what: &str) -> Result<(), IoError> {
    if e.mi == MI_MATRIX {
        Ok(())
    } else {
        Err(buf.invalid(
            e.tag_at,
            &format!("{what}: data type"),
            "miMATRIX",
            mi_name(e.mi),
        ))
    }
}

fn check_count(
    buf: &Buf<'_>,
    e: &Element,
    what: &str,
    found: usize,
    expected: usize,
) -> Result<(), IoError> {
    if found == expected {
        Ok(())
    } else {
        Err(buf.invalid(
            e.tag_at,
            &format!("{what}: number of values"),
            &format!("{expected} (the product of the dimensions)"),
            format!("{found} ({} bytes of {})", e.len, mi_name(e.mi)),
        ))
    }
}

/// The characters of a char array: UTF-16 code units (miUINT16/miUTF16, one per element,
/// unpaired surrogates as U+FFFD), UTF-8 (miUTF8), UTF-32 or 8-bit codes.
fn parse_chars(buf: &Buf<'_>, e: &Element, what: &str) -> Result<Vec<char>, IoError> {
    let d = buf.data(e);
    let bad = || {
        buf.invalid(
            e.tag_at,
            &format!("{what}: data type"),
            "character data (miUINT16, miUTF8, miUTF16, miUTF32, miUINT8)",
            mi_name(e.mi),
        )
    };
    let units = |size: usize| -> Result<Vec<u32>, IoError> {
        if d.len() % size != 0 {
            return Err(buf.invalid(
                e.tag_at,
                &format!("{what}: byte count"),
                &format!("a multiple of {size}"),
                format!("{} bytes", d.len()),
            ));
        }
        Ok(d.chunks_exact(size)
            .map(|c| match (size, buf.big_endian) {
                (1, _) => u32::from(c[0]),
                (2, false) => u32::from(u16::from_le_bytes([c[0], c[1]])),
                (2, true) => u32::from(u16::from_be_bytes([c[0], c[1]])),
                (_, false) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                (_, true) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]),
            })
            .collect())
    };
    let to_char = |u: u32| char::from_u32(u).unwrap_or(char::REPLACEMENT_CHARACTER);
    Ok(match e.mi {
        MI_UINT16 | MI_UTF16 | MI_INT16 => units(2)?.into_iter().map(to_char).collect(),
        MI_UINT8 | MI_INT8 => units(1)?.into_iter().map(to_char).collect(),
        MI_UTF32 | MI_UINT32 | MI_INT32 => units(4)?.into_iter().map(to_char).collect(),
        MI_UTF8 => String::from_utf8_lossy(d).chars().collect(),
        _ => return Err(bad()),
    })
}

/// Parses the bytes of a MAT v5/v7 file; `path` names it in errors.
pub fn parse_mat_file(bytes: &[u8], path: &Path) -> Result<MatFile, IoError> {
    parse(bytes, path)
}

/// Reads a MAT v5/v7 file's variables (any layout).
pub fn read_mat_file(path: impl AsRef<Path>) -> Result<MatFile, IoError> {
    let path = path.as_ref();
    parse_mat_file(&read_file(path)?, path)
}
