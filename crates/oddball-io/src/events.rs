//! Which events are targets: MNE's `event_id` idea for P300 recordings.
//!
//! Many recordings mark flashes with plain codes (`1` = non-target, `2` = target) or with marker
//! texts (`Target` / `NonTarget`) that no reader can interpret on its own. An [`EventMapping`]
//! names the keys of each class; [`EventMapping::apply`] sets every matching event's target flag
//! and drops the events that match neither class (as MNE's `Epochs(event_id=…)` ignores events
//! outside `event_id`). A key is a stimulus code ([`Event::code`]) or a text compared with the
//! event's label ([`Event::label`]: an EDF+ annotation, an XDF or CSV marker string).
//!
//! Written here because the mapping is oddball's own vocabulary over [`Events`]; there is nothing
//! to borrow from a crate.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use oddball_signal::{Event, Events};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One key of an event mapping: a stimulus code or a label text.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(untagged)]
pub enum EventKey {
    /// Matches events whose [`Event::code`] is this value.
    Code(u32),
    /// Matches events whose [`Event::label`] is this text (compared after trimming white space).
    Text(String),
}

impl EventKey {
    /// Whether `event` carries this key.
    pub fn matches(&self, event: &Event) -> bool {
        match self {
            EventKey::Code(c) => event.code == *c,
            EventKey::Text(t) => event.label.as_deref().map(str::trim) == Some(t.as_str()),
        }
    }
}

impl fmt::Display for EventKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EventKey::Code(c) => write!(f, "{c}"),
            EventKey::Text(t) => write!(f, "{t:?}"),
        }
    }
}

impl FromStr for EventKey {
    type Err = EventMapError;

    /// A decimal number is a code; anything else (trimmed, non-empty) is a label text.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        if s.is_empty() {
            return Err(EventMapError::EmptyKey);
        }
        if s.bytes().all(|b| b.is_ascii_digit()) {
            return s
                .parse::<u32>()
                .map(EventKey::Code)
                .map_err(|_| EventMapError::BadKey {
                    text: s.to_string(),
                    why: "a code must fit in 32 bits".into(),
                });
        }
        Ok(EventKey::Text(s.to_string()))
    }
}

/// Parses a comma-separated list of keys, e.g. `2` or `1,3` or `Target`.
pub fn parse_keys(list: &str) -> Result<Vec<EventKey>, EventMapError> {
    list.split(',').map(EventKey::from_str).collect()
}

/// Which keys are targets and which non-targets.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventMapping {
    /// Keys of the attended (target) flashes.
    pub target: Vec<EventKey>,
    /// Keys of the other flashes.
    pub nontarget: Vec<EventKey>,
}

/// What [`EventMapping::apply`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MappingReport {
    pub n_target: usize,
    pub n_nontarget: usize,
    /// Events that matched neither class, by code; they are not in the returned events.
    pub dropped: BTreeMap<u32, usize>,
}

/// A mapping that cannot be used, or a recording it does not fit.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum EventMapError {
    #[error("an empty event key (a code such as 2 or a marker text such as Target)")]
    EmptyKey,
    #[error("event key {text:?}: {why}")]
    BadKey { text: String, why: String },
    #[error("an event mapping needs at least one target and one non-target key (targets: {n_target}, non-targets: {n_nontarget})")]
    Incomplete { n_target: usize, n_nontarget: usize },
    #[error("event key {key} is listed both as a target and as a non-target")]
    Overlap { key: EventKey },
    #[error("the event at sample {onset} (code {code}, label {label:?}) matches both a target and a non-target key")]
    Ambiguous {
        onset: usize,
        code: u32,
        label: Option<String>,
    },
    #[error("no event matches target keys {target} and non-target keys {nontarget}; the recording's events are {present}")]
    NoMatch {
        target: String,
        nontarget: String,
        present: String,
    },
    #[error("the event mapping matched {n_target} targets and {n_nontarget} non-targets; both classes are needed (the recording's events are {present})")]
    OneClass {
        n_target: usize,
        n_nontarget: usize,
        present: String,
    },
}

