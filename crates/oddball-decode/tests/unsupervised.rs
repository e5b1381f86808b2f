//! The unsupervised decoder (EM over the paradigm's constraint) against a dense numpy
//! implementation of the same model (`tools/golden/unsupervised/make_golden.py`), its invariants
//! on random problems (posteriors sum to one per trial and set; the penalised log-likelihood never
//! falls across iterations), and what it recovers from synthetic P300 epochs without labels.

use ndarray::{Array2, Array3};
use oddball_decode::features::amplitude::AmplitudeFeatures;
use oddball_decode::unsupervised::{
    replay, replay_from, Constraint, Covariance, Init, Unsupervised, UnsupervisedError,
    UnsupervisedParams,
};
use proptest::prelude::*;
use serde::Deserialize;

#[derive(Deserialize)]
struct Golden {
    versions: std::collections::HashMap<String, String>,
    sets: Vec<Vec<u32>>,
    x: Vec<Vec<f64>>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    init: Vec<f64>,
    shrinkage: f64,
    mean_prior: f64,
    objective: Vec<f64>,
    posterior: Vec<Vec<f64>>,
    llr: Vec<f64>,
    truth: Vec<Vec<u32>>,
    /// The block-Toeplitz variant's channels (absent: Ledoit–Wolf).
    #[serde(default)]
    n_channels: Option<usize>,
    /// Codes flashed but never attended (absent: none).
    #[serde(default)]
    decoys: Vec<u32>,
    /// Group flashes: code → the choices (of `sets[0]`) it shows (absent: a code per choice).
    #[serde(default)]
    groups: Option<std::collections::BTreeMap<u32, Vec<usize>>>,
    /// The numpy model's choices where they are not the truth (absent: the truth's).
    #[serde(default)]
    decoded: Option<Vec<Vec<u32>>>,
}

fn params(max_iter: usize, tol: f64) -> UnsupervisedParams {
    UnsupervisedParams {
        features: AmplitudeFeatures::decimate(1).unwrap(),
        mean_prior: 2.0,
        n_inits: 4,
        max_iter,
        tol,
        seed: 7,
        covariance: Covariance::LedoitWolf,
        random_until: None,
    }
}

/// Trials whose first set's choice is the attended code.
fn right_of(choices: &[Vec<u32>], attended: &[u32]) -> usize {
    choices
        .iter()
        .zip(attended)
        .filter(|(c, &a)| c[0] == a)
        .count()
}

/// Trials a replay decided right online.
fn online_right(r: &oddball_decode::unsupervised::Replay, attended: &[u32]) -> usize {
    r.online
        .iter()
        .zip(attended)
        .filter(|(c, &a)| c.codes[0] == a)
        .count()
}

fn rows(x: &[Vec<f64>]) -> Array2<f64> {
    Array2::from_shape_fn((x.len(), x[0].len()), |(i, j)| x[i][j])
}

#[test]
fn em_matches_the_dense_numpy_reference() {
    check_golden(include_str!("fixtures/unsupervised_golden.json"));
}

#[test]
fn block_toeplitz_em_matches_the_dense_numpy_reference() {
    check_golden(include_str!("fixtures/unsupervised_toeplitz_golden.json"));
}

/// Decoys (codes never attended) as known non-targets: the dense model enumerates the slots
/// and adds the decoys' non-target likelihood.
#[test]
fn em_with_decoys_matches_the_dense_numpy_reference() {
    check_golden(include_str!("fixtures/unsupervised_decoy_golden.json"));
}

/// Group flashes (each code shows 1–3 of six choices) and a decoy: the dense model enumerates
/// the six choices per trial.
#[test]
fn em_over_group_flashes_matches_the_dense_numpy_reference() {
    check_golden(include_str!("fixtures/unsupervised_groups_golden.json"));
}

