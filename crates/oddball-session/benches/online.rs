//! Processing latency of the online loop: from the chunk that brings the last sample of the
//! deciding epoch to the command reaching the arm. Measured per preset on a model calibrated on
//! the typical simulated subject (8 channels, 500 Hz, 20-sample chunks): causal band-pass of
//! the chunk, epoch cut, pipeline score, evidence update and decision over 5 rounds, arm command.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use ndarray::s;
use oddball_arm::{ArmConfig, ArmSim, Command};
use oddball_decode::decision::DecisionRule;
use oddball_decode::preset::Preset;
use oddball_session::engine::{Session, SessionParams};
use oddball_session::online::{Marker, OnlineEpocher};
use oddball_session::subject::{SubjectParams, SubjectPreset};

fn latency(c: &mut Criterion) {
    let mut group = c.benchmark_group("decision_latency");
    for preset in [Preset::Lda, Preset::Riemann] {
        let subject = SubjectParams::preset(SubjectPreset::Typical)
            .build()
            .unwrap();
        let mut params = SessionParams::paper(preset);
        params.decoder.rule = DecisionRule::Fixed { rounds: 5 };
        let mut session = Session::new(params.clone(), subject, None).unwrap();
        session.calibrate().unwrap();
        let model = session.model().unwrap().clone();
        let decision = model.decision.unwrap();
        // A stream whose marker's epoch completes exactly with the last chunk.
        let mut sim = SubjectParams::preset(SubjectPreset::Typical)
            .with_seed(9)
            .build()
            .unwrap();
        let onset = 4000u64;
        sim.flash(onset, true).unwrap();
        let data = sim.render(5000);
        let (_, n_times) = params.decoder.preprocess.window(500.0);
        let end = onset as usize + n_times; // exclusive: the chunk ending here completes it
        let rounds = vec![vec![Some(0.5), Some(-0.2), Some(-0.4), Some(0.1)]; 4];
        group.bench_function(preset.name(), |b| {
            b.iter_batched(
                || {
                    let mut ep = OnlineEpocher::new(&params.decoder.preprocess, 500.0, 8).unwrap();
                    ep.push_marker(Marker {
                        onset,
                        code: 1,
                        tag: 0,
                    })
                    .unwrap();
                    ep.push_samples(data.slice(s![.., ..end - 20])).unwrap();
                    let arm = ArmSim::from_config(&ArmConfig::default()).unwrap();
                    (ep, arm)
                },
                |(mut ep, mut arm)| {
                    let ready = ep.push_samples(data.slice(s![.., end - 20..end])).unwrap();
                    let e = &ready[0];
                    let score = model.pipeline.score_epoch(e.data.view()).unwrap();
                    let mut r = rounds.clone();
                    r.push(vec![Some(score), Some(-0.3), Some(-0.1), Some(0.0)]);
                    let (verdict, _) = decision.decide(&r);
                    if let oddball_decode::decision::Verdict::Choose { index, .. } = verdict {
                        let cmd =
                            [Command::Up, Command::Right, Command::Down, Command::Left][index];
                        let _ = arm.issue(cmd);
                    }
                    arm
                },
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, latency);
criterion_main!(benches);
