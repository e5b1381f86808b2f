//! Pictures are written as the extension says, and failures name the file.

use oddball_arm::{planned_path, ArmConfig, ArmSim, Command};
use oddball_plot::arm::SessionPaths;
use oddball_plot::PlotError;

fn arm_after(commands: &[Command]) -> ArmSim {
    let mut arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
    arm.set_recording(true);
    for (i, &c) in commands.iter().enumerate() {
        arm.execute(i, c).unwrap();
    }
    arm
}

#[test]
fn the_pen_trace_is_written_as_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let start = ArmSim::from_config(&ArmConfig::default()).unwrap().pen();
    let commands = [Command::Up, Command::Right];
    let arm = arm_after(&commands);
    let expected = planned_path(start, commands.iter().copied(), arm.settings().step_m);
    let paths = SessionPaths {
        intended: &expected,
        executed: &expected,
        missed: &[],
        numbered: true,
    };
    let png = dir.path().join("pen_trace.png");
    oddball_plot::arm::draw_pen_trace(&arm, &paths, &png).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let svg = dir.path().join("pen_trace.svg");
    oddball_plot::arm::draw_pen_trace(&arm, &paths, &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
    assert!(text.contains("pen trace"));
}

#[test]
fn an_unknown_extension_or_an_unwritable_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let arm = arm_after(&[Command::Left]);
    let expected = vec![arm.pen()];
    let expected = SessionPaths {
        intended: &expected,
        executed: &expected,
        missed: &[],
        numbered: true,
    };
    let jpg = dir.path().join("arm.jpg");
    let err = oddball_plot::arm::draw_pen_trace(&arm, &expected, &jpg).unwrap_err();
    assert!(
        matches!(&err, PlotError::Format { path } if path == &jpg),
        "{err}"
    );
    assert!(!jpg.exists());
    let missing = dir.path().join("no such folder").join("arm.png");
    let err = oddball_plot::arm::draw_pen_trace(&arm, &expected, &missing).unwrap_err();
    assert_eq!(err.path(), missing.as_path(), "{err}");
}

#[test]
fn the_drawn_pen_trace_reaches_the_end_of_every_out_and_back_stroke() {
    // The letter G of the stroke font: its top bar and its spur go out and come back.
    let commands = oddball_session::tasks::text_commands("G").unwrap();
    let start = ArmSim::from_config(&ArmConfig::default()).unwrap().pen();
    let arm = arm_after(&commands);
    let expected = planned_path(start, commands.iter().copied(), arm.settings().step_m);
    // A quarter of a pixel of the zoomed panel (750 px over about 6 cm), and a coarse 0.1 mm.
    for tolerance in [2e-5, 1e-4] {
        let drawn: Vec<_> = oddball_plot::arm::drawn_pen_trace(&arm, tolerance)
            .iter()
            .map(|p| oddball_arm::Vector2::new(p.0, p.1))
            .collect();
        for (k, corner) in expected.iter().enumerate() {
            // What `oddball arm` and the session reports measure: the recorded trace.
            let recorded = arm.trace().distance_to(corner).unwrap();
            let pictured = drawn
                .windows(2)
                .map(|w| oddball_arm::trace::point_segment_distance(corner, &w[0], &w[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(
                recorded < 1e-5,
                "corner {k}: the pen passed {recorded} m away"
            );
            assert!(
                pictured <= recorded + tolerance,
                "corner {k}: the picture stops {:.2} mm from it, the pen {:.4} mm",
                pictured * 1e3,
                recorded * 1e3
            );
        }
    }
}

#[test]
fn the_session_picture_draws_the_intended_and_executed_paths_and_marks_missed_decisions() {
    use oddball_session::decision::Decision;
    use oddball_session::report::{executed_path, missed_decisions};
    let start = ArmSim::from_config(&ArmConfig::default()).unwrap().pen();
    // Intended up, left, down; decided up, right (wrong), nothing (abstained).
    let row = |intended, decided: Option<Command>| Decision {
        intended,
        decided,
        abstained: decided.is_none(),
        rounds: 5,
        confidence: 0.5,
        seconds: 10.0,
        ended_s: None,
        arm_refusal: None,
        pen_m: None,
    };
    let rows = [
        row(Command::Up, Some(Command::Up)),
        row(Command::Left, Some(Command::Right)),
        row(Command::Down, None),
    ];
    let arm = arm_after(&[Command::Up, Command::Right]);
    let h = arm.settings().step_m;
    let intended = planned_path(start, [Command::Up, Command::Left, Command::Down], h);
    let executed = executed_path(start, &rows, h);
    let missed = missed_decisions(start, &rows, h);
    assert_eq!(executed.len(), 3);
    let paths = SessionPaths {
        intended: &intended,
        executed: &executed,
        missed: &missed,
        numbered: true,
    };
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("pen_trace.svg");
    oddball_plot::arm::draw_pen_trace(&arm, &paths, &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    for words in [
        "intended path",
        "executed path",
        "1 wrong, 1 abstained",
        "2 wrong",
        "3 abstained",
        "arm at the start (blue, t = 0) and at the end",
    ] {
        assert!(text.contains(words), "{words:?} not in the picture");
    }
    assert!(
        !text.contains("each command"),
        "two poses are not each command's"
    );
    // The drawing task's task.png: the same panel alone, under the task's title.
    let task = dir.path().join("task.svg");
    oddball_plot::arm::draw_pen_paths(&arm, &paths, "Drawing \"L\"", &task).unwrap();
    let text = std::fs::read_to_string(&task).unwrap();
    assert!(text.contains("Drawing \"L\"") || text.contains("Drawing &quot;L&quot;"));
    assert!(text.contains("2 wrong") && !text.contains("shoulder"));
}
