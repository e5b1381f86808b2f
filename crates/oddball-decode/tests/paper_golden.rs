//! The paper's features and classifiers against the Python stack the peer uses: reference values from
//! `tools/golden/decode_paper/make_golden.py` (numpy 2.4.6, scipy 1.17.1, scikit-learn 1.9.1,
//! PyWavelets 1.9.0, EMD-signal 1.10.0).
//!
//! Tolerances: EMD, Hilbert, DWT, StandardScaler, PCA, k-NN and the `paper` feature map agree to
//! round-off (1e-12 … 1e-9 of each quantity's scale, stated per test). The SVM's dual is solved only to
//! the stopping tolerance 1e-3 by both libsvm (scikit-learn) and linfa-svm, so decision values are
//! compared by correlation (> 0.9999), maximum difference (< 5e-3) and support-vector count.

use ndarray::{Array1, Array2, Array3, ArrayView1};
use oddball_decode::classifiers::ensemble::{
    MemberParams, ProbabilisticClassifier, SoftVoteParams,
};
use oddball_decode::classifiers::knn::KnnParams;
use oddball_decode::classifiers::svm::{Calibration, Gamma, Kernel, PlattSigmoid, SvmParams};
use oddball_decode::features::amplitude::PaperFeatures;
use oddball_decode::features::emd::{Emd, EmdParams};
use oddball_decode::features::hilbert::{analytic_signal, HilbertTransform};
use oddball_decode::features::pca::{NComponents, PcaParams};
use oddball_decode::features::scaler::StandardScalerParams;
use oddball_decode::features::wavelet::{wavedec_bior22, DwtFeatures};
use oddball_decode::model_selection::folds::{stratified_folds, stratified_folds_shuffled};
use serde::Deserialize;

#[derive(Deserialize)]
struct Golden {
    emd: Vec<EmdCase>,
    hilbert: HilbertGolden,
    dwt: Vec<DwtCase>,
    scaler: ScalerGolden,
    pca: PcaGolden,
    classifiers: ClfGolden,
    paper: PaperGolden,
}

#[derive(Deserialize)]
struct EmdCase {
    name: String,
    signal: Vec<f64>,
    imf1: Vec<f64>,
    n_sift: usize,
}

#[derive(Deserialize)]
struct HilbertGolden {
    fs: f64,
    signals: Vec<HilbertCase>,
}

#[derive(Deserialize)]
struct HilbertCase {
    name: String,
    x: Vec<f64>,
    amp: Vec<f64>,
    freq: Vec<f64>,
    re: Option<Vec<f64>>,
    im: Option<Vec<f64>>,
}

