//! The stimulus panel in a browser, as a run serves it: started on its address, its two views
//! said on the run's output, and a page waited for before the session starts.

use std::io::Write;
use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

use oddball_live::clock::Clock;
use oddball_live::panel::{PanelConfig, PanelServer};

use crate::error::{AppError, Result, SettingError};

/// The longest wait for a page, seconds (a day).
pub const MAX_WAIT_PAGE_S: f64 = 86_400.0;

/// Where and how the panel is served.
#[derive(Debug, Clone, Default)]
pub struct PanelSettings {
    /// `HOST:PORT` to serve on (`None`: no panel).
    pub serve: Option<String>,
    /// Allow a non-loopback address.
    pub allow_remote: bool,
    /// Seconds to wait for a page before the session starts.
    pub wait_page: f64,
}

impl PanelSettings {
    /// Starts the panel (when served) and waits for a page; says its addresses on `out` first.
    pub fn start(
        &self,
        config: PanelConfig,
        clock: Clock,
        out: &mut dyn Write,
    ) -> Result<Option<PanelServer>> {
        let Some(addr) = &self.serve else {
            return Ok(None);
        };
        if !(self.wait_page.is_finite() && (0.0..=MAX_WAIT_PAGE_S).contains(&self.wait_page)) {
            return Err(SettingError::WaitPage {
                seconds: self.wait_page,
                max: MAX_WAIT_PAGE_S,
            }
            .into());
        }
        let panel = PanelServer::start(resolve(addr)?, self.allow_remote, config, clock)
            .map_err(AppError::Panel)?;
        // Each view's address carries its key: a page without it gets nothing.
        writeln!(out, "panel: {}", panel.subject_url())?;
        writeln!(out, "operator view: {}", panel.operator_url())?;
        if !panel.wait_for_page(Duration::from_secs_f64(self.wait_page)) {
            return Err(AppError::NoPage {
                addr: panel.local_addr().to_string(),
                seconds: self.wait_page,
            });
        }
        let stats = panel.stats();
        writeln!(
            out,
            "panel page connected: frame {:.2} ms, {}",
            stats.frame_ms.unwrap_or(f64::NAN),
            stats.agent.as_deref().unwrap_or("?")
        )?;
        Ok(Some(panel))
    }
}

/// `HOST:PORT` → its first address.
pub fn resolve(addr: &str) -> Result<SocketAddr, SettingError> {
    let bad = |source| SettingError::Address {
        addr: addr.to_string(),
        source,
    };
    addr.to_socket_addrs()
        .map_err(|e| bad(Some(e)))?
        .next()
        .ok_or_else(|| bad(None))
}
