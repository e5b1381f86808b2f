//! The pictures of oddball's reports, for the people reading them: one module per picture
//! ([`erp`], [`accuracy`], [`benchmark`], [`arm`], [`task`]), and what they share: an embedded font (DejaVu Sans,
//! `assets/`, so no system font libraries are needed) and the choice of PNG or SVG by file
//! extension.
//!
//! ```
//! use oddball_plot::PlotFormat;
//! use std::path::Path;
//!
//! assert_eq!(PlotFormat::from_path(Path::new("erp.SVG")).unwrap(), PlotFormat::Svg);
//! assert!(PlotFormat::from_path(Path::new("erp.jpg")).is_err());
//! ```

use std::path::{Path, PathBuf};
use std::sync::Once;

pub mod accuracy;
pub mod arm;
pub mod benchmark;
pub mod erp;
pub mod task;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// The font family name every plot uses.
pub const FONT_FAMILY: &str = "sans-serif";

/// Why a picture could not be drawn; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The file's extension is neither `.png` nor `.svg`.
    #[error("plot file {} must end in .png or .svg", path.display())]
    Format { path: PathBuf },
    /// plotters refused a drawing step (the text is plotters' or the font backend's).
    #[error("{message}")]
    Draw { path: PathBuf, message: String },
    /// The finished picture could not be written.
    #[error("writing {}: {message}", path.display())]
    Write { path: PathBuf, message: String },
}

impl PlotError {
    /// A drawing step's failure, with plotters' text.
    pub fn draw(path: &Path, message: impl std::fmt::Display) -> Self {
        Self::Draw {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }

    /// The file this error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Format { path } | Self::Draw { path, .. } | Self::Write { path, .. } => path,
        }
    }
}

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
    /// `.png` or `.svg` (any case); anything else is [`PlotError::Format`].
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => Ok(Self::Png),
            Some("svg") => Ok(Self::Svg),
            _ => Err(PlotError::Format {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Draws with the body on a PNG or SVG backend chosen by `path`'s extension. The body receives
/// the root drawing area already filled white and evaluates to `Result<(), PlotError>`.
macro_rules! with_backend {
    ($path:expr, $size:expr, |$root:ident| $body:block) => {{
        use plotters::prelude::*;
        $crate::register_font();
        let path: &std::path::Path = $path;
        let write = |e: &dyn std::fmt::Display| $crate::PlotError::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let format = $crate::PlotFormat::from_path(path)?;
        // Drawn into a temporary file beside `path`, renamed into place when whole.
        let file = oddball_io::AtomicFile::create(path).map_err(|e| write(&e))?;
        let temp = file.temp_path().to_path_buf();
        match format {
            $crate::PlotFormat::Png => {
                $crate::draw_on!(BitMapBackend, temp, $size, path, write, |$root| $body)
            }
            $crate::PlotFormat::Svg => {
                $crate::draw_on!(SVGBackend, temp, $size, path, write, |$root| $body)
            }
        }
        file.commit().map_err(|e| write(&e))?;
        Ok::<(), $crate::PlotError>(())
    }};
}
pub(crate) use with_backend;

/// One format's drawing in [`with_backend`]: the root area `$root` of a `$backend` writing
/// `$temp`, filled white, the body drawn on it, presented (errors name `$path`, `$write` makes a
/// write error).
macro_rules! draw_on {
    ($backend:ident, $temp:ident, $size:expr, $path:ident, $write:ident, |$root:ident| $body:block) => {{
        let $root = plotters::prelude::$backend::new(&$temp, $size).into_drawing_area();
        $root
            .fill(&plotters::prelude::WHITE)
            .map_err(|e| $crate::PlotError::draw($path, e))?;
        let r: Result<(), $crate::PlotError> = $body;
        r?;
        $root.present().map_err(|e| $write(&e))?;
    }};
}
pub(crate) use draw_on;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wrong_extension_names_the_file() {
        let err = PlotFormat::from_path(Path::new("out/erp.jpg")).unwrap_err();
        assert_eq!(
            err.to_string(),
            "plot file out/erp.jpg must end in .png or .svg"
        );
        assert_eq!(err.path(), Path::new("out/erp.jpg"));
    }
}