fn check_golden(fixture: &str) {
    let g: Golden = serde_json::from_str(fixture).unwrap();
    println!("reference: {:?}", g.versions);
    let x = rows(&g.x);
    let constraint = match &g.groups {
        Some(groups) => Constraint::groups(g.sets[0].len(), groups.clone()),
        None => Constraint::new(g.sets.clone()),
    }
    .unwrap()
    .with_decoys(&g.decoys)
    .unwrap();
    let n_sets = g.sets.len();
    let covariance = g.n_channels.map_or(Covariance::LedoitWolf, |n_channels| {
        Covariance::BlockToeplitz { n_channels }
    });
    let m = UnsupervisedParams {
        mean_prior: g.mean_prior,
        covariance,
        ..params(g.objective.len(), 0.0)
    }
    .fit_from_scores(x.view(), &g.codes, &g.trials, &constraint, &g.init)
    .unwrap();
    assert_eq!(m.init().0, Init::Given);
    assert!(
        (m.shrinkage() - g.shrinkage).abs() < 1e-12,
        "{} vs {}",
        m.shrinkage(),
        g.shrinkage
    );
    assert_eq!(m.objective().len(), g.objective.len());
    for (k, (a, b)) in m.objective().iter().zip(&g.objective).enumerate() {
        assert!((a - b).abs() < 1e-9 * b.abs(), "iteration {k}: {a} vs {b}");
    }
    for (t, tp) in m.trials().iter().enumerate() {
        assert_eq!(tp.trial, t);
        for (s, p) in tp.sets.iter().enumerate() {
            for (a, b) in p.iter().zip(&g.posterior[n_sets * t + s]) {
                assert!((a - b).abs() < 1e-9, "trial {t} set {s}: {p:?}");
            }
        }
    }
    // The final LLRs are the numpy model's (the golden's last E-step).
    let llr = m.decision_function_features(x.view()).unwrap();
    for (a, b) in llr.iter().zip(&g.llr) {
        assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "{a} vs {b}");
    }
    let decoded = g.decoded.as_ref().unwrap_or(&g.truth);
    assert_eq!(&m.choices(), decoded);
    // The E-step on epochs given afresh (a predict): the numpy model's posteriors and choices.
    let again = m
        .posteriors_features(x.view(), &g.codes, &g.trials)
        .unwrap();
    for (t, tp) in again.iter().enumerate() {
        for (s, p) in tp.sets.iter().enumerate() {
            for (a, b) in p.iter().zip(&g.posterior[n_sets * t + s]) {
                assert!((a - b).abs() < 1e-9, "afresh: trial {t} set {s}: {p:?}");
            }
        }
    }
    assert_eq!(&m.choices_of(&again), decoded);
}

