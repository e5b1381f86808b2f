//! The BCI2000 reader against the independent Python reader `shared/peer/bci2000.py`
//! (values stored by `tools/golden/io/make_bci2000_golden.py` in `fixtures/bci2000_golden.json`).

mod common;

use common::{assert_close, bci2000_file, golden};
use oddball_io::read_bci2000;
use serde_json::Value;

const REL: f64 = 1e-9;

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn check(name: &str) {
    let Some(path) = bci2000_file("bci2000 golden", name) else {
        return;
    };
    let g = &golden("bci2000_golden.json")["files"][name];
    let rec = read_bci2000(&path).unwrap();
    let raw = &rec.raw;
    let info = rec.bci2000().unwrap();

    assert_eq!(raw.n_channels() as u64, g["n_channels"].as_u64().unwrap());
    assert_eq!(raw.n_times() as u64, g["n_times"].as_u64().unwrap());
    assert_eq!(raw.sfreq(), g["sfreq"].as_f64().unwrap());
    let names: Vec<&str> = g["ch_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(raw.ch_names(), names.as_slice());
    assert_eq!(
        info.header.header_len as u64,
        g["header"]["HeaderLen"].as_u64().unwrap()
    );
    assert_eq!(
        info.header.statevector_len as u64,
        g["header"]["StatevectorLen"].as_u64().unwrap()
    );

    let data = raw.data();
    let n = raw.n_times();
    let idx: Vec<usize> = g["indices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    for c in 0..raw.n_channels() {
        let row = data.row(c);
        let abs_sum = g["abs_sums"][c].as_f64().unwrap();
        for (k, want) in f64s(&g["first5"][c]).into_iter().enumerate() {
            assert_close(row[k], want, REL, want, &format!("{name} ch{c} sample {k}"));
        }
        for (k, want) in f64s(&g["last5"][c]).into_iter().enumerate() {
            let t = n - 5 + k;
            assert_close(row[t], want, REL, want, &format!("{name} ch{c} sample {t}"));
        }
        for (&t, want) in idx.iter().zip(f64s(&g["at_indices"][c])) {
            assert_close(row[t], want, REL, want, &format!("{name} ch{c} sample {t}"));
        }
        let sum: f64 = row.sum();
        let our_abs: f64 = row.iter().map(|v| v.abs()).sum();
        assert_close(
            sum,
            g["sums"][c].as_f64().unwrap(),
            REL,
            abs_sum,
            &format!("{name} ch{c} sum"),
        );
        assert_close(
            our_abs,
            abs_sum,
            REL,
            abs_sum,
            &format!("{name} ch{c} sum |x|"),
        );
    }

    let ev = raw.events();
    let onsets: Vec<u64> = ev.iter().map(|e| e.onset as u64).collect();
    let codes: Vec<u64> = ev.iter().map(|e| e.code as u64).collect();
    let targets: Vec<bool> = ev.iter().map(|e| e.target.unwrap()).collect();
    let want_on: Vec<u64> = g["events"]["onset"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    let want_code: Vec<u64> = g["events"]["code"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    let want_t: Vec<bool> = g["events"]["target"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_bool().unwrap())
        .collect();
    assert_eq!(onsets, want_on, "{name} onsets");
    assert_eq!(codes, want_code, "{name} codes");
    assert_eq!(targets, want_t, "{name} targets");

    // Every state: its sum and its values at the fixed indices.
    let states = g["states"].as_object().unwrap();
    assert_eq!(info.states.names().len(), states.len());
    for (sname, sv) in states {
        let series = info
            .states
            .get(sname)
            .unwrap_or_else(|| panic!("state {sname} missing"));
        let sum: u64 = series.iter().sum();
        assert_eq!(sum, sv["sum"].as_u64().unwrap(), "{name} state {sname} sum");
        for (&t, want) in idx.iter().zip(sv["at_indices"].as_array().unwrap()) {
            assert_eq!(
                series[t],
                want.as_u64().unwrap(),
                "{name} state {sname}[{t}]"
            );
            assert_eq!(info.states.value_at(sname, t), Some(series[t]));
        }
    }

    // Parameters as the peer parsed them (single values as strings, lists as numbers/strings).
    for (pname, want) in g["params"].as_object().unwrap() {
        let p = info
            .parameters
            .get(pname)
            .unwrap_or_else(|| panic!("parameter {pname} missing"));
        match want {
            Value::String(s) => assert_eq!(p.as_str(), Some(s.as_str()), "{name} {pname}"),
            Value::Array(items) => {
                let got = p.list_items().unwrap();
                assert_eq!(got.len(), items.len(), "{name} {pname}");
                for (gv, wv) in got.iter().zip(items) {
                    match wv {
                        Value::Number(x) => {
                            assert_eq!(gv.parse::<f64>().unwrap(), x.as_f64().unwrap())
                        }
                        Value::String(s) => assert_eq!(gv, s),
                        other => panic!("{other:?}"),
                    }
                }
            }
            other => panic!("unexpected golden parameter {other:?}"),
        }
    }

    match (&rec.speller, g["decoded_text"].as_str()) {
        (Some(sp), Some(text)) => {
            assert_eq!(sp.decode(raw.events()), text, "{name} decoded text");
            assert_eq!(sp.text_to_spell.as_deref(), g["text_to_spell"].as_str());
        }
        (None, None) => {}
        (s, t) => panic!("{name}: speller {s:?} vs golden text {t:?}"),
    }
}

#[test]
fn eeg3_1_matches_peer_reader() {
    check("eeg3_1.dat");
}

#[test]
fn eeg2_1_matches_peer_reader() {
    check("eeg2_1.dat");
}
