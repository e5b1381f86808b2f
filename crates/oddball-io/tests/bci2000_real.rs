//! The BCI2000 reader on the real sample files: documented facts, speller decoding, states,
//! v1.1 variants made from the real files, and errors on truncated or mangled copies.

mod common;

use common::{bci2000_file, TempDir};
use oddball_io::{
    read, read_bci2000, read_bci2000_with, Bci2000Options, DataFormat, Format, IoError,
};

const EEG3_NAMES: [&str; 8] = ["Fz", "Cz", "P3", "Pz", "P4", "PO7", "Oz", "PO8"];

#[test]
fn eeg3_speller_facts() {
    for (name, text, online) in [
        ("eeg3_1.dat", "T3OF", "TONF"),
        ("eeg3_2.dat", "6MK?", "5MQ?"),
    ] {
        let Some(path) = bci2000_file("eeg3_speller_facts", name) else {
            return;
        };
        let rec = read(&path).unwrap();
        assert_eq!(rec.format, Format::Bci2000);
        let raw = &rec.raw;
        assert_eq!(raw.ch_names(), EEG3_NAMES);
        assert_eq!(raw.sfreq(), 256.0);
        assert_eq!(raw.n_times(), 56840);
        assert_eq!(raw.events().len(), 720, "{name} flashes");
        assert_eq!(raw.events().n_targets(), 120, "{name} targets");
        assert_eq!(raw.events().n_nontargets(), 600);
        let counts = raw.events().counts_by_code();
        assert_eq!(
            counts.keys().copied().collect::<Vec<_>>(),
            (1..=12).collect::<Vec<u32>>()
        );
        assert!(counts.values().all(|&n| n == 60), "{counts:?}");

        let sp = rec.speller.as_ref().expect("speller");
        assert_eq!((sp.n_rows(), sp.n_cols()), (6, 6));
        assert_eq!(sp.flashes_per_character, Some(180));
        assert_eq!(sp.text_to_spell.as_deref(), Some(text));
        let rows: Vec<String> = sp.matrix().iter().map(|r| r.concat()).collect();
        assert_eq!(
            rows,
            ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789?"]
        );
        assert_eq!(sp.decode(raw.events()), text, "{name}");

        // Each character's 180 flashes lie inside one PhaseInSequence == 2 stretch.
        let info = rec.bci2000().unwrap();
        let phase = info.states.get("PhaseInSequence").unwrap();
        let blocks = sp.character_blocks(raw.events());
        assert_eq!(blocks.len(), 4);
        let mut runs = Vec::new();
        for t in 0..phase.len() {
            if phase[t] == 2 && (t == 0 || phase[t - 1] != 2) {
                runs.push((
                    t,
                    (t..phase.len())
                        .find(|&u| phase[u] != 2)
                        .unwrap_or(phase.len()),
                ));
            }
        }
        assert_eq!(runs.len(), 4);
        for (block, (a, b)) in blocks.iter().zip(&runs) {
            assert_eq!(block.len(), 180);
            assert!(
                block.iter().all(|e| (*a..*b).contains(&e.onset)),
                "{name}: block outside {a}..{b}"
            );
        }

        // The online classifier's choices (state SelectedTarget, 1-based into TargetDefinitions).
        let sel = info.states.get("SelectedTarget").unwrap();
        let mut chosen = String::new();
        for t in 0..sel.len() {
            if sel[t] != 0 && (t == 0 || sel[t - 1] != sel[t]) {
                let k = sel[t] as usize - 1;
                chosen.push_str(sp.symbol(k / 6, k % 6).unwrap());
            }
        }
        assert_eq!(chosen, online, "{name} SelectedTarget");

        // Parameters keep units and lists.
        let p = &info.parameters;
        assert_eq!(p.get("SamplingRate").unwrap().as_str(), Some("256"));
        assert_eq!(p.get("SamplingRate").unwrap().trailing[0], "256Hz");
        assert_eq!(
            p.get("ChannelNames").unwrap().list_items().unwrap(),
            EEG3_NAMES
        );
        if name == "eeg3_1.dat" {
            assert_eq!(
                p.get("StorageTime").unwrap().as_str(),
                Some("Thu Mar 05 11:56:24 2009")
            );
        }
        assert_eq!(p.get("EpochLength").unwrap().as_str(), Some("800ms"));
        assert_eq!(info.gains, vec![0.019; 8]);
        assert_eq!(info.offsets, vec![0.0; 8]);
        assert_eq!(info.header.data_format, DataFormat::Int16);
        assert_eq!(info.header.version, "1.0");
        assert_eq!(info.states.names().len(), 27);
        assert!(info.states.get("NoSuchState").is_none());
        let all = info.states.all();
        assert_eq!(all.len(), 27);
        assert_eq!(all["StimulusCode"].len(), 56840);
    }
}