/// A random problem: `n_trials` trials flashing every code of `sets` and every decoy `reps`
/// times, features `p` wide drawn from `values`.
fn problem(
    sets: &[Vec<u32>],
    decoys: &[u32],
    n_trials: usize,
    reps: usize,
    p: usize,
    values: &[f64],
) -> (Array2<f64>, Vec<u32>, Vec<usize>) {
    let all: Vec<u32> = sets.iter().flatten().chain(decoys).copied().collect();
    let mut codes = Vec::new();
    let mut trials = Vec::new();
    for t in 0..n_trials {
        for _ in 0..reps {
            codes.extend(&all);
            trials.extend(std::iter::repeat_n(t, all.len()));
        }
    }
    let n = codes.len();
    let x = Array2::from_shape_fn((n, p), |(i, j)| values[(i * p + j) % values.len()]);
    (x, codes, trials)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn posteriors_sum_to_one_and_the_likelihood_never_falls(
        speller in any::<bool>(),
        grouped in any::<bool>(),
        decoy in any::<bool>(),
        n_trials in 1usize..5,
        reps in 1usize..4,
        p in 1usize..6,
        values in proptest::collection::vec(-5.0f64..5.0, 97),
        init in proptest::collection::vec(-3.0f64..3.0, 1..40),
    ) {
        let sets = if speller { vec![vec![1, 2, 3], vec![4, 5, 6]] } else { vec![vec![1, 2, 3, 4]] };
        let decoys: &[u32] = if decoy { &[9] } else { &[] };
        let (x, codes, trials) = problem(&sets, decoys, n_trials, reps, p, &values);
        // Group flashes: codes 1–4 showing 1 to 3 of four choices.
        let groups = std::collections::BTreeMap::from([
            (1, vec![0, 1]), (2, vec![2]), (3, vec![1, 2, 3]), (4, vec![0, 3]),
        ]);
        let constraint = if grouped && !speller {
            Constraint::groups(4, groups)
        } else {
            Constraint::new(sets.clone())
        }
        .unwrap()
        .with_decoys(decoys)
        .unwrap();
        let init: Vec<f64> = (0..codes.len()).map(|i| init[i % init.len()]).collect();
        // The block-Toeplitz variant over 2 channels when the features split evenly, else 1.
        let toeplitz = UnsupervisedParams {
            covariance: Covariance::BlockToeplitz { n_channels: if p % 2 == 0 { 2 } else { 1 } },
            ..params(30, 0.0)
        };
        let fits = [
            params(30, 0.0).fit_from_scores(x.view(), &codes, &trials, &constraint, &init),
            params(30, 0.0).fit_features(x.view(), &codes, &trials, &constraint, None),
            toeplitz.fit_from_scores(x.view(), &codes, &trials, &constraint, &init),
            toeplitz.fit_features(x.view(), &codes, &trials, &constraint, None),
        ];
        for fit in fits {
            let m = match fit {
                Ok(m) => m,
                // A constant feature set can leave nothing to separate; that must be said.
                Err(e @ UnsupervisedError::Degenerate { .. }) => {
                    prop_assert!(!e.to_string().is_empty());
                    continue;
                }
                Err(e) => return Err(TestCaseError::fail(e.to_string())),
            };
            prop_assert_eq!(m.trials().len(), n_trials);
            for t in m.trials() {
                prop_assert_eq!(t.sets.len(), sets.len());
                for p in &t.sets {
                    let sum: f64 = p.iter().sum();
                    prop_assert!((sum - 1.0).abs() < 1e-12, "{:?}", p);
                    prop_assert!(p.iter().all(|v| (0.0..=1.0).contains(v)));
                }
            }
            for w in m.objective().windows(2) {
                prop_assert!(w[1] >= w[0] - 1e-9 * (1.0 + w[0].abs()), "{:?}", m.objective());
            }
        }
    }
}

/// Uniform draws in [−0.5, 0.5) from a linear congruential generator seeded by `seed`.
fn uniform_from(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }
}

/// Four-bulb trials (codes 1–4, `reps` rounds each) of 4 channels × 64 samples at 64 Hz: noise
/// and a 10 Hz sine, and on the attended bulb's flashes a bump at 300 ms. Returns the epochs, the
/// codes, the trials and the attended code of each trial.
fn four_bulb(
    n_trials: usize,
    reps: usize,
    bump: f64,
    seed: u64,
) -> (Array3<f64>, Vec<u32>, Vec<usize>, Vec<u32>) {
    let mut uniform = uniform_from(seed);
    let mut codes = Vec::new();
    let mut trials = Vec::new();
    let mut attended = Vec::new();
    for t in 0..n_trials {
        let a = 1 + ((uniform() + 0.5) * 4.0).floor().min(3.0) as u32;
        attended.push(a);
        for r in 0..reps {
            for k in 0..4u32 {
                codes.push(1 + (k + r as u32 + t as u32) % 4);
                trials.push(t);
            }
        }
    }
    let n = codes.len();
    let x = Array3::from_shape_fn((n, 4, 64), |(e, c, i)| {
        let tt = i as f64 / 64.0;
        let b = if codes[e] == attended[trials[e]] {
            bump * (c as f64 + 1.0) * (-((tt - 0.3) / 0.05).powi(2)).exp()
        } else {
            0.0
        };
        b + (2.0 * std::f64::consts::PI * 10.0 * tt + c as f64).sin()
    });
    // Noise drawn in a second pass so the bump's parameters do not shift the stream.
    let noise = Array3::from_shape_fn((n, 4, 64), |_| 8.0 * uniform());
    (x + noise, codes, trials, attended)
}

