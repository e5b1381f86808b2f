//! The stimulus panel: two web pages served by the binary (assets embedded), live over
//! WebSockets ([`protocol`] is the one home of the paths and messages).
//!
//! The subject view (`/`) fills the screen (and goes full screen on a click or the F key) with
//! nothing but the task: the four bulbs and the arm scaled to the viewport, the countdown with
//! the cue, the flashes on the schedule the session sends ahead of time, the last decision, the
//! arm with its pen trace (plus the task's targets or planned shape), and when the session is
//! over, that it is. The operator view (`/operator`) shows what the person must not be
//! distracted by: progress ("calibration decision 3 of 40"), presentation faults as alarms
//! naming the fault and when ([`monitor`]), the signal itself (a scrolling trace per channel
//! with a scale control, flat, noisy or lost channels coloured, and the last trial's average
//! epochs: [`scope`]), flash timing and clock figures, per-channel signal quality (epochs
//! rejected as NaN, flat or saturated, noisy), the decisions with their confidence, and
//! pause / resume / abort buttons. A pause holds the session before
//! its next trial ([`oddball_session::roles::Presenter::hold`]); an abort stops it as SIGTERM
//! does. A flash is stamped when the subject page actually draws it: the page
//! keeps the offset of its clock (`performance.now()`) to the server's session clock from
//! ping/pong pairs (the one with the shortest round trip wins) and reports each flash's
//! on and off frames (requestAnimationFrame times) on the server clock. The session turns those
//! stamps into markers ([`crate::live`]).
//!
//! The server runs on its own thread (a small tokio runtime with axum); the session thread
//! talks to it without blocking: [`PanelServer::send`] broadcasts, [`PanelServer::take_drawn`]
//! collects stamps, [`PanelServer::subject_view`] what the subject page says of itself (hidden,
//! its frames). It binds loopback unless told otherwise, rejects malformed and oversized
//! client messages (counted in [`PanelStats`]), and outlives any client that disconnects.

mod assets;
pub mod monitor;
pub mod protocol;
pub mod scope;
mod server;

pub use assets::{COMMON_JS, INDEX_HTML, OPERATOR_HTML, OPERATOR_JS, PANEL_JS};
pub use monitor::{FaultMonitor, SubjectView};
pub use protocol::{
    Alarm, ChannelQuality, ClientMsg, Control, FaultKind, PanelConfig, PresentationFaults,
    ProtocolError, Role, ServerMsg, SignalState, MAX_CLIENT_MESSAGE,
};
pub use scope::{Scope, ScopeRules};
pub use server::{DrawnReport, PanelServer, PanelStats, ORPHANED_PAUSE_S};
