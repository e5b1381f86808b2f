//! Polyphase resampling against scipy: `scipy.signal.resample_poly` (scipy 1.17.1, from
//! `tools/golden/resample/make_golden.py`) on two channels with DC offsets, five up/down
//! factors and both paddings, compared within 1e-10 of each array's peak magnitude.

use ndarray::Array2;
use oddball_signal::resample::{resample_poly, resample_raw, Pad};
use oddball_signal::{Event, Events, Raw};
use serde::Deserialize;

#[derive(Deserialize)]
struct Golden {
    x: Vec<Vec<f64>>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    up: u64,
    down: u64,
    padtype: String,
    y: Vec<Vec<f64>>,
}

fn array(rows: &[Vec<f64>]) -> Array2<f64> {
    Array2::from_shape_fn((rows.len(), rows[0].len()), |(r, c)| rows[r][c])
}

fn golden() -> Golden {
    let text = include_str!("fixtures/resample_golden.json");
    serde_json::from_str(text).expect("the fixture parses")
}

#[test]
fn resample_poly_matches_scipy() {
    let g = golden();
    let x = array(&g.x);
    assert_eq!(g.cases.len(), 10);
    for c in &g.cases {
        let pad = match c.padtype.as_str() {
            "constant" => Pad::Constant,
            "mean" => Pad::Mean,
            other => panic!("padtype {other}"),
        };
        let y = resample_poly(x.view(), c.up, c.down, pad).unwrap();
        let want = array(&c.y);
        assert_eq!(y.dim(), want.dim(), "{}/{} {}", c.up, c.down, c.padtype);
        let peak = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = (&y - &want).iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            err <= 1e-10 * peak,
            "{}/{} {}: max error {err:e} of peak {peak}",
            c.up,
            c.down,
            c.padtype
        );
    }
}

#[test]
fn a_recording_moves_to_another_rate_with_its_events() {
    let g = golden();
    let x = array(&g.x);
    let events = Events::new(vec![Event::new(10, 1).with_target(true), Event::new(95, 2)]);
    let raw = Raw::new(x.clone(), 160.0, vec!["Cz".into(), "Pz".into()], events).unwrap();
    let r = resample_raw(&raw, 256.0).unwrap();
    assert_eq!(r.sfreq(), 256.0);
    assert_eq!(r.n_times(), 156); // ceil(97 · 8 / 5)
    assert_eq!(r.ch_names(), raw.ch_names());
    let onsets: Vec<(usize, u32, Option<bool>)> = r
        .events()
        .iter()
        .map(|e| (e.onset, e.code, e.target))
        .collect();
    assert_eq!(onsets, vec![(16, 1, Some(true)), (152, 2, None)]);
    // The samples are scipy's with padtype="mean".
    let mean = g
        .cases
        .iter()
        .find(|c| (c.up, c.down, c.padtype.as_str()) == (8, 5, "mean"))
        .unwrap();
    let want = array(&mean.y);
    let err = (r.data() - &want)
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(err < 1e-9, "{err:e}");
    // Rates whose ratio is not a small fraction are refused, naming them.
    let e = resample_raw(&raw, 1000.0 / 3.0).unwrap_err().to_string();
    assert!(e.contains("160 Hz") && e.contains("333.3"), "{e}");
}
