//! GDF (General Data Format for biosignals) 1.x and 2.x files, read from scratch, with
//! OpenViBE's P300 stimulation codes understood.
//!
//! # Why not a crate
//! No Rust crate reading GDF was found (a docs.rs search, 2026-11); the reference
//! implementations are C/C++ (`libbiosig`, `libgdf`), which would bring a C toolchain, a
//! system library and FFI into this crate for a format of two headers and a table. So this
//! module reads it itself, with the error rule of this crate (the file, the field and the byte
//! offset; counts checked against the file length before anything is allocated). It is checked
//! against MNE's reader (`mne.io.read_raw_gdf`, 1.13.2) on GDF 1.25 and 2.20 files written by
//! `tools/golden/gdf/make_gdf_fixtures.py`, and on the real OpenViBE recording
//! `openvibe-p300-gdf/data_sample_8ch.gdf`.
//!
//! # Format
//! After the 8-byte version (`GDF 1.xx` or `GDF 2.xx`), a 256-byte fixed header, then 256 bytes
//! per channel (each field stored for all channels in turn), then the data records, then an
//! optional event table. Both versions store the number of records (int64, at byte 236; `-1`,
//! unknown, is refused), the record duration as a fraction of seconds (two uint32, at 244) and
//! the channel count (at 252: uint32 in 1.x, uint16 in 2.x). The header length is an int64 of
//! bytes in 1.x (which must equal 256 × (channels + 1)) and a uint16 of 256-byte blocks in 2.x
//! (at least that; the tag-length-value "header 3" after the channel headers is skipped).
//!
//! Channel headers (1.x / 2.x): label (16 bytes), transducer (80), physical dimension (1.x: 8
//! bytes of text; 2.x: 6 obsolete bytes and a uint16 code), physical min/max (float64),
//! digital min/max (1.x int64, 2.x float64), prefiltering (1.x: 80 bytes of text; 2.x: 68
//! obsolete bytes and low-pass, high-pass, notch as float32), samples per record (uint32), data
//! type (uint32), and reserved / sensor bytes. A record holds, channel after channel, that
//! channel's samples: little-endian int8, uint8, int16, uint16, int32, uint32, int64, uint64,
//! float32, float64 (`GDFTYP` 1–8, 16, 17) or 24-bit integers (279 signed, 535 unsigned).
//!
//! Physical value: `(digital − dmin) × (pmax − pmin) / (dmax − dmin) + pmin` (MNE computes the
//! same affine map as `digital × cal + offset`), then to µV by [`crate::units::microvolts_per`]
//! of the unit: GDF 1.x's text (`uV`, `mV`, …), GDF 2.x's code turned into text (the code's
//! high bits 4256 are volts, its five low bits the decimal prefix: 4256 V, 4259 kV, 4274 mV,
//! 4275 µV, 4276 nV). Channels with another unit are kept unscaled and listed in
//! [`GdfInfo::non_voltage_channels`]. MNE differs there: it scales a 1.x unit not starting with
//! `uV` (`mV` included) as volts, and a 2.x code other than µV and mV by 1 (right for V, not
//! for kV or nV). NaN samples of float channels are kept as NaN (as MNE does).
//!
//! # Event table
//! Mode byte (1 or 3), then in 1.x a 24-bit sample rate and a uint32 count, in 2.x a 24-bit
//! count and a float32 sample rate; then the positions (uint32), the types (uint16), and in mode
//! 3 the channels (uint16) and durations (uint32). Positions are **1-based** (MNE subtracts 1,
//! and so does this reader): position `p` is data sample `p − 1`. A table rate other than 0 or
//! the data's rate scales the positions to the data's rate (MNE ignores the table's rate).
//! Entries outside the recording (position 0, or past the end) are not events; they stay in
//! [`GdfInfo::event_table`] and are counted in [`GdfInfo::events_outside`]. A file that ends
//! with its data records has no event table; bytes after the table are counted in
//! [`GdfInfo::trailing_bytes`].
//!
//! # Events: OpenViBE or plain codes
//! A table that holds at least one OpenViBE label code (0x8101–0x81FF,
//! `OVTK_StimulationId_Label_01…`) **and** at least one target / non-target flag (0x8205
//! `OVTK_StimulationId_Target`, 0x8206 `OVTK_StimulationId_NonTarget`) is read as OpenViBE's P300
//! speller: each label is one flash, with event code `label − 0x8100` (1, 2, …) at the label's
//! sample; its target flag is the nearest unused 0x8205/0x8206 within 2 samples of it (paired by
//! time, not by order in the table; ties go to the earlier flag). A label repeated at the same
//! sample with the same code is one flash. Everything else (0x8001 experiment start,
//! 0x8005/0x8006 trial start/stop, 0x800B/0x800C visual stimulation start/stop, …) is not a
//! flash and is kept in [`OpenVibeEvents`] (counts per code, trial starts, flashes per trial,
//! duplicates, flags with no label, labels with no flag). In the real OpenViBE file the
//! visual-stimulation start comes 16 samples (62.5 ms) after each label: the flash onset here is
//! the label's sample; the visual-stimulation codes stay in the table for whoever epochs on them.
//!
//! Any other table (e.g. BCI Competition IV's 0x0300 trial start, 0x0301… cues) keeps its codes:
//! every entry inside the recording is an event with the entry's type as code and no target flag.
//!
//! No [`Speller`](crate::Speller) is attached: OpenViBE does not record the matrix's symbols, nor
//! which label codes are rows and which columns (in the 7 × 7 sample file, codes 1–7 flash one
//! direction and 8–14 the other). A dataset manifest's `[speller]` can give the geometry.
//!
//! # Limits
//! All kept channels must share one sample rate; a channel with another (or with no samples) is
//! an error unless [`GdfOptions::drop_mismatched_rates`] drops it (listed in
//! [`GdfInfo::dropped_channels`]). Digital minimum and maximum must differ. Every count in the
//! header and the event table is checked against the file length before allocation.
//!
//! # Layout
//! By job: `types.rs` (what a file holds, the data types, the options), `header.rs` (the fixed
//! and channel headers), `events.rs` (the event table and OpenViBE's codes), `read.rs` (records
//! into a [`Recording`](crate::Recording)).

