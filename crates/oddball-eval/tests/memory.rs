//! Peak memory of the library path a command takes — read (EDF+) → label → band-pass and cut
//! epochs → cross-validated evaluation → training with its decision model — measured by a
//! counting global allocator (bytes live at once; no timing), against issue #19's bound: "no
//! input makes a run use more than ~3× the memory of its data plus a fixed margin".
//!
//! The data is the recording as `f64`, `D = n_channels × n_times × 8` bytes, and its epochs
//! `E = n_epochs × n_channels × n_samples × 8`. Epochs of overlapping windows hold the same
//! samples several times (a flash every 0.25 s with 0.8 s windows: `E ≈ 3.2 D`), so epochs
//! held as one array could not meet the bound; `dataset::epoch` keeps them as windows into the
//! band-passed recording (`D` once, whatever the overlap), and `lda` reads them a part at a
//! time into its features (every 4th sample, `E / 4`). The budget is `3 D` plus a fixed margin
//! for what does not grow with the recording (the classifier's matrices, which depend on
//! channels × window only). A copy of all the epochs anywhere (`E` alone is `3.2 D` on the
//! overlapping recording) breaks it.
//!
//! One test function: the counter is process-wide, so nothing else may allocate meanwhile.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use oddball_decode::preprocess::Preprocess;
use oddball_eval::dataset::{self, Labelling};
use oddball_eval::evaluate::{self, EvaluateParams, TrainingSet};
use oddball_signal::{Event, Events, Raw};
use oddball_testkit::TempDir;

#[derive(Debug)]
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(by: usize) {
    let now = LIVE.fetch_add(by, Ordering::SeqCst) + by;
    PEAK.fetch_max(now, Ordering::SeqCst);
}

// SAFETY: every call is passed on unchanged to the system allocator; only sizes are counted.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            // Both blocks may be live during the move: count the new one before the old goes.
            grew(new_size);
            LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
        }
        p
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

const MB: f64 = 1024.0 * 1024.0;

/// What does not grow with the recording: the classifier's matrices (LDA's covariance of
/// 16 channels × 52 samples = 832 features is 5.3 MB, and its decomposition a few more),
/// features of a fold, labels, names, the EDF reader's record buffer.
const MARGIN: usize = 16 << 20;

/// `seconds` of 16-channel EEG at 256 Hz with a flash every `every` s, every fifth a target
/// with a P300-like bump, written as EDF+ to `path`; its `(n_channels, n_times)`.
fn write_recording(path: &std::path::Path, seconds: f64, every: f64) -> (usize, usize) {
    let (sfreq, n_ch) = (256.0, 16);
    let n = (seconds * sfreq) as usize;
    let (data, flashes) = oddball_testkit::flash_train(n_ch, n, sfreq, every, 11);
    let events = flashes
        .into_iter()
        .map(|(onset, target)| Event::new(onset, 1 + u32::from(target)).with_target(target))
        .collect();
    let names = (0..n_ch).map(|c| format!("E{c}")).collect();
    let raw = Raw::new(data, sfreq, names, Events::new(events)).unwrap();
    oddball_io::write_edf_plus(path, &raw).unwrap();
    (n_ch, n)
}

struct Peaks {
    data: usize,
    epochs: usize,
    read: usize,
    epoch: usize,
    pool: usize,
    evaluate: usize,
    train: usize,
}

