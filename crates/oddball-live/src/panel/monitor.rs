//! Presentation faults as alarms: what the server measured (flashes undrawn or late, no
//! subject view) and what the subject page reported of itself (hidden, frames stalled or
//! missed, several bulbs lit) become episodes the operator view shows as alarms, and counts the
//! session's summary carries ([`PresentationFaults`]).
//!
//! An episode is one kind of fault: a state while it lasts (no subject view, hidden, stalled),
//! or events of one kind less than [`EPISODE_GAP_MS`] apart. Its alarm is sent when it begins,
//! at most every [`ALARM_EVERY_MS`] while it grows, and when it ends; however fast a page
//! reports, the operator view gets a bounded stream. [`FaultMonitor::holding`] is the state
//! fault a calibration holds for.

use super::protocol::{Alarm, FaultKind, PresentationFaults};

/// Events of one kind further apart than this (ms) are separate episodes.
pub const EPISODE_GAP_MS: f64 = 3000.0;
/// An episode's alarm is sent again at most this often while it grows, ms.
pub const ALARM_EVERY_MS: f64 = 500.0;
/// A subject view that reported no frame for this long draws nothing (ms).
pub const STALLED_AFTER_MS: f64 = 1000.0;
/// A subject view whose frames came this far apart (ms) in its last report is throttled (a
/// browser draws a background page once a second); a shorter hitch while flashing is a frame
/// gap, counted, not a state.
pub const THROTTLED_GAP_MS: f64 = 500.0;
/// A flash stamped this late (ms after its time) is reported late.
pub const LATE_AFTER_MS: f64 = 50.0;

/// What the server knows of its subject view now, and what it reported since the last look
/// ([`super::PanelServer::subject_view`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubjectView {
    pub connected: bool,
    /// It said it is hidden (and has not said otherwise since).
    pub hidden: bool,
    /// Since its last frame report (or since it connected), ms.
    pub since_frames_ms: f64,
    /// The longest gap between two frames in its last report, ms.
    pub last_max_gap_ms: f64,
    /// Since the last look: gaps of several frame periods while flashing, the longest gap of
    /// the reports that had them (ms), frames with more than one bulb lit.
    pub dropped: u64,
    pub dropped_gap_ms: f64,
    pub multi_lit: u64,
}

