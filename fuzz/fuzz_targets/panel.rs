//! Arbitrary text through the panel's WebSocket message parser (what any page, or anyone on
//! the machine, may send to `oddball online --serve`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use oddball_live::panel::protocol::{parse_client, ClientMsg, MAX_CLIENT_MESSAGE};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(msg) = parse_client(text) {
            assert!(text.len() <= MAX_CLIENT_MESSAGE);
            match msg {
                ClientMsg::Ping { page_ms, .. } => assert!(page_ms.is_finite()),
                ClientMsg::On { code, on_ms, .. } => {
                    assert!(on_ms.is_finite() && (1..=64).contains(&code))
                }
                ClientMsg::Off { off_ms, .. } => assert!(off_ms.is_finite()),
                ClientMsg::Hello { frame_ms, .. } => assert!(frame_ms.is_finite()),
                ClientMsg::Clock { offset_ms, rtt_ms } => {
                    assert!(offset_ms.is_finite() && rtt_ms.is_finite() && rtt_ms >= 0.0)
                }
                ClientMsg::Frames {
                    frames,
                    max_gap_ms,
                    dropped,
                    multi_lit,
                } => {
                    assert!(max_gap_ms.is_finite() && max_gap_ms >= 0.0);
                    assert!(u64::from(dropped) <= u64::from(frames) + 1);
                    assert!(u64::from(multi_lit) <= u64::from(frames) + 1);
                }
                ClientMsg::Control { .. } | ClientMsg::Visibility { .. } => {}
            }
        }
    }
});