#[test]
fn synthetic_four_bulb_trials_are_recovered_without_labels() {
    let (x, codes, trials, attended) = four_bulb(30, 5, 3.0, 11);
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::bin_mean(4).unwrap(),
        ..UnsupervisedParams::for_sfreq(64.0).unwrap()
    };
    let m = params.fit(x.view(), &codes, &trials, &constraint).unwrap();
    let right = right_of(&m.choices(), &attended);
    println!("post hoc {right}/30, objective {:?}", m.objective().last());
    assert!(right >= 28, "{right}/30");
    // Online: the late trials are decided as well as post hoc.
    let r = replay(
        &params,
        x.view(),
        &codes,
        &trials,
        &constraint,
        &mut |_, _| {},
    )
    .unwrap();
    let online: Vec<bool> = r
        .online
        .iter()
        .zip(&attended)
        .map(|(c, &a)| c.codes[0] == a)
        .collect();
    let late = online[10..].iter().filter(|&&b| b).count();
    println!("online {online:?}");
    assert!(late >= 19, "{late}/20 right online after the first 10");
    assert_eq!(
        r.model.choices(),
        m.choices(),
        "post hoc equals the one-shot fit"
    );
}

/// The synthetic bump's own time course as the prior: an epoch's inner product with it.
fn bump_scores(x: &Array3<f64>) -> Vec<f64> {
    let w: Vec<f64> = (0..64)
        .map(|i| (-((i as f64 / 64.0 - 0.3) / 0.05).powi(2)).exp())
        .collect();
    x.outer_iter()
        .map(|e| {
            e.rows()
                .into_iter()
                .map(|r| r.dot(&ndarray::arr1(&w)))
                .sum()
        })
        .collect()
}

#[test]
fn a_prior_starts_em_alone_until_there_are_as_many_epochs_as_features() {
    let (x, codes, trials, attended) = four_bulb(12, 5, 3.0, 5);
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    // 4 channels × 32 bins = 128 features; 20 epochs per trial.
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::bin_mean(2).unwrap(),
        ..UnsupervisedParams::for_sfreq(64.0).unwrap()
    };
    let feats = params.features.transform(x.view()).unwrap();
    let prior = bump_scores(&x);
    let fit = |n: usize| {
        params
            .fit_features_from(
                feats.slice(ndarray::s![..n, ..]),
                &codes[..n],
                &trials[..n],
                &constraint,
                None,
                Some(&prior[..n]),
            )
            .unwrap()
    };
    // 3 trials (60 epochs < 128 features): the prior is the only start.
    let few = fit(60);
    assert_eq!(few.init().1.len(), 1, "{:?}", few.init());
    assert_eq!(few.init().0, Init::Given);
    // 7 trials (140 epochs): the random starts join, the likeliest kept.
    let many = fit(140);
    assert_eq!(many.init().1.len(), 1 + params.n_inits);
    // From the prior, the first trials are already decided right.
    let r = replay_from(
        &params,
        x.view(),
        &codes,
        &trials,
        &constraint,
        Some(&prior),
        &mut |_, _| {},
    )
    .unwrap();
    let right = online_right(&r, &attended);
    assert!(right >= 11, "{right}/12 online from the prior");
    // A prior of the wrong length is named.
    let err = params
        .fit_features_from(
            feats.view(),
            &codes,
            &trials,
            &constraint,
            None,
            Some(&prior[..10]),
        )
        .unwrap_err();
    assert!(
        matches!(err, UnsupervisedError::InitLength { n_scores: 10, .. }),
        "{err}"
    );
}

