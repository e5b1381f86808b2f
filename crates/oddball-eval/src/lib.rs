//! The evaluation harness around [`oddball_decode`]'s estimators, as MOABB is around
//! scikit-learn and pyRiemann: it reads files, scores presets and reports; the estimators,
//! folds, cross-validation spine and tuning stay in the decoding crate.
//!
//! * [`layout`]: the one channel and rate policy of a run (a model's or the first training
//!   recording's channels by name, its rate by polyphase resampling);
//! * [`dataset`]: recordings read, labelled, matched to a run's layout and cut into epochs;
//! * [`erp`]: recordings' target and non-target epochs for their averages;
//! * [`evaluate`]: presets fitted on training recordings and scored on test recordings or by
//!   k-fold cross-validation (tuning nested), speller characters and the Wolpaw ITR; training a
//!   preset with its decision model;
//! * [`benchmark`]: every preset on every subject of data sets, with MOABB's protocols, and
//!   [`stats`] (the Wilcoxon signed-rank test) for the comparisons;
//! * [`unsupervised`]: the EM decoder replayed over speller recordings without labels, scored;
//!   [`pooled`]: its starts pooled from other data sets' labelled recordings;
//! * [`sessions`]: session files of `oddball demo` re-decided offline by a model;
//! * [`text`]: the reports as the command line prints them (tables, result rows, summaries).

pub mod benchmark;
pub mod dataset;
pub mod erp;
pub mod evaluate;
pub mod layout;
pub mod pooled;
pub mod sessions;
pub mod stats;
pub mod text;
pub mod unsupervised;
