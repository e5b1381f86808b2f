//! Pictures are written as the extension says, and failures name the file.

use oddball_arm::{planned_path, ArmConfig, ArmSim, Command};
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
    let png = dir.path().join("pen_trace.png");
    oddball_plot::arm::draw_pen_trace(&arm, &expected, &png).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let svg = dir.path().join("pen_trace.svg");
    oddball_plot::arm::draw_pen_trace(&arm, &expected, &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
    assert!(text.contains("pen trace"));
}

#[test]
fn an_unknown_extension_or_an_unwritable_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let arm = arm_after(&[Command::Left]);
    let expected = vec![arm.pen()];
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
    let commands = oddball_session::task::text_commands("G").unwrap();
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