#[test]
fn random_starts_stop_joining_a_warm_refit_at_random_until_epochs_per_feature() {
    let (x, codes, trials, attended) = four_bulb(30, 5, 3.0, 5);
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    // 128 features, 20 epochs per trial: 4 epochs per feature at 512 epochs.
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::bin_mean(2).unwrap(),
        ..UnsupervisedParams::for_sfreq(64.0).unwrap()
    };
    assert_eq!(params.random_until, Some(4.0));
    let feats = params.features.transform(x.view()).unwrap();
    let prior = bump_scores(&x);
    let fit = |p: &UnsupervisedParams, n: usize, warm: Option<&Unsupervised>| {
        p.fit_features_from(
            feats.slice(ndarray::s![..n, ..]),
            &codes[..n],
            &trials[..n],
            &constraint,
            warm,
            Some(&prior[..n]),
        )
        .unwrap()
    };
    let randoms = |m: &Unsupervised| {
        m.init()
            .1
            .iter()
            .filter(|(i, _)| matches!(i, Init::Random(_)))
            .count()
    };
    let warm = fit(&params, 240, None);
    // Below 512 epochs, or without a warm start, they join; from 512 with one, they do not.
    assert_eq!(randoms(&fit(&params, 500, Some(&warm))), params.n_inits);
    assert_eq!(randoms(&fit(&params, 600, None)), params.n_inits);
    let settled = fit(&params, 600, Some(&warm));
    assert_eq!(randoms(&settled), 0, "{:?}", settled.init());
    assert_eq!(settled.init().1.len(), 2, "the prior and the warm start");
    // Settings saved before the field existed (`None`): they always join.
    let always = UnsupervisedParams {
        random_until: None,
        ..params
    };
    assert_eq!(randoms(&fit(&always, 600, Some(&warm))), params.n_inits);
    // And the settled fit still decides the trials.
    let right = right_of(&settled.choices(), &attended);
    assert!(right >= 28, "{right}/30");
    // A bad value is named.
    let bad = UnsupervisedParams {
        random_until: Some(f64::NAN),
        ..params
    };
    let err = bad
        .fit_features(feats.view(), &codes, &trials, &constraint, None)
        .unwrap_err();
    assert!(err.to_string().contains("random_until"), "{err}");
}

#[test]
fn bad_input_is_named() {
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    let x = Array2::from_shape_fn((8, 2), |(i, j)| (i * 3 + j) as f64 % 5.0);
    let p = params(10, 1e-6);
    let err = p
        .fit_features(
            x.view(),
            &[1, 2, 3, 4, 1, 2, 3, 9],
            &[0; 8],
            &constraint,
            None,
        )
        .unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::UnknownCode {
                index: 7,
                code: 9,
                ..
            }
        ),
        "{err}"
    );
    let err = p
        .fit_features(x.view(), &[1, 2, 3], &[0; 8], &constraint, None)
        .unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::Length {
                n_epochs: 8,
                n_codes: 3,
                ..
            }
        ),
        "{err}"
    );
    assert!(matches!(
        Constraint::new(vec![vec![1, 2], vec![2, 3]]),
        Err(UnsupervisedError::SharedCode { code: 2 })
    ));
    assert!(matches!(
        Constraint::one_of(&[1]),
        Err(UnsupervisedError::TooFewChoices { set: 0, n_codes: 1 })
    ));
    let mut bad = x.clone();
    bad[[5, 1]] = f64::NAN;
    let err = p
        .fit_features(
            bad.view(),
            &[1, 2, 3, 4, 1, 2, 3, 4],
            &[0; 8],
            &constraint,
            None,
        )
        .unwrap_err();
    assert_eq!(
        err,
        UnsupervisedError::NonFinite {
            epoch: 5,
            feature: 1
        }
    );
    let e3 = Array3::<f64>::zeros((8, 1, 2));
    let err = replay(
        &p,
        e3.view(),
        &[1, 2, 1, 2, 1, 2, 1, 2],
        &[0, 0, 1, 1, 0, 0, 2, 2],
        &constraint,
        &mut |_, _| {},
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::TrialsNotContiguous { trial: 0, index: 4 }
        ),
        "{err}"
    );
    // Held-out scores: rows prepared under another covariance, lengths that are not the rows',
    // and responsibilities that are not probabilities are named.
    let rows = p.prepare(x.view()).unwrap();
    assert_eq!(rows.n_epochs(), 8);
    let trials = [0, 0, 0, 0, 1, 1, 1, 1];
    let half = [0.5; 8];
    let toeplitz = UnsupervisedParams {
        covariance: oddball_decode::unsupervised::Covariance::BlockToeplitz { n_channels: 1 },
        ..p
    };
    let err = toeplitz
        .held_out_scores(&rows, &half, &trials, &[0])
        .unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::InvalidParameter {
                name: "covariance",
                ..
            }
        ),
        "{err}"
    );
    let err = p
        .held_out_scores(&rows, &half[..5], &trials, &[0])
        .unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::EpochCount {
                n_epochs: 8,
                got: 5,
                ..
            }
        ),
        "{err}"
    );
    let mut over = half;
    over[2] = 1.5;
    let err = p.held_out_scores(&rows, &over, &trials, &[0]).unwrap_err();
    assert!(
        matches!(
            err,
            UnsupervisedError::InvalidParameter {
                name: "attended",
                ..
            }
        ),
        "{err}"
    );
    let scores = p.held_out_scores(&rows, &half, &trials, &[1]).unwrap();
    assert!(scores[..4].iter().all(Option::is_none));
}

