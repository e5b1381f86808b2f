//! The panel's WebSocket messages, JSON with a `"t"` tag: the one home of the protocol both
//! pages speak.
//!
//! Two pages connect: the subject view (`/`, WebSocket [`SUBJECT_WS`]) draws and stamps the
//! flashes; the operator view (`/operator`, WebSocket [`OPERATOR_WS`]) watches (timing,
//! progress, channel quality, decisions) and sends [`ClientMsg::Control`]. Each socket accepts
//! only its own page's messages ([`Role::accepts`]). Every server message goes to both.
//!
//! Times are milliseconds on the server's session clock ([`crate::clock::Clock`]); the page
//! keeps its own clock offset from ping/pong pairs and converts both ways. Client messages are
//! small: anything over [`MAX_CLIENT_MESSAGE`] bytes, not UTF-8, not JSON or of an unknown kind
//! is rejected with a [`ProtocolError`] naming what was wrong (and counted by the server; the
//! connection stays up).

use oddball_session::online::ChannelFaults;
use serde::{Deserialize, Serialize};

/// Largest client message accepted, bytes.
pub const MAX_CLIENT_MESSAGE: usize = 1024;

/// A flash not stamped by the page this long after its planned onset was not drawn (the server
/// voids it; the page skips it rather than draw it late), ms.
pub const UNDRAWN_AFTER_MS: f64 = 200.0;

/// How often the subject page reports its frames ([`ClientMsg::Frames`]), ms.
pub const FRAMES_EVERY_MS: f64 = 250.0;

/// The most channels the operator view's signal display carries (the first ones).
pub const MAX_SCOPE_CHANNELS: usize = 64;

/// Largest value a page's frame report may carry: frames and gaps (ms) in one report.
const MAX_REPORTED: f64 = 1e7;

/// The subject view's page and WebSocket paths.
pub const SUBJECT_PAGE: &str = "/";
pub const SUBJECT_WS: &str = "/ws";
/// The operator view's page and WebSocket paths.
pub const OPERATOR_PAGE: &str = "/operator";
pub const OPERATOR_WS: &str = "/ws/operator";

/// Which page a socket serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The person's screen: draws and stamps flashes.
    Subject,
    /// The operator's screen: watches and controls.
    Operator,
}

impl Role {
    /// Whether a page of this role may send `msg` (the subject page cannot pause or abort,
    /// the operator page cannot stamp flashes).
    pub fn accepts(self, msg: &ClientMsg) -> bool {
        match msg {
            ClientMsg::Ping { .. } => true,
            ClientMsg::On { .. }
            | ClientMsg::Off { .. }
            | ClientMsg::Hello { .. }
            | ClientMsg::Clock { .. }
            | ClientMsg::Frames { .. }
            | ClientMsg::Visibility { .. } => self == Role::Subject,
            ClientMsg::Control { .. } => self == Role::Operator,
        }
    }
}

/// What the operator asks of the session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Control {
    /// Hold before the next trial (a trial under way finishes first).
    Pause,
    Resume,
    /// Stop the session as SIGTERM does: the recording closed, the summary written.
    Abort,
}

/// One channel's signal quality: epochs its faults cost, in the last trial and in all.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelQuality {
    pub name: String,
    pub last: ChannelFaults,
    pub total: ChannelFaults,
}

/// Static facts the page needs to draw: sent on connect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PanelConfig {
    /// Bulb codes in panel order with their labels (`up`, `right`, …).
    pub bulbs: Vec<(u32, String)>,
    pub flash_ms: f64,
    pub countdown_s: f64,
    /// The board, metres: x_min, x_max, z_min, z_max.
    pub board_m: [f64; 4],
    /// The arm's base, metres.
    pub base_m: [f64; 2],
    /// The arm's pose before it first moves: elbow and pen, metres.
    pub pose_m: [[f64; 2]; 2],
    /// The task: targets to reach (metres), and the planned shape (a polyline, metres).
    pub targets_m: Vec<[f64; 2]>,
    pub plan_m: Vec<[f64; 2]>,
    /// What runs: e.g. "sim typical seed 1, lda".
    pub title: String,
    /// A flash this late (ms after its time) is skipped, not drawn: the server voids it anyway
    /// ([`UNDRAWN_AFTER_MS`]).
    pub undrawn_after_ms: f64,
    /// How often the page reports its frames, ms ([`FRAMES_EVERY_MS`]).
    pub frames_every_ms: f64,
}

