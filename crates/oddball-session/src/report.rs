//! What a copy task's run reports (`oddball demo`'s `summary.json` and printed lines): one row
//! per decision, accuracy and ITR under a stopping rule, the pen's corners against the path of
//! the executed commands, the intended path and the decisions that left it, the calibration without its wall-clock time, and their text (and the
//! drawing task's line), and a session file's decisions re-made offline ([`SessionResult`]).

use std::fmt::Write as _;
use std::path::PathBuf;

use nalgebra::Vector2;
use oddball_arm::{planned_path, ArmSim, Command};
use oddball_decode::decision::DecisionRule;
use oddball_decode::metrics::Itr;
use serde::Serialize;

use crate::decision::{CalibrationReport, Decision, TrialOutcome};
use crate::record::Redecision;
use crate::tasks::DrawReport;
pub use crate::timing::rule_name;

/// A decision as a report's row (`summary.json`'s `decisions`): its number (from 1), the
/// decision, and where the pen was when it was made.
#[derive(Debug, Clone, Serialize)]
pub struct Row<'a> {
    pub index: usize,
    #[serde(flatten)]
    pub decision: &'a Decision,
    /// Pen (x, z) in metres when the decision was made, before its command.
    pub pen_m: Option<[f64; 2]>,
}

/// `decisions` as a report's rows, numbered from 1.
pub fn numbered(decisions: &[Decision]) -> Vec<Row<'_>> {
    decisions
        .iter()
        .enumerate()
        .map(|(i, d)| Row {
            index: i + 1,
            decision: d,
            pen_m: d.pen_m,
        })
        .collect()
}

/// Accuracy, rounds and ITR of a list of decisions.
#[derive(Debug, Clone, Serialize)]
pub struct Scores {
    pub rule: String,
    pub decisions: usize,
    pub correct: usize,
    pub abstained: usize,
    pub accuracy: f64,
    pub mean_rounds: f64,
    pub itr: Itr,
    /// Utility bit rate (Dal Seno et al. 2010): (correct − wrong) · log2 3 bits per minute of
    /// decisions (abstentions cost time only); 0 when errors are as many as hits.
    pub utility_bits_per_min: f64,
}

/// Accuracy, mean rounds and ITR (Wolpaw, 4 choices) of `rows` under `rule`.
pub fn scores(rows: &[Decision], rule: &DecisionRule) -> Scores {
    let n = rows.len().max(1) as f64;
    let correct = rows.iter().filter(|r| r.correct()).count();
    let accuracy = correct as f64 / n;
    let seconds = rows.iter().map(|r| r.seconds).sum::<f64>() / n;
    let wrong = rows
        .iter()
        .filter(|r| r.decided.is_some() && !r.correct())
        .count();
    let utility = oddball_decode::stopping::utility_bits(4, accuracy, wrong as f64 / n);
    Scores {
        rule: rule_name(rule),
        decisions: rows.len(),
        correct,
        abstained: rows.iter().filter(|r| r.abstained).count(),
        accuracy,
        mean_rounds: rows.iter().map(|r| r.rounds as f64).sum::<f64>() / n,
        itr: Itr::new(4, accuracy, seconds),
        utility_bits_per_min: if seconds > 0.0 {
            utility * 60.0 / seconds
        } else {
            0.0
        },
    }
}

/// The minutes after a session's start its headline counts bits over ([`bits_by`]).
pub const HEADLINE_MINUTES: [f64; 2] = [5.0, 10.0];

/// What a session delivered by some minutes after it started (its first sample; a labelled
/// calibration's time counts, and delivers nothing): the decisions made by then and their
/// Wolpaw bits, `made · B(4, correct / made)` — each decision made carries the bits of the
/// accuracy of all made, an abstention carries none.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BitsBy {
    pub minutes: f64,
    /// Decisions that chose a command by then.
    pub made: usize,
    pub correct: usize,
    /// Decisions that abstained by then.
    pub abstained: usize,
    pub bits: f64,
    /// The session ended (its last decision) before this time: the bits are all it delivered.
    pub session_shorter: bool,
}