/// A pooled start of another "subject" (labelled, its own seed), on a session whose channels
/// are a permuted subset/superset by name: it decides the first trials, and a start that is
/// wrong (the pattern negated) is outvoted by the session's evidence.
#[test]
fn a_pooled_start_helps_early_and_a_wrong_one_does_not_hurt_post_hoc() {
    use oddball_decode::unsupervised::{feature_times, replay_starts, PooledPattern, Start};
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::bin_mean(2).unwrap(),
        ..UnsupervisedParams::for_sfreq(64.0).unwrap()
    };
    let times = feature_times(params.features, 64.0, 0.0, 64);
    // The other subject, labelled: channels C1..C4 named as below.
    let (xo, codes_o, trials_o, attended_o) = four_bulb(30, 5, 3.0, 11);
    let y: Vec<bool> = codes_o
        .iter()
        .zip(&trials_o)
        .map(|(c, t)| *c == attended_o[*t])
        .collect();
    let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let fo = params.features.transform(xo.view()).unwrap();
    let pattern = PooledPattern::from_labelled(
        fo.view(),
        &y,
        &names(&["Fz", "Cz", "Pz", "Oz"]),
        &times,
        false,
        "other",
    )
    .unwrap();
    let pattern = PooledPattern::pool(&[pattern]).unwrap();
    // The session: the same four channels, other names' case, in another order, plus one the
    // pattern does not name (its channel 4 carries the largest bump: unknown to the start).
    let (x, codes, trials, attended) = four_bulb(14, 5, 3.0, 5);
    // Session channel k is the other subject's channel order[k] (its bump scales with the
    // channel index, so the names must carry it).
    let session = names(&["fz", "CZ", "pz", "T7"]);
    let scorer = pattern.scorer(&session, &times).unwrap();
    assert_eq!(scorer.n_shared(), 3);
    let constraint = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    let run = |starts: &[Start<'_>]| {
        replay_starts(
            &params,
            x.view(),
            &codes,
            &trials,
            &constraint,
            starts,
            &mut |_, _| {},
        )
        .unwrap()
    };
    let right = |r: &oddball_decode::unsupervised::Replay| {
        let online = online_right(r, &attended);
        let post = right_of(&r.model.choices(), &attended);
        (online, post)
    };
    let pooled = run(&[Start::Pooled(&scorer)]);
    let (online, post) = right(&pooled);
    assert!(
        online >= 12 && post >= 13,
        "pooled start: {online}, {post} of 14"
    );
    // The first trial (20 epochs, 128 features: no random starts yet) is the start's.
    assert_eq!(pooled.online[0].init, Init::Given);
    // A wrong start: the session's own evidence takes over.
    let mut wrong = pattern.clone();
    for row in &mut wrong.effect {
        for v in row.iter_mut() {
            *v = -*v;
        }
    }
    let wrong_scorer = wrong.scorer(&session, &times).unwrap();
    let none = right(
        &replay(
            &params,
            x.view(),
            &codes,
            &trials,
            &constraint,
            &mut |_, _| {},
        )
        .unwrap(),
    );
    let with_wrong = right(&run(&[Start::Pooled(&wrong_scorer)]));
    assert!(
        with_wrong.1 >= none.1,
        "post hoc: wrong start {with_wrong:?}, none {none:?}"
    );
    let later = run(&[Start::Pooled(&wrong_scorer)]);
    assert!(
        later.online.iter().skip(7).any(|o| o.init != Init::Given),
        "the wrong start stops winning once the random starts join: {:?}",
        later.online.iter().map(|o| o.init).collect::<Vec<_>>()
    );
}

