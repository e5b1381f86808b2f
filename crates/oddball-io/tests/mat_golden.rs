//! The MAT reader against scipy.io.loadmat (fixtures and golden.json from
//! tools/golden/mat/make_golden.py): every variable's class, stored type, shape and values, char
//! arrays, structs, struct arrays and cells, in v5 (uncompressed), v7 (zlib), hand-written narrow
//! (class double stored as miINT16/miUINT8, small data elements, UTF-8 chars) little- and
//! big-endian files; and the v7.3 refusal. Element padding and small data elements against
//! the fixtures of tools/golden/mat/make_padding.py (padding_golden.json).

mod common;

use common::{fixture, golden};
use oddball_io::mat::{MatArray, MatClass, MatNumbers, MatType, MatValue};
use oddball_io::{read_mat_file, IoError};
use serde_json::Value;

fn numpy_name(t: MatType, complex: bool) -> &'static str {
    match (t, complex) {
        (MatType::Int8, _) => "int8",
        (MatType::UInt8, _) => "uint8",
        (MatType::Int16, _) => "int16",
        (MatType::UInt16, _) => "uint16",
        (MatType::Int32, _) => "int32",
        (MatType::UInt32, _) => "uint32",
        (MatType::Int64, _) => "int64",
        (MatType::UInt64, _) => "uint64",
        (MatType::Single, false) => "float32",
        (MatType::Double, false) => "float64",
        (MatType::Single, true) => "complex64",
        (MatType::Double, true) => "complex128",
    }
}

fn matlab_class(c: MatClass) -> &'static str {
    match c {
        MatClass::Double => "double",
        MatClass::Single => "single",
        MatClass::Int8 => "int8",
        MatClass::UInt8 => "uint8",
        MatClass::Int16 => "int16",
        MatClass::UInt16 => "uint16",
        MatClass::Int32 => "int32",
        MatClass::UInt32 => "uint32",
        MatClass::Int64 => "int64",
        MatClass::UInt64 => "uint64",
        MatClass::Logical => "logical",
        MatClass::Char => "char",
        MatClass::Struct => "struct",
        MatClass::Cell => "cell",
        MatClass::Object => "object",
        MatClass::Sparse => "sparse",
    }
}

/// The values of an integer array exactly (as i128, so that u64 and i64 both fit).
fn ints(n: &MatNumbers) -> Vec<i128> {
    match n {
        MatNumbers::U64(v) => v.iter().map(|&x| i128::from(x)).collect(),
        other => other.to_i64().into_iter().map(i128::from).collect(),
    }
}

