use super::*;
use crate::classifiers::logistic::LogisticParams;
use crate::features::scaler::StandardScalerParams;
use ndarray::{Array1, Array2, Array3};

/// Synthetic epochs: targets (every 5th) carry a positive bump at 300 ms on the later channels.
fn synthetic(n_epochs: usize, seed: u64) -> (Array3<f64>, Vec<bool>) {
    crate::testutil::synthetic_p300(n_epochs, seed, 5, 0, 4.0, 3.0)
}

#[test]
fn presets_learn_a_separable_p300_and_round_trip_through_json() {
    let (xtr, ytr) = synthetic(200, 1);
    let (xte, yte) = synthetic(100, 2);
    for name in ["lda", "riemann", "lda+riemann", "mdm", "paper-svm"] {
        let p = PipelineParams::preset(name, 64.0).unwrap();
        let m = p.fit(xtr.view(), &ytr).unwrap();
        let scores = m.decision_function(xte.view()).unwrap();
        let auc = crate::metrics::roc_auc(scores.as_slice().unwrap(), &yte).unwrap();
        assert!(auc > 0.9, "{name}: AUC {auc}");
        let model = Model::new(
            Preprocess::peer(),
            64.0,
            ["a", "b", "c", "d"].map(String::from).to_vec(),
            m,
        );
        let back = Model::from_json(&model.to_json()).unwrap();
        let again = back.pipeline.decision_function(xte.view()).unwrap();
        assert_eq!(again, scores, "{name}: a loaded model scores the same");
        let one = back
            .pipeline
            .score_epoch(xte.index_axis(Axis(0), 3))
            .unwrap();
        assert!((one - scores[3]).abs() < 1e-12);
    }
}

