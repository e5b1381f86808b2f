//! The Wilcoxon signed-rank test against scipy.stats.wilcoxon 1.17.1 (tools/golden/stats).

use oddball_eval::stats::{wilcoxon, Alternative, WilcoxonMethod};

#[test]
fn wilcoxon_matches_scipy_on_every_case_and_alternative() {
    let text = include_str!("fixtures/wilcoxon_golden.json");
    let golden: serde_json::Value = serde_json::from_str(text).unwrap();
    let cases = golden["cases"].as_array().unwrap();
    assert!(cases.len() >= 10);
    let mut methods = Vec::new();
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let vec = |k: &str| -> Vec<f64> {
            case[k]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        };
        let (x, y) = (vec("x"), vec("y"));
        for (key, alt) in [
            ("two-sided", Alternative::TwoSided),
            ("greater", Alternative::Greater),
            ("less", Alternative::Less),
        ] {
            let r = wilcoxon(&x, &y, alt).unwrap();
            let want_stat = case[key]["statistic"].as_f64().unwrap();
            let want_p = case[key]["pvalue"].as_f64().unwrap();
            assert_eq!(r.statistic, want_stat, "{name} {key}: statistic");
            assert!(
                (r.pvalue - want_p).abs() <= 1e-12 * want_p.max(1e-300) + 1e-15,
                "{name} {key}: p {} vs scipy {want_p} ({:?})",
                r.pvalue,
                r.method
            );
            methods.push(r.method);
        }
    }
    // Every branch of scipy's method="auto" is exercised.
    for m in [
        WilcoxonMethod::Exact,
        WilcoxonMethod::Permutation,
        WilcoxonMethod::Normal,
    ] {
        assert!(methods.contains(&m), "no case used {m:?}");
    }
}
