//! Writes `HOURS` hours (default 1) of synthetic 64-channel EEG at 256 Hz as EDF+ with a
//! labelled flash every 250 ms (every fifth a target with a P300-like bump), for measuring the
//! peak memory of reading and evaluating an hour of 64-channel EEG (`tools/memory/`).
//!
//! `cargo run --release --example synth_hour -- OUT.edf [HOURS]`

use ndarray::Array2;
use oddball_signal::{Event, Events, Raw};

fn main() {
    let mut args = std::env::args().skip(1);
    let out = args.next().expect("usage: synth_hour OUT.edf [HOURS]");
    let hours: f64 = args.next().map_or(1.0, |h| h.parse().expect("HOURS"));
    let (sfreq, n_ch) = (256.0, 64);
    let n = (hours * 3600.0 * sfreq) as usize;
    let mut state: u64 = 7;
    let mut noise = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 20.0
    };
    let step = (0.25 * sfreq) as usize;
    let mut data = Array2::from_shape_fn((n_ch, n), |_| noise());
    let mut events = Vec::new();
    for (k, onset) in (256..n.saturating_sub(256)).step_by(step).enumerate() {
        let target = k % 5 == 2;
        if target {
            for c in 0..n_ch {
                for t in onset + 77..onset + 128 {
                    data[[c, t]] += 3.0;
                }
            }
        }
        events.push(Event::new(onset, 1 + u32::from(target)).with_target(target));
    }
    let names = (0..n_ch).map(|c| format!("E{c}")).collect();
    let raw = Raw::new(data, sfreq, names, Events::new(events)).expect("a valid recording");
    let s = oddball_io::write_edf_plus(&out, &raw).expect("written");
    eprintln!(
        "{out}: {n_ch} channels × {n} samples ({hours} h), {} events, {} records",
        raw.events().len(),
        s.n_records
    );
}
