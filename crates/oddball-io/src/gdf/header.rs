//! The GDF header: the fixed part (256 bytes, laid out differently in GDF 1.x and 2.x) and the
//! channel headers (256 bytes per channel, each field stored for all channels in turn).

use crate::IoError;

use super::types::*;

pub(super) const FIXED: usize = 256;

/// The file's bytes and path ([`crate::bytes::FileBytes`]: its errors and little-endian reads).
pub(super) type Ctx<'a> = crate::bytes::FileBytes<'a>;

impl Ctx<'_> {
    /// A text field (Latin-1, trailing spaces and NULs trimmed, cut at the first NUL).
    pub(super) fn text(&self, field: &str, off: usize, len: usize) -> Result<String, IoError> {
        let raw = self.slice(field, off, len)?;
        let raw = raw.split(|&b| b == 0).next().unwrap_or(&[]);
        Ok(raw
            .iter()
            .map(|&b| b as char)
            .collect::<String>()
            .trim()
            .to_string())
    }
}

/// The unit text of a GDF 2.x physical dimension code: volts with their decimal prefix (the
/// five low bits: 0 none, 3 kilo, 18 milli, 19 micro, 20 nano), `""` for 0 (unknown), else
/// `code <n>` (not a voltage).
pub(super) fn dimension_text(code: u16) -> String {
    const VOLT: u16 = 4256;
    if code & !0x1F == VOLT {
        let prefix = match code & 0x1F {
            0 => Some(""),
            3 => Some("k"),
            18 => Some("m"),
            19 => Some("u"),
            20 => Some("n"),
            _ => None,
        };
        if let Some(p) = prefix {
            return format!("{p}V");
        }
    }
    if code == 0 {
        String::new()
    } else {
        format!("code {code}")
    }
}

/// Parses the fixed header and the channel headers.
pub(super) fn parse_header(ctx: &Ctx<'_>) -> Result<GdfHeader, IoError> {
    if ctx.bytes.len() < FIXED {
        return Err(ctx.truncated("fixed header (256 bytes)", 0, FIXED as u64));
    }
    let magic = &ctx.bytes[..8];
    let major = match (&magic[..4], magic[4]) {
        (b"GDF ", b'1') => 1u8,
        (b"GDF ", b'2') => 2u8,
        _ => {
            return Err(ctx.invalid(
                "version",
                0,
                "`GDF 1.xx` or `GDF 2.xx`",
                String::from_utf8_lossy(magic).into_owned(),
            ))
        }
    };
    let version = ctx.text("version", 4, 4)?;
    let n_records = ctx.i64("number of data records", 236)?;
    if n_records < 0 {
        return Err(ctx.invalid(
            "number of data records",
            236,
            "a count of 0 or more (-1, unknown, is not read)",
            n_records.to_string(),
        ));
    }
    let num = ctx.u32("duration of a data record (numerator)", 244)?;
    let den = ctx.u32("duration of a data record (denominator)", 248)?;
    if num == 0 || den == 0 {
        return Err(ctx.invalid(
            "duration of a data record",
            244,
            "a positive fraction of seconds",
            format!("{num}/{den}"),
        ));
    }
    let (ns, hb, patient, recording, start) = if major == 1 {
        let ns = ctx.u32("number of channels", 252)? as usize;
        let hb = ctx.i64("number of bytes in header", 184)?;
        let start = ctx.text("start date and time", 168, 16)?;
        (
            ns,
            hb,
            ctx.text("patient", 8, 80)?,
            ctx.text("recording", 88, 80)?,
            start,
        )
    } else {
        let ns = ctx.u16("number of channels", 252)? as usize;
        let blocks = ctx.u16("header length (256-byte blocks)", 184)?;
        let start = ctx.u64("start date and time", 168)?.to_string();
        (
            ns,
            i64::from(blocks) * 256,
            ctx.text("patient", 8, 66)?,
            ctx.text("recording", 88, 64)?,
            start,
        )
    };
    if ns == 0 {
        return Err(ctx.invalid("number of channels", 252, "a positive count", "0"));
    }
    // ns ≤ u32::MAX, so this cannot overflow a u64.
    let needed = (ns as u64 + 1) * FIXED as u64;
    if (ctx.bytes.len() as u64) < needed {
        return Err(ctx.truncated(
            format!("channel headers ({ns} channels × 256 bytes)"),
            FIXED,
            needed,
        ));
    }
    let hb_field = if major == 1 {
        "number of bytes in header"
    } else {
        "header length (256-byte blocks)"
    };
    let header_ok = if major == 1 {
        hb == needed as i64
    } else {
        hb >= needed as i64
    };
    if !header_ok {
        let at_least = if major == 1 { "" } else { "at least " };
        return Err(ctx.invalid(
            hb_field,
            184,
            format!("{at_least}{needed} bytes for {ns} channels"),
            hb.to_string(),
        ));
    }
    let header_bytes = hb as usize;
    if header_bytes > ctx.bytes.len() {
        return Err(ctx.truncated("header", 0, header_bytes as u64));
    }
    let channels = if major == 1 {
        channels_v1(ctx, ns)?
    } else {
        channels_v2(ctx, ns)?
    };
    Ok(GdfHeader {
        version,
        major,
        patient,
        recording,
        start,
        header_bytes,
        n_records: n_records as usize,
        record_duration: (num, den),
        channels,
    })
}

