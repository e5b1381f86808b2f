//! EDF, EDF+ and BDF(+) files: a reader and an EDF+ writer, written from scratch.
//!
//! # Why not `edf-rs`
//! The project's dependency list named `edf-rs` (0.2.0). It builds and reads EDF+, BDF (24-bit)
//! and annotations, but it does not meet this crate's error rule: its `EDFError` variants carry
//! no file, field or byte offset (`InvalidRecordCount`, `FileReadError(io::Error)`, ...), and a
//! file cut inside its last data record was read without any error (checked on a pyedflib-written
//! EDF+ file cut 101 bytes short). It also pulls in `chrono` and `sha2`. The format is small, so
//! it is implemented here instead, tested against files written by pyedflib (`tests/fixtures/`,
//! made by `tools/golden/io/make_edf_fixture.py`) and by an independent numpy BDF writer
//! (`tools/golden/io/make_bdf_fixture.py`).
//!
//! # Format
//! A 256-byte fixed header, then 256 bytes per signal (each field stored for all signals in
//! turn: labels, transducers, physical dimensions, physical min/max, digital min/max,
//! prefiltering, samples per data record, reserved), then the data records. Each record holds,
//! signal after signal, `samples_per_record` little-endian samples: int16 in EDF, 24-bit in BDF
//! (version field `\xFFBIOSEMI`). Physical value:
//! `(dig − dig_min) × (phys_max − phys_min) / (dig_max − dig_min) + phys_min`, converted to µV
//! from the signal's physical dimension by [`crate::units::microvolts_per`] (`uV`/`µV` × 1,
//! `mV` × 10³, `V` × 10⁶, `nV` × 10⁻³, any letter case, also spelled out).
//! Signals with any other dimension are kept unscaled and listed in
//! [`EdfInfo::non_voltage_signals`].
//!
//! # EDF+ annotations
//! Signals labelled `EDF Annotations` / `BDF Annotations` hold TALs
//! (`+onset[\x15duration]\x14text\x14...\x14\x00`). The first TAL of each record is the
//! record's time stamp; the others become [`Annotation`]s and, when they fall inside the
//! recording, events. An annotation text of the form `CODE [target|nontarget][: LABEL]` (the form
//! [`write_edf_plus`] writes; `CODE` a decimal `u32`) gives the event's code, target flag and
//! label; any other text becomes the event's label and gets a code from
//! [`EdfInfo::label_codes`]: one code per distinct text, in order of first appearance, counting
//! up from one above the largest numeric code in the file. EDF+D files are read only when their
//! records are in fact contiguous.
//!
//! # Limits
//! All data signals must share one sample rate; a signal with another rate is an error unless
//! [`EdfOptions::drop_mismatched_rates`] drops it (listed in [`EdfInfo::dropped_signals`]).
//! Every count in the header is checked against the file length before allocation; the file must
//! be exactly the header plus the declared records (`-1` records: a whole number of records).

//!
//! # Layout
//! By job: `types.rs` (what a file holds, and the options), `header.rs` (the fixed and signal
//! headers), `annotations.rs` (TALs and event texts), `read.rs` (records into a
//! [`Recording`](crate::Recording)), `write.rs` (EDF+).

mod annotations;
mod header;
mod read;
mod types;
mod write;

pub use annotations::event_annotation_text;
pub(crate) use annotations::{parse_event_text, text_codes, EventText};
pub use read::{parse_edf, read_edf, read_edf_with};
pub use types::{Annotation, EdfHeader, EdfInfo, EdfOptions, EdfSignal};
pub use write::{write_edf_plus, write_edf_plus_with, EdfStart, EdfWriteOptions, EdfWriteSummary};

#[cfg(test)]
mod tests {
    use super::annotations::*;
    use super::header::*;
    use super::write::*;
    use oddball_signal::Event;
    use std::path::Path;

    #[test]
    fn outward_formatting() {
        assert_eq!(fmt8_outward(12.3456789, true).as_deref(), Some("12.34568"));
        assert_eq!(fmt8_outward(12.3456789, false).as_deref(), Some("12.34567"));
        assert_eq!(
            fmt8_outward(-250.123456, false).as_deref(),
            Some("-250.124")
        );
        assert_eq!(fmt8_outward(3e6, true).as_deref(), Some("3000000"));
        assert_eq!(fmt8_outward(0.0, true).as_deref(), Some("0.000000"));
        assert_eq!(fmt8_outward(1e9, true), None);
        for v in [1e-9, -1e-9, 123.456, -99999.99, 0.1 + 0.2] {
            let lo: f64 = fmt8_outward(v, false).unwrap().parse().unwrap();
            let hi: f64 = fmt8_outward(v, true).unwrap().parse().unwrap();
            assert!(lo <= v && v <= hi, "{v}: {lo} {hi}");
        }
    }

    #[test]
    fn event_texts() {
        assert_eq!(parse_event_text("3"), Some((3, None, None)));
        assert_eq!(parse_event_text("3 target"), Some((3, Some(true), None)));
        assert_eq!(
            parse_event_text("12 nontarget: A b"),
            Some((12, Some(false), Some("A b".into())))
        );
        assert_eq!(parse_event_text("7: x"), Some((7, None, Some("x".into()))));
        assert_eq!(parse_event_text("stim"), None);
        assert_eq!(parse_event_text("2 back"), None);
        assert_eq!(parse_event_text("12:30 lunch"), None);
        assert_eq!(parse_event_text("+3"), None);
        assert_eq!(parse_event_text("99999999999"), None);
        let e = Event::new(5, 4).with_target(true).with_label("Q");
        assert_eq!(event_annotation_text(&e), "4 target: Q");
        assert_eq!(
            parse_event_text(&event_annotation_text(&e)),
            Some((4, Some(true), Some("Q".into())))
        );
    }

    #[test]
    fn tal_parsing() {
        let bytes = b"+0\x14\x14\x00+1.5\x150.2\x14a\x14b\x14\x00\x00\x00";
        let ctx = Ctx {
            path: Path::new("x.edf"),
            bytes,
        };
        let tals = parse_tals(&ctx, bytes, 100, 0).unwrap();
        assert_eq!(tals.len(), 2);
        assert_eq!(tals[0], (0.0, None, vec![String::new()]));
        assert_eq!(
            tals[1],
            (1.5, Some(0.2), vec!["a".to_string(), "b".to_string()])
        );
        for (bad, at) in [
            (&b"+0\x14\x14\x00+x\x14a\x14\x00"[..], 105),
            (&b"+0\x14\x14"[..], 100),
            (&b"5\x14a\x14\x00"[..], 100),
            (&b"+1\x15-2\x14a\x14\x00"[..], 103),
            (&b"+1"[..], 100),
            (&b"+1\x00"[..], 100),
        ] {
            let ctx = Ctx {
                path: Path::new("x.edf"),
                bytes: bad,
            };
            let e = parse_tals(&ctx, bad, 100, 3).unwrap_err();
            assert_eq!(e.offset(), Some(at), "{e}");
            assert!(e.to_string().contains("data record 3"), "{e}");
        }
    }
}