#[test]
fn a_score_fusion_adds_its_members_scores_in_units_of_their_training_spread() {
    let (xtr, ytr) = synthetic(200, 6);
    let (xte, _) = synthetic(30, 7);
    let fused = PipelineParams::preset("lda+riemann", 64.0)
        .unwrap()
        .fit(xtr.view(), &ytr)
        .unwrap();
    assert_eq!(fused.fused().len(), 1);
    // Independently: each preset alone, scaled by the spread of its own training scores.
    let part = |name: &str| {
        let m = PipelineParams::preset(name, 64.0)
            .unwrap()
            .fit(xtr.view(), &ytr)
            .unwrap();
        let train = m.decision_function(xtr.view()).unwrap();
        let n = train.len() as f64;
        let mean = train.sum() / n;
        let sd = (train.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        m.decision_function(xte.view()).unwrap() / sd
    };
    let expected = part("lda") + part("riemann");
    let got = fused.decision_function(xte.view()).unwrap();
    for (g, e) in got.iter().zip(expected.iter()) {
        assert!((g - e).abs() < 1e-9 * e.abs().max(1.0), "{g} vs {e}");
    }
    // The probability is the logistic of the fused score.
    let p = fused.predict_proba(xte.view()).unwrap();
    assert!((p[0] - 1.0 / (1.0 + (-got[0]).exp())).abs() < 1e-12);
    // A model of the older format (version 1, no fusion) still loads.
    let single = PipelineParams::preset("lda", 64.0)
        .unwrap()
        .fit(xtr.view(), &ytr)
        .unwrap();
    let v1 = Model::new(
        Preprocess::peer(),
        64.0,
        ["a", "b", "c", "d"].map(String::from).to_vec(),
        single,
    )
    .to_json()
    .replace(
        &format!("\"format_version\":{MODEL_FORMAT_VERSION}"),
        "\"format_version\":1",
    );
    assert!(v1.contains("\"format_version\":1"));
    assert!(Model::from_json(&v1).is_ok());
    // A fused model whose score scale is not a positive number is refused at load.
    let text = Model::new(
        Preprocess::peer(),
        64.0,
        ["a", "b", "c", "d"].map(String::from).to_vec(),
        fused,
    )
    .to_json();
    assert!(Model::from_json(&text).is_ok());
    // A fused pipeline that fuses again is refused: fusions do not nest (nor their settings).
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let member = v["pipeline"]["fused"][0].clone();
    let mut nested = v.clone();
    nested["pipeline"]["fused"][0]["fused"] = serde_json::json!([member]);
    let mut nested_params = v.clone();
    nested_params["pipeline"]["fused"][0]["params"]["fused"] =
        serde_json::json!([member["params"].clone()]);
    for bad in [nested, nested_params] {
        let err = Model::from_json(&bad.to_string()).unwrap_err();
        assert!(
            matches!(&err, DecodeError::ModelFormat { reason } if reason.contains("do not nest")),
            "{err}"
        );
    }
    let scale = format!("\"score_scale\":{}", {
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["pipeline"]["score_scale"].clone()
    });
    assert!(text.contains(&scale), "{scale}");
    for bad in ["0.0", "-1.0"] {
        let broken = text.replacen(&scale, &format!("\"score_scale\":{bad}"), 1);
        assert!(
            matches!(
                Model::from_json(&broken),
                Err(DecodeError::ModelFormat { .. })
            ),
            "{bad}"
        );
    }
}

/// Each pipeline's scores of every epoch, fitted on full copies of the other folds' epochs
/// (the naive stacking input): `(n_epochs, n_pipelines)`.
fn out_of_fold(
    singles: &[&SingleParams],
    x: &Array3<f64>,
    y: &[bool],
    folds: &crate::model_selection::tuning::Folds,
) -> Array2<f64> {
    let mut oof = Array2::<f64>::zeros((y.len(), singles.len()));
    for f in 0..folds.n_folds() {
        let (tr, te) = folds.split(f);
        let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
        for (k, p) in singles.iter().enumerate() {
            let s = p
                .fit(x.select(Axis(0), &tr).view(), &ytr)
                .unwrap()
                .decision_function(x.select(Axis(0), &te).view())
                .unwrap();
            for (&i, &v) in te.iter().zip(&s) {
                oof[[i, k]] = v;
            }
        }
    }
    oof
}

#[test]
fn a_stacked_fusion_is_a_logistic_regression_on_out_of_fold_scores() {
    let (xtr, ytr) = synthetic(200, 6);
    let (xte, _) = synthetic(30, 7);
    let groups: Vec<usize> = (0..200).map(|i| i / 25).collect();
    let stack = PipelineParams::preset("stack", 64.0).unwrap();
    assert_eq!(stack.fusion, Fusion::Stacked { n_folds: 5 });
    let fused = stack.fit_grouped(xtr.view(), &ytr, Some(&groups)).unwrap();
    assert_eq!(fused.fused().len(), 2);
    // Independently: the three presets alone, scored out of fold on folds keeping the
    // groups whole, then scikit-learn's recipe (StandardScaler → LogisticRegression).
    let names = ["toeplitz-lda", "riemann", "mdm"];
    let folds = crate::model_selection::tuning::cv_folds(&ytr, Some(&groups), 5).unwrap();
    assert!(folds.grouped());
    let fold_of = folds.fold_of();
    assert!((0..200).all(|i| fold_of[i] == fold_of[25 * groups[i]]));
    let alone: Vec<SingleParams> = names
        .iter()
        .map(|name| PipelineParams::preset(name, 64.0).unwrap().main)
        .collect();
    let oof = out_of_fold(&alone.iter().collect::<Vec<_>>(), &xtr, &ytr, &folds);
    let scaler = StandardScalerParams::default().fit(oof.view()).unwrap();
    let lr = LogisticParams::default()
        .fit(scaler.transform(oof.view()).unwrap().view(), &ytr)
        .unwrap();
    let mut expected = Array1::from_elem(30, lr.intercept());
    for (k, name) in names.iter().enumerate() {
        let m = PipelineParams::preset(name, 64.0)
            .unwrap()
            .fit(xtr.view(), &ytr)
            .unwrap();
        let s = m.decision_function(xte.view()).unwrap();
        expected += &s.mapv(|v| lr.coef()[k] * (v - scaler.mean[k]) / scaler.scale[k]);
    }
    let got = fused.decision_function(xte.view()).unwrap();
    for (g, e) in got.iter().zip(expected.iter()) {
        assert!((g - e).abs() < 1e-9 * e.abs().max(1.0), "{g} vs {e}");
    }
    // The learned combination survives saving; a non-finite weight is refused at load.
    let text = Model::new(
        Preprocess::peer(),
        64.0,
        ["a", "b", "c", "d"].map(String::from).to_vec(),
        fused,
    )
    .to_json();
    let back = Model::from_json(&text).unwrap();
    assert_eq!(back.pipeline.decision_function(xte.view()).unwrap(), got);
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let w = format!("\"score_weight\":{}", v["pipeline"]["score_weight"]);
    assert!(text.contains(&w), "{w}");
    let broken = text.replacen(&w, "\"score_weight\":1e999", 1);
    assert!(Model::from_json(&broken).is_err());
    // Without groups the inner folds are stratified: a different, still valid, fit.
    let plain = stack.fit(xtr.view(), &ytr).unwrap();
    assert!(plain
        .decision_function(xte.view())
        .unwrap()
        .iter()
        .all(|v| v.is_finite()));
}

#[test]
fn mdm_scores_are_distance_differences_to_the_class_means() {
    let (xtr, ytr) = synthetic(200, 4);
    let (xte, _) = synthetic(20, 5);
    let m = PipelineParams::preset("mdm", 64.0)
        .unwrap()
        .fit(xtr.view(), &ytr)
        .unwrap();
    let Classifier::Mdm(mdm) = m.classifier() else {
        panic!("mdm ends in an MDM classifier")
    };
    // Features are the xDAWN covariances as matrices: 4 filters × 2 classes → 16×16
    // super-trial covariances (4 channels: 4 filters per class).
    let x = m.features(xte.view()).unwrap();
    let n = mdm.n_channels();
    let FeatureData::Spd(covs) = x else {
        panic!("MDM takes SPD matrices")
    };
    assert_eq!((n, covs.dim()), (16, (20, 16, 16)));
    let d = mdm.distances(covs.view()).unwrap();
    let s = m.decision_function(xte.view()).unwrap();
    for e in 0..20 {
        let want = d[[e, 0]].powi(2) - d[[e, 1]].powi(2);
        assert!(
            (s[e] - want).abs() < 1e-9 * (1.0 + want.abs()),
            "{} vs {want}",
            s[e]
        );
    }
    let p = m.predict_proba(xte.view()).unwrap();
    assert!(p
        .iter()
        .zip(s.iter())
        .all(|(p, s)| (*p > 0.5) == (*s > 0.0)));
    // The fitted pipeline keeps its settings.
    assert_eq!(
        m.params(),
        Some(&PipelineParams::preset("mdm", 64.0).unwrap())
    );
}

#[test]
fn svm_gamma_factor_scales_the_resolved_gamma() {
    let (x, y) = synthetic(120, 6);
    let gamma = |factor: f64| {
        let mut p = PipelineParams::preset("paper-svm", 64.0).unwrap();
        p.main.svm_gamma_scale = factor;
        match p.fit(x.view(), &y).unwrap().classifier() {
            Classifier::Svm(s) => s.gamma().unwrap(),
            _ => unreachable!(),
        }
    };
    let (g1, g05) = (gamma(1.0), gamma(0.5));
    assert!((g05 - 0.5 * g1).abs() < 1e-12 * g1, "{g05} vs {g1}");
    let mut p = PipelineParams::preset("paper-svm", 64.0).unwrap();
    p.main.svm_gamma_scale = 0.0;
    assert!(p.fit(x.view(), &y).is_err());
    // Settings saved without the field read as the plain 'scale'.
    let text = serde_json::to_string(&p)
        .unwrap()
        .replace(",\"svm_gamma_scale\":0.0", "");
    assert!(!text.contains("svm_gamma_scale"));
    let back: PipelineParams = serde_json::from_str(&text).unwrap();
    assert_eq!(back.main.svm_gamma_scale, 1.0);
}

#[test]
fn the_peer_window_and_steps_follow_numpy_and_python() {
    // numpy's x[onset : onset + round(0.8·sfreq)]: 205 samples at 256 Hz, 128 at 160 Hz
    let peer = Preprocess::peer();
    assert_eq!(peer.window(256.0), (0, 205));
    assert_eq!(peer.window(160.0), (0, 128));
    // MNE's both-ends-included window online: 0–0.6 s at 500 Hz is 301 samples
    assert_eq!(Preprocess::online().window(500.0), (0, 301));
    for (pre, sfreq) in [(peer, 256.0), (peer, 160.0), (Preprocess::online(), 500.0)] {
        let (first, n) = pre.window(sfreq);
        let (a, b) = pre.epochs_params().offsets(sfreq).unwrap();
        assert_eq!((a, b - a + 1), (first, n as i64));
    }
    // a model saved before `end_exclusive` existed reads as both ends included
    let old: Preprocess = serde_json::from_str(
        r#"{"band":{"order":4,"band":{"Bandpass":{"l_freq":0.5,"h_freq":20.0}}},"tmin":0.0,"tmax":0.8}"#,
    )
    .unwrap();
    assert_eq!(old.window(256.0), (0, 206));
    // Python's round(160 / 64) = round(2.5) = 2 (ties to even), not 3
    let step =
        |name: &str, sfreq: f64| match PipelineParams::preset(name, sfreq).unwrap().main.features {
            FeatureParams::XdawnTangent(f) => f.step,
            FeatureParams::XdawnCovariances(f) => f.step,
            _ => unreachable!("an xDAWN preset"),
        };
    assert_eq!((step("riemann", 160.0), step("mdm", 160.0)), (2, 2));
    assert_eq!((step("riemann", 256.0), step("riemann", 96.0)), (4, 2));
}

#[test]
fn wrong_version_and_layout_are_clear_errors() {
    let (x, y) = synthetic(60, 3);
    let m = PipelineParams::preset("lda", 64.0)
        .unwrap()
        .fit(x.view(), &y)
        .unwrap();
    let model = Model::new(Preprocess::peer(), 64.0, vec!["Cz".into(); 4], m);
    let text = model.to_json().replace(
        &format!("\"format_version\":{MODEL_FORMAT_VERSION}"),
        "\"format_version\":99",
    );
    assert!(matches!(
        Model::from_json(&text),
        Err(DecodeError::ModelVersion {
            found: Some(99),
            expected: MODEL_FORMAT_VERSION
        })
    ));
    assert!(matches!(
        model.check_layout(&vec!["Cz".to_string(); 3], 64.0),
        Err(DecodeError::LayoutMismatch { .. })
    ));
    let wrong = Array3::zeros((2, 3, 64));
    assert!(matches!(
        model.pipeline.decision_function(wrong.view()),
        Err(DecodeError::ShapeMismatch { .. })
    ));
    assert!(PipelineParams::preset("nope", 64.0).is_err());
}

/// A single xDAWN pipeline reads every k-th sample only: cross-validation fits it on copies of
/// those samples, and its scores are exactly those of the pipeline fitted on full copies.
#[test]
fn a_decimating_pipeline_scores_the_same_fitted_on_decimated_copies() {
    let (x, y) = synthetic(120, 9);
    let tr: Vec<usize> = (0..120).filter(|i| i % 4 != 1).collect();
    let te: Vec<usize> = (0..120).filter(|i| i % 4 == 1).collect();
    let ytr: Vec<bool> = tr.iter().map(|&i| y[i]).collect();
    for name in ["riemann", "mdm"] {
        let p = PipelineParams::preset(name, 256.0).unwrap();
        let (k, _) = p
            .decimated()
            .expect("an xDAWN front reading every k-th sample");
        assert_eq!(k, 4, "{name}");
        let whole = p
            .fit(x.select(Axis(0), &tr).view(), &ytr)
            .unwrap()
            .decision_function(x.select(Axis(0), &te).view())
            .unwrap();
        let mut cache = FrontCache::new(x.view());
        let cached = p
            .fit_score_cached(&mut cache, &tr, &ytr, None, &te)
            .unwrap()
            .scores;
        assert_eq!(cached, whole, "{name}");
    }
    for name in ["lda", "lda+riemann", "stack", "paper"] {
        let p = PipelineParams::preset(name, 256.0).unwrap();
        assert!(p.decimated().is_none(), "{name} reads every sample");
    }
    assert!(PipelineParams::preset("riemann", 64.0)
        .unwrap()
        .decimated()
        .is_none());
}

/// The stack's inner folds take the amplitude features of its LDA once for all folds and fit
/// its xDAWN members on every 4th sample: its learned combination is exactly the one from
/// fitting each member on full copies of each fold's epochs.
#[test]
fn a_stack_learns_the_same_combination_without_full_copies_per_fold() {
    let (x, y) = synthetic(160, 12);
    let stack = PipelineParams::preset("stack", 256.0).unwrap();
    let Fusion::Stacked { n_folds } = stack.fusion else {
        panic!("stack is stacked");
    };
    let singles: Vec<&SingleParams> = stack.singles().collect();
    assert!(singles[0].stateless_features(x.view().into()).is_some());
    assert!(singles[1].decimated().is_some() && singles[2].decimated().is_some());
    let folds = crate::model_selection::tuning::cv_folds(&y, None, n_folds).unwrap();
    let oof = out_of_fold(&singles, &x, &y, &folds);
    let scaler = StandardScalerParams::default().fit(oof.view()).unwrap();
    let lr = LogisticParams::default()
        .fit(scaler.transform(oof.view()).unwrap().view(), &y)
        .unwrap();
    let fused = stack.fit(x.view(), &y).unwrap();
    let terms: Vec<FusionTerm> = std::iter::once(fused.term)
        .chain(fused.fused().iter().map(|m| m.term))
        .collect();
    for (k, t) in terms.iter().enumerate() {
        assert_eq!(t.center, scaler.mean[k], "member {k}");
        assert_eq!(t.scale, scaler.scale[k], "member {k}");
        assert_eq!(t.weight, lr.coef()[k], "member {k}");
    }
    assert_eq!(fused.fusion_intercept, lr.intercept());
}