#[test]
fn eeg2_oddball_facts() {
    for name in ["eeg2_1.dat", "eeg2_2.dat"] {
        let Some(path) = bci2000_file("eeg2_oddball_facts", name) else {
            return;
        };
        let rec = read_bci2000(&path).unwrap();
        let raw = &rec.raw;
        assert_eq!(raw.n_channels(), 64);
        assert_eq!(raw.sfreq(), 160.0);
        assert_eq!(raw.n_times(), 25296);
        assert_eq!(raw.ch_names()[0], "ch1");
        assert_eq!(raw.ch_names()[63], "ch64");
        assert_eq!(raw.events().len(), 100);
        assert_eq!(raw.events().n_targets(), 20);
        let counts = raw.events().counts_by_code();
        assert_eq!(counts.get(&1), Some(&20));
        assert_eq!(counts.get(&2), Some(&80));
        assert!(raw.events().iter().all(|e| e.target == Some(e.code == 1)));
        assert!(rec.speller.is_none());
        let info = rec.bci2000().unwrap();
        assert_eq!(info.gains[0], 0.00776);
        assert_eq!(info.offsets[0], -70.0);
        assert_eq!(info.offsets[63], -263.0);

        let named = read_bci2000_with(
            &path,
            &Bci2000Options {
                standard_64_names: true,
            },
        )
        .unwrap();
        assert_eq!(named.raw.channel_index("Cz").unwrap(), 10);
        assert_eq!(named.raw.channel_index("Pz").unwrap(), 50);
        assert_eq!(named.raw.data(), raw.data());
    }
}

// ---------------------------------------------------------------------------------------------
// Edited copies of eeg3_1.

fn header_len(bytes: &[u8]) -> usize {
    let first =
        std::str::from_utf8(&bytes[..bytes.iter().position(|&b| b == b'\n').unwrap()]).unwrap();
    let v = first
        .split_whitespace()
        .skip_while(|w| *w != "HeaderLen=")
        .nth(1)
        .unwrap();
    v.parse().unwrap()
}

/// The file with its header text (after the first line) edited, a new first line made by
/// `first(header_len)`, and the body made by `body(old_body)`; HeaderLen is recomputed.
fn rebuild(
    bytes: &[u8],
    first: impl Fn(usize) -> String,
    edit: impl Fn(&str) -> String,
    body: impl Fn(&[u8]) -> Vec<u8>,
) -> Vec<u8> {
    let hl = header_len(bytes);
    let eol = bytes.iter().position(|&b| b == b'\n').unwrap();
    let rest = edit(std::str::from_utf8(&bytes[eol + 1..hl]).unwrap());
    let mut n = first(0).len() + 2 + rest.len();
    while first(n).len() + 2 + rest.len() != n {
        n = first(n).len() + 2 + rest.len();
    }
    let mut out = format!("{}\r\n{rest}", first(n)).into_bytes();
    assert_eq!(out.len(), n);
    out.extend(body(&bytes[hl..]));
    out
}

fn v10(n: usize) -> String {
    format!("HeaderLen= {n} SourceCh= 8 StatevectorLen= 36")
}

fn invalid_field(e: &IoError) -> (&str, u64) {
    match e {
        IoError::InvalidField { field, offset, .. } => (field.as_str(), *offset),
        other => panic!("expected InvalidField, got {other}"),
    }
}

fn truncated(e: &IoError) -> (&str, u64) {
    match e {
        IoError::Truncated { field, offset, .. } => (field.as_str(), *offset),
        other => panic!("expected Truncated, got {other}"),
    }
}

fn line_offset(bytes: &[u8], needle: &str) -> u64 {
    let text: String = bytes.iter().map(|&b| b as char).collect();
    let at = text.find(needle).unwrap();
    (text[..at].rfind('\n').unwrap() + 1) as u64
}

