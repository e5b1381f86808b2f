//! Closed-loop simulation speed: simulated seconds per wall-clock second at dt = 1 ms with the
//! inverse-dynamics controller, saturation, safety checks and pen trace in the loop.
//!
//! `cargo bench -p oddball-arm --bench closed_loop`. Criterion reports the time to simulate one
//! second (1000 control steps); the real-time factor is 1 s divided by that time, and is also
//! printed directly at the end from a separate 60-simulated-second run.

use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, Criterion, Throughput};
use oddball_arm::{ArmConfig, ArmSim, Command, ControlUpdate};

/// A simulation drawing back and forth (up/down) so that the controller always has work to do.
fn sim(update: ControlUpdate) -> ArmSim {
    let mut cfg = ArmConfig::default();
    cfg.sim.control_update = update;
    let mut sim = ArmSim::from_config(&cfg).expect("default config is valid");
    sim.set_recording(false);
    sim
}

/// Simulates `seconds` of commanded motion, alternating up and down commands every period.
fn simulate(sim: &mut ArmSim, seconds: f64) {
    let period = sim.settings().command_period_s;
    let mut t = 0.0;
    let mut up = true;
    while t < seconds {
        let cmd = if up { Command::Up } else { Command::Down };
        up = !up;
        sim.issue(cmd)
            .expect("alternating 2 cm moves stay on the board");
        black_box(sim.run_for(period).expect("no safety stop"));
        t += period;
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("closed_loop");
    group.throughput(Throughput::Elements(1000));
    for (name, update) in [
        ("zoh_1s_of_sim_dt_1ms", ControlUpdate::ZeroOrderHold),
        ("continuous_1s_of_sim_dt_1ms", ControlUpdate::Continuous),
    ] {
        let mut s = sim(update);
        // 1000 control steps (1 simulated second) per iteration, re-issuing up/down moves; the
        // simulation is rebuilt every 600 simulated seconds to bound the pen trace.
        group.bench_function(name, |b| {
            b.iter(|| {
                if s.time_s() > 600.0 {
                    s = sim(update);
                }
                let target = s.target();
                if s.transition().end_time_s() <= s.time_s() {
                    let cmd = if target[1] > 0.06 {
                        Command::Down
                    } else {
                        Command::Up
                    };
                    s.issue(cmd).expect("on the board");
                }
                for _ in 0..1000 {
                    black_box(s.step().expect("no safety stop"));
                }
            })
        });
    }
    group.finish();
}

fn report_real_time_factor() {
    for update in [ControlUpdate::ZeroOrderHold, ControlUpdate::Continuous] {
        let mut s = sim(update);
        simulate(&mut s, 2.0); // warm-up
        let seconds = 60.0;
        let start = Instant::now();
        simulate(&mut s, seconds);
        let wall = start.elapsed().as_secs_f64();
        println!(
            "real-time factor ({update:?}, dt = 1 ms): {:.0} simulated s per wall-clock s ({seconds} s simulated in {wall:.4} s)",
            seconds / wall
        );
    }
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    report_real_time_factor();
}
