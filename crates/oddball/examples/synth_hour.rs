//! Writes `HOURS` hours (default 1) of synthetic 64-channel EEG at 256 Hz as EDF+ with a
//! labelled flash every 250 ms (every fifth a target with a P300-like bump), for measuring the
//! peak memory of reading and evaluating an hour of 64-channel EEG (`tools/memory/`).
//!
//! `cargo run --release --example synth_hour -- OUT.edf [HOURS]`

use oddball_signal::{Event, Events, Raw};

fn main() {
    let mut args = std::env::args().skip(1);
    let out = args.next().expect("usage: synth_hour OUT.edf [HOURS]");
    let hours: f64 = args.next().map_or(1.0, |h| h.parse().expect("HOURS"));
    let (sfreq, n_ch) = (256.0, 64);
    let n = (hours * 3600.0 * sfreq) as usize;
    let (data, flashes) = oddball_testkit::flash_train(n_ch, n, sfreq, 0.25, 7);
    let events = flashes
        .into_iter()
        .map(|(onset, target)| Event::new(onset, 1 + u32::from(target)).with_target(target))
        .collect();
    let names = (0..n_ch).map(|c| format!("E{c}")).collect();
    let raw = Raw::new(data, sfreq, names, Events::new(events)).expect("a valid recording");
    let s = oddball_io::write_edf_plus(&out, &raw).expect("written");
    eprintln!(
        "{out}: {n_ch} channels × {n} samples ({hours} h), {} events, {} records",
        raw.events().len(),
        s.n_records
    );
}