impl PanelConfig {
    /// What the page needs to draw `paradigm`'s bulbs and `arm` on its board, with the task's
    /// targets and planned path (metres).
    pub fn for_arm(
        arm: &oddball_arm::ArmSim,
        paradigm: &oddball_session::paradigm::FourBulbParams,
        targets_m: Vec<[f64; 2]>,
        plan_m: Vec<[f64; 2]>,
        title: String,
    ) -> Self {
        let board = arm.workspace().board;
        let elbow = arm.plant().elbow_position(&arm.state().q);
        let pen = arm.pen();
        Self {
            bulbs: paradigm
                .bulbs
                .iter()
                .map(|c| (paradigm.code_of(*c), c.name().to_string()))
                .collect(),
            flash_ms: paradigm.flash_s * 1e3,
            countdown_s: paradigm.countdown_s,
            board_m: [board.x_min_m, board.x_max_m, board.z_min_m, board.z_max_m],
            base_m: [arm.plant().base()[0], arm.plant().base()[1]],
            pose_m: [[elbow[0], elbow[1]], [pen[0], pen[1]]],
            targets_m,
            plan_m,
            title,
            undrawn_after_ms: UNDRAWN_AFTER_MS,
            frames_every_ms: FRAMES_EVERY_MS,
        }
    }
}

/// A fault in what the person is shown, as the operator view's alarm names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// No subject view is connected: nothing is drawn.
    Disconnected,
    /// The subject view is hidden (another tab or window in front, minimised): the browser
    /// draws nothing.
    Hidden,
    /// The subject view draws (almost) no frames: frozen, or throttled by the browser.
    Stalled,
    /// Flashes the page never stamped in time (or whose stamps were refused): their epochs are
    /// dropped.
    Undrawn,
    /// Flashes drawn late (stamped, kept: their epochs follow the stamp).
    Late,
    /// Frames missed while flashing (a gap of several frame periods).
    FrameGap,
    /// More than one bulb lit in one frame (the page's own check of its page).
    MultipleLit,
}

impl FaultKind {
    /// Every kind, in the order the operator view lists them.
    pub const ALL: [FaultKind; 7] = [
        FaultKind::Disconnected,
        FaultKind::Hidden,
        FaultKind::Stalled,
        FaultKind::Undrawn,
        FaultKind::Late,
        FaultKind::FrameGap,
        FaultKind::MultipleLit,
    ];

    /// Whether the fault is a state that lasts (and holds a calibration while it does), not
    /// a count of events.
    pub fn is_state(self) -> bool {
        matches!(
            self,
            FaultKind::Disconnected | FaultKind::Hidden | FaultKind::Stalled
        )
    }
}

/// One presentation fault as the operator view shows it: an episode of one kind (events of
/// that kind less than a few seconds apart, or a state while it lasts).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alarm {
    pub kind: FaultKind,
    /// Still going on (`false`: the episode is over, kept in the operator's log).
    pub active: bool,
    /// When the episode began and when it was last seen, and the server's clock when this was
    /// sent (session-clock ms: the page maps them to its wall clock).
    pub since_ms: f64,
    pub last_ms: f64,
    pub now_ms: f64,
    /// When the episode began by the wall clock, ms since 1970 (what the operator reads).
    pub since_unix_ms: f64,
    /// Events in this episode (1 for a state).
    pub count: u64,
    /// Calibration is held while it lasts.
    pub holds: bool,
    /// What happened, in words.
    pub text: String,
}

