//! The text of the harness's reports, as the command line prints it: the tuning tables, the
//! result rows of `evaluate` under their header, what a training run says it fits, the
//! benchmark's tables, the unsupervised replay's summary, a re-decided session file, a
//! recording's summary and the note that a file was resampled. Every function returns a
//! `String` (whole lines, each ending in a newline) and prints nothing; [`Narration`] turns a
//! run's [`Progress`] into the lines to say as it goes.

use std::fmt::Write as _;
use std::path::Path;

use oddball_decode::model_selection::tuning::TuningReport;
use oddball_io::Recording;
use oddball_session::report::redecision_line;

use crate::benchmark::{BenchmarkReport, Protocol};
use crate::evaluate::{PipelineResult, Progress, Trained};
use crate::layout::Resampled;
use crate::sessions::Redecided;
use crate::unsupervised::UnsupervisedResult;

/// How cross-validation folds were made.
pub fn fold_note(grouped: bool) -> &'static str {
    if grouped {
        "folds keep speller characters whole"
    } else {
        "folds stratified by label"
    }
}

/// The tuning table of preset `name`: every candidate's cross-validated AUC, the chosen one
/// marked; every line starts with `indent`.
pub fn tuning_table(name: &str, r: &TuningReport, indent: &str) -> String {
    let mut s = format!(
        "{indent}tuning {name}: {}-fold CV on the training data ({}), mean epoch AUC\n",
        r.n_folds,
        fold_note(r.grouped)
    );
    for c in &r.candidates {
        let folds: Vec<String> = c.fold_auc.iter().map(|a| format!("{a:.3}")).collect();
        let _ = writeln!(
            s,
            "{indent}  {} {:<28} CV AUC {:.3}  (folds {})",
            if c.label == r.chosen { "*" } else { " " },
            c.label,
            c.cv_auc,
            folds.join(" ")
        );
    }
    let _ = writeln!(s, "{indent}  chosen: {}", r.chosen);
    s
}

/// The legend of [`result_row`]'s columns.
pub const RESULT_HEADER: &str = "pipeline   epoch ROC-AUC, mean fit time, scoring speed  \
    [speller test files: characters right by repetitions, picks, best Wolpaw ITR]\n";

/// One preset's result: epoch AUC, fit time, scoring speed, and for speller test files the
/// characters right by repetitions, the picks and the best ITR; the chosen settings if tuned.
pub fn result_row(r: &PipelineResult) -> String {
    let acc = r
        .speller_accuracy
        .as_deref()
        .map(percents)
        .unwrap_or_default();
    format!(
        "{:<10} AUC {:.3}  fit {:>7.3} s  {:>9.0} epochs/s{}{}{}{}{}\n",
        r.pipeline,
        r.auc,
        r.fit_s,
        r.score_epochs_per_s,
        if acc.is_empty() {
            String::new()
        } else {
            format!("  chars % by reps: {acc}")
        },
        r.speller_text
            .as_ref()
            .map(|t| format!("  picks {t}"))
            .unwrap_or_default(),
        r.reps_for_all_correct
            .map(|n| format!("  all right from {n} reps"))
            .unwrap_or_default(),
        r.itr_at_best
            .map(|i| format!(
                "  best ITR {:.1} bits/min ({:.0} % right, {:.1} s a character)",
                i.bits_per_minute,
                100.0 * i.accuracy,
                i.seconds_per_selection
            ))
            .unwrap_or_default(),
        r.tuning
            .as_ref()
            .map(|t| format!("  [{}]", t.chosen))
            .unwrap_or_default(),
    )
}

/// Why `evaluate --plot` draws no accuracy-vs-repetitions plot: it cross-validated (no test
/// files), or its test files are not spellers.
pub fn no_accuracy_plot(cross_validation: bool) -> String {
    format!(
        "no accuracy-vs-repetitions plot: {} (it needs speller test files)\n",
        if cross_validation {
            "cross-validation has no test files"
        } else {
            "the test files are not spellers"
        }
    )
}

