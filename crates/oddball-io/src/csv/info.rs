//! What a CSV file held besides the samples and events ([`CsvInfo`]).

use serde::{Deserialize, Serialize};

/// What a CSV file held besides the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CsvInfo {
    /// All header names, in file order.
    pub columns: Vec<String>,
    pub time_column: Option<String>,
    pub marker_column: Option<String>,
    /// The time column, one value per sample (as in the file, usually seconds).
    pub timestamps: Option<Vec<f64>>,
    /// `(n − 1) / (t_last − t_first)` from the time column, when there is one.
    pub estimated_sfreq: Option<f64>,
    /// Whether `Raw::sfreq` is that estimate (`false`: it was given in the options).
    pub sfreq_from_timestamps: bool,
}