/// The presentation faults of a session, counted: what its summary reports of them
/// ([`crate::live::LiveSubject::presentation_faults`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PresentationFaults {
    /// Flashes never stamped in time, or whose stamps were refused: their epochs are dropped.
    pub undrawn_flashes: u64,
    /// Of these, in calibration: epochs calibration did not get.
    pub calibration_undrawn_flashes: u64,
    /// Flashes stamped late (several frames after their time; kept, their epochs follow the
    /// stamp).
    pub late_flashes: u64,
    /// Times the subject view was hidden, and for how long in all, s.
    pub hidden: u64,
    pub hidden_s: f64,
    /// Times the subject view drew (almost) no frames while visible, and for how long, s.
    pub stalled: u64,
    pub stalled_s: f64,
    /// Times no subject view was connected once the session ran, and for how long, s.
    pub disconnected: u64,
    pub disconnected_s: f64,
    /// Gaps of several frame periods while flashing, and the longest gap reported, ms.
    pub frame_gaps: u64,
    pub longest_frame_gap_ms: f64,
    /// Frames with more than one bulb lit.
    pub multiple_lit_frames: u64,
    /// Times calibration held between trials for a fault, and for how long in all, s.
    pub calibration_holds: u64,
    pub calibration_held_s: f64,
}

impl PresentationFaults {
    /// Whether anything went wrong at all.
    pub fn any(&self) -> bool {
        *self != Self::default()
    }
}

/// A channel's live state on the operator's signal display, by the session's epoch rules
/// applied to the last epoch-length of its band-passed signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SignalState {
    Ok,
    /// Peak-to-peak under the flat threshold: disconnected, or stuck at a rail (saturated).
    Flat,
    /// Peak-to-peak over the rejection threshold.
    Noisy,
    /// Samples lost (NaN or infinite).
    Nan,
}

/// Server → page.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "t", rename_all = "snake_case")]
pub enum ServerMsg {
    Config(PanelConfig),
    /// A trial's countdown starts at `at_ms`; the person is cued to attend `cue` (`None`:
    /// nothing; calibration and copy tasks show it). It is number `number` (from 1) of its
    /// phase, of `of` when the session knows how many there will be.
    Trial {
        trial: usize,
        phase: String,
        number: usize,
        of: Option<usize>,
        cue: Option<u32>,
        at_ms: f64,
        countdown_s: f64,
    },
    /// Draw bulb `code` from `at_ms` for `dur_ms`; `id` comes back in [`ClientMsg::On`] and [`ClientMsg::Off`].
    Flash {
        id: u64,
        code: u32,
        at_ms: f64,
        dur_ms: f64,
    },
    /// Flashes announced for the trial that ended but not yet drawn are void.
    Cancel {
        after_ms: f64,
    },
    /// Online decision number `trial` (from 1): `code` chosen (`None`: abstained) after
    /// `rounds` rounds.
    Decision {
        trial: usize,
        code: Option<u32>,
        intended: Option<u32>,
        posterior: Vec<f64>,
        /// The posterior of the decided bulb (abstaining: of the best one).
        confidence: f64,
        rounds: usize,
        refused: Option<String>,
    },
    /// The arm at `t_ms`: elbow and pen, metres.
    Arm {
        t_ms: f64,
        elbow_m: [f64; 2],
        pen_m: [f64; 2],
    },
    /// Server-side timing figures for the operator's diagnostics.
    Diag {
        text: String,
    },
    /// Per channel, the epochs rejected because of it (after every trial).
    Quality {
        channels: Vec<ChannelQuality>,
    },
    /// The session holds between trials (`true`: the operator paused it, or a presentation
    /// fault holds a calibration) or runs on.
    Paused {
        paused: bool,
        at_ms: f64,
        /// Why it holds when not at the operator's request (a presentation fault).
        #[serde(default)]
        fault: Option<FaultKind>,
    },
    /// A presentation fault began, goes on or ended (operator view only).
    Alarm(Alarm),
    /// The presentation faults counted so far (operator view only).
    Faults {
        counts: PresentationFaults,
    },
    /// The signal display's channels and scales (operator view only, sent once): bins of
    /// `bin_ms`, the flat and noisy thresholds (µV peak-to-peak), and the averages' window
    /// (first sample at `erp_tmin_ms` after the onset, `erp_dt_ms` apart).
    Scope {
        names: Vec<String>,
        bin_ms: f64,
        flat_uv: f64,
        noisy_uv: Option<f64>,
        band: String,
        erp_tmin_ms: f64,
        erp_dt_ms: f64,
    },
    /// The band-passed signal from `t_ms` on, per channel the lowest and highest value of each
    /// bin (µV), and each channel's state now (operator view only).
    Signal {
        t_ms: f64,
        lo: Vec<Vec<f32>>,
        hi: Vec<Vec<f32>>,
        state: Vec<SignalState>,
    },
    /// The last trial's average epoch per channel (µV): the flashes of `target` (the cued bulb,
    /// else the decided one) and of the others (operator view only). The trial is number
    /// `trial` (from 1) of its phase.
    Average {
        trial: usize,
        phase: String,
        target: Option<u32>,
        n_target: usize,
        n_other: usize,
        target_uv: Vec<Vec<f32>>,
        other_uv: Vec<Vec<f32>>,
    },
    Pong {
        id: u64,
        page_ms: f64,
        server_ms: f64,
    },
    /// Pages connected now: subject views and operator views (sent on every connect and
    /// disconnect).
    Pages {
        subject: usize,
        operator: usize,
        /// Subject pages refused because one was already open (the first keeps the panel).
        #[serde(default)]
        refused_subjects: usize,
    },
    /// The session is over.
    End {
        summary: String,
    },
}