/// The bits `rows` delivered by `minutes` after the session's start; `None` when a row has no
/// session time (a replay).
pub fn bits_by(rows: &[Decision], minutes: f64) -> Option<BitsBy> {
    let limit = minutes * 60.0;
    let mut by = BitsBy {
        minutes,
        made: 0,
        correct: 0,
        abstained: 0,
        bits: 0.0,
        session_shorter: true,
    };
    for r in rows {
        let at = r.ended_s?;
        if at > limit {
            by.session_shorter = false;
            continue;
        }
        if r.decided.is_some() {
            by.made += 1;
            by.correct += usize::from(r.correct());
        } else {
            by.abstained += 1;
        }
    }
    if by.made > 0 {
        let p = by.correct as f64 / by.made as f64;
        by.bits = by.made as f64 * oddball_decode::metrics::wolpaw_bits(4, p);
    }
    Some(by)
}

/// The headline: bits by each of [`HEADLINE_MINUTES`] (empty for a replay).
pub fn headline(rows: &[Decision]) -> Vec<BitsBy> {
    HEADLINE_MINUTES
        .iter()
        .filter_map(|&m| bits_by(rows, m))
        .collect()
}

/// `bits delivered (Wolpaw, decisions made): first 5 min 31.4 bits (17 made, 16 right, 1
/// abstained); first 10 min …`.
pub fn headline_text(headline: &[BitsBy]) -> Option<String> {
    if headline.is_empty() {
        return None;
    }
    let parts: Vec<String> = headline
        .iter()
        .map(|b| {
            format!(
                "first {} min {:.1} bits ({} made, {} right, {} abstained{})",
                b.minutes,
                b.bits,
                b.made,
                b.correct,
                b.abstained,
                if b.session_shorter {
                    "; the session ended before"
                } else {
                    ""
                }
            )
        })
        .collect();
    Some(format!(
        "bits delivered since the session started (Wolpaw, on decisions made): {}",
        parts.join("; ")
    ))
}

/// The decisions of one stretch of a session (`first`..=`last`, from 1).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stretch {
    pub first: usize,
    pub last: usize,
    pub correct: usize,
    pub abstained: usize,
    /// Right decisions over all decisions of the stretch (abstentions count as not right).
    pub accuracy: f64,
}

/// Accuracy over time: `rows` cut into stretches of `size` decisions (1–10, 11–20, …; the last
/// may be shorter). Shows how an uncalibrated session learns.
pub fn accuracy_over_time(rows: &[Decision], size: usize) -> Vec<Stretch> {
    rows.chunks(size.max(1))
        .enumerate()
        .map(|(k, c)| {
            let correct = c.iter().filter(|r| r.correct()).count();
            Stretch {
                first: k * size.max(1) + 1,
                last: k * size.max(1) + c.len(),
                correct,
                abstained: c.iter().filter(|r| r.abstained).count(),
                accuracy: correct as f64 / c.len() as f64,
            }
        })
        .collect()
}

/// `accuracy over time: 1–10 6/10 (3 abstained), 11–20 10/10`.
pub fn accuracy_over_time_text(stretches: &[Stretch]) -> String {
    let parts: Vec<String> = stretches
        .iter()
        .map(|s| {
            let mut t = format!(
                "{}–{} {}/{}",
                s.first,
                s.last,
                s.correct,
                s.last - s.first + 1
            );
            if s.abstained > 0 {
                let _ = write!(t, " ({} abstained)", s.abstained);
            }
            t
        })
        .collect();
    format!("accuracy over time: {}", parts.join(", "))
}

/// The pen's corners against the path of the commands the arm executed, and the path the
/// person intended.
#[derive(Debug, Clone, Serialize)]
pub struct PenReport {
    /// Pen at each decision and at the end, metres.
    pub corners_m: Vec<[f64; 2]>,
    /// Where the intended commands would have put the reference, metres (from the start).
    pub intended_m: Vec<[f64; 2]>,
    /// Where the executed commands put the reference, metres (from the start).
    pub executed_m: Vec<[f64; 2]>,
    pub max_corner_error_mm: f64,
    /// Every decision was the intended command and the arm executed it.
    pub drew_intended_path: bool,
    /// The decisions that did not move the pen as intended.
    pub missed: Vec<MissedDecision>,
}

