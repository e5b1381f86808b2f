//! A stimulus program's paradigm as a file: its choices, which marker flashes which of them, how
//! a trial starts and ends, which markers flag targets or cue the attended choice, and the epoch
//! window — what `oddball decode` needs to decode another program's session.
//!
//! ```toml
//! name = "four-bulb"
//! decoys = [5]               # optional: codes flashed that show no choice (never attended)
//! [choices]                  # one choice per code (a speller takes its symbols from [speller])
//! labels = ["up", "down", "left", "right"]
//! codes = [1, 2, 3, 4]       # or [groups]: "1" = ["up", "left"]  (code → the choices it flashes)
//! [markers]                  # `{code}` a stimulus code (an integer), `{label}` a choice's label
//! flash = ["Stim/{code}"]    # one or more patterns; "{code}" alone reads a numeric stream
//! trial_start = "TrialStart" # optional
//! trial_end = "TrialEnd"     # or flashes_per_trial = 40
//! cue = "Cue/{label}"        # optional: the attended choice of a calibration trial
//! [events]                   # the manifest's table: markers flagging the flash at their timestamp
//! target = ["Target"]
//! nontarget = ["NonTarget"]
//! [speller]                  # the manifest's table (matrix, columns, rows, repetitions)
//! [epoch]                    # optional, s after the flash
//! tmin = 0.0
//! tmax = 0.8
//! ```
//!
//! **Decoys** are flashes of something nobody is asked to attend (a blank, an extra symbol that
//! is never a target, as in Hübner et al. 2017's label-proportion speller). They count as
//! flashes but add evidence to no choice; a calibration takes them as non-targets, and so does
//! the unsupervised decoder, which is where they pay: their epochs are the one group whose labels
//! the paradigm gives away (`oddball_decode::unsupervised::Constraint::with_decoys`).
//!
//! The `[events]` and `[speller]` tables are the data-set manifest's ([`crate::manifest`]): one
//! vocabulary for a recording's events and a live program's markers. [`Paradigm::parse`] checks
//! everything that can be checked before a stream is opened (unknown keys, patterns, codes
//! flashing unknown choices, a trial with no end); [`Paradigm::read`] classifies one marker.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::events::{EventKey, EventMapping};
use crate::manifest::SpellerSpec;
use crate::speller::Speller;

/// Most choices a paradigm may have (a 16×16 matrix).
pub const MAX_CHOICES: usize = 256;
/// Longest marker text a paradigm reads; longer markers are not its own.
pub const MAX_MARKER_CHARS: usize = 256;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParadigmFile {
    name: String,
    decoys: Option<Vec<u32>>,
    choices: Option<ChoicesTable>,
    groups: Option<BTreeMap<String, Vec<String>>>,
    speller: Option<SpellerSpec>,
    markers: MarkersTable,
    events: Option<EventMapping>,
    epoch: Option<EpochTable>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ChoicesTable {
    labels: Vec<String>,
    codes: Option<Vec<u32>>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum OneOrMany {
    One(String),
    Many(Vec<String>),
}

impl OneOrMany {
    fn into_vec(self) -> Vec<String> {
        match self {
            Self::One(s) => vec![s],
            Self::Many(v) => v,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MarkersTable {
    flash: OneOrMany,
    trial_start: Option<OneOrMany>,
    trial_end: Option<OneOrMany>,
    flashes_per_trial: Option<usize>,
    cue: Option<OneOrMany>,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
struct EpochTable {
    tmin: f64,
    tmax: f64,
}

/// What a placeholder in a marker pattern stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Code,
    Label,
}

/// A marker pattern: literal text around at most one placeholder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pattern {
    prefix: String,
    slot: Option<Slot>,
    suffix: String,
    text: String,
}

impl Pattern {
    fn parse(text: &str) -> Result<Self, String> {
        let t = text.trim();
        if t.is_empty() {
            return Err("an empty marker pattern".into());
        }
        let mut found = None;
        for (name, slot) in [("{code}", Slot::Code), ("{label}", Slot::Label)] {
            if let Some(i) = t.find(name) {
                if found.is_some() || t[i + name.len()..].contains(name) {
                    return Err(format!("{t:?} has more than one placeholder"));
                }
                found = Some((i, name.len(), slot));
            }
        }
        let (prefix, slot, suffix) = match found {
            Some((i, n, slot)) => (&t[..i], Some(slot), &t[i + n..]),
            None => (t, None, ""),
        };
        if prefix.contains(['{', '}']) || suffix.contains(['{', '}']) {
            return Err(format!(
                "{t:?}: the only placeholders are {{code}} and {{label}}"
            ));
        }
        Ok(Self {
            prefix: prefix.to_string(),
            slot,
            suffix: suffix.to_string(),
            text: t.to_string(),
        })
    }

    /// The text between the literal parts, when `marker` fits this pattern.
    fn capture<'a>(&self, marker: &'a str) -> Option<&'a str> {
        let rest = marker.strip_prefix(self.prefix.as_str())?;
        let mid = rest.strip_suffix(self.suffix.as_str())?;
        match self.slot {
            None => mid.is_empty().then_some(mid),
            Some(_) => (!mid.is_empty()).then_some(mid),
        }
    }

    /// The pattern as written.
    pub fn as_str(&self) -> &str {
        &self.text
    }
}

/// What one marker means.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MarkerKind {
    /// A flash of stimulus `code`.
    Flash {
        code: u32,
    },
    /// The flash at this timestamp was a target (`true`) or not.
    Flag {
        target: bool,
    },
    TrialStart,
    TrialEnd,
    /// The attended choice of the coming (or current) trial.
    Cue {
        choice: usize,
    },
    /// None of the paradigm's markers (an unknown text, a code no choice has).
    Unknown,
}

/// How a trial ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrialEnd {
    /// At a marker.
    Marker,
    /// After this many flashes.
    Flashes(usize),
}