impl ServerMsg {
    /// Whether only operator views get this message (the signal, the averages, the alarms).
    pub fn operator_only(&self) -> bool {
        matches!(
            self,
            ServerMsg::Alarm(_)
                | ServerMsg::Faults { .. }
                | ServerMsg::Scope { .. }
                | ServerMsg::Signal { .. }
                | ServerMsg::Average { .. }
        )
    }
}

/// Page → server.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "t", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMsg {
    /// Clock sync: the page's `performance.now()` when sent.
    Ping { id: u64, page_ms: f64 },
    /// Flash `id` was put on screen in the frame stamped `on_ms` (server clock), sent at once.
    On { id: u64, code: u32, on_ms: f64 },
    /// Flash `id` was taken off in the frame stamped `off_ms`.
    Off { id: u64, off_ms: f64 },
    /// The page's refresh interval as measured (ms) and its user agent.
    Hello { frame_ms: f64, agent: String },
    /// The page's clock sync: its offset to the server clock (server − page, ms) and the round
    /// trip of the ping that set it (ms), sent when it improves.
    Clock { offset_ms: f64, rtt_ms: f64 },
    /// The operator pauses, resumes or aborts the session.
    Control { action: Control },
    /// The subject page's frames since its last report (sent from its animation frames every
    /// [`FRAMES_EVERY_MS`]): how many, the longest gap between two (ms), gaps of several frame
    /// periods while flashing, and frames with more than one bulb lit (its own check of its
    /// page).
    Frames {
        frames: u32,
        max_gap_ms: f64,
        dropped: u32,
        multi_lit: u32,
    },
    /// The subject page became hidden or visible again (`document.hidden`), and on connect.
    Visibility { hidden: bool },
}

/// Why a client message was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolError {
    #[error("message of {len} bytes exceeds the {max}-byte limit")]
    TooLarge { len: usize, max: usize },
    #[error("binary messages are not part of the protocol")]
    Binary,
    #[error("malformed message at line {line}, column {column}: {reason}")]
    Malformed {
        line: usize,
        column: usize,
        reason: String,
    },
    #[error("field {field} = {value}: {reason}")]
    BadValue {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
}

