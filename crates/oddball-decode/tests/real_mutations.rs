//! Issue #19, deliverable 5 (the CI part): a short seeded mutation run over every real file in
//! `../shared/data`, the way the probe found its defects. Each mutated file goes the
//! whole way `oddball inspect` / `evaluate` take it: read → the one preprocessing path (hold
//! non-finite, detrend, zero-phase band-pass, epochs, rejection) → fit and score `lda` when
//! both classes are there. Asserted: no panic, no hang (a watchdog per file), and a named cause
//! for every refusal (the error names the file, or the field, channel or step at fault).
//!
//! Bounded: `ODDBALL_MUTATIONS` per file (default 5; 26 files → 130 runs, about 40 s
//! in the test profile). Mutations favour the first 4 KiB, where the headers are.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use oddball_decode::pipeline::{PipelineParams, Preprocess};

/// xorshift64*: seeded, so a failure names its seed and reproduces.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

const INTERESTING: &[&[u8]] = &[
    b"0",
    b"-1",
    b"99999999",
    b"1e300",
    b"nan",
    b"inf",
    b"18446744073709551616",
    b"\x00",
    b"\n",
    b",",
    b" ",
    b"\xff\xff\xff\x7f",
];

fn mutate(rng: &mut Rng, base: &[u8]) -> Vec<u8> {
    let mut b = base.to_vec();
    for _ in 0..1 + rng.below(3) {
        let len = b.len();
        // Half the time within the first 4 KiB (headers), else anywhere.
        let at = |rng: &mut Rng, n: usize| {
            if rng.below(2) == 0 {
                rng.below(n.min(4096))
            } else {
                rng.below(n)
            }
        };
        match rng.below(5) {
            0 if len > 0 => {
                let i = at(rng, len);
                b[i] = rng.next() as u8;
            }
            1 => b.truncate(rng.below(len + 1)),
            2 => {
                let i = at(rng, len + 1);
                let s = INTERESTING[rng.below(INTERESTING.len())];
                b.splice(i..i, s.iter().copied());
            }
            3 if len > 0 => {
                let i = at(rng, len);
                let s = INTERESTING[rng.below(INTERESTING.len())];
                for (k, &c) in s.iter().enumerate() {
                    if i + k < len {
                        b[i + k] = c;
                    }
                }
            }
            _ if len > 0 => {
                let i = at(rng, len);
                let j = (i + 1 + rng.below(32)).min(len);
                b.drain(i..j);
            }
            _ => {}
        }
    }
    b
}

/// Every data file below `dir` (not the provenance notes, not electrode layouts).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("dat" | "csv" | "edf" | "bdf" | "easy" | "xdf" | "mat")
            ) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// What happened to one mutated file.
#[derive(Debug)]
enum Outcome {
    /// Read, preprocessed and (when both classes were there) fitted and scored.
    Used,
    /// Refused at `step` with this message.
    Refused { step: &'static str, message: String },
}

/// Read → preprocess → fit/score, the way `oddball evaluate` goes.
fn run(path: &Path) -> Outcome {
    let refused = |step, e: &dyn std::fmt::Display| Outcome::Refused {
        step,
        message: e.to_string(),
    };
    let rec = match oddball_io::read(path) {
        Ok(r) => r,
        Err(e) => return refused("read", &e),
    };
    let (epochs, _log) = match Preprocess::peer().params().epochs_owned(rec.raw) {
        Ok(x) => x,
        Err(e) => return refused("preprocess", &e),
    };
    let y: Vec<Option<bool>> = epochs.targets();
    if y.iter().any(Option::is_none) || epochs.n_epochs() < 10 {
        return Outcome::Used;
    }
    let y: Vec<bool> = y.into_iter().map(|t| t == Some(true)).collect();
    let params = match PipelineParams::preset("lda", epochs.sfreq()) {
        Ok(p) => p,
        Err(e) => return refused("preset", &e),
    };
    match params.fit(epochs.data().view(), &y) {
        Ok(p) => match p.decision_function(epochs.data().view()) {
            Ok(s) if s.iter().all(|v| v.is_finite()) => Outcome::Used,
            Ok(_) => Outcome::Refused {
                step: "score",
                message: String::new(),
            },
            Err(e) => refused("score", &e),
        },
        Err(e) => refused("fit", &e),
    }
}

#[test]
fn mutated_real_files_never_panic_hang_or_fail_without_a_cause() {
    let Some(data) =
        oddball_testkit::data_dir("mutated_real_files_never_panic_hang_or_fail_without_a_cause")
    else {
        return;
    };
    let per_file: usize = std::env::var("ODDBALL_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let dir = oddball_testkit::TempDir::new("real-mutations");
    let files = files(&data);
    assert!(files.len() >= 20, "{} data files", files.len());
    let (mut used, mut refused) = (0, 0);
    for (fi, src) in files.iter().enumerate() {
        let base = std::fs::read(src).unwrap();
        let ext = src.extension().unwrap().to_str().unwrap();
        // A NIC .easy reads its .info beside it: copy that unchanged.
        let info = src.with_extension("info");
        for k in 0..per_file {
            let seed = 0x9E37_79B9_7F4A_7C15 ^ ((fi as u64) << 32 | k as u64);
            let mut rng = Rng(seed | 1);
            let path = dir.join(format!("m{fi}_{k}.{ext}"));
            std::fs::write(&path, mutate(&mut rng, &base)).unwrap();
            if info.exists() {
                std::fs::copy(&info, path.with_extension("info")).unwrap();
            }
            let (tx, rx) = mpsc::channel();
            let p = path.clone();
            std::thread::spawn(move || {
                let _ = tx.send(run(&p));
            });
            let what = format!("{} mutated with seed {seed:#x}", src.display());
            match rx.recv_timeout(Duration::from_secs(60)) {
                Ok(Outcome::Used) => used += 1,
                Ok(Outcome::Refused { step, message }) => {
                    refused += 1;
                    // A named cause: the reader's errors name the file; later steps name the
                    // value, channel or step at fault (never an empty or unbounded message).
                    assert!(
                        !message.is_empty(),
                        "{what}: refused at {step} without a cause"
                    );
                    assert!(
                        message.len() < 4000,
                        "{what}: a {}-byte message",
                        message.len()
                    );
                    if step == "read" {
                        assert!(
                            message.contains(path.file_name().unwrap().to_str().unwrap()),
                            "{what}: the error does not name the file: {message}"
                        );
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    panic!("{what}: panicked (see the thread's message above)")
                }
                Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: hung (more than 60 s)"),
            }
            std::fs::remove_file(&path).ok();
        }
    }
    eprintln!(
        "{} mutated files: {used} read and used, {refused} refused with a cause",
        used + refused
    );
}