impl SubjectView {
    /// The state fault this view is in, if any (the first in [`FaultKind::ALL`]'s order).
    pub fn state_fault(&self) -> Option<FaultKind> {
        if !self.connected {
            Some(FaultKind::Disconnected)
        } else if self.hidden {
            Some(FaultKind::Hidden)
        } else if self.since_frames_ms > STALLED_AFTER_MS || self.last_max_gap_ms > THROTTLED_GAP_MS
        {
            Some(FaultKind::Stalled)
        } else {
            None
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Episode {
    active: bool,
    since_ms: f64,
    last_ms: f64,
    count: u64,
    /// The worst value seen (ms late, gap ms, bulbs).
    peak: f64,
    sent_ms: f64,
    dirty: bool,
}

/// Turns fault states and events into alarms and counts.
#[derive(Debug, Clone, Default)]
pub struct FaultMonitor {
    counts: PresentationFaults,
    episodes: [Episode; FaultKind::ALL.len()],
    /// Whether state faults hold the session now (a calibration).
    holds: bool,
}

fn index(kind: FaultKind) -> usize {
    FaultKind::ALL
        .iter()
        .position(|&k| k == kind)
        .expect("every kind is listed")
}

impl FaultMonitor {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether state faults hold the session from now on (it calibrates).
    pub fn set_holds(&mut self, holds: bool) {
        if holds != self.holds {
            self.holds = holds;
            for e in self.episodes.iter_mut().filter(|e| e.active) {
                e.dirty = true;
                e.sent_ms = f64::NEG_INFINITY;
            }
        }
    }

    /// The state fault the session should hold for now, if it holds for faults at all.
    pub fn holding(&self) -> Option<FaultKind> {
        if !self.holds {
            return None;
        }
        FaultKind::ALL
            .into_iter()
            .find(|&k| k.is_state() && self.episodes[index(k)].active)
    }

    /// `n` events of `kind` at `now_ms`, the worst of them `value`.
    pub fn event(&mut self, kind: FaultKind, now_ms: f64, n: u64, value: f64) {
        if n == 0 {
            return;
        }
        let c = &mut self.counts;
        match kind {
            FaultKind::Undrawn => c.undrawn_flashes += n,
            FaultKind::Late => c.late_flashes += n,
            FaultKind::FrameGap => {
                c.frame_gaps += n;
                c.longest_frame_gap_ms = c.longest_frame_gap_ms.max(value);
            }
            FaultKind::MultipleLit => c.multiple_lit_frames += n,
            FaultKind::Disconnected | FaultKind::Hidden | FaultKind::Stalled => {}
        }
        let e = &mut self.episodes[index(kind)];
        if !e.active || now_ms - e.last_ms > EPISODE_GAP_MS {
            *e = Episode {
                active: true,
                since_ms: now_ms,
                last_ms: now_ms,
                count: 0,
                peak: f64::NEG_INFINITY,
                sent_ms: f64::NEG_INFINITY,
                dirty: true,
            };
        }
        e.count += n;
        e.last_ms = now_ms;
        e.peak = e.peak.max(value);
        e.dirty = true;
    }

    /// Undrawn flashes in calibration: epochs calibration did not get (counted besides
    /// [`FaultMonitor::event`]'s undrawn flashes).
    pub fn calibration_undrawn(&mut self, n: u64) {
        self.counts.calibration_undrawn_flashes += n;
    }

    /// Time held for a fault (s), counted once per hold when `new` is set.
    pub fn held(&mut self, seconds: f64, new: bool) {
        self.counts.calibration_holds += u64::from(new);
        self.counts.calibration_held_s += seconds;
    }

    /// The subject view's state and reports at `now_ms`.
    pub fn view(&mut self, v: &SubjectView, now_ms: f64) {
        let state = v.state_fault();
        for kind in [
            FaultKind::Disconnected,
            FaultKind::Hidden,
            FaultKind::Stalled,
        ] {
            self.state(kind, state == Some(kind), now_ms);
        }
        self.event(FaultKind::FrameGap, now_ms, v.dropped, v.dropped_gap_ms);
        self.event(FaultKind::MultipleLit, now_ms, v.multi_lit, 2.0);
    }

    fn state(&mut self, kind: FaultKind, on: bool, now_ms: f64) {
        let e = &mut self.episodes[index(kind)];
        match (e.active, on) {
            (false, true) => {
                *e = Episode {
                    active: true,
                    since_ms: now_ms,
                    last_ms: now_ms,
                    count: 1,
                    peak: 0.0,
                    sent_ms: f64::NEG_INFINITY,
                    dirty: true,
                };
                let c = &mut self.counts;
                match kind {
                    FaultKind::Disconnected => c.disconnected += 1,
                    FaultKind::Hidden => c.hidden += 1,
                    FaultKind::Stalled => c.stalled += 1,
                    _ => {}
                }
            }
            (true, true) => e.last_ms = now_ms,
            (true, false) => {
                e.last_ms = now_ms;
                e.active = false;
                e.dirty = true;
                let s = (now_ms - e.since_ms).max(0.0) / 1e3;
                let c = &mut self.counts;
                match kind {
                    FaultKind::Disconnected => c.disconnected_s += s,
                    FaultKind::Hidden => c.hidden_s += s,
                    FaultKind::Stalled => c.stalled_s += s,
                    _ => {}
                }
            }
            (false, false) => {}
        }
    }

    /// The alarms to send at `now_ms`: episodes begun, grown (at most every
    /// [`ALARM_EVERY_MS`]) or ended since the last call.
    pub fn alarms(&mut self, now_ms: f64) -> Vec<Alarm> {
        let unix_now_ms = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64() * 1e3);
        let mut out = Vec::new();
        for (k, kind) in FaultKind::ALL.into_iter().enumerate() {
            let holds = self.holds && kind.is_state();
            let e = &mut self.episodes[k];
            // An episode of events ends when none came for a while.
            if e.active && !kind.is_state() && now_ms - e.last_ms > EPISODE_GAP_MS {
                e.active = false;
                e.dirty = true;
            }
            let due = e.dirty
                && (!e.active
                    || e.sent_ms == f64::NEG_INFINITY
                    || now_ms - e.sent_ms >= ALARM_EVERY_MS);
            if !due {
                continue;
            }
            e.dirty = false;
            e.sent_ms = now_ms;
            out.push(Alarm {
                kind,
                active: e.active,
                since_ms: e.since_ms,
                last_ms: e.last_ms,
                now_ms,
                since_unix_ms: unix_now_ms - (now_ms - e.since_ms),
                count: e.count,
                holds: holds && e.active,
                text: describe(kind, e.count, e.peak, holds && e.active),
            });
        }
        out
    }

    /// The counts so far, states still going on counted up to `now_ms`.
    pub fn counts(&self, now_ms: f64) -> PresentationFaults {
        let mut c = self.counts.clone();
        for kind in [
            FaultKind::Disconnected,
            FaultKind::Hidden,
            FaultKind::Stalled,
        ] {
            let e = &self.episodes[index(kind)];
            if e.active {
                let s = (now_ms - e.since_ms).max(0.0) / 1e3;
                match kind {
                    FaultKind::Disconnected => c.disconnected_s += s,
                    FaultKind::Hidden => c.hidden_s += s,
                    _ => c.stalled_s += s,
                }
            }
        }
        c
    }
}

/// The alarm's words.
fn describe(kind: FaultKind, count: u64, peak: f64, holds: bool) -> String {
    let s = |n: u64| if n == 1 { "" } else { "s" };
    let mut text = match kind {
        FaultKind::Disconnected => "no subject view connected: nothing is shown".to_string(),
        FaultKind::Hidden => {
            "subject view hidden (another tab or window in front, or minimised): no flash is drawn"
                .to_string()
        }
        FaultKind::Stalled => {
            "subject view draws (almost) no frames: frozen, or throttled by the browser".to_string()
        }
        FaultKind::Undrawn => format!(
            "{count} flash{} not drawn in time: their epochs are dropped",
            if count == 1 { "" } else { "es" }
        ),
        FaultKind::Late => format!(
            "{count} flash{} drawn late, up to {peak:.0} ms after their time",
            if count == 1 { "" } else { "es" }
        ),
        FaultKind::FrameGap => format!(
            "{count} frame gap{} while flashing, the longest {peak:.0} ms",
            s(count)
        ),
        FaultKind::MultipleLit => format!("{count} frame{} with more than one bulb lit", s(count)),
    };
    if holds {
        text.push_str("; calibration holds until it is over");
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view(connected: bool, hidden: bool, since: f64) -> SubjectView {
        SubjectView {
            connected,
            hidden,
            since_frames_ms: since,
            last_max_gap_ms: 17.0,
            ..SubjectView::default()
        }
    }

    #[test]
    fn a_hidden_view_is_one_alarm_while_it_lasts_and_holds_only_a_calibration() {
        let mut m = FaultMonitor::new();
        m.view(&view(true, false, 100.0), 0.0);
        assert!(m.alarms(0.0).is_empty());
        m.view(&view(true, true, 100.0), 1000.0);
        let a = m.alarms(1000.0);
        assert_eq!(a.len(), 1);
        assert_eq!(
            (a[0].kind, a[0].active, a[0].holds),
            (FaultKind::Hidden, true, false)
        );
        assert_eq!(m.holding(), None, "online: no hold");
        m.set_holds(true);
        assert_eq!(m.holding(), Some(FaultKind::Hidden));
        // Told again that it now holds, once; nothing new while it merely lasts.
        let a = m.alarms(1100.0);
        assert!(a.len() == 1 && a[0].holds && a[0].text.contains("calibration holds"));
        for t in 0..20 {
            m.view(&view(true, true, 100.0), 1200.0 + t as f64 * 40.0);
            assert!(m.alarms(1200.0 + t as f64 * 40.0).is_empty());
        }
        m.view(&view(true, false, 10.0), 4000.0);
        let a = m.alarms(4000.0);
        assert_eq!((a.len(), a[0].active, a[0].since_ms), (1, false, 1000.0));
        assert_eq!(m.holding(), None);
        let c = m.counts(5000.0);
        assert_eq!((c.hidden, c.hidden_s), (1, 3.0));
    }

    #[test]
    fn states_rank_disconnected_hidden_stalled() {
        assert_eq!(
            view(false, true, 5000.0).state_fault(),
            Some(FaultKind::Disconnected)
        );
        assert_eq!(
            view(true, true, 5000.0).state_fault(),
            Some(FaultKind::Hidden)
        );
        assert_eq!(
            view(true, false, 5000.0).state_fault(),
            Some(FaultKind::Stalled)
        );
        let throttled = SubjectView {
            last_max_gap_ms: 1000.0,
            ..view(true, false, 10.0)
        };
        assert_eq!(throttled.state_fault(), Some(FaultKind::Stalled));
        assert_eq!(view(true, false, 10.0).state_fault(), None);
    }

    #[test]
    fn events_make_bounded_alarms_and_exact_counts() {
        let mut m = FaultMonitor::new();
        // A page reporting a thousand times a second: alarms at most every 500 ms.
        let mut sent = 0;
        for i in 0..2000 {
            let t = i as f64;
            m.event(FaultKind::Undrawn, t, 1, 0.0);
            sent += m.alarms(t).len();
        }
        assert!((4..=5).contains(&sent), "{sent} alarms in 2 s");
        assert_eq!(m.counts(2000.0).undrawn_flashes, 2000);
        // Quiet for longer than an episode's gap: the episode ends, a new one begins.
        let end = m.alarms(2000.0 + EPISODE_GAP_MS + 1.0);
        assert!(end.len() == 1 && !end[0].active && end[0].count == 2000);
        m.event(FaultKind::FrameGap, 9000.0, 3, 480.0);
        let a = m.alarms(9000.0);
        assert_eq!(a[0].since_ms, 9000.0);
        assert!(a[0].text.contains("3 frame gaps") && a[0].text.contains("480 ms"));
        let c = m.counts(9000.0);
        assert_eq!((c.frame_gaps, c.longest_frame_gap_ms), (3, 480.0));
        assert!(c.any() && !PresentationFaults::default().any());
    }
}