/// Parses and checks one client text message.
pub fn parse_client(text: &str) -> Result<ClientMsg, ProtocolError> {
    if text.len() > MAX_CLIENT_MESSAGE {
        return Err(ProtocolError::TooLarge {
            len: text.len(),
            max: MAX_CLIENT_MESSAGE,
        });
    }
    let msg: ClientMsg = serde_json::from_str(text).map_err(|e| ProtocolError::Malformed {
        line: e.line(),
        column: e.column(),
        reason: e.to_string(),
    })?;
    let finite = |field: &'static str, v: f64| {
        if v.is_finite() {
            Ok(())
        } else {
            Err(ProtocolError::BadValue {
                field,
                value: v.to_string(),
                reason: "not a finite number",
            })
        }
    };
    match &msg {
        ClientMsg::Ping { page_ms, .. } => finite("page_ms", *page_ms)?,
        ClientMsg::On { code, on_ms, .. } => {
            finite("on_ms", *on_ms)?;
            if !(1..=64).contains(code) {
                return Err(ProtocolError::BadValue {
                    field: "code",
                    value: code.to_string(),
                    reason: "not a stimulus code",
                });
            }
        }
        ClientMsg::Off { off_ms, .. } => finite("off_ms", *off_ms)?,
        ClientMsg::Hello { frame_ms, .. } => finite("frame_ms", *frame_ms)?,
        ClientMsg::Clock { offset_ms, rtt_ms } => {
            finite("offset_ms", *offset_ms)?;
            finite("rtt_ms", *rtt_ms)?;
            if *rtt_ms < 0.0 {
                return Err(ProtocolError::BadValue {
                    field: "rtt_ms",
                    value: rtt_ms.to_string(),
                    reason: "a round trip cannot be negative",
                });
            }
        }
        ClientMsg::Frames {
            frames,
            max_gap_ms,
            dropped,
            multi_lit,
        } => {
            finite("max_gap_ms", *max_gap_ms)?;
            let within = |field: &'static str, v: f64, max: f64| {
                if (0.0..=max).contains(&v) {
                    Ok(())
                } else {
                    Err(ProtocolError::BadValue {
                        field,
                        value: v.to_string(),
                        reason: "out of range",
                    })
                }
            };
            within("max_gap_ms", *max_gap_ms, MAX_REPORTED)?;
            within("frames", f64::from(*frames), MAX_REPORTED)?;
            within("dropped", f64::from(*dropped), f64::from(*frames) + 1.0)?;
            within("multi_lit", f64::from(*multi_lit), f64::from(*frames) + 1.0)?;
        }
        ClientMsg::Control { .. } | ClientMsg::Visibility { .. } => {}
    }
    Ok(msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn good_messages_parse() {
        assert_eq!(
            parse_client(r#"{"t":"ping","id":3,"page_ms":12.5}"#).unwrap(),
            ClientMsg::Ping {
                id: 3,
                page_ms: 12.5
            }
        );
        assert_eq!(
            parse_client(r#"{"t":"on","id":7,"code":2,"on_ms":1000.0}"#).unwrap(),
            ClientMsg::On {
                id: 7,
                code: 2,
                on_ms: 1000.0
            }
        );
        assert_eq!(
            parse_client(r#"{"t":"control","action":"pause"}"#).unwrap(),
            ClientMsg::Control {
                action: Control::Pause
            }
        );
        assert_eq!(
            parse_client(r#"{"t":"off","id":7,"off_ms":1100.2}"#).unwrap(),
            ClientMsg::Off {
                id: 7,
                off_ms: 1100.2
            }
        );
    }

    #[test]
    fn bad_messages_say_what_is_wrong() {
        let big = format!(
            r#"{{"t":"hello","frame_ms":16,"agent":"{}"}}"#,
            "x".repeat(2000)
        );
        assert!(matches!(
            parse_client(&big),
            Err(ProtocolError::TooLarge { max: 1024, .. })
        ));
        for bad in [
            "",
            "{",
            "null",
            r#"{"t":"launch","id":1}"#,
            r#"{"t":"ping","id":-1,"page_ms":0}"#,
            r#"{"t":"ping","id":1,"page_ms":0,"extra":1}"#,
            r#"{"t":"on","id":1,"code":2}"#,
            r#"{"t":"control","action":"explode"}"#,
            r#"{"t":"control"}"#,
        ] {
            assert!(
                matches!(parse_client(bad), Err(ProtocolError::Malformed { .. })),
                "{bad}"
            );
        }
        let e = parse_client(r#"{"t":"clock","offset_ms":5,"rtt_ms":-1}"#).unwrap_err();
        assert!(e.to_string().contains("rtt_ms = -1"), "{e}");
        let e = parse_client(r#"{"t":"on","id":1,"code":0,"on_ms":5}"#).unwrap_err();
        assert!(e.to_string().contains("code = 0"), "{e}");
        // serde_json refuses NaN literals, and 1e999 overflows to infinity: both refused.
        assert!(parse_client(r#"{"t":"ping","id":1,"page_ms":NaN}"#).is_err());
        assert!(parse_client(r#"{"t":"ping","id":1,"page_ms":1e999}"#).is_err());
    }

    /// The subject page's reports of itself are checked like its stamps: bounded, finite, in
    /// range, no field more or less.
    #[test]
    fn frame_and_visibility_reports_are_checked() {
        assert_eq!(
            parse_client(
                r#"{"t":"frames","frames":15,"max_gap_ms":17.1,"dropped":0,"multi_lit":0}"#
            )
            .unwrap(),
            ClientMsg::Frames {
                frames: 15,
                max_gap_ms: 17.1,
                dropped: 0,
                multi_lit: 0
            }
        );
        assert_eq!(
            parse_client(r#"{"t":"visibility","hidden":true}"#).unwrap(),
            ClientMsg::Visibility { hidden: true }
        );
        for (bad, field) in [
            (
                r#"{"t":"frames","frames":1,"max_gap_ms":-5,"dropped":0,"multi_lit":0}"#,
                "max_gap_ms",
            ),
            (
                r#"{"t":"frames","frames":1,"max_gap_ms":1e8,"dropped":0,"multi_lit":0}"#,
                "max_gap_ms",
            ),
            (
                r#"{"t":"frames","frames":4000000000,"max_gap_ms":5,"dropped":0,"multi_lit":0}"#,
                "frames",
            ),
            (
                r#"{"t":"frames","frames":2,"max_gap_ms":5,"dropped":900,"multi_lit":0}"#,
                "dropped",
            ),
            (
                r#"{"t":"frames","frames":2,"max_gap_ms":5,"dropped":0,"multi_lit":900}"#,
                "multi_lit",
            ),
        ] {
            let e = parse_client(bad).unwrap_err();
            assert!(
                matches!(e, ProtocolError::BadValue { field: f, .. } if f == field),
                "{bad}: {e}"
            );
        }
        for bad in [
            r#"{"t":"frames","frames":1,"max_gap_ms":5,"dropped":0}"#,
            r#"{"t":"frames","frames":-1,"max_gap_ms":5,"dropped":0,"multi_lit":0}"#,
            r#"{"t":"frames","frames":1,"max_gap_ms":5,"dropped":0,"multi_lit":0,"x":1}"#,
            r#"{"t":"visibility","hidden":"yes"}"#,
            r#"{"t":"visibility"}"#,
        ] {
            assert!(
                matches!(parse_client(bad), Err(ProtocolError::Malformed { .. })),
                "{bad}"
            );
        }
        let frames =
            parse_client(r#"{"t":"frames","frames":1,"max_gap_ms":5,"dropped":0,"multi_lit":0}"#)
                .unwrap();
        let hidden = ClientMsg::Visibility { hidden: true };
        for m in [&frames, &hidden] {
            assert!(Role::Subject.accepts(m) && !Role::Operator.accepts(m));
        }
    }

    #[test]
    fn what_only_operators_see() {
        let signal = ServerMsg::Signal {
            t_ms: 0.0,
            lo: vec![],
            hi: vec![],
            state: vec![],
        };
        assert!(signal.operator_only());
        assert!(!ServerMsg::Cancel { after_ms: 0.0 }.operator_only());
        // A pause carries its fault, and an older message without one still reads.
        let p: ServerMsg =
            serde_json::from_str(r#"{"t":"paused","paused":true,"at_ms":5}"#).unwrap();
        assert_eq!(
            p,
            ServerMsg::Paused {
                paused: true,
                at_ms: 5.0,
                fault: None
            }
        );
        let held = ServerMsg::Paused {
            paused: true,
            at_ms: 5.0,
            fault: Some(FaultKind::Hidden),
        };
        assert!(serde_json::to_string(&held)
            .unwrap()
            .contains(r#""fault":"hidden""#));
    }

    #[test]
    fn each_page_sends_only_its_own_messages() {
        let on = ClientMsg::On {
            id: 1,
            code: 2,
            on_ms: 5.0,
        };
        let pause = ClientMsg::Control {
            action: Control::Pause,
        };
        let ping = ClientMsg::Ping {
            id: 1,
            page_ms: 0.0,
        };
        assert!(Role::Subject.accepts(&on) && !Role::Operator.accepts(&on));
        assert!(Role::Operator.accepts(&pause) && !Role::Subject.accepts(&pause));
        assert!(Role::Subject.accepts(&ping) && Role::Operator.accepts(&ping));
    }
}