/// A checked paradigm.
#[derive(Debug, Clone, PartialEq)]
pub struct Paradigm {
    pub name: String,
    /// The choices' labels (a speller's: its symbols, row by row).
    pub labels: Vec<String>,
    /// Each stimulus code and the choices (indices into `labels`) it flashes.
    pub groups: BTreeMap<u32, Vec<usize>>,
    /// Codes flashed that show no choice (never attended), ascending.
    pub decoys: Vec<u32>,
    /// The speller, when the choices are a row/column matrix.
    pub speller: Option<Speller>,
    /// Epoch window (s after the flash), when the file gives one.
    pub epoch: Option<(f64, f64)>,
    pub trial_end: TrialEnd,
    flash: Vec<Pattern>,
    trial_start: Vec<Pattern>,
    trial_end_markers: Vec<Pattern>,
    cue: Vec<Pattern>,
    flags: Option<EventMapping>,
    /// The file read (for messages).
    pub path: PathBuf,
}

/// A paradigm file that cannot be used, with the file and the field at fault.
#[derive(Debug, Error)]
pub enum ParadigmError {
    #[error(transparent)]
    File(Box<crate::IoError>),
    #[error("{path}: cannot read the paradigm: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Parse {
        path: PathBuf,
        source: Box<toml::de::Error>,
    },
    #[error("{path}: {field}: {what}")]
    Invalid {
        path: PathBuf,
        field: &'static str,
        what: String,
    },
}

/// Paradigm files larger than this are not paradigm files.
const MAX_FILE_BYTES: u64 = 1 << 20;

