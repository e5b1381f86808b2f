//! oddball-signal against scipy: reference values from `tools/golden/signal/make_golden.py`
//! (scipy 1.17.1), compared within 1e-9 of each array's peak magnitude.

use ndarray::Array2;
use oddball_signal::decimate::{antialias_filter, decimate};
use oddball_signal::detrend::{detrend, DetrendKind};
use oddball_signal::filter::{Band, SosFilter};
use serde::Deserialize;

#[derive(Deserialize)]
struct Golden {
    x: Vec<Vec<f64>>,
    butter: Vec<Butter>,
    cheby1: Vec<Cheby>,
    detrend: Detrend,
    decimate: Vec<Decimated>,
}

#[derive(Deserialize)]
struct Butter {
    name: String,
    order: usize,
    btype: String,
    wn: Vec<f64>,
    fs: f64,
    sos: Vec<Vec<f64>>,
    zi: Vec<Vec<f64>>,
    sosfiltfilt: Vec<Vec<f64>>,
    sosfilt_rest: Option<Vec<Vec<f64>>>,
    sosfilt_steady: Option<Vec<Vec<f64>>>,
}

#[derive(Deserialize)]
struct Cheby {
    q: usize,
    sos: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct Detrend {
    constant: Vec<Vec<f64>>,
    linear: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct Decimated {
    q: usize,
    y: Vec<Vec<f64>>,
}

const TOL: f64 = 1e-9;

fn golden() -> Golden {
    let text = include_str!("fixtures/signal_golden.json");
    serde_json::from_str(text).expect("fixture parses")
}

fn to_array(rows: &[Vec<f64>]) -> Array2<f64> {
    let n = rows[0].len();
    Array2::from_shape_fn((rows.len(), n), |(r, c)| rows[r][c])
}

/// Largest difference relative to the reference array's peak magnitude.
fn assert_close(what: &str, ours: &Array2<f64>, reference: &[Vec<f64>]) {
    let reference = to_array(reference);
    assert_eq!(ours.dim(), reference.dim(), "{what}: shape");
    let peak = reference
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    let worst = ours
        .iter()
        .zip(reference.iter())
        .map(|(a, b)| (a - b).abs() / peak)
        .fold(0.0f64, f64::max);
    assert!(
        worst <= TOL,
        "{what}: worst relative error {worst:e} > {TOL:e}"
    );
}

fn band(b: &Butter) -> Band {
    match b.btype.as_str() {
        "bandpass" => Band::Bandpass {
            l_freq: b.wn[0],
            h_freq: b.wn[1],
        },
        "bandstop" => Band::Bandstop {
            l_freq: b.wn[0],
            h_freq: b.wn[1],
        },
        "lowpass" => Band::Lowpass { h_freq: b.wn[0] },
        "highpass" => Band::Highpass { l_freq: b.wn[0] },
        other => panic!("unknown btype {other}"),
    }
}

#[test]
fn butterworth_design_and_filtering_match_scipy() {
    let g = golden();
    let x = to_array(&g.x);
    assert_eq!(g.butter.len(), 7);
    for b in &g.butter {
        let f = SosFilter::butter(b.order, band(b), b.fs).unwrap();
        let sos = Array2::from_shape_fn((f.n_sections(), 6), |(r, c)| f.sections()[r][c]);
        assert_close(&format!("{} sos", b.name), &sos, &b.sos);
        let zi = Array2::from_shape_fn((f.n_sections(), 2), |(r, c)| f.zi()[r][c]);
        assert_close(&format!("{} zi", b.name), &zi, &b.zi);
        assert_close(
            &format!("{} sosfiltfilt", b.name),
            &f.sosfiltfilt(x.view()).unwrap(),
            &b.sosfiltfilt,
        );
        if let Some(rest) = &b.sosfilt_rest {
            assert_close(
                &format!("{} sosfilt", b.name),
                &f.sosfilt(x.view(), false),
                rest,
            );
        }
        if let Some(steady) = &b.sosfilt_steady {
            assert_close(
                &format!("{} sosfilt steady", b.name),
                &f.sosfilt(x.view(), true),
                steady,
            );
        }
    }
}

#[test]
fn chebyshev_antialias_design_matches_scipy() {
    let g = golden();
    for c in &g.cheby1 {
        let f = antialias_filter(c.q).unwrap();
        let sos = Array2::from_shape_fn((f.n_sections(), 6), |(r, k)| f.sections()[r][k]);
        assert_close(&format!("cheby1 q={}", c.q), &sos, &c.sos);
    }
}

#[test]
fn decimate_matches_scipy() {
    let g = golden();
    let x = to_array(&g.x);
    for d in &g.decimate {
        assert_close(
            &format!("decimate q={}", d.q),
            &decimate(x.view(), d.q).unwrap(),
            &d.y,
        );
    }
}

#[test]
fn detrend_matches_scipy() {
    let g = golden();
    let mut c = to_array(&g.x);
    detrend(c.view_mut(), DetrendKind::Constant);
    assert_close("detrend constant", &c, &g.detrend.constant);
    let mut l = to_array(&g.x);
    detrend(l.view_mut(), DetrendKind::Linear);
    assert_close("detrend linear", &l, &g.detrend.linear);
}