fn join(keys: &[EventKey]) -> String {
    keys.iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A short description of the codes and labels present, for error messages: `code 1 ×400, code
/// 2 ×80 ("Target")`. At most 12 entries are listed.
pub fn describe_events(events: &Events) -> String {
    if events.is_empty() {
        return "none".into();
    }
    let mut by_key: BTreeMap<(u32, Option<String>), usize> = BTreeMap::new();
    for e in events.iter() {
        let label = e.label.as_deref().map(|l| {
            let l = l.trim();
            // Never echo a huge cell back: 40 characters are enough to recognise a marker.
            l.chars().take(40).collect::<String>()
        });
        *by_key.entry((e.code, label)).or_default() += 1;
    }
    let mut parts: Vec<String> = by_key
        .iter()
        .take(12)
        .map(|((code, label), n)| match label {
            Some(l) => format!("code {code} {l:?} ×{n}"),
            None => format!("code {code} ×{n}"),
        })
        .collect();
    if by_key.len() > 12 {
        parts.push(format!("and {} more", by_key.len() - 12));
    }
    parts.join(", ")
}

impl EventMapping {
    /// A mapping from comma-separated key lists, e.g. `("2", "1")` or `("Target", "NonTarget")`;
    /// checked by [`EventMapping::validate`].
    pub fn parse(target: &str, nontarget: &str) -> Result<Self, EventMapError> {
        let m = Self {
            target: parse_keys(target)?,
            nontarget: parse_keys(nontarget)?,
        };
        m.validate()?;
        Ok(m)
    }

    /// Both classes named, no key in both, no empty text.
    pub fn validate(&self) -> Result<(), EventMapError> {
        if self.target.is_empty() || self.nontarget.is_empty() {
            return Err(EventMapError::Incomplete {
                n_target: self.target.len(),
                n_nontarget: self.nontarget.len(),
            });
        }
        for k in self.target.iter().chain(&self.nontarget) {
            if let EventKey::Text(t) = k {
                if t.trim().is_empty() {
                    return Err(EventMapError::EmptyKey);
                }
            }
        }
        if let Some(k) = self.target.iter().find(|k| self.nontarget.contains(k)) {
            return Err(EventMapError::Overlap { key: k.clone() });
        }
        Ok(())
    }

    /// The class of one event: `Some(true)` target, `Some(false)` non-target, `None` neither.
    pub fn classify(&self, event: &Event) -> Result<Option<bool>, EventMapError> {
        let t = self.target.iter().any(|k| k.matches(event));
        let n = self.nontarget.iter().any(|k| k.matches(event));
        match (t, n) {
            (true, true) => Err(EventMapError::Ambiguous {
                onset: event.onset,
                code: event.code,
                label: event.label.clone(),
            }),
            (true, false) => Ok(Some(true)),
            (false, true) => Ok(Some(false)),
            (false, false) => Ok(None),
        }
    }

    /// The events with their target flags set by this mapping; events matching neither class are
    /// dropped (counted in the report). An error when nothing matches or only one class does,
    /// naming the codes and labels the recording has.
    pub fn apply(&self, events: &Events) -> Result<(Events, MappingReport), EventMapError> {
        self.validate()?;
        let mut report = MappingReport::default();
        let mut kept = Vec::with_capacity(events.len());
        for e in events.iter() {
            match self.classify(e)? {
                Some(target) => {
                    if target {
                        report.n_target += 1;
                    } else {
                        report.n_nontarget += 1;
                    }
                    kept.push(e.clone().with_target(target));
                }
                None => *report.dropped.entry(e.code).or_default() += 1,
            }
        }
        if kept.is_empty() {
            return Err(EventMapError::NoMatch {
                target: join(&self.target),
                nontarget: join(&self.nontarget),
                present: describe_events(events),
            });
        }
        if report.n_target == 0 || report.n_nontarget == 0 {
            return Err(EventMapError::OneClass {
                n_target: report.n_target,
                n_nontarget: report.n_nontarget,
                present: describe_events(events),
            });
        }
        Ok((Events::new(kept), report))
    }
}

/// Why a recording's events could not be labelled.
#[derive(Debug, Error)]
pub enum LabelError {
    #[error(transparent)]
    Mapping(#[from] EventMapError),
    #[error(transparent)]
    Text(#[from] crate::speller::TextLabelError),
    #[error("a spelled text labels speller recordings, and this one is not")]
    NotSpeller,
    #[error(transparent)]
    Signal(#[from] oddball_signal::SignalError),
}

impl crate::Recording {
    /// Labels the events by `mapping` ([`EventMapping::apply`]: events matching neither class
    /// are left out).
    pub fn map_events(&mut self, mapping: &EventMapping) -> Result<MappingReport, LabelError> {
        let (events, report) = mapping.apply(self.raw.events())?;
        self.raw.set_events(events)?;
        Ok(report)
    }

    /// Labels a speller recording's flashes from the text it spelled
    /// ([`crate::Speller::label_from_text`]) and records the text as the text to spell.
    pub fn label_from_text(&mut self, text: &str) -> Result<(), LabelError> {
        let speller = self.speller.as_mut().ok_or(LabelError::NotSpeller)?;
        let events = speller.label_from_text(self.raw.events(), text)?;
        speller.text_to_spell = Some(text.to_string());
        self.raw.set_events(events)?;
        Ok(())
    }
}

/// Codes for event texts that carry none (EDF+ annotations, EEGLAB event types, BrainVision
/// marker descriptions that are not numbers): one code per distinct text, in order of first
/// appearance, counting up from one above the largest numeric code of the file. The one home
/// of that rule for every reader.
#[derive(Debug, Default)]
pub(crate) struct LabelCodes {
    codes: BTreeMap<String, u32>,
    next: u32,
}

impl LabelCodes {
    /// Codes starting at `max_numeric_code + 1` (saturating).
    pub(crate) fn after(max_numeric_code: u32) -> Self {
        Self {
            codes: BTreeMap::new(),
            next: max_numeric_code.saturating_add(1),
        }
    }

    /// The code of `text`: the one it already has, else the next free one.
    pub(crate) fn code(&mut self, text: &str) -> u32 {
        if let Some(&c) = self.codes.get(text) {
            return c;
        }
        let c = self.next;
        self.next = self.next.saturating_add(1);
        self.codes.insert(text.to_string(), c);
        c
    }

    /// Every text with its code.
    pub(crate) fn into_map(self) -> BTreeMap<String, u32> {
        self.codes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events() -> Events {
        Events::new(vec![
            Event::new(10, 1),
            Event::new(20, 2),
            Event::new(30, 1),
            Event::new(40, 3),
            Event::new(50, 7).with_label("Target"),
            Event::new(60, 8).with_label(" NonTarget "),
        ])
    }

    #[test]
    fn codes_set_flags_and_other_events_are_dropped() {
        let m = EventMapping::parse("2", "1").unwrap();
        let (ev, report) = m.apply(&events()).unwrap();
        let flags: Vec<(usize, Option<bool>)> = ev.iter().map(|e| (e.onset, e.target)).collect();
        assert_eq!(
            flags,
            vec![(10, Some(false)), (20, Some(true)), (30, Some(false))]
        );
        assert_eq!((report.n_target, report.n_nontarget), (1, 2));
        assert_eq!(report.dropped, BTreeMap::from([(3, 1), (7, 1), (8, 1)]));
    }

    #[test]
    fn texts_match_labels_after_trimming() {
        let m = EventMapping::parse("Target", "NonTarget").unwrap();
        let (ev, _) = m.apply(&events()).unwrap();
        let flags: Vec<(u32, Option<bool>)> = ev.iter().map(|e| (e.code, e.target)).collect();
        assert_eq!(flags, vec![(7, Some(true)), (8, Some(false))]);
    }

    #[test]
    fn lists_and_mixed_keys_parse() {
        let keys = parse_keys("1, 3,Target").unwrap();
        assert_eq!(
            keys,
            vec![
                EventKey::Code(1),
                EventKey::Code(3),
                EventKey::Text("Target".into())
            ]
        );
        assert!(matches!(parse_keys("1,,2"), Err(EventMapError::EmptyKey)));
        assert!(matches!(
            "99999999999".parse::<EventKey>(),
            Err(EventMapError::BadKey { .. })
        ));
    }

    #[test]
    fn unusable_mappings_are_refused_with_the_facts() {
        assert_eq!(
            EventMapping::parse("2", "2,1").unwrap_err(),
            EventMapError::Overlap {
                key: EventKey::Code(2)
            }
        );
        let none = EventMapping::parse("5", "6").unwrap();
        let err = none.apply(&events()).unwrap_err().to_string();
        assert!(
            err.contains("code 1 ×2") && err.contains("\"Target\""),
            "{err}"
        );
        let one = EventMapping::parse("2", "9").unwrap();
        assert!(matches!(
            one.apply(&events()),
            Err(EventMapError::OneClass {
                n_target: 1,
                n_nontarget: 0,
                ..
            })
        ));
        let ambiguous = EventMapping {
            target: vec![EventKey::Code(7)],
            nontarget: vec![EventKey::Text("Target".into())],
        };
        assert!(matches!(
            ambiguous.apply(&events()),
            Err(EventMapError::Ambiguous { onset: 50, .. })
        ));
    }

    #[test]
    fn a_mapping_reads_from_toml_with_codes_and_texts() {
        let m: EventMapping = toml::from_str("target = [2, \"Target\"]\nnontarget = [1]").unwrap();
        assert_eq!(
            m.target,
            vec![EventKey::Code(2), EventKey::Text("Target".into())]
        );
        assert!(
            toml::from_str::<EventMapping>("target = [2]\nnontarget = [1]\nextra = 1").is_err()
        );
    }

    #[test]
    fn descriptions_are_short_even_for_huge_labels() {
        let big = "x".repeat(10_000);
        let ev = Events::new(vec![Event::new(0, 1).with_label(big)]);
        assert!(describe_events(&ev).len() < 80);
    }

    #[test]
    fn label_codes_in_order_of_first_appearance() {
        let mut c = LabelCodes::after(7);
        assert_eq!(c.code("b"), 8);
        assert_eq!(c.code("a"), 9);
        assert_eq!(c.code("b"), 8);
        let map = c.into_map();
        assert_eq!(map.len(), 2);
        assert_eq!(map["a"], 9);
        let mut top = LabelCodes::after(u32::MAX);
        assert_eq!(top.code("x"), u32::MAX);
    }
}
