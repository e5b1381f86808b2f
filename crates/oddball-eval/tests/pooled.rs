//! A pooled start judged leave-one-data-set-out on real data: the start eeg3 is replayed from
//! is built from the other shipped data sets only (labelled by their manifests), names eeg3's
//! channels (a subset of the 64-channel recordings' by name, at another rate), and with the
//! P300 template beside it the replay is as good as from the template alone — the start only
//! competes for where EM begins.

use oddball_decode::pipeline::Preprocess;
use oddball_decode::unsupervised::{PooledStart, POOLED_VERSION};
use oddball_eval::benchmark::Progress;
use oddball_eval::dataset::{load_epochs, Labelling};
use oddball_eval::pooled::{pool_without, subject_patterns};
use oddball_eval::unsupervised::{replay, ReplaySettings};
use oddball_io::Manifest;

#[test]
fn eeg3_from_a_start_built_without_eeg3() {
    let test = "eeg3_from_a_start_built_without_eeg3";
    let Some(data) = oddball_testkit::data_dir(test) else {
        return;
    };
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../datasets");
    let names = [
        "bci2000-eeg3",
        "bci-competition-ii-iib",
        "bci2000-eeg2",
        "muse-visual-p300",
        "openvibe-p300-gdf",
    ];
    let manifests: Vec<Manifest> = names
        .iter()
        .map(|n| Manifest::load_with_root(format!("{dir}/{n}.toml"), Some(&data)).unwrap())
        .collect();
    let pre = Preprocess::peer();
    let quiet = |_: Progress<'_>| {};
    let patterns = subject_patterns(&manifests, &pre, &quiet).unwrap();
    // The OpenViBE run's channels are only numbered: it has no pattern.
    assert_eq!(
        patterns.len(),
        4,
        "{:?}",
        patterns.iter().map(|(d, _)| d).collect::<Vec<_>>()
    );
    let without = pool_without(&patterns, Some(0)).unwrap().unwrap();
    assert!(without
        .sources
        .iter()
        .all(|s| !s.starts_with("bci2000-eeg3")));
    let start = PooledStart {
        version: POOLED_VERSION,
        patterns: vec![without],
    };
    let m = &manifests[0];
    let subj = &m.subjects[0];
    let runs = subj
        .runs()
        .map(|run| (run.as_path(), Labelling::of_run(m, subj, run)));
    let (recs, _) = load_epochs(runs, &pre, None, None, &mut |_, _, _| {}).unwrap();
    let settings = |transfer| ReplaySettings {
        template: true,
        transfer,
        block_toeplitz: false,
    };
    let alone = replay(&pre, &recs, &settings(None), &mut |_, _| {}).unwrap();
    let both = replay(&pre, &recs, &settings(Some(&start)), &mut |_, _| {}).unwrap();
    let online = |r: &oddball_eval::unsupervised::UnsupervisedResult| {
        r.online_correct
            .iter()
            .map(|&c| usize::from(c))
            .sum::<usize>()
    };
    println!(
        "template {} online, AUC {:.3}; with the start {} online, AUC {:.3}, starts kept {:?}",
        online(&alone),
        alone.auc,
        online(&both),
        both.auc,
        both.online_inits
    );
    assert!(online(&both) >= online(&alone));
    assert_eq!(both.posthoc_chars_by_reps.last(), Some(&1.0));
    assert!(both.auc >= alone.auc - 0.005);
}