/// The field layout of the channel headers: (name, width) in file order.
const FIELDS_V1: [(&str, usize); 11] = [
    ("label", 16),
    ("transducer", 80),
    ("physical dimension", 8),
    ("physical minimum", 8),
    ("physical maximum", 8),
    ("digital minimum", 8),
    ("digital maximum", 8),
    ("prefiltering", 80),
    ("samples per record", 4),
    ("data type", 4),
    ("reserved", 32),
];

const FIELDS_V2: [(&str, usize); 16] = [
    ("label", 16),
    ("transducer", 80),
    ("physical dimension (text)", 6),
    ("physical dimension code", 2),
    ("physical minimum", 8),
    ("physical maximum", 8),
    ("digital minimum", 8),
    ("digital maximum", 8),
    ("prefiltering (text)", 68),
    ("low-pass", 4),
    ("high-pass", 4),
    ("notch", 4),
    ("samples per record", 4),
    ("data type", 4),
    ("sensor position", 12),
    ("sensor information", 20),
];

/// Byte offset of field `name` of channel `i`, and the field's name for messages.
struct Fields<'f> {
    layout: &'f [(&'f str, usize)],
    ns: usize,
}

impl Fields<'_> {
    fn at(&self, name: &str, i: usize) -> usize {
        let mut off = FIXED;
        for &(n, w) in self.layout {
            if n == name {
                return off + i * w;
            }
            off += w * self.ns;
        }
        debug_assert!(false, "no GDF channel field {name}");
        FIXED
    }
}

fn field_name(i: usize, label: &str, field: &str) -> String {
    format!("channel {} ({label}) {field}", i + 1)
}

/// Checks a channel's numbers: finite ranges, distinct digital limits, a known data type.
#[allow(clippy::too_many_arguments)]
fn checked_channel(
    ctx: &Ctx<'_>,
    f: &Fields<'_>,
    i: usize,
    label: String,
    (pmin, pmax, dmin, dmax): (f64, f64, f64, f64),
    spr: u32,
    typ: u32,
    rest: GdfChannel,
) -> Result<GdfChannel, IoError> {
    for (name, v) in [
        ("physical minimum", pmin),
        ("physical maximum", pmax),
        ("digital minimum", dmin),
        ("digital maximum", dmax),
    ] {
        if !v.is_finite() {
            return Err(ctx.invalid(
                field_name(i, &label, name),
                f.at(name, i),
                "a finite number",
                v.to_string(),
            ));
        }
    }
    let gain = (pmax - pmin) / (dmax - dmin);
    if dmax == dmin || !gain.is_finite() {
        return Err(ctx.invalid(
            field_name(i, &label, "digital maximum"),
            f.at("digital maximum", i),
            format!("a value other than the digital minimum {dmin} giving a finite scale"),
            dmax.to_string(),
        ));
    }
    let data_type = GdfType::from_code(typ).ok_or_else(|| {
        ctx.invalid(
            field_name(i, &label, "data type"),
            f.at("data type", i),
            "a GDF data type: 1-8 (int8…uint64), 16 (float32), 17 (float64), 279 (int24), 535 (uint24)",
            typ.to_string(),
        )
    })?;
    Ok(GdfChannel {
        label,
        physical_min: pmin,
        physical_max: pmax,
        digital_min: dmin,
        digital_max: dmax,
        samples_per_record: spr as usize,
        data_type,
        ..rest
    })
}

