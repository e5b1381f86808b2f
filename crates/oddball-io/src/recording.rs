//! A recording read from a file ([`Recording`]): the samples and events, the [`Format`], the
//! speller layout, and the format's own [`Details`]. Every reader makes one; nothing here reads.

use std::path::PathBuf;

use oddball_signal::Raw;
use serde::{Deserialize, Serialize};

use crate::bci2000::Bci2000Info;
use crate::brainvision::BrainVisionInfo;
use crate::csv::CsvInfo;
use crate::easy::EasyInfo;
use crate::edf::EdfInfo;
use crate::eeglab::EeglabInfo;
use crate::fif::FifInfo;
use crate::gdf::GdfInfo;
use crate::mat::MatInfo;
use crate::speller::Speller;
use crate::xdf::XdfInfo;

/// The file format a recording was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    /// BCI2000 `.dat` (v1.0 or v1.1).
    Bci2000,
    Csv,
    Edf,
    EdfPlus,
    Bdf,
    BdfPlus,
    /// Neuroelectrics NIC `.easy` (with its `.info`).
    Easy,
    /// Lab Streaming Layer XDF.
    Xdf,
    /// MATLAB MAT v5/v7 (BCI Competition layout).
    Mat,
    /// BrainVision `.vhdr` + `.vmrk` + binary data.
    BrainVision,
    /// EEGLAB `.set` (+ `.fdt`).
    Eeglab,
    /// MNE / Neuromag FIF raw.
    Fif,
    /// GDF 1.x or 2.x (the version is in [`GdfInfo::header`]).
    Gdf,
}

/// The format-specific contents of a recording.
#[derive(Debug, Clone, PartialEq)]
pub enum Details {
    Bci2000(Box<Bci2000Info>),
    Csv(CsvInfo),
    Edf(Box<EdfInfo>),
    Easy(EasyInfo),
    Xdf(Box<XdfInfo>),
    Mat(Box<MatInfo>),
    BrainVision(Box<BrainVisionInfo>),
    Eeglab(Box<EeglabInfo>),
    Fif(Box<FifInfo>),
    Gdf(Box<GdfInfo>),
}

/// A recording read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Samples in µV, `(n_channels, n_times)`, with the stimulus events.
    pub raw: Raw,
    pub format: Format,
    /// The file it was read from.
    pub path: PathBuf,
    /// The speller layout, for P300-speller recordings (BCI2000 files with `TargetDefinitions`).
    pub speller: Option<Speller>,
    pub details: Details,
}

impl Recording {
    /// BCI2000 parameters, states and header, for `.dat` files.
    pub fn bci2000(&self) -> Option<&Bci2000Info> {
        match &self.details {
            Details::Bci2000(b) => Some(b),
            _ => None,
        }
    }

    /// Column names and timestamps, for CSV files.
    pub fn csv(&self) -> Option<&CsvInfo> {
        match &self.details {
            Details::Csv(c) => Some(c),
            _ => None,
        }
    }

    /// Header and annotations, for EDF/BDF files.
    pub fn edf(&self) -> Option<&EdfInfo> {
        match &self.details {
            Details::Edf(e) => Some(e),
            _ => None,
        }
    }

    /// Layout, triggers, timestamps, accelerometer and `.info` entries, for `.easy` files.
    pub fn easy(&self) -> Option<&EasyInfo> {
        match &self.details {
            Details::Easy(e) => Some(e),
            _ => None,
        }
    }

    /// Streams, markers, timestamps and truncation, for XDF files.
    pub fn xdf(&self) -> Option<&XdfInfo> {
        match &self.details {
            Details::Xdf(x) => Some(x),
            _ => None,
        }
    }

    /// Header, variables, states and sampling-rate source, for MAT files.
    pub fn mat(&self) -> Option<&MatInfo> {
        match &self.details {
            Details::Mat(m) => Some(m),
            _ => None,
        }
    }

    /// Header settings, channels and markers, for BrainVision files.
    pub fn brainvision(&self) -> Option<&BrainVisionInfo> {
        match &self.details {
            Details::BrainVision(b) => Some(b),
            _ => None,
        }
    }

    /// MAT header, `EEG` fields, data file and events, for EEGLAB files.
    pub fn eeglab(&self) -> Option<&EeglabInfo> {
        match &self.details {
            Details::Eeglab(e) => Some(e),
            _ => None,
        }
    }

    /// Channel records, trigger channels, annotations, skips and split parts, for FIF files.
    pub fn fif(&self) -> Option<&FifInfo> {
        match &self.details {
            Details::Fif(f) => Some(f),
            _ => None,
        }
    }

    /// Header, event table and OpenViBE stimulations, for GDF files.
    pub fn gdf(&self) -> Option<&GdfInfo> {
        match &self.details {
            Details::Gdf(g) => Some(g),
            _ => None,
        }
    }
}
