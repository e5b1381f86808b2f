//! Learning from label proportions and MIX against numpy (`tools/golden/unsupervised/make_llp.py`:
//! `lstsq` on the group means, a dense shrinkage LDA, the variance-weighted mixture), LLP's
//! consistency (its error to the true class means falls with the number of epochs), and its
//! refusal of groups that do not identify the means.

use ndarray::Array2;
use oddball_decode::unsupervised::{ClassMeans, LlpParams, UnsupervisedError};
use serde::Deserialize;

#[derive(Deserialize)]
struct Means {
    target: Vec<f64>,
    non_target: Vec<f64>,
    variance: Vec<f64>,
}

#[derive(Deserialize)]
struct Decoded {
    target: Vec<f64>,
    non_target: Vec<f64>,
    variance: Vec<f64>,
    coef: Vec<f64>,
    intercept: f64,
    llr: Vec<f64>,
    #[serde(default)]
    gamma: Vec<f64>,
}

#[derive(Deserialize)]
struct Golden {
    versions: std::collections::HashMap<String, String>,
    groups: Vec<f64>,
    x: Vec<Vec<f64>>,
    group_of_epoch: Vec<usize>,
    shrinkage: f64,
    llp: Decoded,
    responsibilities: Vec<f64>,
    mean_prior: f64,
    em: Means,
    mix: Decoded,
}

fn rows(x: &[Vec<f64>]) -> Array2<f64> {
    Array2::from_shape_fn((x.len(), x[0].len()), |(i, j)| x[i][j])
}

/// Largest absolute difference, asserting it is below 1e-9.
fn close(what: &str, got: impl IntoIterator<Item = f64>, want: &[f64]) -> f64 {
    let got: Vec<f64> = got.into_iter().collect();
    assert_eq!(got.len(), want.len(), "{what}: length");
    let d = got
        .iter()
        .zip(want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        d < 1e-9,
        "{what}: max diff {d:e}\n got {got:?}\nwant {want:?}"
    );
    d
}