/// Accuracies (0 to 1) as whole percents, space-separated.
fn percents(a: &[f64]) -> String {
    a.iter()
        .map(|v| format!("{:.0}", v * 100.0))
        .collect::<Vec<_>>()
        .join(" ")
}

/// What a training or evaluation run says as its [`Progress`] comes: for training what its
/// fits are for, the cross-validation's folds, the tuning tables and the result rows under
/// [`RESULT_HEADER`] (said once). The fits themselves are for a progress bar, not said.
#[derive(Debug, Clone, Default)]
pub struct Narration {
    /// Training: the preset and what its epochs are, said with the number of fits.
    training: Option<(String, String)>,
    header_said: bool,
}

impl Narration {
    /// An evaluation's narration.
    pub fn evaluating() -> Self {
        Self::default()
    }

    /// A training run's: `preset` fitted on `on` (what its epochs are).
    pub fn training(preset: &str, on: &str) -> Self {
        Self {
            training: Some((preset.to_string(), on.to_string())),
            header_said: false,
        }
    }

    /// The lines to say on `p` (empty when there is nothing to say).
    pub fn on(&mut self, p: &Progress<'_>) -> String {
        let mut s = String::new();
        match *p {
            Progress::Plan {
                fits,
                cross_validation,
            } => {
                if let Some((what, on)) = &self.training {
                    let _ = writeln!(
                        s,
                        "training {what} on {on}: {fits} cross-validation fits for its decision \
                         model, then one fit on all epochs"
                    );
                }
                if let Some(f) = cross_validation {
                    let _ = writeln!(
                        s,
                        "{}-fold cross-validation on the training data ({})",
                        f.n_folds(),
                        fold_note(f.grouped())
                    );
                }
            }
            Progress::Preset(_) | Progress::Fit => {}
            Progress::Tuned {
                preset,
                fold,
                report,
            } => match fold {
                Some((k, n)) => {
                    let _ = writeln!(s, "fold {k}/{n}:");
                    s += &tuning_table(preset.name(), report, "  ");
                }
                None => s += &tuning_table(preset.name(), report, ""),
            },
            Progress::Scored(r) => {
                if !std::mem::replace(&mut self.header_said, true) {
                    s += RESULT_HEADER;
                }
                s += &result_row(r);
            }
        }
        s
    }
}

/// What `oddball train` made: `trained` (zero-phase, as tuned) and `live` (causal, as a session
/// runs it) of `preset` from `n_files` files in `seconds`, written to `out`.
pub fn trained(
    preset: &str,
    trained: &Trained,
    live: &Trained,
    n_files: usize,
    seconds: f64,
    out: &Path,
) -> String {
    format!(
        "trained {preset}{} on {} epochs ({} targets) from {n_files} file(s) in {seconds:.3} s \
         (the final fit {:.3} s); wrote {}\n\
         decision models from {}-fold cross-validated scores: zero-phase band-pass AUC {:.3} \
         (d' {:.2}); causal, as a session runs it, AUC {:.3} (d' {:.2})\n",
        trained
            .tuning
            .as_ref()
            .map(|t| format!(" ({})", t.chosen))
            .unwrap_or_default(),
        trained.n_epochs,
        trained.n_targets,
        trained.fit_s,
        out.display(),
        trained.cv_folds,
        trained.cv_auc,
        trained.decision.scores.d_prime(),
        live.cv_auc,
        live.decision.scores.d_prime()
    )
}

