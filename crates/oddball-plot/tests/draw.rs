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
