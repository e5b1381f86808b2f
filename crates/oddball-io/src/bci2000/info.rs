//! What a BCI2000 file holds besides the µV samples ([`Bci2000Info`]): its first header line,
//! parameters and state vectors.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::params::Parameters;

/// The sample type of the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum DataFormat {
    Int16,
    Int32,
    Float32,
}

impl DataFormat {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        match self {
            DataFormat::Int16 => 2,
            DataFormat::Int32 | DataFormat::Float32 => 4,
        }
    }
}

/// The first header line.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Bci2000Header {
    /// `BCI2000V`, or `"1.0"` when the line has none.
    pub version: String,
    /// Header length in bytes (the body starts here).
    pub header_len: usize,
    /// Number of channels.
    pub source_ch: usize,
    /// State-vector bytes per sample.
    pub statevector_len: usize,
    pub data_format: DataFormat,
}

/// One line of the state vector definition.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StateDef {
    pub name: String,
    /// Bits, 1..=64.
    pub length: u32,
    pub default: u64,
    pub byte_location: usize,
    /// 0..=7.
    pub bit_location: u32,
}

impl StateDef {
    pub(super) fn first_bit(&self) -> usize {
        self.byte_location * 8 + self.bit_location as usize
    }
}

/// The state vectors of every sample, decoded on request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct States {
    pub(super) defs: Vec<StateDef>,
    pub(super) record_len: usize,
    pub(super) n_samples: usize,
    pub(super) bytes: Vec<u8>,
}

impl States {
    /// The definitions, in file order.
    pub fn defs(&self) -> &[StateDef] {
        &self.defs
    }

    /// The state names, in file order.
    pub fn names(&self) -> Vec<&str> {
        self.defs.iter().map(|d| d.name.as_str()).collect()
    }

    pub fn def(&self, name: &str) -> Option<&StateDef> {
        self.defs.iter().find(|d| d.name == name)
    }

    pub fn n_samples(&self) -> usize {
        self.n_samples
    }

    /// The raw state-vector bytes of sample `i` (`StatevectorLen` bytes).
    pub fn vector(&self, i: usize) -> Option<&[u8]> {
        (i < self.n_samples).then(|| &self.bytes[i * self.record_len..(i + 1) * self.record_len])
    }

    pub(super) fn decode_at(&self, d: &StateDef, i: usize) -> u64 {
        let start = d.first_bit();
        let (b0, shift) = (start / 8, start % 8);
        let b1 = (start + d.length as usize - 1) / 8;
        let base = i * self.record_len;
        let mut acc: u128 = 0;
        for (k, &byte) in self.bytes[base + b0..=base + b1].iter().enumerate() {
            acc |= (byte as u128) << (8 * k);
        }
        let mask: u128 = (1u128 << d.length) - 1;
        ((acc >> shift) & mask) as u64
    }

    /// The value of state `name` at sample `i`.
    pub fn value_at(&self, name: &str, i: usize) -> Option<u64> {
        let d = self.def(name)?;
        (i < self.n_samples).then(|| self.decode_at(d, i))
    }

    /// The whole time series of state `name` (one value per sample).
    pub fn get(&self, name: &str) -> Option<Vec<u64>> {
        let d = self.def(name)?;
        Some((0..self.n_samples).map(|i| self.decode_at(d, i)).collect())
    }

    /// Every state's time series, by name.
    pub fn all(&self) -> BTreeMap<String, Vec<u64>> {
        self.defs
            .iter()
            .map(|d| {
                (
                    d.name.clone(),
                    (0..self.n_samples).map(|i| self.decode_at(d, i)).collect(),
                )
            })
            .collect()
    }
}

/// Everything a BCI2000 file holds besides the µV samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Bci2000Info {
    pub header: Bci2000Header,
    pub parameters: Parameters,
    pub states: States,
    /// µV per A/D unit of each channel (from `SourceChGain`, units applied).
    pub gains: Vec<f64>,
    /// A/D offset of each channel (from `SourceChOffset`).
    pub offsets: Vec<f64>,
}