impl Paradigm {
    /// Reads and checks a paradigm file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ParadigmError> {
        let path = path.as_ref();
        crate::check_file(path).map_err(|e| ParadigmError::File(Box::new(e)))?;
        let read = |source| ParadigmError::Read {
            path: path.to_path_buf(),
            source,
        };
        let len = std::fs::metadata(path).map_err(read)?.len();
        if len > MAX_FILE_BYTES {
            return Err(ParadigmError::Invalid {
                path: path.to_path_buf(),
                field: "file",
                what: format!("{len} bytes; a paradigm file is under {MAX_FILE_BYTES} bytes"),
            });
        }
        let text = std::fs::read_to_string(path).map_err(read)?;
        Self::parse(&text, path)
    }

    /// Parses and checks paradigm text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ParadigmError> {
        let f: ParadigmFile = toml::from_str(text).map_err(|e| ParadigmError::Parse {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
        let bad = |field: &'static str, what: String| ParadigmError::Invalid {
            path: path.to_path_buf(),
            field,
            what,
        };
        if f.name.trim().is_empty() {
            return Err(bad("name", "is empty".into()));
        }
        let (labels, groups, speller) = match (&f.choices, &f.speller) {
            (Some(_), Some(_)) => {
                return Err(bad(
                    "[choices]",
                    "give [choices] or [speller], not both (a speller's choices are its symbols)"
                        .into(),
                ))
            }
            (None, None) => return Err(bad("[choices]", "missing (or give [speller])".into())),
            (None, Some(sp)) => {
                if f.groups.is_some() {
                    return Err(bad(
                        "[groups]",
                        "a speller's rows and columns are its groups".into(),
                    ));
                }
                sp.validate().map_err(|w| bad("[speller]", w))?;
                let speller = sp.speller().map_err(|w| bad("[speller]", w))?;
                let n_cols = speller.n_cols();
                let labels: Vec<String> = speller.matrix().iter().flatten().cloned().collect();
                let mut groups = BTreeMap::new();
                for r in 0..speller.n_rows() {
                    groups.insert(
                        speller.code_of_row(r),
                        (0..n_cols).map(|c| r * n_cols + c).collect(),
                    );
                }
                for c in 0..n_cols {
                    groups.insert(
                        speller.code_of_col(c),
                        (0..speller.n_rows()).map(|r| r * n_cols + c).collect(),
                    );
                }
                (labels, groups, Some(speller))
            }
            (Some(ch), None) => {
                let labels: Vec<String> = ch.labels.iter().map(|l| l.trim().to_string()).collect();
                if labels.len() < 2 || labels.len() > MAX_CHOICES {
                    return Err(bad(
                        "choices.labels",
                        format!(
                            "{} choices; a paradigm has 2 to {MAX_CHOICES}",
                            labels.len()
                        ),
                    ));
                }
                for (i, l) in labels.iter().enumerate() {
                    if l.is_empty() || l.chars().count() > MAX_MARKER_CHARS {
                        return Err(bad(
                            "choices.labels",
                            format!("label {} is empty or too long", i + 1),
                        ));
                    }
                    if labels[..i].contains(l) {
                        return Err(bad("choices.labels", format!("{l:?} is listed twice")));
                    }
                }
                let mut groups = BTreeMap::new();
                match (&ch.codes, &f.groups) {
                    (Some(_), Some(_)) | (None, None) => {
                        return Err(bad(
                            "choices.codes",
                            "give the code of each choice (choices.codes) or the choices of each code ([groups]), one of them".into(),
                        ))
                    }
                    (Some(codes), None) => {
                        if codes.len() != labels.len() {
                            return Err(bad(
                                "choices.codes",
                                format!("{} codes for {} labels", codes.len(), labels.len()),
                            ));
                        }
                        for (i, &c) in codes.iter().enumerate() {
                            if groups.insert(c, vec![i]).is_some() {
                                return Err(bad("choices.codes", format!("code {c} is listed twice")));
                            }
                        }
                    }
                    (None, Some(g)) => {
                        for (code, members) in g {
                            let c: u32 = code.trim().parse().map_err(|_| {
                                bad("[groups]", format!("{code:?} is not a stimulus code (an integer)"))
                            })?;
                            let mut idx = Vec::new();
                            for m in members {
                                let i = labels.iter().position(|l| l == m.trim()).ok_or_else(|| {
                                    bad("[groups]", format!("code {c} flashes {m:?}, which is not one of the choices"))
                                })?;
                                if idx.contains(&i) {
                                    return Err(bad("[groups]", format!("code {c} lists {m:?} twice")));
                                }
                                idx.push(i);
                            }
                            if idx.is_empty() {
                                return Err(bad("[groups]", format!("code {c} flashes no choice")));
                            }
                            idx.sort_unstable();
                            if groups.insert(c, idx).is_some() {
                                return Err(bad("[groups]", format!("code {c} is listed twice")));
                            }
                        }
                        for (i, l) in labels.iter().enumerate() {
                            if !groups.values().any(|g: &Vec<usize>| g.contains(&i)) {
                                return Err(bad("[groups]", format!("no code flashes {l:?}")));
                            }
                        }
                    }
                }
                (labels, groups, None)
            }
        };
        let patterns = |field: &'static str, v: Option<OneOrMany>| {
            v.map(OneOrMany::into_vec)
                .unwrap_or_default()
                .iter()
                .map(|p| Pattern::parse(p).map_err(|w| bad(field, w)))
                .collect::<Result<Vec<_>, _>>()
        };
        let m = f.markers;
        let flash = patterns("markers.flash", Some(m.flash))?;
        if flash.is_empty() || flash.iter().any(|p| p.slot != Some(Slot::Code)) {
            return Err(bad(
                "markers.flash",
                "every flash pattern holds {code} (e.g. \"Stim/{code}\", or \"{code}\" for a numeric stream)".into(),
            ));
        }
        let trial_start = patterns("markers.trial_start", m.trial_start)?;
        let trial_end_markers = patterns("markers.trial_end", m.trial_end)?;
        let cue = patterns("markers.cue", m.cue)?;
        for (field, ps) in [
            ("markers.trial_start", &trial_start),
            ("markers.trial_end", &trial_end_markers),
        ] {
            if let Some(p) = ps.iter().find(|p| p.slot.is_some()) {
                return Err(bad(
                    field,
                    format!("{:?}: a trial marker has no placeholder", p.text),
                ));
            }
        }
        if let Some(p) = cue.iter().find(|p| p.slot.is_none()) {
            return Err(bad(
                "markers.cue",
                format!("{:?} names no choice: use {{label}} or {{code}}", p.text),
            ));
        }
        let trial_end = match (trial_end_markers.is_empty(), m.flashes_per_trial) {
            (false, None) => TrialEnd::Marker,
            (true, Some(n)) if n >= 1 => TrialEnd::Flashes(n),
            (true, Some(_)) => return Err(bad("markers.flashes_per_trial", "at least 1".into())),
            (false, Some(_)) => {
                return Err(bad(
                    "markers.trial_end",
                    "give trial_end or flashes_per_trial, not both".into(),
                ))
            }
            (true, None) => {
                return Err(bad(
                    "markers.trial_end",
                    "how does a trial end? give trial_end (a marker) or flashes_per_trial".into(),
                ))
            }
        };
        let mut decoys = f.decoys.unwrap_or_default();
        if decoys.len() > MAX_CHOICES {
            return Err(bad(
                "decoys",
                format!("{} codes; at most {MAX_CHOICES}", decoys.len()),
            ));
        }
        decoys.sort_unstable();
        if let Some(w) = decoys.windows(2).find(|w| w[0] == w[1]) {
            return Err(bad("decoys", format!("code {} is listed twice", w[0])));
        }
        if let Some(c) = decoys.iter().find(|c| groups.contains_key(c)) {
            return Err(bad(
                "decoys",
                format!("code {c} flashes a choice; a decoy flashes none"),
            ));
        }
        if let Some(e) = &f.events {
            e.validate().map_err(|e| bad("[events]", e.to_string()))?;
        }
        let epoch = match f.epoch {
            Some(EpochTable { tmin, tmax }) => {
                if !(tmin.is_finite()
                    && tmax.is_finite()
                    && tmin >= -1.0
                    && tmin < tmax
                    && tmax <= 2.0)
                {
                    return Err(bad(
                        "[epoch]",
                        format!("tmin {tmin}, tmax {tmax}: need -1 <= tmin < tmax <= 2 (s)"),
                    ));
                }
                Some((tmin, tmax))
            }
            None => None,
        };
        Ok(Self {
            name: f.name,
            labels,
            groups,
            decoys,
            speller,
            epoch,
            trial_end,
            flash,
            trial_start,
            trial_end_markers,
            cue,
            flags: f.events,
            path: path.to_path_buf(),
        })
    }

    /// The stimulus codes, ascending.
    pub fn codes(&self) -> Vec<u32> {
        self.groups.keys().copied().collect()
    }

    /// The choices (indices into `labels`) code `code` flashes: none for a decoy or an unknown
    /// code.
    pub fn choices_of(&self, code: u32) -> &[usize] {
        self.groups.get(&code).map_or(&[], Vec::as_slice)
    }

    /// Whether `code` is one of the paradigm's flashes: a choice's or a decoy's.
    pub fn is_flash(&self, code: u32) -> bool {
        self.groups.contains_key(&code) || self.decoys.binary_search(&code).is_ok()
    }

    /// Whether each code flashes exactly one choice and each choice has one code.
    pub fn one_choice_per_flash(&self) -> bool {
        self.groups.values().all(|g| g.len() == 1) && self.groups.len() == self.labels.len()
    }

    /// Whether the paradigm can say which flashes are targets (flags or cues).
    pub fn labels_targets(&self) -> bool {
        self.flags.is_some() || !self.cue.is_empty()
    }

    /// What `marker` means. Flash patterns are tried first, then the flags, trial markers and
    /// cues; a text no pattern reads, or a code or label the paradigm does not have, is
    /// [`MarkerKind::Unknown`].
    pub fn read(&self, marker: &str) -> MarkerKind {
        let t = marker.trim();
        if t.is_empty() || t.chars().count() > MAX_MARKER_CHARS {
            return MarkerKind::Unknown;
        }
        for p in &self.flash {
            if let Some(code) = p.capture(t).and_then(parse_code) {
                return if self.is_flash(code) {
                    MarkerKind::Flash { code }
                } else {
                    MarkerKind::Unknown
                };
            }
        }
        if let Some(m) = &self.flags {
            let hit = |keys: &[EventKey]| keys.iter().any(|k| key_matches(k, t));
            match (hit(&m.target), hit(&m.nontarget)) {
                (true, false) => return MarkerKind::Flag { target: true },
                (false, true) => return MarkerKind::Flag { target: false },
                _ => {}
            }
        }
        if self.trial_start.iter().any(|p| p.capture(t).is_some()) {
            return MarkerKind::TrialStart;
        }
        if self
            .trial_end_markers
            .iter()
            .any(|p| p.capture(t).is_some())
        {
            return MarkerKind::TrialEnd;
        }
        for p in &self.cue {
            let Some(v) = p.capture(t) else { continue };
            let choice = match p.slot {
                Some(Slot::Label) => self.labels.iter().position(|l| l == v),
                Some(Slot::Code) => parse_code(v)
                    .and_then(|c| self.groups.get(&c))
                    .filter(|g| g.len() == 1)
                    .map(|g| g[0]),
                None => None,
            };
            if let Some(choice) = choice {
                return MarkerKind::Cue { choice };
            }
        }
        MarkerKind::Unknown
    }
}

