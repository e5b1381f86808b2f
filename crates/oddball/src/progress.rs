//! The progress the long commands (`train`, `evaluate`, `benchmark`) show: one style. On a
//! terminal, an indicatif bar on stderr; otherwise (a log file, a pipe, CI) a plain line on
//! stderr every [`PLAIN_EVERY`] at most and at the end, so a run of minutes is never silent:
//! `benchmark: 120/1600 (7%) 0:01:23`.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How often a plain progress line is written at most.
pub const PLAIN_EVERY: Duration = Duration::from_secs(10);

/// A progress display of `len` steps (see the module doc).
#[derive(Debug)]
pub struct Bar {
    bar: ProgressBar,
    /// `Some` when stderr is not a terminal: when the plain lines started and the last one.
    plain: Option<Mutex<Plain>>,
}

#[derive(Debug)]
struct Plain {
    start: Instant,
    last: Option<Instant>,
}

/// A progress display of `len` steps drawn by `template` on a terminal.
pub fn bar(len: u64, template: &str) -> Bar {
    Bar::new(len, template, std::io::stderr().is_terminal())
}

impl Bar {
    fn new(len: u64, template: &str, terminal: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            Some(len),
            if terminal {
                ProgressDrawTarget::stderr()
            } else {
                ProgressDrawTarget::hidden()
            },
        );
        bar.set_style(
            ProgressStyle::with_template(template)
                .expect("a valid template")
                .progress_chars("=> "),
        );
        Self {
            bar,
            plain: (!terminal).then(|| {
                Mutex::new(Plain {
                    start: Instant::now(),
                    last: None,
                })
            }),
        }
    }

    pub fn set_length(&self, len: u64) {
        self.bar.set_length(len);
    }

    pub fn set_message(&self, msg: String) {
        self.bar.set_message(msg);
    }

    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.tick(false);
    }

    pub fn set_position(&self, pos: u64) {
        self.bar.set_position(pos);
        self.tick(false);
    }

    /// Runs `f` (which prints) with the bar out of the way.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar.suspend(f)
    }

    pub fn finish_and_clear(&self) {
        self.tick(true);
        self.bar.finish_and_clear();
    }

    /// Writes a plain line when one is due, and at the end.
    fn tick(&self, end: bool) {
        let Some(plain) = &self.plain else {
            return;
        };
        let mut p = plain.lock().unwrap_or_else(|e| e.into_inner());
        let due = p.last.is_none_or(|t| t.elapsed() >= PLAIN_EVERY);
        if end || due {
            eprintln!("{}", self.plain_line(p.start.elapsed()));
            p.last = Some(Instant::now());
        }
    }

    /// `msg: pos/len (pct%) h:mm:ss`.
    fn plain_line(&self, elapsed: Duration) -> String {
        let (pos, len) = (self.bar.position(), self.bar.length().unwrap_or(0));
        let pct = (100 * pos).checked_div(len).unwrap_or(0);
        let s = elapsed.as_secs();
        let msg = self.bar.message();
        let msg = if msg.is_empty() {
            "progress".into()
        } else {
            msg
        };
        format!(
            "{msg}: {pos}/{len} ({pct}%) {}:{:02}:{:02}",
            s / 3600,
            s / 60 % 60,
            s % 60
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_line_says_what_how_far_and_how_long() {
        let b = Bar::new(40, "{msg} {pos}", false);
        b.set_message("benchmark".into());
        b.set_position(10);
        assert_eq!(
            b.plain_line(Duration::from_secs(3723)),
            "benchmark: 10/40 (25%) 1:02:03"
        );
        let t = Bar::new(4, "{msg} {pos}", true);
        assert!(t.plain.is_none());
    }
}
