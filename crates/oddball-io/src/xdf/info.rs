//! What an XDF recording holds besides the EEG samples and events ([`XdfInfo`]).

use serde::{Deserialize, Serialize};

use super::types::XdfStreamInfo;

/// One marker (a string sample or a marker-stream number).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfMarker {
    pub stream_id: u32,
    /// As in the file (before clock synchronization).
    pub timestamp: f64,
    /// The full text (channels joined with TAB; a number as Rust prints it).
    pub text: String,
    /// The event code given to it.
    pub code: u32,
    pub target: Option<bool>,
    /// The EEG sample it was put at; `None` when outside the EEG's time span.
    pub sample: Option<usize>,
}

/// What an XDF file held besides the EEG samples and events.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct XdfInfo {
    pub version: Option<String>,
    pub header_xml: Option<String>,
    /// Every stream (header, counts, timestamps of first and last sample, clock offsets, footer).
    pub streams: Vec<XdfStreamInfo>,
    /// Index in [`XdfInfo::streams`] of the stream read as EEG.
    pub eeg_stream: usize,
    /// The EEG samples' timestamps (after clock synchronization).
    pub eeg_timestamps: Vec<f64>,
    /// The unit of each EEG channel and the factor applied to reach µV.
    pub eeg_units: Vec<String>,
    pub scale_to_uv: Vec<f64>,
    /// Markers of all marker streams, stream after stream, each in file order.
    pub markers: Vec<XdfMarker>,
    /// The file ends inside a chunk (a recorder stopped while writing).
    pub truncated: bool,
    pub truncated_at: Option<u64>,
    pub n_chunks: usize,
    pub n_boundaries: usize,
    pub n_unknown_chunks: usize,
}

impl XdfInfo {
    /// The recording was closed properly: not cut inside a chunk and every stream has a
    /// StreamFooter.
    pub fn finished(&self) -> bool {
        !self.truncated && self.streams.iter().all(|s| s.footer.is_some())
    }

    /// The stream read as EEG.
    pub fn eeg(&self) -> &XdfStreamInfo {
        &self.streams[self.eeg_stream]
    }
}
