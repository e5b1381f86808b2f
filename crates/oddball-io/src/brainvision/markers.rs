//! The marker file (`.vmrk`): `[Marker Infos]` entries `MkN=Type,Description,Position,Size,
//! Channel[,Date]`, and the events they make.

use std::collections::BTreeMap;
use std::path::Path;

use oddball_signal::Event;

use crate::events::LabelCodes;
use crate::IoError;

use super::ini;
use super::types::BvMarker;

/// Every marker, the events, the codes of the texts.
pub(super) type Markers = (Vec<BvMarker>, Vec<Event>, BTreeMap<String, u32>);

/// The markers of a `.vmrk` file in file order, the events of those inside the recording's
/// `n_times` samples, and the codes given to non-numeric descriptions.
pub(super) fn parse_markers(bytes: &[u8], path: &Path, n_times: usize) -> Result<Markers, IoError> {
    let ini = ini::parse(bytes, path, "Marker")?;
    let mut markers = Vec::new();
    for e in ini.section("Marker Infos") {
        let is_marker = e.key.get(..2).is_some_and(|p| p.eq_ignore_ascii_case("mk"))
            && e.key.len() > 2
            && e.key.bytes().skip(2).all(|b| b.is_ascii_digit());
        if !is_marker {
            continue;
        }
        let f = ini.fields(e);
        if f.len() < 4 {
            return Err(ini.invalid(
                format!("[Marker Infos] {}", e.key),
                e.value_at,
                "`Type,Description,Position,Size[,Channel[,Date]]`",
                ini.text(e),
            ));
        }
        let number = |i: usize, what: &str, empty: i64| -> Result<i64, IoError> {
            let t = f[i].text.trim();
            if t.is_empty() {
                return Ok(empty);
            }
            t.parse::<i64>().map_err(|_| {
                ini.invalid(
                    format!("[Marker Infos] {} {what}", e.key),
                    f[i].at,
                    "a whole number",
                    f[i].text.clone(),
                )
            })
        };
        let position = number(2, "position", 0)?;
        let onset = (if position >= 1 {
            usize::try_from(position - 1).ok()
        } else {
            None
        })
        .ok_or_else(|| {
            ini.invalid(
                format!("[Marker Infos] {} position", e.key),
                f[2].at,
                "a 1-based sample number (1 or more)",
                f[2].text.clone(),
            )
        })?;
        let size = number(3, "size", 0)?;
        let size = u64::try_from(size).map_err(|_| {
            ini.invalid(
                format!("[Marker Infos] {} size", e.key),
                f[3].at,
                "a number of samples (0 or more)",
                f[3].text.clone(),
            )
        })?;
        let channel = if f.len() > 4 {
            number(4, "channel", 0)?
        } else {
            0
        };
        let date = f
            .get(5)
            .map(|d| d.text.trim().to_string())
            .filter(|d| !d.is_empty());
        markers.push(BvMarker {
            kind: f[0].text.clone(),
            description: f[1].text.clone(),
            onset,
            size,
            channel,
            date,
            code: None,
        });
    }
    let (events, codes) = marker_events(&mut markers, n_times);
    Ok((markers, events, codes))
}

/// The events of the markers: `Stimulus` `S n` → code n, `Response` `R n` → code 1000 + n
/// (MNE's numbering), any other `Stimulus`/`Response` description → a code from
/// [`LabelCodes`]; each labelled `Type/Description` as MNE names its annotation.
fn marker_events(markers: &mut [BvMarker], n_times: usize) -> (Vec<Event>, BTreeMap<String, u32>) {
    let numeric: Vec<Option<u32>> = markers.iter().map(numeric_code).collect();
    let max = numeric.iter().flatten().copied().max().unwrap_or(0);
    let mut labels = LabelCodes::after(max);
    let mut events = Vec::new();
    for (m, num) in markers.iter_mut().zip(numeric) {
        if m.kind != "Stimulus" && m.kind != "Response" {
            continue;
        }
        let label = format!("{}/{}", m.kind, m.description);
        let code = num.unwrap_or_else(|| labels.code(&label));
        m.code = Some(code);
        if m.onset < n_times {
            events.push(Event::new(m.onset, code).with_label(label));
        }
    }
    (events, labels.into_map())
}

/// `S  1` of a `Stimulus` → 1, `R 12` of a `Response` → 1012; `None` for anything else.
fn numeric_code(m: &BvMarker) -> Option<u32> {
    let (letter, offset) = match m.kind.as_str() {
        "Stimulus" => ('S', 0u32),
        "Response" => ('R', 1000),
        _ => return None,
    };
    let digits = m.description.strip_prefix(letter)?.trim();
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse::<u32>().ok()?.checked_add(offset)
}

/// The marker type and description that [`numeric_code`] reads back as `code`: `Response`
/// `R  n` for 1000 + n (n ≤ 999), else `Stimulus` `S  n`; the number right-aligned in three
/// characters as pybv and BrainVision Recorder write it (MNE reads the last three characters,
/// so a code from 2000 up reads back here but not as MNE's number).
pub(super) fn marker_of_code(code: u32) -> (&'static str, String) {
    match code {
        1000..=1999 => ("Response", format!("R{:>3}", code - 1000)),
        _ => ("Stimulus", format!("S{code:>3}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_is_written_as_the_marker_that_reads_back_as_it() {
        for code in (0..3000).chain([9999, 65535, u32::MAX]) {
            let (kind, description) = marker_of_code(code);
            let m = BvMarker {
                kind: kind.into(),
                description: description.clone(),
                onset: 0,
                size: 1,
                channel: 0,
                date: None,
                code: None,
            };
            assert_eq!(numeric_code(&m), Some(code), "{kind},{description}");
        }
        assert_eq!(marker_of_code(1), ("Stimulus", "S  1".to_string()));
        assert_eq!(marker_of_code(1003), ("Response", "R  3".to_string()));
        assert_eq!(marker_of_code(2000), ("Stimulus", "S2000".to_string()));
    }
}
