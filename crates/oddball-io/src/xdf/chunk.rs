//! The binary layer of XDF: varlen integers, chunks and little-endian values.

use super::types::*;

pub(super) fn put_varlen(out: &mut Vec<u8>, n: u64) {
    if n <= u64::from(u8::MAX) {
        out.push(1);
        out.push(n as u8);
    } else if n <= u64::from(u32::MAX) {
        out.push(4);
        out.extend_from_slice(&(n as u32).to_le_bytes());
    } else {
        out.push(8);
        out.extend_from_slice(&n.to_le_bytes());
    }
}

/// Appends one chunk: `[NumLengthBytes][Length][tag][parts…]`.
pub(super) fn put_chunk(out: &mut Vec<u8>, tag: u16, parts: &[&[u8]]) {
    let len = 2 + parts.iter().map(|p| p.len() as u64).sum::<u64>();
    put_varlen(out, len);
    out.extend_from_slice(&tag.to_le_bytes());
    for p in parts {
        out.extend_from_slice(p);
    }
}

/// Appends `x` in `format`; `Err(reason)` when it does not fit.
pub(super) fn put_value(out: &mut Vec<u8>, format: XdfFormat, x: f64) -> Result<(), &'static str> {
    fn int(x: f64, min: f64, max: f64) -> Result<f64, &'static str> {
        if !x.is_finite() {
            return Err("not a finite number (the stream stores integers)");
        }
        let r = x.round();
        if r < min || r > max {
            return Err("beyond the range of the stream's integer type");
        }
        Ok(r)
    }
    match format {
        XdfFormat::Int8 => out.push(int(x, -128.0, 127.0)? as i8 as u8),
        XdfFormat::Int16 => {
            out.extend_from_slice(&(int(x, -32768.0, 32767.0)? as i16).to_le_bytes())
        }
        XdfFormat::Int32 => out.extend_from_slice(
            &(int(x, f64::from(i32::MIN), f64::from(i32::MAX))? as i32).to_le_bytes(),
        ),
        XdfFormat::Int64 => {
            // 2^63 is exactly representable; every f64 below it fits.
            let r = int(x, -9_223_372_036_854_775_808.0, 9_223_372_036_854_774_784.0)?;
            out.extend_from_slice(&(r as i64).to_le_bytes())
        }
        XdfFormat::Float32 => {
            let y = x as f32;
            if x.is_finite() && !y.is_finite() {
                return Err("beyond the float32 range");
            }
            out.extend_from_slice(&y.to_le_bytes())
        }
        XdfFormat::Double64 => out.extend_from_slice(&x.to_le_bytes()),
        XdfFormat::String => return Err("a number for a string stream"),
    }
    Ok(())
}

pub(super) fn le_u64(b: &[u8]) -> u64 {
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    u64::from_le_bytes(a)
}

pub(super) fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

pub(super) fn le_f64(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap_or([0; 8]))
}

/// Reads a varlen integer at `content[p]`; `Err((offset in content, problem))`.
pub(super) fn varlen(content: &[u8], p: usize) -> Result<(u64, usize), (usize, String)> {
    let Some(&n) = content.get(p) else {
        return Err((p, "the end of the chunk".into()));
    };
    if !matches!(n, 1 | 4 | 8) {
        return Err((p, format!("byte count {n}")));
    }
    let n = n as usize;
    let bytes = content
        .get(p + 1..p + 1 + n)
        .ok_or_else(|| (p, "the end of the chunk".to_string()))?;
    Ok((le_u64(bytes), p + 1 + n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varlen_and_chunks() {
        for n in [
            0u64,
            255,
            256,
            65_536,
            u64::from(u32::MAX),
            u64::from(u32::MAX) + 1,
        ] {
            let mut b = Vec::new();
            put_varlen(&mut b, n);
            assert_eq!(varlen(&b, 0).unwrap(), (n, b.len()));
        }
        assert!(varlen(&[2, 0, 0], 0).is_err());
        assert!(varlen(&[4, 0, 0], 0).is_err());
        assert!(varlen(&[], 0).is_err());
    }
}
