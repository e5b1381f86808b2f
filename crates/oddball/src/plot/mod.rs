//! The pictures of the reports, one file per picture ([`arm`], [`task`]), and what they share:
//! an embedded font (no system font libraries needed) and
//! the choice of PNG or SVG by file extension.

use std::path::Path;
use std::sync::Once;

use anyhow::{bail, Result};

pub mod accuracy;
pub mod arm;
pub mod erp;
pub mod task;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// The font family name every plot uses.
pub const FONT_FAMILY: &str = "sans-serif";

/// Registers the embedded DejaVu Sans as `sans-serif` for plotters' ab_glyph text backend.
/// Safe to call any number of times.
pub fn register_font() {
    REGISTER.call_once(|| {
        for style in [
            plotters::style::FontStyle::Normal,
            plotters::style::FontStyle::Bold,
            plotters::style::FontStyle::Italic,
            plotters::style::FontStyle::Oblique,
        ] {
            // The font is a fixed, valid TTF compiled into the binary.
            let _ = plotters::style::register_font(FONT_FAMILY, style, FONT);
        }
    });
}

/// The image format of a plot file, from its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotFormat {
    Png,
    Svg,
}

impl PlotFormat {
    pub fn from_path(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => Ok(Self::Png),
            Some("svg") => Ok(Self::Svg),
            _ => bail!("plot file {} must end in .png or .svg", path.display()),
        }
    }
}

/// Draws with `draw` on a PNG or SVG backend chosen by `path`'s extension.
/// `draw` receives the root drawing area already filled white.
#[macro_export]
macro_rules! with_backend {
    ($path:expr, $size:expr, |$root:ident| $body:block) => {{
        use plotters::prelude::*;
        $crate::plot::register_font();
        let path: &std::path::Path = $path;
        match $crate::plot::PlotFormat::from_path(path)? {
            $crate::plot::PlotFormat::Png => {
                let $root = BitMapBackend::new(path, $size).into_drawing_area();
                $root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
                let r: anyhow::Result<()> = $body;
                r?;
                $root
                    .present()
                    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
            }
            $crate::plot::PlotFormat::Svg => {
                let $root = SVGBackend::new(path, $size).into_drawing_area();
                $root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
                let r: anyhow::Result<()> = $body;
                r?;
                $root
                    .present()
                    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
            }
        }
        anyhow::Ok(())
    }};
}
