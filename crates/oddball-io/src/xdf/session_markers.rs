//! The marker texts an oddball session writes to its XDF recording (one home for the writer,
//! `oddball_live::record`, and this crate's reader): each flash carries its bulb's code and
//! whether it was the attended one, and calibration trials say so, so a live recording opens,
//! trains and evaluates like any labelled file, and a replay can tell calibration from control.
//!
//! | marker | meaning |
//! |---|---|
//! | `flash C target` / `flash C nontarget` | bulb `C` drawn; attended or not |
//! | `cue C calibration` / `cue C` | a calibration / an online trial starts, attending `C` (0: none) |
//! | `decision C`, `abstain`, `end` | a trial's outcome, the session's end |
//! | `pause`, `resume` | the session held before its next trial (an operator's pause), and went on |
//!
//! The live marker stream (LSL) carries the same texts without the flag and the phase
//! (`flash C`, `cue C`), which is what other programs following it expect.

/// The recorded text of a hold before the next trial (an operator's pause).
pub const PAUSE: &str = "pause";
/// The recorded text of the end of a hold: the next trial starts.
pub const RESUME: &str = "resume";

/// The recorded text of a flash of bulb `code`, attended or not.
pub fn flash_marker(code: u32, attended: bool) -> String {
    format!(
        "flash {code} {}",
        if attended { "target" } else { "nontarget" }
    )
}

/// The recorded text of a trial's cue (`intended` 0: attending nothing).
pub fn cue_marker(intended: u32, calibration: bool) -> String {
    if calibration {
        format!("cue {intended} calibration")
    } else {
        format!("cue {intended}")
    }
}

/// A recorded flash: (code, attended). `flash C` without a flag is not one (an older
/// recording, or the live stream's text).
pub fn parse_flash_marker(text: &str) -> Option<(u32, bool)> {
    let mut w = text.split_whitespace();
    let (Some("flash"), Some(code), Some(flag), None) = (w.next(), w.next(), w.next(), w.next())
    else {
        return None;
    };
    let attended = match flag {
        "target" => true,
        "nontarget" => false,
        _ => return None,
    };
    Some((code.parse().ok()?, attended))
}

/// A recorded cue: (intended code, calibration trial).
pub fn parse_cue_marker(text: &str) -> Option<(u32, bool)> {
    let mut w = text.split_whitespace();
    let (Some("cue"), Some(code)) = (w.next(), w.next()) else {
        return None;
    };
    let calibration = match (w.next(), w.next()) {
        (None, None) => false,
        (Some("calibration"), None) => true,
        _ => return None,
    };
    Some((code.parse().ok()?, calibration))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texts_read_back() {
        for (c, a) in [(1, true), (4, false)] {
            assert_eq!(parse_flash_marker(&flash_marker(c, a)), Some((c, a)));
        }
        assert_eq!(parse_flash_marker("flash 3"), None);
        assert_eq!(parse_flash_marker("flash 3 target x"), None);
        assert_eq!(parse_flash_marker("flash x target"), None);
        for (c, cal) in [(0, true), (2, false)] {
            assert_eq!(parse_cue_marker(&cue_marker(c, cal)), Some((c, cal)));
        }
        assert_eq!(parse_cue_marker("cue 2 online"), None);
    }
}