/// Why a decision did not move the pen as intended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Miss {
    /// Another command than the intended one was decided (and the arm moved that way).
    Wrong,
    /// No command was decided; the arm stayed.
    Abstained,
    /// A command was decided and the arm refused it (it would leave the board); the arm stayed.
    Refused,
}

/// A decision that did not move the pen as intended, and where.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissedDecision {
    /// The decision's number (from 1).
    pub index: usize,
    pub miss: Miss,
    /// The commanded position before the decision and after it (the same unless the arm
    /// moved), metres.
    pub from_m: [f64; 2],
    pub to_m: [f64; 2],
}

/// The path of the commands the arm executed, from `pen_start`, metres.
pub fn executed_path(pen_start: Vector2<f64>, rows: &[Decision], step_m: f64) -> Vec<Vector2<f64>> {
    let executed = rows
        .iter()
        .filter_map(|r| r.decided.filter(|_| r.arm_refusal.is_none()));
    planned_path(pen_start, executed, step_m)
}

/// The decisions that did not move the pen as intended (wrong, abstained, refused by the arm),
/// each where the commanded position was, starting from `pen_start`.
pub fn missed_decisions(
    pen_start: Vector2<f64>,
    rows: &[Decision],
    step_m: f64,
) -> Vec<MissedDecision> {
    let mut at = pen_start;
    let mut out = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let from = at;
        if let Some(c) = r.decided.filter(|_| r.arm_refusal.is_none()) {
            at = c.apply(&at, step_m);
        }
        let miss = match r.decided {
            None => Miss::Abstained,
            Some(_) if r.arm_refusal.is_some() => Miss::Refused,
            Some(c) if c != r.intended => Miss::Wrong,
            Some(_) => continue,
        };
        out.push(MissedDecision {
            index: i + 1,
            miss,
            from_m: [from[0], from[1]],
            to_m: [at[0], at[1]],
        });
    }
    out
}

/// What every session command's `summary.json` holds first, in one schema (`demo`, `task`,
/// `online`): the command, who took part, the pipeline and seed, the paradigm's timing, and
/// the calibration (`trials` 0 when the session did not calibrate).
#[derive(Debug, Serialize)]
pub struct SessionFacts<'a> {
    /// `demo`, `task draw`, `task track` or `online`.
    pub command: &'a str,
    /// A simulated subject's preset, the replayed files, or the live source.
    pub subject: &'a str,
    pub pipeline: &'a str,
    pub seed: u64,
    pub paradigm: crate::paradigm::FourBulbParams,
    pub calibration: CalibrationSummary,
}

/// The calibration report without its wall-clock fit time (the files must not depend on it).
#[derive(Debug, Serialize)]
pub struct CalibrationSummary {
    pub trials: usize,
    pub epochs: usize,
    pub targets: usize,
    pub rejected: usize,
    pub cv_auc: f64,
    pub d_prime: f64,
}

impl From<&CalibrationReport> for CalibrationSummary {
    fn from(c: &CalibrationReport) -> Self {
        Self {
            trials: c.n_trials,
            epochs: c.n_epochs,
            targets: c.n_targets,
            rejected: c.n_rejected,
            cv_auc: c.cv_auc,
            d_prime: c.d_prime,
        }
    }
}

