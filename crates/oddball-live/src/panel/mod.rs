//! The stimulus panel a person looks at: a web page served by the binary (assets embedded),
//! live over a WebSocket.
//!
//! The page draws the four bulbs, the countdown with the cue, the flashes on the schedule the
//! session sends ahead of time, the decision, and the arm with its pen trace (plus the task's
//! targets or planned shape). A flash is stamped when the page actually draws it: the page
//! keeps the offset of its clock (`performance.now()`) to the server's session clock from
//! ping/pong pairs (the one with the shortest round trip wins) and reports each flash's
//! on and off frames (requestAnimationFrame times) on the server clock. The session turns those
//! stamps into markers ([`crate::live`]).
//!
//! The server runs on its own thread (a small tokio runtime with axum); the session thread
//! talks to it without blocking: [`PanelServer::send`] broadcasts, [`PanelServer::take_drawn`]
//! collects stamps. It binds loopback unless told otherwise, rejects malformed and oversized
//! client messages (counted in [`PanelStats`]), and outlives any client that disconnects.

pub mod protocol;
mod server;

pub use protocol::{ClientMsg, PanelConfig, ProtocolError, ServerMsg, MAX_CLIENT_MESSAGE};
pub use server::{DrawnReport, PanelServer, PanelStats};

/// The page, embedded in the binary.
pub const INDEX_HTML: &str = include_str!("../../assets/index.html");
/// Its script.
pub const PANEL_JS: &str = include_str!("../../assets/panel.js");
