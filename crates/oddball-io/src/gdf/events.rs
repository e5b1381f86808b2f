//! The event table after the data records, and the events it gives: the flashes of OpenViBE's
//! stimulation codes, or the table's own codes.

use std::collections::HashSet;

use oddball_signal::Event;

use crate::IoError;

use super::header::Ctx;
use super::types::*;

/// `OVTK_StimulationId_Label_01`: labels 0x8101..=0x81FF name the flashed row or column.
pub const OPENVIBE_LABEL_FIRST: u16 = 0x8101;
/// `OVTK_StimulationId_Label_FF`, the last label code.
pub const OPENVIBE_LABEL_LAST: u16 = 0x81FF;
/// `OVTK_StimulationId_Target`.
pub const OPENVIBE_TARGET: u16 = 0x8205;
/// `OVTK_StimulationId_NonTarget`.
pub const OPENVIBE_NONTARGET: u16 = 0x8206;
/// `OVTK_StimulationId_TrialStart`.
pub const OPENVIBE_TRIAL_START: u16 = 0x8005;
/// The most samples between a label and the target / non-target flag that goes with it.
pub const OPENVIBE_FLAG_TOLERANCE: usize = 2;

/// Reads the event table starting at byte `at` (the end of the data records): the table, or
/// `None` when the file ends there, and the number of bytes after it.
pub(super) fn parse_event_table(
    ctx: &Ctx<'_>,
    major: u8,
    at: usize,
) -> Result<(Option<GdfEventTable>, usize), IoError> {
    let len = ctx.bytes.len();
    if at >= len {
        return Ok((None, 0));
    }
    ctx.slice("event table header (8 bytes)", at, 8)?;
    let mode = ctx.u8("event table mode", at)?;
    if mode != 1 && mode != 3 {
        return Err(ctx.invalid(
            "event table mode",
            at,
            "1 (position, type) or 3 (position, type, channel, duration)",
            mode.to_string(),
        ));
    }
    let (n, sample_rate, sr_at) = if major == 1 {
        let sr = ctx.u24("event table sample rate", at + 1)?;
        (ctx.u32("number of events", at + 4)?, f64::from(sr), at + 1)
    } else {
        let sr = ctx.f32("event table sample rate", at + 4)?;
        (ctx.u24("number of events", at + 1)?, f64::from(sr), at + 4)
    };
    if !sample_rate.is_finite() || sample_rate < 0.0 {
        return Err(ctx.invalid(
            "event table sample rate",
            sr_at,
            "a rate in Hz ≥ 0 (0: the data's rate)",
            sample_rate.to_string(),
        ));
    }
    let per: u64 = if mode == 3 { 12 } else { 6 };
    let needed = at as u64 + 8 + u64::from(n) * per;
    if needed > len as u64 {
        return Err(ctx.truncated(
            format!("event table ({n} events of {per} bytes)"),
            at,
            needed,
        ));
    }
    // needed ≤ len, so every offset below is in the file.
    let n = n as usize;
    let base = at + 8;
    let mut events = Vec::with_capacity(n);
    for k in 0..n {
        let (channel, duration) = if mode == 3 {
            (
                ctx.u16("event channel", base + 6 * n + 2 * k)?,
                ctx.u32("event duration", base + 8 * n + 4 * k)?,
            )
        } else {
            (0, 0)
        };
        events.push(GdfEvent {
            position: ctx.u32("event position", base + 4 * k)?,
            typ: ctx.u16("event type", base + 4 * n + 2 * k)?,
            channel,
            duration,
        });
    }
    Ok((
        Some(GdfEventTable {
            mode,
            sample_rate,
            events,
        }),
        len - needed as usize,
    ))
}

/// The events of a table, with the entries outside the recording counted and, for OpenViBE
/// files, what the stimulation codes made.
pub(super) struct TableEvents {
    pub(super) events: Vec<Event>,
    pub(super) outside: usize,
    pub(super) openvibe: Option<OpenVibeEvents>,
}

/// The 0-based data sample of a table position (1-based, at the table's rate; a rate of 0 or
/// the data's own means samples of the data), if inside the recording.
pub(super) fn sample_of(
    position: u32,
    table_rate: f64,
    sfreq: f64,
    n_times: usize,
) -> Option<usize> {
    let p = f64::from(position.checked_sub(1)?);
    let s = if table_rate > 0.0 && table_rate != sfreq {
        (p * sfreq / table_rate).round()
    } else {
        p
    };
    (s < n_times as f64).then_some(s as usize)
}