/// Four-bulb trials of feature rows with a decoy (code 5, never attended) flashed once a round:
/// `p` features of correlated noise, a mean shift of `shift` on the attended bulb's flashes.
/// Returns the rows, codes, trials and the attended code of each trial.
fn four_bulb_rows_with_decoy(
    n_trials: usize,
    reps: usize,
    shift: f64,
    seed: u64,
) -> (Array2<f64>, Vec<u32>, Vec<usize>, Vec<u32>) {
    let mut uniform = uniform_from(seed);
    let p = 6;
    let (mut codes, mut trials, mut attended) = (Vec::new(), Vec::new(), Vec::new());
    for t in 0..n_trials {
        attended.push(1 + ((uniform() + 0.5) * 4.0).floor().min(3.0) as u32);
        for r in 0..reps {
            for k in 0..5u32 {
                codes.push(1 + (k + r as u32 + t as u32) % 5);
                trials.push(t);
            }
        }
    }
    let n = codes.len();
    let mut x = Array2::zeros((n, p));
    for i in 0..n {
        // Noise shared by neighbouring features (correlated, as EEG samples are).
        let z: Vec<f64> = (0..=p).map(|_| 3.5 * uniform()).collect();
        for j in 0..p {
            let target = codes[i] == attended[trials[i]];
            x[[i, j]] = z[j]
                + z[j + 1]
                + if target {
                    shift * (j as f64 + 1.0) / p as f64
                } else {
                    0.0
                };
        }
    }
    (x, codes, trials, attended)
}

/// What the paradigm gives away by flashing decoys (their labels) helps the EM: on weak
/// synthetic trials it recovers more of them with the decoys' epochs taken as non-targets than
/// with those epochs left out, and (a control) than with them left in as a fifth choice.
#[test]
fn decoys_as_known_non_targets_help_the_em() {
    let (mut with, mut without, mut as_choice, mut total) = (0, 0, 0, 0);
    let params = params(200, 1e-9);
    for seed in 0..30u64 {
        let (x, codes, trials, attended) = four_bulb_rows_with_decoy(6, 5, 1.6, 100 + seed);
        let decoyed = Constraint::one_of(&[1, 2, 3, 4])
            .unwrap()
            .with_decoys(&[5])
            .unwrap();
        let m = params
            .fit_features(x.view(), &codes, &trials, &decoyed, None)
            .unwrap();
        with += right_of(&m.choices(), &attended);
        let keep: Vec<usize> = (0..codes.len()).filter(|&i| codes[i] != 5).collect();
        let xs = x.select(ndarray::Axis(0), &keep);
        let cs: Vec<u32> = keep.iter().map(|&i| codes[i]).collect();
        let ts: Vec<usize> = keep.iter().map(|&i| trials[i]).collect();
        let plain = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
        let m = params
            .fit_features(xs.view(), &cs, &ts, &plain, None)
            .unwrap();
        without += right_of(&m.choices(), &attended);
        let five = Constraint::one_of(&[1, 2, 3, 4, 5]).unwrap();
        let m = params
            .fit_features(x.view(), &codes, &trials, &five, None)
            .unwrap();
        as_choice += right_of(&m.choices(), &attended);
        total += attended.len();
    }
    println!("right: decoys known {with}, decoys dropped {without}, decoy a choice {as_choice} of {total}");
    assert!(with > without, "{with} vs {without} of {total}");
    assert!(with > as_choice, "{with} vs {as_choice} of {total}");
}