/// The one line of an unsupervised replay's result.
pub fn unsupervised(r: &UnsupervisedResult) -> String {
    let right = r.online_correct.iter().map(|&b| b as usize).sum::<usize>();
    format!(
        "unsupervised: {} characters, no labels seen; online {right}/{} ({}), post hoc {} \
         (chars % by reps: {}), final model AUC {:.3} ({})\n",
        r.n_characters,
        r.n_characters,
        r.online_text,
        r.posthoc_text,
        percents(&r.posthoc_chars_by_reps),
        r.auc,
        r.auc_by_recording
            .iter()
            .map(|a| format!("{} {:.3}", a.recording, a.auc))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// A benchmark's tables: every row under its subject, the mean ± sd over subjects, the
/// Wilcoxon tests per protocol, and the wall time.
pub fn benchmark(report: &BenchmarkReport) -> String {
    let mut s = String::new();
    let mut last = None;
    for r in &report.results {
        let key = (&r.dataset, &r.subject, &r.session, r.protocol);
        if last != Some(key) {
            let _ = writeln!(
                s,
                "\n{} / subject {}{} ({}): {} epochs, {} targets{}",
                r.dataset,
                r.subject,
                r.session
                    .as_ref()
                    .map(|s| format!(" / session {s}"))
                    .unwrap_or_default(),
                r.protocol,
                r.n_epochs,
                r.n_targets,
                r.n_chars
                    .map(|n| format!(", {n} characters"))
                    .unwrap_or_default()
            );
            last = Some(key);
        }
        let chars = r
            .chars_by_reps
            .as_ref()
            .map(|c| {
                let c: Vec<String> = c.iter().map(|v| v.to_string()).collect();
                format!("  chars right by reps: {}", c.join(" "))
            })
            .unwrap_or_default();
        let online = r
            .online_chars
            .zip(r.n_chars)
            .map(|(k, n)| format!("  online {k}/{n}"))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "  {:<12} AUC {:.3}  fit {:>7.3} s{online}{}{}",
            r.preset,
            r.auc,
            r.fit_s,
            chars,
            r.itr_bits_per_min
                .map(|v| format!("  ITR {v:.1} bits/min"))
                .unwrap_or_default()
        );
    }
    s += "\nmean ± sd over subjects:\n";
    for m in &report.summary {
        let _ = writeln!(
            s,
            "  {:<15} {:<12} AUC {:.3} ± {}  (n = {}){}",
            m.protocol.name(),
            m.preset,
            m.auc_mean,
            m.auc_sd
                .map(|v| format!("{v:.3}"))
                .unwrap_or_else(|| "  –  ".into()),
            m.n,
            m.char_accuracy_by_reps
                .as_ref()
                .map(|a| format!("  chars % by reps: {}", percents(a)))
                .unwrap_or_default()
        );
    }
    for protocol in Protocol::ALL {
        comparisons(&mut s, report, protocol);
    }
    let _ = writeln!(
        s,
        "\nwall time {:.1} s on {} thread(s)",
        report.wall_s, report.threads
    );
    s
}

/// The table of `protocol`'s Wilcoxon tests (none if it has no comparisons).
fn comparisons(s: &mut String, report: &BenchmarkReport, protocol: Protocol) {
    let cs: Vec<_> = report
        .comparisons
        .iter()
        .filter(|c| c.protocol == protocol)
        .collect();
    let Some(n) = cs.iter().map(|c| c.n).max() else {
        return;
    };
    let mut names: Vec<&str> = Vec::new();
    for c in &cs {
        if !names.contains(&c.a.as_str()) {
            names.push(&c.a);
        }
    }
    let _ = write!(
        s,
        "\n{protocol}: p of the one-sided Wilcoxon signed-rank test that the row's AUC is \
         larger than the column's (paired by subject, n = {n}):\n  {:<12}",
        ""
    );
    for b in &names {
        let _ = write!(s, " {b:>12}");
    }
    s.push('\n');
    for a in &names {
        let _ = write!(s, "  {a:<12}");
        for b in &names {
            let cell = cs
                .iter()
                .find(|c| c.a == *a && c.b == *b)
                .map(|c| match c.pvalue {
                    Some(p) => format!("{p:.3}"),
                    None => "tie".into(),
                })
                .unwrap_or_else(|| "–".into());
            let _ = write!(s, " {cell:>12}");
        }
        s.push('\n');
    }
}

/// A re-decided session file: its path, a line per decision and the summary.
pub fn redecided(r: &Redecided) -> String {
    let mut s = format!("{}:\n", r.result.file.display());
    for d in &r.result.decisions {
        let _ = writeln!(s, "{}", redecision_line(d, &r.bulbs));
    }
    s + &r.result.summary_line() + "\n"
}

/// The note that `run` was resampled to the rate of `of` (a [`Layout`](crate::layout::Layout)).
pub fn resampled(run: &Path, r: Resampled, of: &str) -> String {
    format!(
        "{}: resampled from {} Hz to {} Hz (polyphase) to match {of}\n",
        run.display(),
        r.from,
        r.to
    )
}

/// What a recording holds: its format, channels, rate, duration, events by code, targets, and
/// for a speller its text and matrix.
pub fn recording(rec: &Recording) -> String {
    let raw = &rec.raw;
    let name = rec
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| rec.path.display().to_string());
    let mut s = format!("{name}  ({:?})\n", rec.format);
    let _ = writeln!(
        s,
        "  channels   {}: {}",
        raw.n_channels(),
        raw.ch_names().join(" ")
    );
    let _ = writeln!(s, "  sfreq      {} Hz", raw.sfreq());
    let _ = writeln!(
        s,
        "  duration   {:.1} s ({} samples)",
        raw.duration(),
        raw.n_times()
    );
    let events = raw.events();
    let codes: Vec<String> = events
        .counts_by_code()
        .iter()
        .map(|(code, n)| format!("{code}×{n}"))
        .collect();
    let _ = writeln!(
        s,
        "  events     {} (per code: {})",
        events.len(),
        if codes.is_empty() {
            "none".to_string()
        } else {
            codes.join(" ")
        }
    );
    let unknown = events.len() - events.n_targets() - events.n_nontargets();
    let _ = write!(
        s,
        "  targets    {} target, {} non-target",
        events.n_targets(),
        events.n_nontargets()
    );
    if unknown > 0 {
        let _ = write!(s, ", {unknown} unlabelled");
    }
    s.push('\n');
    if let Some(speller) = &rec.speller {
        let decoded = speller.decode(events);
        let _ = match &speller.text_to_spell {
            Some(text) => writeln!(
                s,
                "  text       {text} (TextToSpell; decoded from the target flashes: {decoded})"
            ),
            None => writeln!(
                s,
                "  text       {decoded} (decoded from the target flashes)"
            ),
        };
        let rows: Vec<String> = speller.matrix().iter().map(|r| r.concat()).collect();
        let _ = writeln!(
            s,
            "  speller    {}×{} matrix: {}",
            speller.n_rows(),
            speller.n_cols(),
            rows.join(" / ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(pipeline: &str) -> PipelineResult {
        PipelineResult {
            pipeline: pipeline.to_string(),
            auc: 0.8771,
            auc_folds: vec![0.8771],
            speller_accuracy: Some(vec![0.5, 1.0]),
            speller_choices: Some(36),
            speller_n_chars: Some(2),
            speller_text: Some("HI".into()),
            reps_for_all_correct: Some(2),
            itr_at_best: None,
            fit_s: 0.25,
            score_epochs_per_s: 1000.0,
            tuning: None,
            tuning_per_fold: None,
        }
    }

    #[test]
    fn rows_come_under_one_header() {
        let mut n = Narration::evaluating();
        let (a, b) = (result("lda"), result("riemann"));
        let first = n.on(&Progress::Scored(&a));
        assert_eq!(
            first,
            format!(
                "{RESULT_HEADER}lda        AUC 0.877  fit   0.250 s       1000 epochs/s  chars % \
                 by reps: 50 100  picks HI  all right from 2 reps\n"
            )
        );
        let second = n.on(&Progress::Scored(&b));
        assert!(second.starts_with("riemann    AUC 0.877"), "{second}");
        assert_eq!(n.on(&Progress::Fit), "");
    }
}