/// Corners: the pen after each executed command (at the next decision, or at the end)
/// against where the executed commands put the reference; the intended path beside it.
pub fn pen_report(arm: &ArmSim, pen_start: Vector2<f64>, rows: &[Decision]) -> PenReport {
    let step_m = arm.settings().step_m;
    let expected = executed_path(pen_start, rows, step_m);
    let intended = planned_path(pen_start, rows.iter().map(|r| r.intended), step_m);
    let missed = missed_decisions(pen_start, rows, step_m);
    let end_pen = [arm.pen()[0], arm.pen()[1]];
    let mut measured = Vec::new();
    let mut errors = Vec::new();
    let mut target = expected.iter().skip(1);
    for (k, row) in rows.iter().enumerate() {
        if row.decided.is_some() && row.arm_refusal.is_none() {
            let target = target.next().expect("one target per executed command");
            // The pen when the next decision comes (or at the end) shows where this one left it.
            let pen = rows.get(k + 1).and_then(|r| r.pen_m).unwrap_or(end_pen);
            measured.push(pen);
            errors.push((Vector2::new(pen[0], pen[1]) - target).norm());
        }
    }
    let xz = |v: Vec<Vector2<f64>>| v.iter().map(|p| [p[0], p[1]]).collect();
    PenReport {
        corners_m: measured,
        intended_m: xz(intended),
        executed_m: xz(expected),
        max_corner_error_mm: errors.iter().copied().fold(0.0, f64::max) * 1000.0,
        drew_intended_path: missed.is_empty(),
        missed,
    }
}

/// The `index`-th decision (from 1) as printed (`decision  1: intended up    decided up      ok
/// rounds …`).
pub fn row_text(index: usize, r: &Decision) -> String {
    let name = |c: Option<Command>| c.map_or("—".to_string(), |c| c.to_string());
    let decided = if r.abstained {
        "abstain".to_string()
    } else {
        name(r.decided)
    };
    let mark = if r.correct() { "ok" } else { "WRONG" };
    let mut s = format!(
        "decision {:>2}: intended {:<5} decided {:<7} {:<5} rounds {}  confidence {:.3}  {:.2} s",
        index,
        name(Some(r.intended)),
        decided,
        mark,
        r.rounds,
        r.confidence,
        r.seconds
    );
    if let Some(e) = &r.arm_refusal {
        let _ = write!(s, "  (arm refused: {e})");
    }
    s
}

/// The closing lines: accuracy and ITR under the rule (and the fixed-rounds comparison), the pen.
pub fn report_text(
    simulated_seconds: f64,
    result: &Scores,
    comparison: Option<&Scores>,
    pen: &PenReport,
) -> String {
    let mut s = String::new();
    let line = |s: &mut String, sc: &Scores| {
        let _ = writeln!(
            s,
            "  {:<48} accuracy {:>5.1} % ({}/{}, {} abstained)  mean rounds {:.2}  {:.2} s/decision  ITR {:.2} bits/decision, {:.2} bits/min, utility {:.2} bits/min",
            sc.rule,
            100.0 * sc.accuracy,
            sc.correct,
            sc.decisions,
            sc.abstained,
            sc.mean_rounds,
            sc.itr.seconds_per_selection,
            sc.itr.bits_per_selection,
            sc.itr.bits_per_minute,
            sc.utility_bits_per_min
        );
    };
    let _ = writeln!(
        s,
        "command accuracy and information transfer rate (Wolpaw, 4 choices):"
    );
    line(&mut s, result);
    if let Some(c) = comparison {
        line(&mut s, c);
    }
    let count = |m: Miss| pen.missed.iter().filter(|d| d.miss == m).count();
    let _ = writeln!(
        s,
        "pen: after each of its {} moves within {:.1e} mm of where the executed commands put it; {}",
        pen.corners_m.len(),
        pen.max_corner_error_mm,
        if pen.drew_intended_path {
            "drew the intended path".to_string()
        } else {
            format!(
                "did NOT draw the intended path ({} wrong, {} abstained, {} refused by the arm)",
                count(Miss::Wrong),
                count(Miss::Abstained),
                count(Miss::Refused)
            )
        }
    );
    let _ = writeln!(s, "simulated time {:.1} s", simulated_seconds);
    s
}

/// What a drawing task printed: the text, completion, decisions against the plan, the pen's
/// deviation from the plan (mm) and the task's totals.
pub fn draw_text(r: &DrawReport) -> String {
    format!(
        "drew {:?}: {} in {} decisions (plan {} moves); pen trace from the plan: mean {:.4} mm, max {:.4} mm\n{}",
        r.text,
        if r.completed { "completed" } else { "NOT completed" },
        r.decisions,
        r.min_decisions,
        r.mean_deviation_m * 1e3,
        r.max_deviation_m * 1e3,
        r.totals
    )
}