#[test]
fn v11_data_formats_read_like_v10() {
    let Some(path) = bci2000_file("v11_data_formats", "eeg3_1.dat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let base = read_bci2000(&path).unwrap();
    let tmp = TempDir::new("bci2000-v11");
    let record = 8 * 2 + 36;
    for (fmt, width) in [("int16", 2usize), ("int32", 4), ("float32", 4)] {
        let first = |n: usize| {
            format!("BCI2000V= 1.1 HeaderLen= {n} SourceCh= 8 StatevectorLen= 36 DataFormat= {fmt}")
        };
        let body = |b: &[u8]| {
            let mut out = Vec::new();
            for rec in b.chunks(record) {
                for s in rec[..16].chunks(2) {
                    let v = i16::from_le_bytes([s[0], s[1]]);
                    match fmt {
                        "int16" => out.extend(v.to_le_bytes()),
                        "int32" => out.extend((v as i32).to_le_bytes()),
                        _ => out.extend((v as f32).to_le_bytes()),
                    }
                }
                out.extend(&rec[16..]);
            }
            out
        };
        let file = tmp.write(
            &format!("v11_{fmt}.dat"),
            &rebuild(&bytes, first, |s| s.to_string(), body),
        );
        let rec = read(&file).unwrap();
        let info = rec.bci2000().unwrap();
        assert_eq!(info.header.version, "1.1");
        assert_eq!(info.header.data_format.bytes(), width);
        assert_eq!(rec.raw.data(), base.raw.data(), "{fmt}");
        assert_eq!(rec.raw.events(), base.raw.events(), "{fmt}");
        assert_eq!(rec.speller, base.speller);
    }
}

#[test]
fn gains_with_units_and_single_values() {
    let Some(path) = bci2000_file("gains_with_units", "eeg3_1.dat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let base = read_bci2000(&path).unwrap();
    let tmp = TempDir::new("bci2000-units");
    let old = "SourceChGain= 8 0.019 0.019 0.019 0.019 0.019 0.019 0.019 0.019";
    for (new, factor) in [
        (
            "SourceChGain= 8 19muV 19muV 19muV 19muV 19muV 19muV 19muV 19muV",
            1000.0,
        ),
        ("SourceChGain= 1 0.019uV", 1.0),
        (
            "SourceChGain= 8 0.000019mV 0.019 0.019 0.019 0.019 0.019 0.019 0.019",
            1.0,
        ),
    ] {
        let file = tmp.write(
            "g.dat",
            &rebuild(&bytes, v10, |s| s.replace(old, new), |b| b.to_vec()),
        );
        let rec = read_bci2000(&file).unwrap();
        let (a, b) = (rec.raw.data(), base.raw.data());
        for (x, y) in a.iter().zip(b.iter()) {
            assert!(
                (x - y * factor).abs() <= 1e-12 * (y * factor).abs(),
                "{new}: {x} vs {}",
                y * factor
            );
        }
    }
    let bad = rebuild(
        &bytes,
        v10,
        |s| {
            s.replace(
                old,
                "SourceChGain= 8 0.019 0.019 0.019 0.019 0.019 0.019 0.019 0.019furlong",
            )
        },
        |b| b.to_vec(),
    );
    let e = read_bci2000(tmp.write("bad.dat", &bad)).unwrap_err();
    let (field, offset) = invalid_field(&e);
    assert_eq!(field, "parameter SourceChGain[7]");
    assert_eq!(offset, line_offset(&bad, "SourceChGain="));
    let short = rebuild(
        &bytes,
        v10,
        |s| s.replace(old, "SourceChGain= 3 1 1 1"),
        |b| b.to_vec(),
    );
    let e = read_bci2000(tmp.write("short.dat", &short)).unwrap_err();
    assert_eq!(invalid_field(&e).0, "parameter SourceChGain");
}

#[test]
fn truncated_copies_name_the_offset() {
    let Some(path) = bci2000_file("truncated_copies", "eeg3_1.dat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let hl = header_len(&bytes) as u64;
    assert_eq!(hl, 27803);
    let record = 52u64;
    let tmp = TempDir::new("bci2000-trunc");
    let cases: Vec<(u64, &str, u64)> = vec![
        (10, "first header line", 0),
        (5000, "header (HeaderLen= 27803)", 0),
        (hl, "sample record 0", hl),
        (hl + 1000, "sample record 19", hl + 19 * record),
        (hl + 1_000_003, "sample record 19230", hl + 19230 * record),
        (
            bytes.len() as u64 - 7,
            "sample record 56839",
            hl + 56839 * record,
        ),
    ];
    for (cut, field, offset) in cases {
        let file = tmp.write("cut.dat", &bytes[..cut as usize]);
        let e = read_bci2000(&file).unwrap_err();
        let (f, o) = truncated(&e);
        assert!(
            f.starts_with(field),
            "cut {cut}: field {f:?}, wanted {field:?}"
        );
        assert_eq!(o, offset, "cut {cut}: {e}");
        let msg = e.to_string();
        assert!(
            msg.contains("cut.dat") && msg.contains(&offset.to_string()),
            "{msg}"
        );
        assert_eq!(e.path(), file.as_path());
    }
}

#[test]
fn mangled_headers_name_the_field() {
    let Some(path) = bci2000_file("mangled_headers", "eeg3_1.dat") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let tmp = TempDir::new("bci2000-mangle");
    let same = |b: &[u8]| b.to_vec();

    // First-line fields.
    let e = read_bci2000(tmp.write(
        "a.dat",
        &rebuild(
            &bytes,
            |n| format!("HeaderLen= {n} SourceCh= x StatevectorLen= 36"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(invalid_field(&e), ("SourceCh", 27));
    let e = read_bci2000(tmp.write(
        "b.dat",
        &rebuild(
            &bytes,
            |n| format!("HeaderLen= {n} SourceCh= -8 StatevectorLen= 36"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(invalid_field(&e).0, "SourceCh");
    let e = read_bci2000(tmp.write(
        "c.dat",
        &rebuild(
            &bytes,
            |n| format!("HeaderLen= {n} StatevectorLen= 36"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(invalid_field(&e).0, "SourceCh");
    let e = read_bci2000(tmp.write(
        "d.dat",
        &rebuild(
            &bytes,
            |n| {
                format!(
                    "BCI2000V= 1.1 HeaderLen= {n} SourceCh= 8 StatevectorLen= 36 DataFormat= int64"
                )
            },
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(invalid_field(&e), ("DataFormat", 74));
    let e = read_bci2000(tmp.write(
        "e.dat",
        &rebuild(
            &bytes,
            |n| format!("BCI2000V= 3.0 HeaderLen= {n} SourceCh= 8 StatevectorLen= 36"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(invalid_field(&e).0, "BCI2000V");
    let e = read_bci2000(tmp.write("f.dat", b"garbage that is not BCI2000")).unwrap_err();
    assert_eq!(invalid_field(&e), ("first header line", 0));

    // Absurd sizes are refused from the file length, before allocating.
    let e = read_bci2000(tmp.write(
        "g.dat",
        &rebuild(
            &bytes,
            |n| format!("HeaderLen= {n} SourceCh= 1000000000000 StatevectorLen= 36"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    let (f, _) = truncated(&e);
    assert!(f.contains("1000000000000 channels"), "{e}");
    let e = read_bci2000(tmp.write(
        "h.dat",
        &rebuild(
            &bytes,
            |n| format!("HeaderLen= {n} SourceCh= 8 StatevectorLen= 18446744073709551615"),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert!(
        matches!(e, IoError::InvalidField { .. } | IoError::Truncated { .. }),
        "{e}"
    );
    let e = read_bci2000(tmp.write(
        "i.dat",
        &rebuild(
            &bytes,
            |_| "HeaderLen= 999999999999 SourceCh= 8 StatevectorLen= 36".into(),
            |s| s.into(),
            same,
        ),
    ))
    .unwrap_err();
    assert_eq!(truncated(&e), ("header (HeaderLen= 999999999999)", 0));

    // Header lines: offsets are those of the line.
    let cases: Vec<(&str, &str, &str)> = vec![
        (
            "StimulusType 1 0 2 0",
            "StimulusType 1 0 2 9",
            "state StimulusType BitLocation",
        ),
        (
            "StimulusType 1 0 2 0",
            "StimulusType 1 0 40 0",
            "state StimulusType ByteLocation",
        ),
        (
            "StimulusType 1 0 2 0",
            "StimulusType 0 0 2 0",
            "state StimulusType Length",
        ),
        (
            "StimulusType 1 0 2 0",
            "StimulusType 1 0 2",
            "state StimulusType definition",
        ),
        (
            "SamplingRate= 256 256Hz",
            "SamplingRate= 0 256Hz",
            "parameter SamplingRate",
        ),
        (
            "SamplingRate= 256 256Hz",
            "SamplingRate= 256parsec 256Hz",
            "parameter SamplingRate",
        ),
        (
            "NumberOfSequences= 15",
            "NumberOfSequences= many",
            "parameter NumberOfSequences",
        ),
        (
            "TargetDefinitions= 36 5",
            "TargetDefinitions= 99 5",
            "parameter TargetDefinitions",
        ),
        (
            "ChannelNames= 8 Fz",
            "ChannelNames= 80 Fz",
            "parameter ChannelNames",
        ),
        (
            "NumMatrixRows= 1 6",
            "NumMatrixRows= 1 7",
            "parameter TargetDefinitions",
        ),
    ];
    for (old, new, field) in cases {
        let file = rebuild(&bytes, v10, |s| s.replacen(old, new, 1), same);
        let e = read_bci2000(tmp.write("m.dat", &file)).unwrap_err();
        let (f, o) = invalid_field(&e);
        assert_eq!(f, field, "{new}: {e}");
        // The matrix-size mismatch is reported at the TargetDefinitions line.
        let at = if new.starts_with("NumMatrixRows") {
            "TargetDefinitions="
        } else {
            new
        };
        assert_eq!(o, line_offset(&file, at), "{new}: {e}");
    }
    // A missing SamplingRate is named.
    let file = rebuild(
        &bytes,
        v10,
        |s| s.replace("SamplingRate=", "SamplingRateX="),
        same,
    );
    let e = read_bci2000(tmp.write("n.dat", &file)).unwrap_err();
    assert!(
        matches!(&e, IoError::Missing { name, .. } if name == "SamplingRate"),
        "{e}"
    );
}
