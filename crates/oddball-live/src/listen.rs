//! Every listener oddball opens (the panel, the NIC simulator's data and panel ports): loopback
//! only unless the caller allows remote connections, and a bind error naming the address.

use std::net::{SocketAddr, TcpListener};

use crate::LiveError;

/// Binds `addr` for `name` (the option that gave it, for the error's facts): refused unless its
/// address is loopback or `allow_remote`.
pub fn bind(
    addr: SocketAddr,
    allow_remote: bool,
    name: &'static str,
) -> Result<TcpListener, LiveError> {
    if !allow_remote && !addr.ip().is_loopback() {
        return Err(LiveError::InvalidParameter {
            name,
            value: addr.to_string(),
            reason: "not a loopback address: it would be reachable from the network \
                     (allow it explicitly to do so)"
                .into(),
        });
    }
    TcpListener::bind(addr).map_err(|e| LiveError::Bind {
        addr: addr.to_string(),
        reason: e.to_string(),
    })
}
