//! MATLAB MAT files, versions 5 and 7 (v7 = v5 with zlib-compressed variables), read from
//! scratch; and the BCI Competition layout (`signal` + per-sample `StimulusCode` / `Flashing` /
//! `StimulusType`, data set IIb of BCI Competition II and II of III) as a speller [`Recording`](crate::Recording)
//! (see [`bci`]).
//!
//! # Why not a crate
//! The two Rust MAT crates were tried first (2026-11-25, on the six BCI Competition II IIb runs
//! and on v5/v7 files written by scipy 1.17.1 with a struct, a char array and an int16 matrix):
//! * `matrw` 0.1.4 read the competition files but refused both scipy-written files (header
//!   parse error on `matfile_ver`); 6 of 300 randomly mutated copies of a real file made it
//!   panic (`unimplemented!` in `parser/v7/variable7.rs:56`); its errors are binrw backtraces
//!   without the variable at fault.
//! * `matfile` 0.5.0 read the numeric variables (no panic in 2,000 mutations) but silently
//!   drops structs and char arrays, and its errors are nom `Eof`s with no byte offset.
//!
//! Neither gives the byte-offset errors the other readers of this crate give, so this module
//! parses the container itself (about 600 lines); zlib is `flate2`'s.
//!
//! # What it reads ([`parse_mat_file`])
//! * The 128-byte header (text, subsystem offset, version 0x0100, `IM`/`MI` byte order: both
//!   byte orders are read). Version 7.3 (HDF5) and v4 files are errors naming the version.
//! * `miMATRIX` and `miCOMPRESSED` variables; normal and small (≤ 4 bytes) data elements.
//! * Numeric arrays of every class (double, single, int8 … uint64), real or complex, with the
//!   values kept in the type they are **stored** in ([`MatNumbers`]), which MAT files often make
//!   narrower than the class (the competition's `signal` is class double stored as miINT16).
//!   MATLAB (and `scipy.io.loadmat(mat_dtype=True)`) casts them to the class; [`MatNumbers`]
//!   gives them as `f64` or `i64`, which for every file MATLAB writes is the same numbers.
//! * Logical arrays, char arrays (UTF-16 code units, UTF-8, UTF-32), cell arrays and structs
//!   (nested at most 32 deep); sparse arrays, objects and function handles are kept as
//!   [`MatValue::Unsupported`] so that the rest of the file still reads.
//! * All data column-major, as MATLAB stores it: element `(i, j)` of an `m × n` array is at
//!   `i + j·m`.
//!
//! Every length is checked against the bytes that contain it before anything is allocated; the
//! only allocation not bounded by the file's bytes is zlib's output, which is bounded by the
//! compressed element's announced size and by what its stream actually inflates to. Errors name
//! the byte offset and the element (variable number and name, part of the array); inside a
//! compressed variable the offset is that of its `miCOMPRESSED` tag and the text gives the byte
//! within the decompressed data.

//!
//! # Layout
//! `file.rs` holds the contents of a MAT file ([`MatFile`] and its arrays), `parse.rs` reads
//! them from bytes, `info.rs` holds what a recording keeps of them ([`MatInfo`]), `bci.rs` makes a [`Recording`](crate::Recording) of the BCI Competition
//! layout, `competition3.rs` turns BCI Competition III's per-character blocks into that layout.

pub mod bci;
mod competition3;
mod file;
mod info;
mod parse;

pub use bci::{parse_mat, read_mat, read_mat_with, MatOptions, BCI_COMPETITION_SFREQ};
pub use file::{
    MatArray, MatClass, MatFile, MatHeader, MatNumbers, MatType, MatValue, MatVariable,
};
pub use info::{MatInfo, MatVarSummary};
pub use parse::{parse_mat_file, read_mat_file};
