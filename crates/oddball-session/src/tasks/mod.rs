//! Tasks people do with the BCI: copying commands, point-to-point target tracking, and drawing
//! text.
//!
//! A [`Pilot`] turns an intended direction into a decided command that moves the arm: a live or
//! simulated [`Session`](crate::engine::Session), or a [`ReplayPilot`] of real speller EEG. The tasks choose the
//! intention the way a person would and measure what a BCI study reports.
//!
//! * **Tracking** ([`run_tracking`]): targets on the board's `h`-grid, seeded (each 2–5 steps
//!   from the previous one) or given. The person intends the direction that shrinks the larger
//!   remaining error of the pen's commanded position, so a wrong decision costs a real detour.
//!   A target is reached when the commanded position is on it and the pen has settled within
//!   `tolerance_m`. Metrics per target: success, commands used against the minimum (path
//!   efficiency), wrong moves, abstentions, time to target, decisions per minute, ITR, final
//!   placement error of the pen.
//! * **Drawing** ([`stroke_plan`], [`run_drawing`]): letters and digits from a built-in stroke
//!   font on a grid 2 steps wide and 4 high, starting at the glyph's bottom-left corner. The
//!   board model has no pen-up state, so every glyph is one continuous path that retraces its
//!   own strokes where it must, ends on the baseline at its right edge where it can, and the
//!   travel to the next glyph (down to the baseline, then right to one step past the glyph) is
//!   part of the plan and drawn. The person intends the next planned move; after a wrong
//!   move they intend the way back to the plan. The trace is scored against the planned path
//!   (mean and max distance of the pen from it).

//!
//! Files: [`pilot`] (who decides), [`copy`] (the copy task, a task's totals, the board check),
//! [`track`], [`draw`] and [`font`] (the stroke font).

pub mod copy;
pub mod draw;
pub mod font;
pub mod pilot;
pub mod track;

pub use copy::{check_path, run_copy, CopyRun, TaskTotals};
pub use draw::{check_drawing, drawing_path, run_drawing, DrawReport};
pub use font::{glyph_extents, stroke_plan, text_commands, GlyphExtent, PlannedMove};
pub use pilot::{Pilot, ReplayPilot};
pub use track::{
    direction_towards, intended_track_path, run_tracking, seeded_targets, task_targets,
    TargetResult, TrackParams, TrackReport, MAX_TARGETS,
};