/// Whether a table holds OpenViBE's P300 stimulations: at least one label code
/// (0x8101..=0x81FF) and at least one target or non-target flag (0x8205/0x8206).
pub fn is_openvibe(events: &[GdfEvent]) -> bool {
    events.iter().any(|e| is_label(e.typ)) && events.iter().any(|e| is_flag(e.typ))
}

fn is_label(t: u16) -> bool {
    (OPENVIBE_LABEL_FIRST..=OPENVIBE_LABEL_LAST).contains(&t)
}

fn is_flag(t: u16) -> bool {
    t == OPENVIBE_TARGET || t == OPENVIBE_NONTARGET
}

pub(super) fn table_events(
    table: Option<&GdfEventTable>,
    sfreq: f64,
    n_times: usize,
) -> TableEvents {
    let Some(table) = table else {
        return TableEvents {
            events: Vec::new(),
            outside: 0,
            openvibe: None,
        };
    };
    let samples: Vec<Option<usize>> = table
        .events
        .iter()
        .map(|e| sample_of(e.position, table.sample_rate, sfreq, n_times))
        .collect();
    let outside = samples.iter().filter(|s| s.is_none()).count();
    if is_openvibe(&table.events) {
        let (events, ov) = openvibe_flashes(&table.events, &samples);
        return TableEvents {
            events,
            outside,
            openvibe: Some(ov),
        };
    }
    let events = table
        .events
        .iter()
        .zip(&samples)
        .filter_map(|(e, s)| s.map(|s| Event::new(s, u32::from(e.typ))))
        .collect();
    TableEvents {
        events,
        outside,
        openvibe: None,
    }
}

/// OpenViBE's flashes: one per label (a label repeated at the same sample counts once), code
/// `label − 0x8100`, its target flag from the nearest unused 0x8205/0x8206 within
/// [`OPENVIBE_FLAG_TOLERANCE`] samples (ties: the earlier flag).
fn openvibe_flashes(table: &[GdfEvent], samples: &[Option<usize>]) -> (Vec<Event>, OpenVibeEvents) {
    let inside = |pred: fn(u16) -> bool| -> Vec<(usize, u16, usize)> {
        let mut v: Vec<(usize, u16, usize)> = table
            .iter()
            .zip(samples)
            .enumerate()
            .filter_map(|(i, (e, s))| s.filter(|_| pred(e.typ)).map(|s| (s, e.typ, i)))
            .collect();
        v.sort_by_key(|&(s, _, i)| (s, i));
        v
    };
    let labels = inside(is_label);
    let flags = inside(is_flag);
    let mut seen = HashSet::new();
    let mut ov = OpenVibeEvents::default();
    let mut used = vec![false; flags.len()];
    let mut events = Vec::new();
    for &(s, t, _) in &labels {
        if !seen.insert((s, t)) {
            ov.duplicate_labels += 1;
            continue;
        }
        let lo = flags.partition_point(|f| f.0 + OPENVIBE_FLAG_TOLERANCE < s);
        let best = (lo..flags.len())
            .take_while(|&j| flags[j].0 <= s + OPENVIBE_FLAG_TOLERANCE)
            .filter(|&j| !used[j])
            .min_by_key(|&j| (flags[j].0.abs_diff(s), flags[j].0, flags[j].2));
        let mut e = Event::new(s, u32::from(t - 0x8100));
        match best {
            Some(j) => {
                used[j] = true;
                e = e.with_target(flags[j].1 == OPENVIBE_TARGET);
            }
            None => ov.unflagged_labels += 1,
        }
        events.push(e);
    }
    ov.orphan_flags = used.iter().filter(|u| !**u).count();
    ov.trial_starts = inside(|t| t == OPENVIBE_TRIAL_START)
        .into_iter()
        .map(|(s, _, _)| s)
        .collect();
    ov.flashes_per_trial = ov
        .trial_starts
        .iter()
        .enumerate()
        .map(|(k, &start)| {
            let end = ov.trial_starts.get(k + 1).copied().unwrap_or(usize::MAX);
            events
                .iter()
                .filter(|e| e.onset >= start && e.onset < end)
                .count()
        })
        .collect();
    for e in table.iter().filter(|e| !is_label(e.typ) && !is_flag(e.typ)) {
        *ov.other_codes.entry(e.typ).or_default() += 1;
    }
    (events, ov)
}
