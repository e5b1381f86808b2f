//! Times `oddball_io::read` on the given files: the median and fastest of 20 reads each.
//!
//! `cargo run --release -p oddball-io --example read_speed -- FILE...`

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for path in std::env::args().skip(1) {
        let mut ms = Vec::new();
        let mut shape = (0, 0, 0);
        for _ in 0..20 {
            let t = Instant::now();
            let rec = oddball_io::read(&path)?;
            ms.push(t.elapsed().as_secs_f64() * 1e3);
            shape = (
                rec.raw.n_channels(),
                rec.raw.n_times(),
                rec.raw.events().len(),
            );
        }
        ms.sort_by(f64::total_cmp);
        println!(
            "{path}: {} ch x {} samples, {} events: median {:.2} ms, min {:.2} ms",
            shape.0,
            shape.1,
            shape.2,
            ms[ms.len() / 2],
            ms[0]
        );
    }
    Ok(())
}
