//! `oddball arm`: simulate the two-link arm drawing on its board from direction commands (the
//! paper's letter G by default), write the trajectory as CSV and a picture of the arm at key
//! instants with the pen trace, and print each step's settle time and final error.

use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use oddball_arm::config::TransitionConfig;
use oddball_arm::{ArmConfig, ArmSim, ProgramReport, StepOutcome, Vector2};

/// Options of `oddball arm`.
#[derive(Debug, clap::Args)]
pub struct ArmArgs {
    #[arg(long, default_value = crate::args::LETTER_G, value_parser = crate::args::commands_arg, help = crate::args::COMMANDS_HELP)]
    pub commands: std::vec::Vec<oddball_arm::Command>,
    /// TOML model of the arm, board, controller and simulation (default: the built-in desk arm;
    /// see --print-config).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Step h per command in metres [default: from the config, 0.02 m].
    #[arg(long, value_name = "METRES")]
    pub step: Option<f64>,
    /// Output directory for trajectory.csv and the plot.
    #[arg(long, value_name = "DIR", default_value = "out/arm", value_parser = crate::args::output_dir)]
    pub out: PathBuf,
    /// Plot file, .png or .svg [default: <out>/arm.png].
    #[arg(long, value_name = "FILE", value_parser = crate::args::plot_file)]
    pub plot: Option<PathBuf>,
    /// Integration step and control period in seconds [default: from the config, 0.001 s].
    #[arg(long, value_name = "SECONDS")]
    pub dt: Option<f64>,
    /// Move the reference in plain steps instead of minimum-jerk transitions.
    #[arg(long)]
    pub plain_step: bool,
    /// Print the full configuration in effect (TOML) and exit.
    #[arg(long)]
    pub print_config: bool,
}

pub fn run(args: &ArmArgs) -> Result<()> {
    let mut config = match &args.config {
        Some(path) => ArmConfig::from_toml_path(path)?,
        None => ArmConfig::default(),
    };
    if let Some(step) = args.step {
        config.reference.step_m = step;
    }
    if let Some(dt) = args.dt {
        config.sim.dt_s = dt;
    }
    if args.plain_step {
        config.reference.transition = TransitionConfig::Step;
    }
    if args.print_config {
        print!("{}", config.to_toml_string());
        return Ok(());
    }
    let mut sim = ArmSim::from_config(&config).context("setting up the arm simulation")?;
    let start = sim.pen();

    let report = sim.run_program(&args.commands);

    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let csv_path = args.out.join("trajectory.csv");
    write_csv(&sim, &csv_path)?;
    let plot_path = args
        .plot
        .clone()
        .unwrap_or_else(|| args.out.join("arm.png"));
    if let Some(parent) = plot_path.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    let expected = expected_path(start, &report);
    let keys = key_configurations(&sim, &report);
    oddball_plot::arm::draw(&sim, &keys, &expected, &plot_path)
        .with_context(|| format!("drawing {}", plot_path.display()))?;

    print!("{}", table(&sim, &config, &report, &expected));
    println!("wrote {} and {}", csv_path.display(), plot_path.display());
    if let Some(stop) = report.stopped {
        return Err(stop).context("the simulation stopped for safety");
    }
    Ok(())
}

/// The start point and the target of every executed command: the path the pen should draw.
fn expected_path(start: Vector2<f64>, report: &ProgramReport) -> Vec<Vector2<f64>> {
    std::iter::once(start)
        .chain(report.executed().map(|r| r.target))
        .collect()
}

fn write_csv(sim: &ArmSim, path: &Path) -> Result<()> {
    let file = oddball_io::AtomicFile::create(path)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(
        w,
        "t_s,theta1_rad,theta2_rad,theta1_dot_rad_s,theta2_dot_rad_s,u1_n_m,u2_n_m,x_m,z_m,x_d_m,z_d_m,saturated"
    )?;
    for s in sim.samples() {
        writeln!(
            w,
            "{:.6},{:.12},{:.12},{:.12},{:.12},{:.9},{:.9},{:.12},{:.12},{:.12},{:.12},{}",
            s.t_s,
            s.q[0],
            s.q[1],
            s.qd[0],
            s.qd[1],
            s.u[0],
            s.u[1],
            s.p[0],
            s.p[1],
            s.p_d[0],
            s.p_d[1],
            u8::from(s.saturated[0] || s.saturated[1]),
        )?;
    }
    let file = w
        .into_inner()
        .map_err(|e| e.into_error())
        .with_context(|| format!("writing {}", path.display()))?;
    file.commit()?;
    Ok(())
}

fn table(
    sim: &ArmSim,
    config: &ArmConfig,
    report: &ProgramReport,
    expected: &[Vector2<f64>],
) -> String {
    let settings = sim.settings();
    let mut out = String::new();
    let transition = match config.reference.transition {
        TransitionConfig::MinJerk => format!("minimum-jerk {} s", config.reference.transition_s),
        TransitionConfig::Step => "plain step".to_string(),
    };
    let _ = writeln!(
        out,
        "arm: step h = {} m, {transition}, {} s per command, dt = {} s, settle tolerance {} mm",
        settings.step_m,
        settings.command_period_s,
        settings.dt_s,
        settings.settle_tolerance_m * 1e3
    );
    let _ = writeln!(
        out,
        "{:>4}  {:<7} {:>20}  {:>10}  {:>16}  {:>20}  {:>15}",
        "step",
        "command",
        "target (x, z) m",
        "settle (s)",
        "final error (mm)",
        "max |u1|, |u2| (N·m)",
        "saturated steps"
    );
    for o in &report.outcomes {
        let s = o.stats();
        match o {
            StepOutcome::Executed(r) => {
                let settle = s
                    .settle_time_s
                    .map_or_else(|| "not settled".to_string(), |t| format!("{t:.3}"));
                let _ = writeln!(
                    out,
                    "{:>4}  {:<7} {:>20}  {:>10}  {:>16.6}  {:>20}  {:>15}",
                    r.index + 1,
                    r.command.name(),
                    format!("({:.4}, {:.4})", r.target[0], r.target[1]),
                    settle,
                    s.final_error_m * 1e3,
                    format!(
                        "{:.2}, {:.2}",
                        s.max_abs_torque_n_m[0], s.max_abs_torque_n_m[1]
                    ),
                    format!("{} ({:.3} s)", s.saturated_steps, s.saturated_duration_s),
                );
            }
            StepOutcome::Refused {
                index,
                command,
                error,
                ..
            } => {
                let _ = writeln!(
                    out,
                    "{:>4}  {:<7} refused, arm held still: {error}",
                    index + 1,
                    command.name()
                );
            }
        }
    }
    if let Some(stop) = &report.stopped {
        let _ = writeln!(
            out,
            "stopped after {} command(s): {stop}",
            report.outcomes.len()
        );
    }
    let worst = expected
        .iter()
        .filter_map(|c| sim.trace().distance_to(c))
        .fold(0.0f64, f64::max);
    let _ = writeln!(
        out,
        "pen trace: {} vertices, {:.1} mm drawn; passes all {} corners of the expected path within {:.6} mm",
        sim.trace().points().len(),
        sim.trace().length_m() * 1e3,
        expected.len(),
        worst * 1e3
    );
    out
}

/// Joint angles at the key instants: the start, and the end of every command's period.
fn key_configurations(sim: &ArmSim, report: &ProgramReport) -> Vec<(f64, Vector2<f64>)> {
    let times: Vec<f64> = std::iter::once(0.0)
        .chain(report.outcomes.iter().map(|o| o.stats().t_end_s))
        .collect();
    oddball_plot::arm::configurations_at(sim, &times)
}