/// The peak bytes above what was live before, of each stage and of the whole path, for the
/// recordings at `paths` (each `n_times` samples of `n_ch` channels) as one training set.
fn run(paths: &[std::path::PathBuf], n_ch: usize, n_times: usize) -> Peaks {
    let base = LIVE.load(Ordering::SeqCst);
    let since = |stage_base: usize| PEAK.swap(stage_base, Ordering::SeqCst) - base;
    PEAK.store(base, Ordering::SeqCst);

    let (mut read, mut epoch, mut epochs) = (0, 0, 0);
    let mut recs = Vec::new();
    for path in paths {
        // Reading is measured above what the earlier recordings' epochs hold.
        let held = LIVE.load(Ordering::SeqCst) - base;
        let rec = dataset::read_labelled(path, Labelling::default()).unwrap();
        read = read.max(since(LIVE.load(Ordering::SeqCst)) - held);
        let rec = dataset::epoch(rec, &Preprocess::peer()).unwrap();
        epoch = epoch.max(since(LIVE.load(Ordering::SeqCst)));
        assert!(!rec.epochs.is_preloaded(), "the epochs are windows");
        let (n_epochs, n_ch, n_samples) = rec.epochs.dim();
        epochs += n_epochs * n_ch * n_samples * 8;
        recs.push(rec);
    }
    let set = TrainingSet::pool(recs).unwrap();
    let pool = since(LIVE.load(Ordering::SeqCst));
    let params = EvaluateParams {
        presets: vec![oddball_decode::preset::Preset::Lda],
        folds: 5,
        tune: false,
    };
    let results = evaluate::evaluate(&params, &set, &[], &mut |_| {}).unwrap();
    let evaluate = since(LIVE.load(Ordering::SeqCst));
    assert!(
        results[0].auc > 0.7,
        "the bump is found: AUC {}",
        results[0].auc
    );
    let trained =
        evaluate::train(oddball_decode::preset::Preset::Lda, &set, None, &mut |_| {}).unwrap();
    let train = since(LIVE.load(Ordering::SeqCst));
    assert!(trained.cv_auc > 0.7, "AUC {}", trained.cv_auc);
    Peaks {
        data: paths.len() * n_ch * n_times * 8,
        epochs,
        read,
        epoch,
        pool,
        evaluate,
        train,
    }
}

#[test]
fn peak_memory_is_linear_in_the_recording_and_its_epochs() {
    let dir = TempDir::new("memory");
    // Overlapping windows (E ≈ 3.2 D), then windows 0.2 s apart (E = 0.8 D), then the
    // overlapping ones as two recordings of half the length pooled into one training set.
    for (name, n_files, seconds, every) in [
        ("dense.edf", 1, 1200.0, 0.25),
        ("sparse.edf", 1, 1200.0, 1.0),
        ("half.edf", 2, 600.0, 0.25),
    ] {
        let mut paths = Vec::new();
        let mut size = (0, 0);
        for k in 0..n_files {
            let path = dir.path().join(format!("{k}-{name}"));
            size = write_recording(&path, seconds, every);
            paths.push(path);
        }
        let p = run(&paths, size.0, size.1);
        let budget = 3 * p.data + MARGIN;
        let peak = [p.read, p.epoch, p.evaluate, p.train]
            .into_iter()
            .max()
            .unwrap();
        eprintln!(
            "{n_files} × {name}: data {:.1} MB, epochs {:.1} MB; peak read {:.1}, epoch {:.1}, \
             pool {:.1}, evaluate {:.1}, train {:.1} MB; budget {:.1} MB; peak / data {:.2}, \
             peak / max(data, epochs) {:.2}",
            p.data as f64 / MB,
            p.epochs as f64 / MB,
            p.read as f64 / MB,
            p.epoch as f64 / MB,
            p.pool as f64 / MB,
            p.evaluate as f64 / MB,
            p.train as f64 / MB,
            budget as f64 / MB,
            peak as f64 / p.data as f64,
            peak as f64 / p.data.max(p.epochs) as f64,
        );
        // The margin must not be what the budget is made of.
        assert!(
            p.data > 2 * MARGIN,
            "{name}: a recording too small to measure"
        );
        assert!(
            peak <= budget,
            "{name}: peak {:.1} MB over the budget of {:.1} MB (data {:.1} MB, epochs {:.1} MB)",
            peak as f64 / MB,
            budget as f64 / MB,
            p.data as f64 / MB,
            p.epochs as f64 / MB
        );
        // Pooling moves each recording's windows into the set: nothing is copied.
        assert!(
            p.pool <= p.data + MARGIN,
            "{name}: pooling peaks at {:.1} MB for {:.1} MB of data",
            p.pool as f64 / MB,
            p.data as f64 / MB
        );
        // The windows overlap: their samples, if they were held, would break the budget.
        if every < 0.5 {
            assert!(p.epochs > 3 * p.data, "{name}: epochs that overlap");
        }
        // Reading holds the samples once, plus what the reader holds of the file.
        assert!(
            p.read <= 2 * p.data + MARGIN,
            "{name}: reading peaks at {:.1} MB for {:.1} MB of samples",
            p.read as f64 / MB,
            p.data as f64 / MB
        );
    }
}