#[derive(Deserialize)]
struct DwtCase {
    x: Vec<f64>,
    level: usize,
    coeffs: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct ScalerGolden {
    x: Vec<Vec<f64>>,
    mean: Vec<f64>,
    scale: Vec<f64>,
    var: Vec<f64>,
    x_test: Vec<Vec<f64>>,
    transform: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct PcaGolden {
    x: Vec<Vec<f64>>,
    x_test: Vec<Vec<f64>>,
    cases: Vec<PcaCase>,
    wide: PcaWide,
}

#[derive(Deserialize)]
struct PcaCase {
    n_components: f64,
    n_components_: usize,
    mean: Vec<f64>,
    components: Vec<Vec<f64>>,
    explained_variance: Vec<f64>,
    explained_variance_ratio: Vec<f64>,
    singular_values: Vec<f64>,
    transform: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct PcaWide {
    x: Vec<Vec<f64>>,
    n_components_: usize,
    components: Vec<Vec<f64>>,
    explained_variance: Vec<f64>,
    transform: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct SvmCase {
    decision_test: Vec<f64>,
    decision_train: Vec<f64>,
    n_support: usize,
    intercept: f64,
    gamma: f64,
}

#[derive(Deserialize)]
struct Sigmoid {
    a: f64,
    b: f64,
}

#[derive(Deserialize)]
struct ScaledSigmoid {
    f: Vec<f64>,
    a: f64,
    b: f64,
}

#[derive(Deserialize)]
struct ClfGolden {
    x_train: Vec<Vec<f64>>,
    y_train: Vec<u8>,
    x_test: Vec<Vec<f64>>,
    svm_rbf: SvmCase,
    svm_linear: SvmCase,
    sigmoid_train_decisions: Sigmoid,
    sigmoid_scaled_decisions: ScaledSigmoid,
    stratified_folds: Vec<usize>,
    calibrated_svm_proba_test: Vec<f64>,
    knn3_proba_test: Vec<f64>,
    knn5_proba_test: Vec<f64>,
    vote_proba_test: Vec<f64>,
    shuffled_folds: Vec<ShuffledFolds>,
    calibrated_svm_shuffled_proba_test: Vec<f64>,
    vote_shuffled_proba_test: Vec<f64>,
}

#[derive(Deserialize)]
struct ShuffledFolds {
    y: Vec<u8>,
    n_splits: usize,
    seed: u32,
    folds: Vec<usize>,
}

#[derive(Deserialize)]
struct PaperGolden {
    fs: f64,
    epochs: Vec<Vec<Vec<f64>>>,
    y: Vec<u8>,
    features: Vec<Vec<f64>>,
    n_train: usize,
    pca_n_components: usize,
    svm_decision_test: Vec<f64>,
    knn3_proba_test: Vec<f64>,
}

fn golden() -> Golden {
    serde_json::from_str(include_str!("fixtures/paper_golden.json")).expect("fixture parses")
}

fn arr2(rows: &[Vec<f64>]) -> Array2<f64> {
    Array2::from_shape_fn((rows.len(), rows[0].len()), |(i, j)| rows[i][j])
}

fn labels(y: &[u8]) -> Vec<bool> {
    y.iter().map(|&v| v == 1).collect()
}

fn peak<'a>(v: impl IntoIterator<Item = &'a f64>) -> f64 {
    v.into_iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Max |a − b| over two equally long sequences.
fn max_err<'a>(a: impl IntoIterator<Item = &'a f64>, b: impl IntoIterator<Item = &'a f64>) -> f64 {
    let (a, b): (Vec<f64>, Vec<f64>) = (
        a.into_iter().copied().collect(),
        b.into_iter().copied().collect(),
    );
    assert_eq!(a.len(), b.len(), "lengths differ");
    a.iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn corr(a: ArrayView1<f64>, b: ArrayView1<f64>) -> f64 {
    let (ma, mb) = (a.mean().unwrap(), b.mean().unwrap());
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b.iter()) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

#[test]
fn emd_first_imf_matches_pyemd() {
    let g = golden();
    let mut emd = Emd::new(EmdParams::default()).unwrap();
    for c in &g.emd {
        let mut out = vec![0.0; c.signal.len()];
        let rep = emd.first_imf(&c.signal, &mut out).unwrap();
        let err = max_err(&out, &c.imf1);
        println!(
            "EMD {}: {} siftings (PyEMD {}), max |error| {err:.2e} (peak {:.1})",
            c.name,
            rep.n_siftings,
            c.n_sift,
            peak(&c.imf1)
        );
        assert_eq!(rep.n_siftings, c.n_sift, "{}: sifting count", c.name);
        assert!(err <= 1e-12 * peak(&c.imf1).max(1.0), "{}: {err}", c.name);
    }
}

#[test]
fn hilbert_matches_scipy() {
    let g = golden();
    let fs = g.hilbert.fs;
    for c in &g.hilbert.signals {
        let n = c.x.len();
        let mut h = HilbertTransform::new(n).unwrap();
        let (mut amp, mut freq) = (vec![0.0; n], vec![0.0; n]);
        h.amplitude_frequency(&c.x, fs, &mut amp, &mut freq)
            .unwrap();
        let ea = max_err(&amp, &c.amp);
        let ef = max_err(&freq, &c.freq);
        println!(
            "Hilbert {}: amplitude {ea:.2e} (peak {:.1}), frequency {ef:.2e} Hz (peak {:.1})",
            c.name,
            peak(&c.amp),
            peak(&c.freq)
        );
        assert!(ea <= 1e-12, "{}: amplitude {ea}", c.name);
        // the frequency is a phase difference times sfreq/2π ≈ 41: round-off grows by that factor
        assert!(ef <= 1e-11, "{}: frequency {ef}", c.name);
        if let (Some(re), Some(im)) = (&c.re, &c.im) {
            let (r, i) = analytic_signal(&c.x).unwrap();
            let (er, ei) = (max_err(&r, re), max_err(&i, im));
            println!(
                "Hilbert {}: real part {er:.2e}, imaginary part {ei:.2e}",
                c.name
            );
            assert!(er <= 1e-12 && ei <= 1e-12);
        }
    }
}

#[test]
fn dwt_matches_pywavelets() {
    let g = golden();
    for c in &g.dwt {
        let got = wavedec_bior22(&c.x, c.level).unwrap();
        assert_eq!(got.len(), c.coeffs.len());
        let mut worst = 0.0f64;
        for (a, b) in got.iter().zip(&c.coeffs) {
            worst = worst.max(max_err(a, b));
        }
        let scale = c.coeffs.iter().map(peak).fold(1.0, f64::max);
        println!(
            "DWT n={} level {}: max |error| {worst:.2e} (peak {scale:.1})",
            c.x.len(),
            c.level
        );
        assert!(worst <= 1e-12 * scale, "n={}: {worst}", c.x.len());
        // the feature extractor's level-L bands are the first two arrays
        let f = DwtFeatures::new(c.level).unwrap();
        let x = Array3::from_shape_fn((1, 1, c.x.len()), |(_, _, t)| c.x[t]);
        let row = f.transform(x.view()).unwrap();
        let nc = f.n_coefficients(c.x.len());
        assert_eq!(nc, c.coeffs[0].len());
        assert!(max_err(row.row(0).iter().take(nc), &c.coeffs[0]) <= 1e-12 * scale);
        assert!(max_err(row.row(0).iter().skip(nc), &c.coeffs[1]) <= 1e-12 * scale);
    }
}

#[test]
fn standard_scaler_matches_sklearn() {
    let g = golden().scaler;
    let s = StandardScalerParams::default()
        .fit(arr2(&g.x).view())
        .unwrap();
    let t = s.transform(arr2(&g.x_test).view()).unwrap();
    let errs = [
        max_err(&s.mean, &g.mean) / peak(&g.mean),
        max_err(&s.var, &g.var) / peak(&g.var),
        max_err(&s.scale, &g.scale) / peak(&g.scale),
        max_err(&t, &arr2(&g.transform)) / peak(&arr2(&g.transform)),
    ];
    println!(
        "StandardScaler relative errors (mean, var, scale, transform): {:.2e} {:.2e} {:.2e} {:.2e}",
        errs[0], errs[1], errs[2], errs[3]
    );
    assert!(errs.iter().all(|&e| e <= 1e-12));
    assert_eq!(s.scale[3], 1.0, "constant feature keeps scale 1");
}

#[test]
fn pca_matches_sklearn() {
    let g = golden().pca;
    let x = arr2(&g.x);
    let xt = arr2(&g.x_test);
    for c in &g.cases {
        let params = if c.n_components < 1.0 {
            PcaParams::variance_fraction(c.n_components)
        } else {
            PcaParams::count(c.n_components as usize)
        };
        let p = params.fit(x.view()).unwrap();
        assert_eq!(
            p.n_components(),
            c.n_components_,
            "n_components={}",
            c.n_components
        );
        let comps = arr2(&c.components);
        let ev = Array1::from(c.explained_variance.clone());
        let e_comp = max_err(&p.components, &comps);
        let e_ev = max_err(&p.explained_variance, &ev) / ev[0];
        let e_ratio = max_err(&p.explained_variance_ratio, &c.explained_variance_ratio);
        let e_sv = max_err(&p.singular_values, &c.singular_values) / c.singular_values[0];
        let e_mean = max_err(&p.mean, &c.mean);
        let tr = arr2(&c.transform);
        let e_tr = max_err(&p.transform(xt.view()).unwrap(), &tr) / peak(&tr);
        println!(
            "PCA n_components={}: kept {} | components {e_comp:.1e}, explained variance {e_ev:.1e} (rel), \
             ratio {e_ratio:.1e}, singular values {e_sv:.1e} (rel), mean {e_mean:.1e}, transform {e_tr:.1e} (rel)",
            c.n_components,
            p.n_components()
        );
        for e in [e_comp, e_ev, e_ratio, e_sv, e_mean, e_tr] {
            assert!(e <= 1e-9, "n_components={}: {e}", c.n_components);
        }
    }
    // fewer samples than features (the Gram-matrix route), as the paper features usually are
    let w = &g.wide;
    let xw = arr2(&w.x);
    let p = PcaParams::variance_fraction(0.95).fit(xw.view()).unwrap();
    assert_eq!(p.n_components(), w.n_components_);
    let e_comp = max_err(&p.components, &arr2(&w.components));
    let ev = Array1::from(w.explained_variance.clone());
    let e_ev = max_err(&p.explained_variance, &ev) / ev[0];
    let tr = arr2(&w.transform);
    let e_tr = max_err(&p.transform(xw.view()).unwrap(), &tr) / peak(&tr);
    println!("PCA wide 15x40: kept {} | components {e_comp:.1e}, explained variance {e_ev:.1e}, transform {e_tr:.1e}", p.n_components());
    for e in [e_comp, e_ev, e_tr] {
        assert!(e <= 1e-9, "wide: {e}");
    }
    let all = PcaParams {
        n_components: NComponents::All,
    };
    assert_eq!(all.fit(x.view()).unwrap().n_components(), 12);
}

fn check_svm(name: &str, got: &Array1<f64>, want: &[f64], n_sv: usize, want_sv: usize) {
    let want = Array1::from(want.to_vec());
    let r = corr(got.view(), want.view());
    let e = max_err(got, &want);
    println!("SVM {name}: decision correlation {r:.7}, max |difference| {e:.2e} (peak {:.2}), support vectors {n_sv} (sklearn {want_sv})", peak(&want));
    assert!(r > 0.9999, "{name}: correlation {r}");
    assert!(e < 5e-3, "{name}: max difference {e}");
    assert_eq!(n_sv, want_sv, "{name}: support vectors");
    // same sign everywhere the reference is not within the tolerance of 0
    for (a, b) in got.iter().zip(want.iter()) {
        if b.abs() > 5e-3 {
            assert_eq!(a > &0.0, b > &0.0);
        }
    }
}

#[test]
fn svm_matches_sklearn_within_solver_tolerance() {
    let g = golden().classifiers;
    let (x, xt, y) = (arr2(&g.x_train), arr2(&g.x_test), labels(&g.y_train));
    for (name, kernel, case) in [
        ("rbf", Kernel::Rbf(Gamma::Scale), &g.svm_rbf),
        ("linear", Kernel::Linear, &g.svm_linear),
    ] {
        let m = SvmParams {
            kernel,
            calibration: Calibration::None,
            ..SvmParams::default()
        }
        .fit(x.view(), &y)
        .unwrap();
        if let Some(gm) = m.gamma() {
            assert!(
                (gm - case.gamma).abs() <= 1e-14 * case.gamma,
                "gamma {gm} vs {}",
                case.gamma
            );
        }
        check_svm(
            &format!("{name} test"),
            &m.decision_function(xt.view()).unwrap(),
            &case.decision_test,
            m.n_support(),
            case.n_support,
        );
        check_svm(
            &format!("{name} train"),
            &m.decision_function(x.view()).unwrap(),
            &case.decision_train,
            m.n_support(),
            case.n_support,
        );
        assert!(
            (m.intercept() - case.intercept).abs() < 5e-3,
            "{name} intercept"
        );
    }
}

#[test]
fn platt_folds_calibration_knn_and_vote_match_sklearn() {
    let g = golden().classifiers;
    let (x, xt, y) = (arr2(&g.x_train), arr2(&g.x_test), labels(&g.y_train));
    // Platt's sigmoid on fixed decision values (only the optimiser differs: L-BFGS gtol 1e-6 vs Newton)
    let s = PlattSigmoid::fit(&g.svm_rbf.decision_train, &y).unwrap();
    let (da, db) = (
        (s.a - g.sigmoid_train_decisions.a).abs(),
        (s.b - g.sigmoid_train_decisions.b).abs(),
    );
    let s2 = PlattSigmoid::fit(&g.sigmoid_scaled_decisions.f, &y).unwrap();
    let (da2, db2) = (
        (s2.a - g.sigmoid_scaled_decisions.a).abs(),
        (s2.b - g.sigmoid_scaled_decisions.b).abs(),
    );
    println!("Platt a, b: |diff| {da:.1e}, {db:.1e}; rescaled decisions: {da2:.1e}, {db2:.1e}");
    assert!(da < 1e-5 && db < 1e-5 && da2 < 1e-6 && db2 < 1e-5);
    // fold assignment: exactly StratifiedKFold(5), and StratifiedKFold(k, shuffle=True,
    // random_state=seed) for several labels, k and seeds (numpy's MT19937 stream reproduced)
    assert_eq!(stratified_folds(&y, 5).unwrap(), g.stratified_folds);
    for case in &g.shuffled_folds {
        let yy = labels(&case.y);
        assert_eq!(
            stratified_folds_shuffled(&yy, case.n_splits, case.seed).unwrap(),
            case.folds,
            "k = {}, seed {}",
            case.n_splits,
            case.seed
        );
    }
    // CalibratedClassifierCV(SVC, sigmoid, StratifiedKFold(5[, shuffle, seed 0]), ensemble=False)
    let unshuffled = SvmParams {
        calibration: Calibration::CrossValidated {
            n_folds: 5,
            shuffle_seed: None,
        },
        ..SvmParams::default()
    };
    for (params, want, what) in [
        (unshuffled, &g.calibrated_svm_proba_test, "unshuffled folds"),
        (
            SvmParams::default(),
            &g.calibrated_svm_shuffled_proba_test,
            "folds shuffled with seed 0 (the default)",
        ),
    ] {
        let svm = params.fit(x.view(), &y).unwrap();
        let p = svm.predict_proba(xt.view()).unwrap();
        let want = Array1::from(want.clone());
        let ep = max_err(&p, &want);
        println!(
            "calibrated SVM P(target), {what}: max |difference| {ep:.2e}, correlation {:.6}",
            corr(p.view(), want.view())
        );
        assert!(ep < 5e-3);
    }
    // k-NN: exact (no distance ties in this data)
    for (k, want) in [(3, &g.knn3_proba_test), (5, &g.knn5_proba_test)] {
        let m = KnnParams { k }.fit(x.view(), &y).unwrap();
        let p = m.predict_proba(xt.view()).unwrap();
        assert_eq!(p.to_vec(), *want, "k={k}");
    }
    // soft vote of the calibrated SVM (the peer's shuffled folds) and the 3-NN
    let vote = SoftVoteParams::paper().fit(x.view(), &y).unwrap();
    let pv = vote.predict_proba(xt.view()).unwrap();
    let ev = max_err(&pv, &g.vote_shuffled_proba_test);
    println!("soft vote P(target): max |difference| {ev:.2e}");
    assert!(ev < 5e-3);
    // the same vote on unshuffled folds
    let mut unshuffled_vote = SoftVoteParams::paper();
    unshuffled_vote.members[0] = MemberParams::Svm(unshuffled);
    let pu = unshuffled_vote
        .fit(x.view(), &y)
        .unwrap()
        .predict_proba(xt.view())
        .unwrap();
    assert!(max_err(&pu, &g.vote_proba_test) < 5e-3);
    assert!(matches!(
        SoftVoteParams::paper().members[1],
        MemberParams::Knn(KnnParams { k: 3 })
    ));
}

#[test]
fn paper_features_and_pipeline_match_the_peer() {
    let g = golden().paper;
    let (n_ep, n_ch, n_t) = (g.epochs.len(), g.epochs[0].len(), g.epochs[0][0].len());
    let x = Array3::from_shape_fn((n_ep, n_ch, n_t), |(e, c, t)| g.epochs[e][c][t]);
    let pf = PaperFeatures::for_sfreq(g.fs).unwrap();
    let f = pf.transform(x.view()).unwrap();
    let want = arr2(&g.features);
    assert_eq!(f.dim(), want.dim());
    let lay = pf.layout(n_ch, n_t);
    let mut start = 0;
    for (name, w) in [
        ("amplitude", lay.amplitude),
        ("inst. amplitude", lay.inst_amplitude),
        ("inst. frequency", lay.inst_frequency),
        ("DWT approximation", lay.dwt_approx),
        ("DWT detail", lay.dwt_detail),
    ] {
        let a = f.slice(ndarray::s![.., start..start + w]);
        let b = want.slice(ndarray::s![.., start..start + w]);
        let e = max_err(a, b);
        println!(
            "paper features, {name} block ({w} columns): max |error| {e:.2e} (peak {:.1})",
            peak(b)
        );
        assert!(e <= 1e-11 * peak(b).max(1.0), "{name}: {e}");
        start += w;
    }
    // the peer's pipeline: StandardScaler -> PCA(0.95) -> SVC / 3-NN, trained on the first n_train
    let y = labels(&g.y);
    let ntr = g.n_train;
    let (ftr, fte) = (
        f.slice(ndarray::s![..ntr, ..]),
        f.slice(ndarray::s![ntr.., ..]),
    );
    let sc = StandardScalerParams::default().fit(ftr).unwrap();
    let (ztr, zte) = (sc.transform(ftr).unwrap(), sc.transform(fte).unwrap());
    let pca = PcaParams::variance_fraction(0.95).fit(ztr.view()).unwrap();
    assert_eq!(pca.n_components(), g.pca_n_components);
    let (ptr, pte) = (
        pca.transform(ztr.view()).unwrap(),
        pca.transform(zte.view()).unwrap(),
    );
    let svm = SvmParams {
        calibration: Calibration::None,
        ..SvmParams::default()
    }
    .fit(ptr.view(), &y[..ntr])
    .unwrap();
    let d = svm.decision_function(pte.view()).unwrap();
    let want_d = Array1::from(g.svm_decision_test.clone());
    let e = max_err(&d, &want_d);
    println!(
        "paper pipeline: PCA kept {}, SVM decision max |difference| {e:.2e}, correlation {:.7}",
        pca.n_components(),
        corr(d.view(), want_d.view())
    );
    assert!(e < 5e-3 && corr(d.view(), want_d.view()) > 0.9999);
    let knn = KnnParams::default().fit(ptr.view(), &y[..ntr]).unwrap();
    assert_eq!(
        knn.predict_proba(pte.view()).unwrap().to_vec(),
        g.knn3_proba_test
    );
}
