//! Helpers shared by the integration tests: where the real data (the test-kit's switch: skip
//! locally, fail under `ODDBALL_REQUIRE_DATA=1`) and the fixtures are, temporary directories.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

#[allow(unused_imports)] // not every test binary uses each
pub use oddball_testkit::{data_dir, data_file, TempDir};

pub fn bci2000_file(test: &str, name: &str) -> Option<PathBuf> {
    data_file(test, &format!("bci2000-samplefiles-p300/{name}"))
}

pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

pub fn golden(name: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(fixture(name)).expect("fixture JSON");
    serde_json::from_str(&text).expect("valid JSON")
}

/// `|a − b| <= rel × scale`, with a message naming what differs.
pub fn assert_close(a: f64, b: f64, rel: f64, scale: f64, what: &str) {
    let tol = rel * scale.abs().max(f64::MIN_POSITIVE);
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b} (tolerance {tol})");
}

/// xorshift64*: a small seeded generator, so failures reproduce.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// One to four random mutations of `base`: a byte changed, a cut, one of `interesting` inserted,
/// a stretch deleted, a stretch overwritten with one of the first three of `interesting`
/// (put numeric strings there), a random byte inserted.
pub fn mutate(rng: &mut Rng, base: &[u8], interesting: &[&[u8]]) -> Vec<u8> {
    let mut b = base.to_vec();
    for _ in 0..1 + rng.below(4) {
        let len = b.len();
        match rng.below(6) {
            0 if len > 0 => {
                let i = rng.below(len);
                b[i] = rng.next() as u8;
            }
            1 => b.truncate(rng.below(len + 1)),
            2 => {
                let i = rng.below(len + 1);
                let s = interesting[rng.below(interesting.len())];
                b.splice(i..i, s.iter().copied());
            }
            3 if len > 0 => {
                let i = rng.below(len);
                let j = (i + 1 + rng.below(16)).min(len);
                b.drain(i..j);
            }
            4 if len > 0 => {
                // Overwrite a stretch with one of the first three (numeric) strings.
                let i = rng.below(len);
                let s = interesting[rng.below(interesting.len().min(3))];
                for (k, &c) in s.iter().enumerate() {
                    if i + k < len {
                        b[i + k] = c;
                    }
                }
            }
            _ => {
                let i = rng.below(len + 1);
                b.insert(i, rng.next() as u8);
            }
        }
    }
    b
}
