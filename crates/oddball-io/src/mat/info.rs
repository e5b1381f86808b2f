//! What a MAT recording holds besides the samples and events ([`MatInfo`]).

use std::collections::BTreeMap;

use super::file::MatHeader;

/// One variable of the file, without its values.
#[derive(Debug, Clone, PartialEq)]
pub struct MatVarSummary {
    pub name: String,
    pub dims: Vec<usize>,
    /// `"double stored as miINT16"`, `"char"`, `"struct"` …
    pub kind: String,
    pub offset: u64,
    pub compressed: bool,
}

/// What a MAT recording holds besides the samples and events.
#[derive(Debug, Clone, PartialEq)]
pub struct MatInfo {
    pub header: MatHeader,
    /// Every variable of the file, in file order.
    pub variables: Vec<MatVarSummary>,
    /// Every numeric variable with one value per sample other than the signal (the BCI2000
    /// states: `StimulusCode`, `Flashing`, `PhaseInSequence` …), as `f64`.
    pub states: BTreeMap<String, Vec<f64>>,
    /// Every char variable, its rows joined by newlines (`filename`, `evalstring` …).
    pub strings: BTreeMap<String, String>,
    /// Whether the sampling rate came from [`MatOptions::sfreq`](super::MatOptions::sfreq) or the file's own variable
    /// (else it is [`BCI_COMPETITION_SFREQ`](super::BCI_COMPETITION_SFREQ)).
    pub sfreq_given: bool,
    /// The units of the samples ([`RAW_UNITS`](super::bci::RAW_UNITS)).
    pub units: &'static str,
}
