//! The progress bars the long commands (`train`, `evaluate`, `benchmark`) draw: one style.

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar of `len` steps on stderr drawn by `template`; indicatif hides it when stderr
/// is not a terminal (or `TERM` is unset or `dumb`), so logs and pipes stay clean.
pub fn bar(len: u64, template: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(template)
            .expect("a valid template")
            .progress_chars("=> "),
    );
    pb
}