/// A stimulus code from a marker: a decimal integer, or an integral number written as a float
/// (`3.0`, what a float marker stream sends).
fn parse_code(s: &str) -> Option<u32> {
    let s = s.trim();
    if let Ok(c) = s.parse::<u32>() {
        return Some(c);
    }
    let f: f64 = s.parse().ok()?;
    (f.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(&f)).then_some(f as u32)
}

fn key_matches(key: &EventKey, text: &str) -> bool {
    match key {
        EventKey::Code(c) => parse_code(text) == Some(*c),
        EventKey::Text(k) => k.trim() == text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FOUR: &str = r#"
name = "four"
[choices]
labels = ["up", "down", "left", "right"]
codes = [1, 2, 3, 4]
[markers]
flash = ["Stim/{code}", "{code}"]
trial_start = "TrialStart"
trial_end = "TrialEnd"
cue = "Cue/{label}"
[events]
target = ["Target"]
nontarget = ["NonTarget"]
"#;

    fn parse(text: &str) -> Result<Paradigm, ParadigmError> {
        Paradigm::parse(text, Path::new("p.toml"))
    }

    #[test]
    fn markers_are_read_by_their_patterns() {
        let p = parse(FOUR).unwrap();
        assert!(p.one_choice_per_flash());
        assert_eq!(p.read("Stim/3"), MarkerKind::Flash { code: 3 });
        assert_eq!(p.read(" 2 "), MarkerKind::Flash { code: 2 });
        assert_eq!(p.read("4.0"), MarkerKind::Flash { code: 4 });
        assert_eq!(p.read("Stim/9"), MarkerKind::Unknown);
        assert_eq!(p.read("Stim/"), MarkerKind::Unknown);
        assert_eq!(p.read("Target"), MarkerKind::Flag { target: true });
        assert_eq!(p.read("NonTarget"), MarkerKind::Flag { target: false });
        assert_eq!(p.read("TrialStart"), MarkerKind::TrialStart);
        assert_eq!(p.read("TrialEnd"), MarkerKind::TrialEnd);
        assert_eq!(p.read("Cue/left"), MarkerKind::Cue { choice: 2 });
        assert_eq!(p.read("Cue/north"), MarkerKind::Unknown);
        assert_eq!(p.read(&"x".repeat(1000)), MarkerKind::Unknown);
    }

    #[test]
    fn a_speller_flashes_its_rows_and_columns() {
        let p = parse(
            r#"
name = "sp"
[speller]
matrix = ["ABC", "DEF"]
columns = [3, 4, 5]
rows = [1, 2]
[markers]
flash = "{code}"
flashes_per_trial = 50
"#,
        )
        .unwrap();
        assert_eq!(p.labels, ["A", "B", "C", "D", "E", "F"]);
        assert_eq!(p.groups[&4], vec![1, 4]);
        assert_eq!(p.groups[&2], vec![3, 4, 5]);
        assert_eq!(p.trial_end, TrialEnd::Flashes(50));
        assert!(!p.one_choice_per_flash());
    }

    #[test]
    fn faults_name_the_field() {
        let cases = [
            (
                FOUR.replace("codes = [1, 2, 3, 4]", "codes = [1, 2, 3]"),
                "choices.codes",
            ),
            (FOUR.replace("Stim/{code}", "Stim/{cod}"), "markers.flash"),
            (
                FOUR.replace("trial_end = \"TrialEnd\"", ""),
                "markers.trial_end",
            ),
            (FOUR.replace("Cue/{label}", "Cue"), "markers.cue"),
            (
                FOUR.replace("\"left\", \"right\"]", "\"left\", \"up\"]"),
                "choices.labels",
            ),
            (FOUR.replace("NonTarget", "Target"), "[events]"),
            (
                format!("{FOUR}\n[epoch]\ntmin = 0.5\ntmax = 0.1\n"),
                "[epoch]",
            ),
            (
                FOUR.replace("name = \"four\"", "name = \"four\"\ndecoys = [4]"),
                "decoys: code 4 flashes a choice",
            ),
            (
                FOUR.replace("name = \"four\"", "name = \"four\"\ndecoys = [7, 7]"),
                "decoys: code 7 is listed twice",
            ),
        ];
        for (text, field) in cases {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(field), "{field}: {e}");
        }
        let e = parse(&FOUR.replace("[markers]", "[markers]\nflsh = 1")).unwrap_err();
        assert!(e.to_string().contains("unknown field"), "{e}");
    }

    #[test]
    fn decoys_are_flashes_of_no_choice() {
        let p =
            parse(&FOUR.replace("name = \"four\"", "name = \"four\"\ndecoys = [9, 5]")).unwrap();
        assert_eq!(p.decoys, vec![5, 9]);
        assert_eq!(p.read("Stim/9"), MarkerKind::Flash { code: 9 });
        assert_eq!(p.read("5"), MarkerKind::Flash { code: 5 });
        assert_eq!(p.read("Stim/6"), MarkerKind::Unknown);
        assert!(p.choices_of(9).is_empty());
        assert_eq!(p.choices_of(3), &[2]);
        // Still one choice per (choice's) flash: the decoys are not choices.
        assert!(p.one_choice_per_flash());
        assert_eq!(p.codes(), vec![1, 2, 3, 4]);
    }

    #[test]
    fn groups_map_codes_to_any_choices() {
        let p = parse(
            r#"
name = "g"
[choices]
labels = ["a", "b", "c"]
[groups]
"1" = ["a", "b"]
"2" = ["c"]
"3" = ["a"]
[markers]
flash = "F{code}"
trial_end = "end"
"#,
        )
        .unwrap();
        assert_eq!(p.groups[&1], vec![0, 1]);
        assert_eq!(p.read("F3"), MarkerKind::Flash { code: 3 });
        let e = parse(
            r#"
name = "g"
[choices]
labels = ["a", "b", "c"]
[groups]
"1" = ["a", "b"]
[markers]
flash = "F{code}"
trial_end = "end"
"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("no code flashes \"c\""), "{e}");
    }
}