#[test]
fn llp_and_mix_match_numpy() {
    let g: Golden = serde_json::from_str(include_str!("fixtures/llp_golden.json")).unwrap();
    assert!(g.versions.contains_key("numpy"));
    let x = rows(&g.x);
    let llp = LlpParams {
        groups: g.groups.clone(),
    }
    .fit(x.view(), &g.group_of_epoch)
    .unwrap();
    let mut worst: f64 = 0.0;
    worst = worst.max(close("shrinkage", [llp.lda().shrinkage()], &[g.shrinkage]));
    let m = llp.means();
    worst = worst.max(close("LLP target", m.target.iter().copied(), &g.llp.target));
    worst = worst.max(close(
        "LLP non-target",
        m.non_target.iter().copied(),
        &g.llp.non_target,
    ));
    worst = worst.max(close("LLP variance", m.variance, &g.llp.variance));
    worst = worst.max(close(
        "LLP coef",
        llp.lda().coef().iter().copied(),
        &g.llp.coef,
    ));
    worst = worst.max(close(
        "LLP intercept",
        [llp.lda().intercept()],
        &[g.llp.intercept],
    ));
    let llr = llp.decision_function(x.view()).unwrap();
    worst = worst.max(close("LLP llr", llr.iter().copied(), &g.llp.llr));

    let em =
        ClassMeans::from_responsibilities(x.view(), &g.responsibilities, g.mean_prior).unwrap();
    worst = worst.max(close("EM target", em.target.iter().copied(), &g.em.target));
    worst = worst.max(close(
        "EM non-target",
        em.non_target.iter().copied(),
        &g.em.non_target,
    ));
    worst = worst.max(close("EM variance", em.variance, &g.em.variance));

    let mix = llp.mix(x.view(), &em).unwrap();
    worst = worst.max(close("MIX gamma", mix.gamma(), &g.mix.gamma));
    let mm = mix.means();
    worst = worst.max(close(
        "MIX target",
        mm.target.iter().copied(),
        &g.mix.target,
    ));
    worst = worst.max(close(
        "MIX non-target",
        mm.non_target.iter().copied(),
        &g.mix.non_target,
    ));
    worst = worst.max(close("MIX variance", mm.variance, &g.mix.variance));
    worst = worst.max(close(
        "MIX coef",
        mix.lda().coef().iter().copied(),
        &g.mix.coef,
    ));
    worst = worst.max(close(
        "MIX intercept",
        [mix.lda().intercept()],
        &[g.mix.intercept],
    ));
    let llr = mix.decision_function(x.view()).unwrap();
    worst = worst.max(close("MIX llr", llr.iter().copied(), &g.mix.llr));
    println!("golden max abs diff {worst:e}");
}

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut rand_mt::Mt) -> f64 {
    let u = |rng: &mut rand_mt::Mt| ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let (u1, u2) = (u(rng), u(rng));
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Epochs of two sequence types (π₁ = 3/8, π₂ = 2/18, equally many of each) with class means
/// `mu_t`, `mu_n` and correlated noise; returns the rows and each epoch's group.
fn draw(n: usize, seed: u32, mu_t: &[f64], mu_n: &[f64]) -> (Array2<f64>, Vec<usize>) {
    let groups = [3.0 / 8.0, 2.0 / 18.0];
    let p = mu_t.len();
    let mut rng = rand_mt::Mt::new(seed);
    let mut x = Array2::zeros((n, p));
    let mut group_of = Vec::with_capacity(n);
    for i in 0..n {
        let g = i % 2;
        group_of.push(g);
        let u = ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        let mu = if u < groups[g] { mu_t } else { mu_n };
        let z: Vec<f64> = (0..p).map(|_| normal(&mut rng)).collect();
        for j in 0..p {
            // Noise with neighbouring features correlated.
            let e = z[j] + if j > 0 { 0.5 * z[j - 1] } else { 0.0 };
            x[[i, j]] = mu[j] + e;
        }
    }
    (x, group_of)
}

/// Root of the summed squared error of both class means, averaged over `seeds`.
fn mean_error(n: usize, seeds: std::ops::Range<u32>, mu_t: &[f64], mu_n: &[f64]) -> f64 {
    let k = seeds.len() as f64;
    seeds
        .map(|seed| {
            let (x, g) = draw(n, seed, mu_t, mu_n);
            let fit = LlpParams {
                groups: vec![3.0 / 8.0, 2.0 / 18.0],
            }
            .fit(x.view(), &g)
            .unwrap();
            let m = fit.means();
            let sq: f64 = m
                .target
                .iter()
                .zip(mu_t)
                .chain(m.non_target.iter().zip(mu_n))
                .map(|(a, b)| (a - b).powi(2))
                .sum();
            sq.sqrt()
        })
        .sum::<f64>()
        / k
}

#[test]
fn llp_means_approach_the_truth_as_epochs_accrue() {
    let mu_t = [1.5, 1.0, 0.5, 0.0, -0.5, 0.2];
    let mu_n = [0.0, -0.2, 0.1, 0.3, 0.0, 0.0];
    let e400 = mean_error(400, 0..8, &mu_t, &mu_n);
    let e4000 = mean_error(4000, 0..8, &mu_t, &mu_n);
    println!("LLP mean error: n=400 {e400:.4}, n=4000 {e4000:.4}");
    assert!(e4000 < e400, "n=4000 {e4000} not below n=400 {e400}");
    // Sampling error falls as 1/√n: at ten times the epochs, well under half.
    assert!(e4000 < 0.5 * e400, "n=4000 {e4000} vs n=400 {e400}");
}

#[test]
fn llp_refuses_groups_of_equal_proportion() {
    let (x, g) = draw(200, 1, &[1.0, 0.0], &[0.0, 0.0]);
    // The row/column speller: every flash set holds the target with the same share.
    let err = LlpParams {
        groups: vec![1.0 / 6.0, 1.0 / 6.0],
    }
    .fit(x.view(), &g)
    .unwrap_err();
    assert!(
        matches!(err, UnsupervisedError::NotIdentified { .. }),
        "{err}"
    );
    let err = LlpParams { groups: vec![0.25] }
        .fit(x.view(), &vec![0; x.nrows()])
        .unwrap_err();
    assert!(matches!(err, UnsupervisedError::NotIdentified { .. }));
}

#[test]
fn llp_checks_its_input() {
    let (mut x, g) = draw(50, 2, &[1.0, 0.0], &[0.0, 0.0]);
    let params = LlpParams {
        groups: vec![0.375, 0.1],
    };
    let bad_pi = LlpParams {
        groups: vec![0.375, 1.5],
    };
    assert!(matches!(
        bad_pi.fit(x.view(), &g).unwrap_err(),
        UnsupervisedError::InvalidParameter { .. }
    ));
    assert!(matches!(
        params.fit(x.view(), &g[1..]).unwrap_err(),
        UnsupervisedError::EpochCount { .. }
    ));
    let all_zero = vec![0; x.nrows()];
    assert!(matches!(
        params.fit(x.view(), &all_zero).unwrap_err(),
        UnsupervisedError::EmptyGroup { group: 1 }
    ));
    let mut unknown = g.clone();
    unknown[3] = 2;
    assert!(matches!(
        params.fit(x.view(), &unknown).unwrap_err(),
        UnsupervisedError::UnknownGroup {
            index: 3,
            group: 2,
            ..
        }
    ));
    x[[4, 1]] = f64::NAN;
    assert!(matches!(
        params.fit(x.view(), &g).unwrap_err(),
        UnsupervisedError::NonFinite {
            epoch: 4,
            feature: 1
        }
    ));
}

/// A paradigm where both apply: trials of type 0 flash codes 1–4 (one attended: π = 1/4), of
/// type 1 codes 5–12 (one attended: π = 1/8). The EM's means (from its posterior) and the LLP's
/// are mixed; the mixture's weights are in [0, 1] and its decoder separates the classes.
#[test]
fn mix_combines_an_em_fit_with_llp() {
    use oddball_decode::features::amplitude::AmplitudeFeatures;
    use oddball_decode::unsupervised::{Constraint, Covariance, UnsupervisedParams};
    let mu_t = [1.2, 0.8, 0.4, 0.0];
    let p = mu_t.len();
    let mut rng = rand_mt::Mt::new(11);
    let (mut rows_x, mut codes, mut trials, mut group_of, mut attended) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for t in 0..24usize {
        let g = t % 2;
        let pool: Vec<u32> = if g == 0 {
            (1..=4).collect()
        } else {
            (5..=12).collect()
        };
        let target = pool[(rng.next_u32() as usize) % pool.len()];
        for _ in 0..3 {
            for &c in &pool {
                let z: Vec<f64> = (0..p).map(|_| normal(&mut rng)).collect();
                for j in 0..p {
                    let e = z[j] + if j > 0 { 0.5 * z[j - 1] } else { 0.0 };
                    rows_x.push(if c == target { mu_t[j] } else { 0.0 } + e);
                }
                codes.push(c);
                trials.push(t);
                group_of.push(g);
                attended.push(c == target);
            }
        }
    }
    let x = Array2::from_shape_vec((codes.len(), p), rows_x).unwrap();
    let constraint = Constraint::new(vec![(1..=4).collect(), (5..=12).collect()]).unwrap();
    let params = UnsupervisedParams {
        features: AmplitudeFeatures::decimate(1).unwrap(),
        mean_prior: 1.0,
        n_inits: 8,
        max_iter: 100,
        tol: 1e-8,
        seed: 3,
        covariance: Covariance::LedoitWolf,
        random_until: None,
    };
    let model = params
        .fit_features(x.view(), &codes, &trials, &constraint, None)
        .unwrap();
    let em = ClassMeans::from_em(&model, x.view(), &codes, &trials, 1.0).unwrap();
    let llp = LlpParams {
        groups: vec![0.25, 0.125],
    }
    .fit(x.view(), &group_of)
    .unwrap();
    let mix = llp.mix(x.view(), &em).unwrap();
    for gamma in mix.gamma() {
        assert!((0.0..=1.0).contains(&gamma), "{gamma}");
    }
    let err = |m: &ClassMeans| {
        m.target
            .iter()
            .zip(&mu_t)
            .chain(m.non_target.iter().zip(&[0.0; 4]))
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let (e_em, e_llp, e_mix) = (err(&em), err(llp.means()), err(mix.means()));
    println!(
        "EM error {e_em:.4}, LLP error {e_llp:.4}, MIX error {e_mix:.4}, gamma {:?}",
        mix.gamma()
    );
    assert!(e_mix <= e_em.max(e_llp) + 1e-12);
    // The mixture's LLR ranks targets above non-targets (AUC; single epochs of this shift and
    // noise are separable to about 0.8 even with the true means).
    let llr = mix.decision_function(x.view()).unwrap();
    let (mut above, mut pairs) = (0usize, 0usize);
    for (i, &ai) in attended.iter().enumerate() {
        for (j, &aj) in attended.iter().enumerate() {
            if ai && !aj {
                pairs += 1;
                above += usize::from(llr[i] > llr[j]);
            }
        }
    }
    let auc = above as f64 / pairs as f64;
    println!("MIX AUC {auc:.3}");
    assert!(auc > 0.7, "AUC {auc}");
}