fn channels_v1(ctx: &Ctx<'_>, ns: usize) -> Result<Vec<GdfChannel>, IoError> {
    let f = Fields {
        layout: &FIELDS_V1,
        ns,
    };
    (0..ns)
        .map(|i| {
            let label = ctx.text("label", f.at("label", i), 16)?;
            let g = |name: &str| field_name(i, &label, name);
            let dimension = ctx.text(&g("physical dimension"), f.at("physical dimension", i), 8)?;
            let nums = (
                ctx.f64(&g("physical minimum"), f.at("physical minimum", i))?,
                ctx.f64(&g("physical maximum"), f.at("physical maximum", i))?,
                ctx.i64(&g("digital minimum"), f.at("digital minimum", i))? as f64,
                ctx.i64(&g("digital maximum"), f.at("digital maximum", i))? as f64,
            );
            let rest = GdfChannel {
                label: String::new(),
                transducer: ctx.text(&g("transducer"), f.at("transducer", i), 80)?,
                dimension,
                dimension_code: None,
                physical_min: 0.0,
                physical_max: 0.0,
                digital_min: 0.0,
                digital_max: 0.0,
                prefiltering: ctx.text(&g("prefiltering"), f.at("prefiltering", i), 80)?,
                filters: None,
                samples_per_record: 0,
                data_type: GdfType::Int8,
            };
            let spr = ctx.u32(&g("samples per record"), f.at("samples per record", i))?;
            let typ = ctx.u32(&g("data type"), f.at("data type", i))?;
            checked_channel(ctx, &f, i, label, nums, spr, typ, rest)
        })
        .collect()
}

fn channels_v2(ctx: &Ctx<'_>, ns: usize) -> Result<Vec<GdfChannel>, IoError> {
    let f = Fields {
        layout: &FIELDS_V2,
        ns,
    };
    (0..ns)
        .map(|i| {
            let label = ctx.text("label", f.at("label", i), 16)?;
            let g = |name: &str| field_name(i, &label, name);
            let code = ctx.u16(
                &g("physical dimension code"),
                f.at("physical dimension code", i),
            )?;
            let dimension = if code == 0 {
                ctx.text(
                    &g("physical dimension (text)"),
                    f.at("physical dimension (text)", i),
                    6,
                )?
            } else {
                dimension_text(code)
            };
            let nums = (
                ctx.f64(&g("physical minimum"), f.at("physical minimum", i))?,
                ctx.f64(&g("physical maximum"), f.at("physical maximum", i))?,
                ctx.f64(&g("digital minimum"), f.at("digital minimum", i))?,
                ctx.f64(&g("digital maximum"), f.at("digital maximum", i))?,
            );
            let filters = [
                ctx.f32(&g("low-pass"), f.at("low-pass", i))?,
                ctx.f32(&g("high-pass"), f.at("high-pass", i))?,
                ctx.f32(&g("notch"), f.at("notch", i))?,
            ];
            let rest = GdfChannel {
                label: String::new(),
                transducer: ctx.text(&g("transducer"), f.at("transducer", i), 80)?,
                dimension,
                dimension_code: Some(code),
                physical_min: 0.0,
                physical_max: 0.0,
                digital_min: 0.0,
                digital_max: 0.0,
                prefiltering: String::new(),
                filters: Some(filters),
                samples_per_record: 0,
                data_type: GdfType::Int8,
            };
            let spr = ctx.u32(&g("samples per record"), f.at("samples per record", i))?;
            let typ = ctx.u32(&g("data type"), f.at("data type", i))?;
            checked_channel(ctx, &f, i, label, nums, spr, typ, rest)
        })
        .collect()
}