/// A session file's decisions made again offline by a model and scored (`oddball evaluate
/// --model model.json --test session.dat`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionResult {
    pub file: PathBuf,
    pub decisions: Vec<Redecision>,
    /// Decisions equal to the recorded ones.
    pub identical_to_recorded: usize,
    pub accuracy: f64,
    pub itr: Itr,
}

impl SessionResult {
    /// Scores `decisions` re-made from `file`: Wolpaw ITR with 4 choices.
    pub fn new(file: PathBuf, decisions: Vec<Redecision>) -> Self {
        let same = decisions
            .iter()
            .filter(|d| d.decided() == d.recorded)
            .count();
        let n = decisions.len().max(1) as f64;
        let correct = Self::count_correct(&decisions);
        let seconds = decisions.iter().map(|d| d.seconds).sum::<f64>() / n;
        let accuracy = correct as f64 / n;
        Self {
            file,
            identical_to_recorded: same,
            decisions,
            accuracy,
            itr: Itr::new(4, accuracy, seconds),
        }
    }

    fn count_correct(decisions: &[Redecision]) -> usize {
        decisions
            .iter()
            .filter(|d| d.decided().is_some() && d.decided() == d.intended)
            .count()
    }

    /// Decisions equal to the intended command.
    pub fn correct(&self) -> usize {
        Self::count_correct(&self.decisions)
    }

    /// `  N online decisions: K identical to the recorded ones; accuracy …, ITR …`.
    pub fn summary_line(&self) -> String {
        format!(
            "  {} online decisions: {} identical to the recorded ones; accuracy {:.1} % ({}/{}), ITR {:.2} bits/decision, {:.2} bits/min",
            self.decisions.len(),
            self.identical_to_recorded,
            100.0 * self.accuracy,
            self.correct(),
            self.decisions.len(),
            self.itr.bits_per_selection,
            self.itr.bits_per_minute
        )
    }
}

