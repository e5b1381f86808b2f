//! Converts any readable recording to EDF+ with its events as annotations.
//!
//! `cargo run --release -p oddball-io --example to_edf_plus -- IN OUT.edf`

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, output] = args.as_slice() else {
        return Err("usage: to_edf_plus IN OUT.edf".into());
    };
    let rec = oddball_io::read(input)?;
    let s = oddball_io::write_edf_plus(output, &rec.raw)?;
    println!(
        "{input}: {} channels, {} samples at {} Hz, {} events -> {output}: {} records of {} s ({} samples padded)",
        rec.raw.n_channels(),
        rec.raw.n_times(),
        rec.raw.sfreq(),
        rec.raw.events().len(),
        s.n_records,
        s.record_duration,
        s.padded_samples
    );
    Ok(())
}
