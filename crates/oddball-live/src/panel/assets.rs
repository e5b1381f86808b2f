//! The panel's pages and scripts, embedded in the binary.

/// The subject view, embedded in the binary.
pub const INDEX_HTML: &str = include_str!("../../assets/index.html");
/// Its script.
pub const PANEL_JS: &str = include_str!("../../assets/panel.js");
/// The operator view.
pub const OPERATOR_HTML: &str = include_str!("../../assets/operator.html");
/// Its script.
pub const OPERATOR_JS: &str = include_str!("../../assets/operator.js");
/// What both scripts share: the WebSocket connection and the bulbs' labels.
pub const COMMON_JS: &str = include_str!("../../assets/common.js");
