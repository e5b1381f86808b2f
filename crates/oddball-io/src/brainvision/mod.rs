//! BrainVision Core Data Format 1.0 (Brain Products' BrainVision Recorder and Analyzer; pybv
//! and MNE's `export_raw(fmt="brainvision")`), read from scratch, and written as pybv writes
//! float data ([`write_brainvision`]: `IEEE_FLOAT_32`, multiplexed, µV; see `write.rs`).
//!
//! # Why no crate
//! There is no maintained Rust reader of the format, and it is small: two INI-like text files
//! and a headerless binary file. Written here, it gives the crate's error rule (file, field and
//! byte offset; a short data file is an error, never a shorter recording).
//!
//! # Format
//! A recording is three files. The **header** (`.vhdr`, the one [`read_brainvision`] and
//! [`crate::read`] are given) starts with `Brain Vision Data Exchange Header File Version 1.0`
//! and holds `[Section]`s of `Key=Value` lines (`;` starts a comment):
//! * `[Common Infos]`: `DataFile` and `MarkerFile` (file names relative to the header's folder;
//!   a name with a root or a `..` part is refused, and each file must be a regular file),
//!   `DataFormat=BINARY` (ASCII data is refused as unsupported), `DataOrientation`
//!   (`MULTIPLEXED`, the default: sample after sample; or `VECTORIZED`: channel after channel),
//!   `NumberOfChannels`, `SamplingInterval` in µs (rate = 10⁶ / interval), optionally
//!   `DataPoints` (then the data file must hold exactly that many samples), `Codepage`.
//! * `[Binary Infos]`: `BinaryFormat` = `INT_16`, `INT_32` or `IEEE_FLOAT_32` (little-endian;
//!   the formats MNE reads; `UseBigEndianOrder=YES` is refused).
//! * `[Channel Infos]`: `ChN=Name,Reference,Resolution,Unit` for N = 1 … `NumberOfChannels`
//!   (`\1` in a name stands for a comma). A value in µV is `stored × Resolution ×` the unit's
//!   factor from [`crate::units::microvolts_per`]; an empty resolution is 1 and an empty unit
//!   µV. A channel whose unit is not a voltage (`°C`, `ARU`, `µS` …) is kept as `stored ×
//!   Resolution` and listed in [`BrainVisionInfo::non_voltage_channels`].
//!
//! The **data file** must be exactly `NumberOfChannels × n_times × bytes per value` long: a
//! file cut inside a sample is an [`IoError::Truncated`](crate::IoError::Truncated) naming the
//! sample and its byte offset. With `DataPoints` in the header every cut is an error; without
//! it (pybv and MNE do not write it) the file's length is all that gives `n_times`, so a file
//! cut exactly between two samples cannot be told from a shorter recording.
//!
//! The **marker file** (`.vmrk`, same INI form, `Marker` for `Header` in its first line) lists
//! `[Marker Infos]` `MkN=Type,Description,Position,Size,Channel[,Date]` with a 1-based
//! `Position` in samples. Every marker is kept in [`BrainVisionInfo::markers`]; the
//! `Stimulus` and `Response` markers inside the recording become events:
//! * `Stimulus` `S  n` → code n, `Response` `R  n` → code **1000 + n**, so that responses
//!   never share a code with stimuli (MNE's `events_from_annotations` numbering);
//! * any other `Stimulus`/`Response` description gets a code per distinct text in order of
//!   first appearance, counting up from one above the largest numeric code (the rule of EDF+
//!   annotations; [`BrainVisionInfo::label_codes`]).
//!
//! Each event is labelled `Type/Description` (`Stimulus/S  1`), the text of MNE's annotation.
//! `New Segment`, `Comment`, `SyncStatus` and other markers are not events.
//!
//! Header and marker files are read in UTF-8, or as their `Codepage` line says (`ANSI` is
//! Windows-1252, `Latin-1`); a file that is not valid UTF-8 and names no other codepage is read
//! as Latin-1 (older recorders), as MNE does. Values are checked against MNE 1.13.2's reading
//! of files written by pybv 0.8.1 and byte by byte (`tools/golden/brainvision/`).
//!
//! # Layout
//! By job: `types.rs` (what a recording holds: [`BrainVisionInfo`]), `ini.rs` (the INI-like
//! text, encodings, byte offsets), `read.rs` (settings, channels, data file, events),
//! `markers.rs` (the marker file, and the marker of a code for the writer), `write.rs`
//! ([`write_brainvision`]).

mod ini;
mod markers;
mod read;
mod types;
mod write;

pub use read::{parse_brainvision, read_brainvision};
pub use types::{BrainVisionInfo, BvBinaryFormat, BvChannel, BvMarker, BvOrientation};
pub use write::{write_brainvision, BvWriteSummary};

#[cfg(test)]
mod tests {
    use super::ini::*;
    use std::path::Path;

    #[test]
    fn encodings() {
        assert_eq!(
            Encoding::Cp1252.decode(b"\x80 \xb5V \xb0C \x81"),
            "€ µV °C \u{81}"
        );
        assert_eq!(Encoding::Latin1.decode(b"\x80\xb5"), "\u{80}µ");
        let ini = parse(
            b"Brain Vision Data Exchange Header File Version 1.0\nCodepage=ANSI\n[S]\nk=\xb5V\n",
            Path::new("x.vhdr"),
            "Header",
        )
        .unwrap();
        assert_eq!(ini.encoding, Encoding::Cp1252);
        assert_eq!(ini.text(ini.get("s", "K").unwrap()), "µV");
        // Not valid UTF-8 and no codepage: Latin-1.
        let ini = parse(
            b"BrainVision Data Header File\n[S]\nk=\xb5\n",
            Path::new("x"),
            "Header",
        )
        .unwrap();
        assert_eq!(ini.encoding, Encoding::Latin1);
    }

    #[test]
    fn fields_keep_their_offsets() {
        let text = b"Brain Vision Data Exchange Header File Version 1.0\r\n[Channel Infos]\r\nCh1= a\\1b,ref,,uV \r\n";
        let ini = parse(text, Path::new("x.vhdr"), "Header").unwrap();
        let e = ini.get("channel infos", "ch1").unwrap();
        let f = ini.fields(e);
        let texts: Vec<&str> = f.iter().map(|x| x.text.as_str()).collect();
        assert_eq!(texts, ["a,b", "ref", "", "uV"]);
        for x in &f[1..] {
            assert_eq!(&text[x.at..x.at + x.text.len()], x.text.as_bytes());
        }
        assert_eq!(f[0].at, 74);
        assert!(parse(
            b"Brain Vision Data Exchange Marker File\n",
            Path::new("x"),
            "Header"
        )
        .is_err());
        assert!(parse(b"", Path::new("x"), "Header").is_err());
    }
}
