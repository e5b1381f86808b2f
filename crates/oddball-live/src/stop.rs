//! A request to stop a live session (SIGINT or SIGTERM, which the binary points here with
//! `signal-hook`): the next block of EEG is not taken, the session ends with
//! [`crate::LiveError::Stopped`], and the caller closes the recording and writes its summary
//! as when a replayed recording runs out ([`crate::online::is_recording_end`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();
static REASON: Mutex<Option<String>> = Mutex::new(None);

/// The process's stop flag (for a signal handler to set).
pub fn flag() -> Arc<AtomicBool> {
    STOP.get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone()
}

/// Asks every live session of this process to stop.
pub fn request() {
    flag().store(true, Ordering::SeqCst);
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    STOP.get().is_some_and(|f| f.load(Ordering::SeqCst))
}

/// Records why a live session stopped early (a stop request, a source that ended), for the
/// report written afterwards.
pub fn note(reason: String) {
    if let Ok(mut r) = REASON.lock() {
        r.get_or_insert(reason);
    }
}

/// Why a live session stopped early, if one did.
pub fn reason() -> Option<String> {
    REASON.lock().ok().and_then(|r| r.clone())
}
