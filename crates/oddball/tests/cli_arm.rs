//! `oddball arm`: the paper's G end to end through the command line.

mod common;

fn arm(args: &[&str]) -> (bool, String, String) {
    let mut all = vec!["arm"];
    all.extend_from_slice(args);
    common::oddball(&all)
}

#[test]
fn draws_the_g_and_writes_trajectory_and_svg() {
    let dir = oddball_testkit::TempDir::new("arm");
    let plot = dir.join("arm.svg");
    let (ok, out, err) = arm(&[
        "--out",
        dir.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    // Six settled steps, each with a settle time and a final error well under 0.1 mm.
    let steps: Vec<&str> = out
        .lines()
        .filter(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.len() > 2
                && w[0].parse::<usize>().is_ok()
                && ["up", "down", "left", "right"].contains(&w[1])
        })
        .collect();
    assert_eq!(steps.len(), 6, "{out}");
    for line in &steps {
        assert!(!line.contains("refused"), "{line}");
    }
    assert!(out.contains("passes all 7 corners"), "{out}");
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).expect("trajectory written");
    let rows = csv.lines().count();
    assert!(
        rows > 4000,
        "4.8 s at 1 ms gives thousands of rows, got {rows}"
    );
    assert!(csv.starts_with("t_s,theta1_rad,theta2_rad"));
    let svg = std::fs::read_to_string(&plot).expect("plot written");
    assert!(svg.contains("<svg"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_command_off_the_board_is_refused_and_the_arm_holds() {
    let dir = oddball_testkit::TempDir::new("arm-off");
    let cmds = "up,up,up,up,up,up,up,up";
    let (ok, out, err) = arm(&["--commands", cmds, "--out", dir.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("refused, arm held still"), "{out}");
    assert!(out.contains("outside the board"), "{out}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn an_unknown_command_is_a_usage_error() {
    let (ok, _, err) = arm(&["--commands", "up,sideways"]);
    assert!(!ok);
    assert!(err.contains("unknown arm command `sideways`"), "{err}");
}
