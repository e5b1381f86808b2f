//! EDF+ annotations: time-stamped annotation lists (TALs) and the event text `CODE [target|nontarget][: LABEL]`.

use std::collections::BTreeMap;

use oddball_signal::Event;

use crate::events::LabelCodes;
use crate::IoError;

use super::header::*;

/// One TAL: onset, duration, texts.
pub(super) type Tal = (f64, Option<f64>, Vec<String>);

/// Parses the TALs in one annotation signal's bytes of one record (`base` = file offset).
pub(super) fn parse_tals(
    ctx: &Ctx<'_>,
    b: &[u8],
    base: usize,
    record: usize,
) -> Result<Vec<Tal>, IoError> {
    let field = || format!("annotation in data record {record}");
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == 0 {
            i += 1;
            continue;
        }
        let start = i;
        let end = b[i..]
            .iter()
            .position(|&c| c == 0)
            .map(|p| i + p)
            .ok_or_else(|| {
                ctx.invalid(
                    field(),
                    base + start,
                    "a TAL ending in 0x00",
                    "no 0x00 before the end of the signal",
                )
            })?;
        let tal = &b[start..end];
        i = end + 1;
        let Some(sep) = tal.iter().position(|&c| c == 0x14) else {
            return Err(ctx.invalid(
                field(),
                base + start,
                "`+onset[\\x15duration]\\x14text\\x14`",
                String::from_utf8_lossy(tal).into_owned(),
            ));
        };
        let stamp = &tal[..sep];
        let (onset_b, dur_b) = match stamp.iter().position(|&c| c == 0x15) {
            Some(p) => (&stamp[..p], Some(&stamp[p + 1..])),
            None => (stamp, None),
        };
        let number = |s: &[u8], signed: bool, what: &str, off: usize| -> Result<f64, IoError> {
            let text = String::from_utf8_lossy(s);
            let body = if signed {
                text.strip_prefix('+').or_else(|| text.strip_prefix('-'))
            } else {
                Some(&*text)
            };
            let ok = body.is_some_and(|d| {
                !d.is_empty()
                    && d.bytes().all(|c| c.is_ascii_digit() || c == b'.')
                    && d.bytes().filter(|&c| c == b'.').count() <= 1
                    && d.bytes().any(|c| c.is_ascii_digit())
            });
            let v = if ok { text.parse::<f64>().ok() } else { None };
            v.ok_or_else(|| ctx.invalid(field(), off, what, text.into_owned()))
        };
        let onset = number(onset_b, true, "an onset like +12.5", base + start)?;
        let duration = match dur_b {
            Some(d) => Some(number(
                d,
                false,
                "a duration like 0.25",
                base + start + onset_b.len() + 1,
            )?),
            None => None,
        };
        let mut texts: Vec<String> = tal[sep + 1..]
            .split(|&c| c == 0x14)
            .map(|t| String::from_utf8_lossy(t).into_owned())
            .collect();
        if texts.last().is_some_and(|t| t.is_empty()) {
            texts.pop();
        }
        out.push((onset, duration, texts));
    }
    Ok(out)
}

/// Code, target flag and label of an annotation text.
pub(crate) type EventText = (u32, Option<bool>, Option<String>);

/// Splits an annotation text of the form `CODE [target|nontarget][: LABEL]`.
pub(crate) fn parse_event_text(text: &str) -> Option<EventText> {
    let t = text.trim();
    let (head, label) = match t.split_once(": ") {
        Some((h, l)) => (h, Some(l.to_string())),
        None => (t, None),
    };
    let mut words = head.split_whitespace();
    let code: u32 = words.next()?.parse().ok()?;
    if !head.trim_start().starts_with(|c: char| c.is_ascii_digit()) {
        return None;
    }
    let target = match words.next() {
        None => None,
        Some("target") => Some(true),
        Some("nontarget") => Some(false),
        Some(_) => return None,
    };
    if words.next().is_some() {
        return None;
    }
    Some((code, target, label))
}

/// The code, target flag and label of each annotation text, and the codes given to the texts
/// that do not have the form `CODE [target|nontarget][: LABEL]`: one code per distinct text, in
/// order of first appearance, counting up from one above the largest code in the texts and
/// `other_max` (the largest code the recording's events have otherwise, so none is shared).
/// EDF+ and FIF annotations both get their codes here.
pub(crate) fn text_codes<'a>(
    texts: impl IntoIterator<Item = &'a str>,
    other_max: u32,
) -> (Vec<EventText>, BTreeMap<String, u32>) {
    let texts: Vec<&str> = texts.into_iter().collect();
    let parsed: Vec<Option<EventText>> = texts.iter().map(|t| parse_event_text(t)).collect();
    let max_code = parsed
        .iter()
        .flatten()
        .map(|p| p.0)
        .fold(other_max, u32::max);
    let mut label_codes = LabelCodes::after(max_code);
    let out = texts
        .iter()
        .zip(parsed)
        .map(|(text, p)| match p {
            Some(p) => p,
            None => (label_codes.code(text), None, Some(text.to_string())),
        })
        .collect();
    (out, label_codes.into_map())
}

/// The annotation text [`write_edf_plus`](super::write_edf_plus) writes for an event: `CODE [target|nontarget][: LABEL]`.
pub fn event_annotation_text(e: &Event) -> String {
    let mut s = e.code.to_string();
    match e.target {
        Some(true) => s.push_str(" target"),
        Some(false) => s.push_str(" nontarget"),
        None => {}
    }
    if let Some(l) = &e.label {
        s.push_str(": ");
        s.push_str(l);
    }
    s
}
