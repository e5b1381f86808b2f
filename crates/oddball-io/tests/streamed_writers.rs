//! The block-by-block writers (a session's samples spilled to disk, states as runs) write the
//! same bytes as the in-memory writers they share their code with, across block boundaries.

mod common;

use common::TempDir;
use ndarray::Array2;
use oddball_io::{
    stimulus_runs, stimulus_states, write_bci2000, write_bci2000_blocks, write_easy,
    write_easy_blocks, Bci2000WriteOptions, EasyWriteOptions, IoError, SampleSpill, StateProblem,
    StateRun, StateRuns,
};
use oddball_signal::{Event, Events, Raw};
use proptest::prelude::*;

fn spill(data: &Array2<f64>, chunk: usize) -> oddball_io::SpilledSamples {
    let mut s = SampleSpill::new(data.nrows()).unwrap();
    let n = data.ncols();
    for start in (0..n).step_by(chunk) {
        s.push(data.slice(ndarray::s![.., start..(start + chunk).min(n)]))
            .unwrap();
    }
    s.finish().unwrap()
}

fn events(n_times: usize, seed: u64) -> Vec<Event> {
    // Flashes every 40–79 samples, some at one sample twice, some one sample apart.
    let mut out = Vec::new();
    let (mut t, mut x) = (3usize, seed);
    while t < n_times + 50 {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let code = (x >> 60) as u32 % 5;
        out.push(Event::new(t, code).with_target(x >> 40 & 1 == 1));
        if x >> 50 & 7 == 0 {
            out.push(Event::new(t, code + 1));
        }
        t += if x >> 53 & 7 == 0 {
            1
        } else {
            40 + (x >> 20) as usize % 40
        };
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn block_writers_write_the_in_memory_writers_bytes(
        n_times in 1usize..10_000, n_ch in 1usize..4, chunk in 1usize..5000, seed in 0u64..1000,
        duration in 1usize..60,
    ) {
        let dir = TempDir::new("streamed-writers");
        let data = Array2::from_shape_fn((n_ch, n_times), |(c, t)| {
            ((t * 7 + c * 13 + seed as usize) % 1000) as f64 * 0.37 - 150.0
        });
        let names: Vec<String> = (0..n_ch).map(|c| format!("C{c}")).collect();
        let ev = events(n_times, seed);
        let in_range: Vec<Event> = ev.iter().filter(|e| e.onset < n_times).cloned().collect();
        let raw = Raw::new(data.clone(), 500.0, names.clone(), Events::new(in_range.clone())).unwrap();
        let stored = spill(&data, chunk);

        // BCI2000: stimulus states dense vs runs, plus a trial-like state.
        let trial = StateRuns::new("TrialNumber", 16, vec![
            StateRun { start: 0, end: n_times.div_ceil(3), value: 1 },
            StateRun { start: n_times.div_ceil(3) + (n_times > 3) as usize, end: n_times, value: 2 },
        ].into_iter().filter(|r| r.start < r.end).collect());
        let mut runs = stimulus_runs(&ev, n_times, duration);
        runs.push(trial.clone());
        let mut dense = stimulus_states(&Events::new(ev.clone()), n_times, duration);
        dense.push(trial.to_column(n_times));
        let opts = Bci2000WriteOptions::default();
        let a = dir.join("a.dat");
        let b = dir.join("b.dat");
        let sa = write_bci2000(&a, &raw, &dense, &opts).unwrap();
        let sb = write_bci2000_blocks(&b, &stored, 500.0, &names, &runs, &opts).unwrap();
        prop_assert_eq!(sa, sb);
        prop_assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());

        // .easy (+ .info).
        let eo = EasyWriteOptions::default();
        let a = dir.join("a.easy");
        let b = dir.join("b.easy");
        let sa = write_easy(&a, &raw, &eo).unwrap();
        let sb = write_easy_blocks(&b, &stored, 500.0, &names, &in_range, &eo).unwrap();
        prop_assert_eq!(sa.n_triggers, sb.n_triggers);
        prop_assert_eq!(sa.events_lost, sb.events_lost);
        prop_assert_eq!(sa.bytes, sb.bytes);
        prop_assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());
    }
}

#[test]
fn runs_out_of_order_or_beyond_the_recording_are_refused() {
    let dir = TempDir::new("streamed-writers-runs");
    let data = Array2::zeros((1, 100));
    let stored = spill(&data, 30);
    let names = vec!["Cz".to_string()];
    let opts = Bci2000WriteOptions::default();
    for (runs, bad) in [
        (vec![(0, 10, 1), (5, 20, 2)], 1),
        (vec![(0, 101, 1)], 0),
        (vec![(4, 4, 1)], 0),
    ] {
        let runs = runs
            .into_iter()
            .map(|(start, end, value)| StateRun { start, end, value })
            .collect();
        let path = dir.join("x.dat");
        let err = write_bci2000_blocks(
            &path,
            &stored,
            500.0,
            &names,
            &[StateRuns::new("S", 8, runs)],
            &opts,
        )
        .unwrap_err();
        match err {
            IoError::InvalidState {
                problem: StateProblem::Run { index, .. },
                ..
            } => assert_eq!(index, bad),
            other => panic!("{other}"),
        }
        assert!(!path.exists());
    }
}