#[test]
fn groups_are_checked() {
    use std::collections::BTreeMap;
    let ok = BTreeMap::from([(1, vec![0, 1]), (2, vec![2])]);
    let c = Constraint::groups(3, ok.clone()).unwrap();
    assert_eq!(c.sets(), &[vec![0, 1, 2]]);
    assert_eq!(c.targets_of(1), Some((0, vec![0, 1])));
    assert_eq!(c.targets_of(0), None);
    assert_eq!(c.locate(1), None);
    assert!((c.attended_weight(1, &[vec![0.5, 0.2, 0.3]]) - 0.7).abs() < 1e-15);
    let back: Constraint = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
    assert_eq!(back, c);
    // Read back through the same checks: a saved group out of range, or sets that are not the
    // choices, are refused, not indexed.
    for bad in [
        r#"{"sets":[[0,1,2]],"groups":{"1":[0,7]}}"#,
        r#"{"sets":[[0,1,5]],"groups":{"1":[0,1],"2":[2]}}"#,
        r#"{"sets":[[1,2],[2,3]]}"#,
        r#"{"sets":[[1,2,3]],"decoys":[2]}"#,
    ] {
        assert!(serde_json::from_str::<Constraint>(bad).is_err(), "{bad}");
    }
    for (n, groups, what) in [
        (4, ok.clone(), "choice 3"),
        (
            3,
            BTreeMap::from([(1, vec![0, 1, 3]), (2, vec![2])]),
            "code 1",
        ),
        (
            3,
            BTreeMap::from([(1, vec![0, 0, 1]), (2, vec![2])]),
            "code 1",
        ),
        (3, BTreeMap::from([(1, vec![0, 1]), (2, vec![])]), "code 2"),
    ] {
        let e = Constraint::groups(n, groups).unwrap_err().to_string();
        assert!(e.contains(what), "{e}");
    }
    assert!(Constraint::groups(1, BTreeMap::from([(1, vec![0])])).is_err());
    let e = c.with_decoys(&[2]).unwrap_err().to_string();
    assert!(e.contains("decoy code 2 is in a choice set"), "{e}");
}

#[test]
fn a_decoy_is_no_choice() {
    let c = Constraint::one_of(&[1, 2, 3, 4]).unwrap();
    let e = c.clone().with_decoys(&[3]).unwrap_err();
    assert!(
        e.to_string().contains("decoy code 3 is in a choice set"),
        "{e}"
    );
    let e = c.clone().with_decoys(&[5, 5]).unwrap_err();
    assert!(
        e.to_string().contains("decoy code 5 is listed twice"),
        "{e}"
    );
    let d = c.with_decoys(&[5]).unwrap();
    assert!(d.is_decoy(5) && !d.is_decoy(4));
    // Saved and read back with its decoys; a constraint saved before decoys reads as none.
    let back: Constraint = serde_json::from_str(&serde_json::to_string(&d).unwrap()).unwrap();
    assert_eq!(back, d);
    let old: Constraint = serde_json::from_str(r#"{"sets":[[1,2,3,4]]}"#).unwrap();
    assert!(old.decoys().is_empty());
}