/// One re-made decision as printed, the session's bulbs naming the codes (`—` for none).
pub fn redecision_line(d: &Redecision, bulbs: &[Command]) -> String {
    let name = |c: Option<u32>| {
        c.and_then(|c| bulbs.get(c as usize - 1))
            .map_or("—".to_string(), |b| b.to_string())
    };
    let decided = match d.outcome {
        TrialOutcome::Chosen { code } => name(Some(code)),
        _ => "abstain".into(),
    };
    format!(
        "  trial {:>3}: intended {:<5} decided {:<7} rounds {}  recorded {:<7} {}",
        d.number,
        name(d.intended),
        decided,
        d.rounds,
        if d.recorded.is_some() {
            name(d.recorded)
        } else {
            "abstain".into()
        },
        if d.decided() == d.recorded {
            "same"
        } else {
            "DIFFERENT"
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(intended: Command, decided: Option<Command>) -> Decision {
        Decision {
            intended,
            decided,
            abstained: decided.is_none(),
            rounds: 4,
            confidence: 0.9,
            seconds: 2.0,
            ended_s: None,
            arm_refusal: None,
            pen_m: None,
        }
    }

    #[test]
    fn the_headline_counts_the_bits_of_decisions_made_by_each_time() {
        // A labelled session: 4 minutes of calibration, then a decision every 30 s.
        let decided = [
            Some(Command::Up),
            Some(Command::Up),
            None,
            Some(Command::Down),
            Some(Command::Up),
            Some(Command::Up),
            Some(Command::Up),
        ];
        let rows: Vec<Decision> = decided
            .iter()
            .enumerate()
            .map(|(i, &d)| Decision {
                ended_s: Some(240.0 + 30.0 * (i + 1) as f64),
                ..row(Command::Up, d)
            })
            .collect();
        // By 5 min: the first decision (270 s) and the second (300 s, on the limit), both right.
        let five = bits_by(&rows, 5.0).unwrap();
        assert_eq!((five.made, five.correct, five.abstained), (2, 2, 0));
        assert!((five.bits - 4.0).abs() < 1e-12);
        assert!(!five.session_shorter);
        // By 10 min: all 7; 6 made, 5 right: 6 · B(4, 5/6).
        let ten = bits_by(&rows, 10.0).unwrap();
        assert_eq!((ten.made, ten.correct, ten.abstained), (6, 5, 1));
        let b = 2.0 + (5.0 / 6.0) * (5.0f64 / 6.0).log2() + (1.0 / 6.0) * (1.0f64 / 18.0).log2();
        assert!((ten.bits - 6.0 * b).abs() < 1e-12, "{ten:?}");
        assert!(ten.session_shorter);
        let text = headline_text(&headline(&rows)).unwrap();
        assert!(text.contains("first 5 min 4.0 bits (2 made, 2 right, 0 abstained)"));
        assert!(text.contains("the session ended before"), "{text}");
        // Nothing decided by then, or a replay without a session clock.
        assert_eq!(bits_by(&rows, 4.0).unwrap().bits, 0.0);
        assert!(bits_by(&[row(Command::Up, None)], 5.0).is_none());
        assert!(headline_text(&headline(&[row(Command::Up, None)])).is_none());
    }

    #[test]
    fn scores_count_right_wrong_and_abstained_decisions() {
        let rows = [
            row(Command::Up, Some(Command::Up)),
            row(Command::Left, Some(Command::Right)),
            row(Command::Down, None),
            row(Command::Down, Some(Command::Down)),
        ];
        let s = scores(&rows, &DecisionRule::Fixed { rounds: 4 });
        assert_eq!(s.rule, "fixed 4 rounds");
        assert_eq!((s.decisions, s.correct, s.abstained), (4, 2, 1));
        assert_eq!(s.accuracy, 0.5);
        assert_eq!(s.mean_rounds, 4.0);
        assert_eq!(s.itr, Itr::new(4, 0.5, 2.0));
        // (2 right − 1 wrong) / 4 decisions · log2 3 bits per 2 s.
        assert!((s.utility_bits_per_min - 0.25 * 3f64.log2() * 30.0).abs() < 1e-12);
    }

    #[test]
    fn missed_decisions_are_placed_where_the_arm_stood() {
        let h = 0.02;
        let mut refused = row(Command::Up, Some(Command::Up));
        refused.arm_refusal = Some("off the board".into());
        let rows = [
            row(Command::Up, Some(Command::Up)),
            row(Command::Left, Some(Command::Right)),
            row(Command::Down, None),
            refused,
            row(Command::Down, Some(Command::Down)),
        ];
        let start = Vector2::new(0.0, 0.0);
        let missed = missed_decisions(start, &rows, h);
        let kinds: Vec<(usize, Miss)> = missed.iter().map(|m| (m.index, m.miss)).collect();
        assert_eq!(
            kinds,
            [(2, Miss::Wrong), (3, Miss::Abstained), (4, Miss::Refused)]
        );
        // Up to (0, h); the wrong move right to (h, h); the abstention and refusal stay there.
        assert_eq!((missed[0].from_m, missed[0].to_m), ([0.0, h], [h, h]));
        assert_eq!((missed[1].from_m, missed[1].to_m), ([h, h], [h, h]));
        assert_eq!((missed[2].from_m, missed[2].to_m), ([h, h], [h, h]));
        let executed = executed_path(start, &rows, h);
        assert_eq!(executed.last(), Some(&Vector2::new(h, 0.0)));
        assert_eq!(executed.len(), 4);
    }

    #[test]
    fn a_row_prints_its_mark_and_an_abstention() {
        let ok = row_text(1, &row(Command::Up, Some(Command::Up)));
        assert_eq!(
            ok,
            "decision  1: intended up    decided up      ok    rounds 4  confidence 0.900  2.00 s"
        );
        let abstained = row_text(12, &row(Command::Up, None));
        assert!(abstained.starts_with("decision 12: intended up    decided abstain WRONG"));
    }
}
