//! oddball's reading of a recording, for checks in Python: the samples as a NumPy `.npy` file
//! (float64 µV, `(n_channels, n_times)`) and the rest as JSON (`ch_names`, `sfreq`, `events` as
//! `[onset, code, target]` with target `null` when the file does not say). With two more
//! arguments the events are labelled by that mapping first (`2 1`: code 2 targets, 1 not), as
//! `oddball export --target-events 2 --nontarget-events 1` labels them.
//!
//! `cargo run --release -p oddball-io --example to_npy -- IN OUT_PREFIX [TARGETS NONTARGETS]`

use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (input, out, mapping) = match args.as_slice() {
        [_, i, o] => (i, o, None),
        [_, i, o, t, n] => (i, o, Some(oddball_io::EventMapping::parse(t, n)?)),
        _ => return Err("usage: to_npy IN OUT_PREFIX [TARGETS NONTARGETS]".into()),
    };
    let mut rec = oddball_io::read(input)?;
    if let Some(m) = &mapping {
        rec.map_events(m)?;
    }
    let raw = &rec.raw;
    let (n_ch, n_times) = (raw.n_channels(), raw.n_times());
    let mut header =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({n_ch}, {n_times}), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut f = std::io::BufWriter::new(std::fs::File::create(format!("{out}.npy"))?);
    f.write_all(b"\x93NUMPY\x01\x00")?;
    f.write_all(&(header.len() as u16).to_le_bytes())?;
    f.write_all(header.as_bytes())?;
    for row in raw.data().rows() {
        for v in row {
            f.write_all(&v.to_le_bytes())?;
        }
    }
    f.flush()?;
    let events: Vec<serde_json::Value> = raw
        .events()
        .iter()
        .map(|e| serde_json::json!([e.onset, e.code, e.target]))
        .collect();
    let json = serde_json::json!({
        "ch_names": raw.ch_names(),
        "sfreq": raw.sfreq(),
        "events": events,
    });
    std::fs::write(format!("{out}.json"), serde_json::to_string(&json)?)?;
    println!(
        "{input}: {n_ch} channels x {n_times} samples, {} events -> {out}.npy, {out}.json",
        raw.events().len()
    );
    Ok(())
}