fn check(g: &Value, a: &MatArray, at: &str) {
    let shape: Vec<usize> = g["shape"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(a.dims, shape, "{at}: shape");
    match (g["kind"].as_str().unwrap(), &a.value) {
        ("numeric", MatValue::Numeric { class, real, imag }) => {
            if let Some(w) = g.get("whos_class") {
                assert_eq!(matlab_class(*class), w.as_str().unwrap(), "{at}: class");
            }
            assert_eq!(
                numpy_name(real.stored_type(), imag.is_some()),
                g["stored"].as_str().unwrap(),
                "{at}: stored type"
            );
            let values = g["values"].as_array().unwrap();
            assert_eq!(real.len(), values.len(), "{at}: count");
            match imag {
                Some(im) => {
                    for (i, v) in values.iter().enumerate() {
                        let re_im = v.as_array().unwrap();
                        assert_eq!(real.get_f64(i), re_im[0].as_f64(), "{at}[{i}] real");
                        assert_eq!(im.get_f64(i), re_im[1].as_f64(), "{at}[{i}] imag");
                    }
                }
                None if values.iter().all(|v| v.is_i64() || v.is_u64()) => {
                    let want: Vec<i128> = values
                        .iter()
                        .map(|v| {
                            v.as_i64()
                                .map(i128::from)
                                .unwrap_or_else(|| i128::from(v.as_u64().unwrap()))
                        })
                        .collect();
                    assert_eq!(ints(real), want, "{at}: values");
                }
                None => {
                    let want: Vec<f64> = values.iter().map(|v| v.as_f64().unwrap()).collect();
                    assert_eq!(real.to_f64(), want, "{at}: values");
                }
            }
        }
        ("char", MatValue::Char(chars)) => {
            let want: String = g["chars"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_str().unwrap())
                .collect();
            assert_eq!(chars.iter().collect::<String>(), want, "{at}: chars");
        }
        ("struct", MatValue::Struct { fields, values }) => {
            let want: Vec<&str> = g["fields"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| f.as_str().unwrap())
                .collect();
            assert_eq!(fields, &want, "{at}: fields");
            let elements = g["elements"].as_array().unwrap();
            assert_eq!(values.len(), elements.len() * fields.len(), "{at}: values");
            for (e, ge) in elements.iter().enumerate() {
                for (f, name) in fields.iter().enumerate() {
                    check(
                        &ge[name.as_str()],
                        &values[e * fields.len() + f],
                        &format!("{at}({}).{name}", e + 1),
                    );
                }
            }
        }
        ("cell", MatValue::Cell(cells)) => {
            let want = g["cells"].as_array().unwrap();
            assert_eq!(cells.len(), want.len(), "{at}: cells");
            for (i, (gc, c)) in want.iter().zip(cells).enumerate() {
                check(gc, c, &format!("{at}{{{}}}", i + 1));
            }
        }
        (kind, v) => panic!("{at}: scipy reads {kind}, we read {v:?}"),
    }
}

#[test]
fn every_fixture_reads_as_scipy_reads_it() {
    let gold = golden("mat/golden.json");
    let files = gold["files"].as_object().unwrap();
    assert_eq!(files.len(), 5);
    for (name, g) in files {
        let file = read_mat_file(fixture(&format!("mat/{name}"))).unwrap();
        assert_eq!(file.header.text, g["header"].as_str().unwrap().trim_end());
        let order: Vec<&str> = g["order"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert_eq!(file.names(), order, "{name}: variables");
        for var in &file.variables {
            check(
                &g["variables"][var.name.as_str()],
                &var.array,
                &format!("{name}:{}", var.name),
            );
        }
        assert_eq!(file.header.big_endian, name == "narrow_be.mat");
        let compressed = file.variables.iter().filter(|v| v.compressed).count();
        let want = if name == "v7.mat" || name == "bci_small.mat" {
            order.len()
        } else {
            0
        };
        assert_eq!(compressed, want, "{name}: compressed variables");
    }
}

#[test]
fn narrow_storage_keeps_the_stored_type_and_the_class() {
    let file = read_mat_file(fixture("mat/narrow.mat")).unwrap();
    let sig = &file.get("sig").unwrap().array;
    let MatValue::Numeric { class, real, .. } = &sig.value else {
        panic!("{sig:?}")
    };
    assert_eq!(*class, MatClass::Double);
    assert_eq!(real, &MatNumbers::I16(vec![-128, 64, 160, 608, -32, 1000]));
    assert_eq!(file.get("utf").unwrap().array.char_rows().unwrap(), ["aµb"]);
    let v5 = read_mat_file(fixture("mat/v5.mat")).unwrap();
    assert_eq!(
        v5.get("text2").unwrap().array.char_rows().unwrap(),
        ["ab", "cd"]
    );
}

/// The tiny BCI Competition layout file: events at `Flashing` 0 → 1, columns-first codes, the
/// targets spell "BZ".
#[test]
fn bci_layout_fixture_reads_as_a_speller_recording() {
    let rec = oddball_io::read(fixture("mat/bci_small.mat")).unwrap();
    let raw = &rec.raw;
    assert_eq!(raw.ch_names(), ["ch1", "ch2", "ch3"]);
    assert_eq!(raw.sfreq(), 240.0);
    assert_eq!(raw.n_times(), 700);
    assert_eq!(raw.events().len(), 48);
    assert_eq!(raw.events().n_targets(), 8);
    let g = &golden("mat/golden.json")["files"]["bci_small.mat"]["variables"];
    let signal: Vec<f64> = g["signal"]["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // Column-major n_times × n_channels is the (n_channels, n_times) data row by row.
    assert_eq!(raw.data().iter().copied().collect::<Vec<_>>(), signal);
    let flashing = g["Flashing"]["values"].as_array().unwrap();
    for e in raw.events().iter() {
        assert_eq!(flashing[e.onset].as_u64(), Some(1));
        assert_eq!(flashing[e.onset - 1].as_u64(), Some(0));
    }
    let sp = rec.speller.as_ref().unwrap();
    assert_eq!(sp.flashes_per_character, Some(24));
    assert_eq!(sp.decode(raw.events()), "BZ");
    assert_eq!(rec.mat().unwrap().strings["filename"], "bci_small.mat");
}

#[test]
fn a_v73_file_is_refused_naming_the_version() {
    let gold = golden("mat/golden.json");
    assert!(gold["v73_scipy"]
        .as_str()
        .unwrap()
        .starts_with("NotImplementedError"));
    let path = fixture("mat/v73.mat");
    for err in [
        read_mat_file(&path).unwrap_err(),
        oddball_io::read(&path).unwrap_err(),
    ] {
        assert!(matches!(err, IoError::Unsupported { .. }), "{err:?}");
        assert!(err.to_string().contains("version 7.3"), "{err}");
    }
}

/// Element padding and small data elements as scipy reads them (fixtures and
/// padding_golden.json from tools/golden/mat/make_padding.py): odd lengths, 1- to 4-byte small
/// elements and compressed variables back to back as savemat writes them; a variable at an odd
/// offset after an unpadded compressed one (little- and big-endian); a top-level variable that
/// ends unpadded. Where scipy refuses (padding after a compressed variable, or written but not
/// counted), the reader refuses too, naming the byte where scipy found no tag.
#[test]
fn element_padding_reads_as_scipy_reads_it() {
    let gold = golden("mat/padding/padding_golden.json");
    let files = gold["files"].as_object().unwrap();
    assert_eq!(files.len(), 8);
    let mut read = 0;
    for (name, g) in files {
        let path = fixture(&format!("mat/padding/{name}"));
        let got = read_mat_file(&path);
        if let Some(e) = g.get("error") {
            let err = got.expect_err(name);
            let at = gold["bad_tag_at"][name.as_str()].as_u64().unwrap();
            let offset = match &err {
                IoError::InvalidField { offset, .. } | IoError::Truncated { offset, .. } => *offset,
                other => panic!("{name}: {other:?}"),
            };
            assert_eq!(offset, at, "{name}: scipy: {e}; we: {err}");
            continue;
        }
        let file = got.unwrap_or_else(|e| panic!("{name}: {e}"));
        let order: Vec<&str> = g["order"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert_eq!(file.names(), order, "{name}: variables");
        for var in &file.variables {
            check(
                &g["variables"][var.name.as_str()],
                &var.array,
                &format!("{name}:{}", var.name),
            );
        }
        read += 1;
    }
    assert_eq!(read, 5, "files scipy reads");
}