mod events;
mod header;
mod read;
mod types;

pub use events::{
    is_openvibe, OPENVIBE_FLAG_TOLERANCE, OPENVIBE_LABEL_FIRST, OPENVIBE_LABEL_LAST,
    OPENVIBE_NONTARGET, OPENVIBE_TARGET, OPENVIBE_TRIAL_START,
};
pub use read::{parse_gdf, read_gdf, read_gdf_with};
pub use types::{
    GdfChannel, GdfEvent, GdfEventTable, GdfHeader, GdfInfo, GdfOptions, GdfType, OpenVibeEvents,
};

#[cfg(test)]
mod tests {
    use super::events::sample_of;
    use super::header::dimension_text;
    use super::types::GdfType;

    #[test]
    fn dimension_codes() {
        assert_eq!(dimension_text(4256), "V");
        assert_eq!(dimension_text(4259), "kV");
        assert_eq!(dimension_text(4274), "mV");
        assert_eq!(dimension_text(4275), "uV");
        assert_eq!(dimension_text(4276), "nV");
        assert_eq!(dimension_text(0), "");
        assert_eq!(dimension_text(512), "code 512");
        assert_eq!(dimension_text(4257), "code 4257");
        assert_eq!(
            crate::units::microvolts_per(&dimension_text(4274)),
            Some(1e3)
        );
        assert_eq!(crate::units::microvolts_per(&dimension_text(512)), None);
    }

    #[test]
    fn positions_are_one_based() {
        assert_eq!(sample_of(0, 0.0, 256.0, 10), None);
        assert_eq!(sample_of(1, 0.0, 256.0, 10), Some(0));
        assert_eq!(sample_of(10, 256.0, 256.0, 10), Some(9));
        assert_eq!(sample_of(11, 256.0, 256.0, 10), None);
        // A table at half the data's rate.
        assert_eq!(sample_of(4, 128.0, 256.0, 10), Some(6));
        assert_eq!(
            sample_of(u32::MAX, 1.0, 1e6, usize::MAX),
            Some(4294967294000000)
        );
    }

    #[test]
    fn data_types() {
        for code in [1, 2, 3, 4, 5, 6, 7, 8, 16, 17, 279, 535] {
            let t = GdfType::from_code(code).unwrap();
            assert_eq!(t.code(), code);
        }
        for code in [0, 9, 18, 280, 536, u32::MAX] {
            assert_eq!(GdfType::from_code(code), None);
        }
        assert_eq!(GdfType::Int24.decode(&[0xFF, 0xFF, 0xFF]), -1.0);
        assert_eq!(GdfType::Int24.decode(&[0x00, 0x00, 0x80]), -8388608.0);
        assert_eq!(GdfType::Uint24.decode(&[0xFF, 0xFF, 0xFF]), 16777215.0);
        assert_eq!(GdfType::Int8.decode(&[0x80]), -128.0);
        assert_eq!(GdfType::Uint16.decode(&[0xFF, 0xFF]), 65535.0);
        assert_eq!(GdfType::Int64.decode(&(-5i64).to_le_bytes()), -5.0);
        assert_eq!(GdfType::Float32.decode(&1.5f32.to_le_bytes()), 1.5);
    }
}
