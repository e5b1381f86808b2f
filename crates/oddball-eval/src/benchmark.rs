//! Every preset on every subject of one or more data sets ([`Manifest`]s), with MOABB's
//! evaluation protocols, and the across-subject statistics a paper reports.
//!
//! * [`Protocol::TrainTest`]: fitted on a subject's `train` runs, scored on its `test` runs
//!   (AUC; for spellers the characters right after 1..N repetitions and the Wolpaw ITR from the
//!   recording's own flash timing).
//! * [`Protocol::WithinSession`]: k-fold cross-validation inside each session of a subject
//!   (MOABB's `WithinSessionEvaluation`): speller folds keep characters whole, other data is
//!   stratified by label. The AUC is the mean over folds; characters are not scored (a fold
//!   holds a fraction of a recording's characters).
//! * [`Protocol::CrossSubject`]: leave one subject out (MOABB's `CrossSubjectEvaluation`):
//!   fitted on every run of the data set's other subjects, scored on all of the subject's runs.
//!   The channel names and the sampling rate of all subjects must agree.
//! * [`Protocol::Unsupervised`]: no training: a speller subject's runs in order as one unlabelled
//!   session ([`crate::unsupervised::replay`], from the P300 template): characters right online
//!   and post hoc by repetitions, the final model's AUC; one row (preset `unsupervised`) per
//!   subject, the labels only score. Subjects that are not spellers are skipped once read.
//!
//! Everything that can be checked is checked before any EEG is read ([`BenchmarkParams::plan`]):
//! presets, folds, which protocol applies to which subject (a subject without test runs has
//! no train → test row; a data set of one subject has no cross-subject rows: both are listed as
//! skipped, not errors). Subjects are read in parallel, then the evaluations run in parallel
//! (rayon), each reporting through a [`Progress`] callback.
//!
//! The summary gives per protocol and preset the mean ± sd of the AUC over subjects (sessions
//! for within-session) and the mean character accuracy by repetitions; the comparisons are
//! one-sided Wilcoxon signed-rank tests of every ordered pair of presets over the subjects both
//! scored, as MOABB's `compute_dataset_statistics` reports them ([`crate::stats::wilcoxon`]).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Mutex;
use std::time::Instant;

use oddball_io::Manifest;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

use crate::dataset::{self, DatasetError, Labelling};
use crate::evaluate::{
    self, EpochedRecording, EvaluateError, EvaluateParams, PipelineResult, TrainingSet,
};
use crate::layout::{Layout, Resampled};
use crate::stats::{wilcoxon, Alternative};
use crate::unsupervised::ReplayError;
use oddball_decode::preprocess::Preprocess;
use oddball_decode::preset::Preset;

/// How a subject's data is split into training and test data (MOABB's evaluations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Protocol {
    /// Fit on the manifest's train runs, score on its test runs.
    TrainTest,
    /// k-fold cross-validation inside each session.
    WithinSession,
    /// Leave one subject out.
    CrossSubject,
    /// All of a speller subject's runs as one unlabelled session (no training).
    Unsupervised,
}

impl Protocol {
    pub const ALL: [Protocol; 4] = [
        Protocol::TrainTest,
        Protocol::WithinSession,
        Protocol::CrossSubject,
        Protocol::Unsupervised,
    ];

    /// The name on the command line and in results.
    pub fn name(self) -> &'static str {
        match self {
            Protocol::TrainTest => "train-test",
            Protocol::WithinSession => "within-session",
            Protocol::CrossSubject => "cross-subject",
            Protocol::Unsupervised => UNSUPERVISED,
        }
    }
}

impl std::fmt::Display for Protocol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Protocol {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Protocol::ALL
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| {
                format!(
                    "unknown protocol {s:?}; known: {}",
                    Protocol::ALL.map(Protocol::name).join(", ")
                )
            })
    }
}

/// The protocol's name, and the preset name of its rows.
pub const UNSUPERVISED: &str = "unsupervised";

/// Why a benchmark could not run; each variant names the data set and subject at fault.
#[derive(Debug, Error)]
pub enum BenchmarkError {
    #[error("no presets to run")]
    NoPresets,
    #[error("no protocols to run")]
    NoProtocols,
    #[error("{0} folds: cross-validation needs at least 2")]
    Folds(usize),
    #[error("nothing to run: {}", .skipped.join("; "))]
    NothingToRun { skipped: Vec<String> },
    #[error("data set {dataset:?}, subject {subject:?}")]
    Dataset {
        dataset: String,
        subject: String,
        #[source]
        source: Box<DatasetError>,
    },
    #[error("data set {dataset:?}, subject {subject:?}, {protocol}{}", .session.as_ref().map(|s| format!(", session {s:?}")).unwrap_or_default())]
    Evaluate {
        dataset: String,
        subject: String,
        protocol: Protocol,
        session: Option<String>,
        #[source]
        source: Box<EvaluateError>,
    },
    #[error("pooled start: {0}")]
    Pooled(#[source] Box<oddball_decode::unsupervised::UnsupervisedError>),
    #[error("data set {dataset:?}, subject {subject:?}, unsupervised")]
    Unsupervised {
        dataset: String,
        subject: String,
        #[source]
        source: Box<ReplayError>,
    },
    #[error(
        "data set {dataset:?}: subjects {subject:?} and {other:?} differ in {what}, so one cannot \
         be scored by a model of the other (cross-subject)"
    )]
    Layout {
        dataset: String,
        subject: String,
        other: String,
        what: String,
    },
}

/// Settings of a benchmark (unfitted; [`BenchmarkParams::plan`] checks them).
#[derive(Debug, Clone, PartialEq)]
pub struct BenchmarkParams {
    /// Presets, in this order.
    pub presets: Vec<Preset>,
    pub protocols: Vec<Protocol>,
    /// Folds of the within-session cross-validation.
    pub folds: usize,
    /// How every recording becomes epochs (the peer stack's by default).
    pub preprocess: Preprocess,
    /// The unsupervised protocol's pooled start (none by default).
    pub transfer: crate::pooled::Transfer,
}

impl Default for BenchmarkParams {
    fn default() -> Self {
        Self {
            presets: vec![Preset::Lda],
            protocols: vec![Protocol::TrainTest],
            folds: 5,
            preprocess: Preprocess::peer(),
            transfer: crate::pooled::Transfer::None,
        }
    }
}

/// One evaluation to make: a protocol on one subject (and session).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unit {
    /// Index into the manifests.
    pub dataset: usize,
    /// Index into the data set's subjects.
    pub subject: usize,
    pub protocol: Protocol,
    /// Within-session: the session's name and its runs.
    pub session: Option<(String, Vec<PathBuf>)>,
}

/// What a benchmark will do, found without reading EEG.
#[derive(Debug, Clone)]
pub struct Plan {
    pub units: Vec<Unit>,
    /// Protocol × subject combinations that do not apply, and why.
    pub skipped: Vec<String>,
}

impl BenchmarkParams {
    /// Checks the settings against the manifests and lists the evaluations to make.
    pub fn plan(&self, manifests: &[Manifest]) -> Result<Plan, BenchmarkError> {
        if self.presets.is_empty() {
            return Err(BenchmarkError::NoPresets);
        }
        if self.protocols.is_empty() {
            return Err(BenchmarkError::NoProtocols);
        }
        if self.protocols.contains(&Protocol::WithinSession) && self.folds < 2 {
            return Err(BenchmarkError::Folds(self.folds));
        }
        let mut units = Vec::new();
        let mut skipped = Vec::new();
        for &protocol in &self.protocols {
            for (d, m) in manifests.iter().enumerate() {
                if protocol == Protocol::CrossSubject && m.subjects.len() < 2 {
                    skipped.push(format!(
                        "{protocol} on {:?}: it has one subject (leave-one-subject-out needs two)",
                        m.name
                    ));
                    continue;
                }
                for (s, subj) in m.subjects.iter().enumerate() {
                    let unit = |session| Unit {
                        dataset: d,
                        subject: s,
                        protocol,
                        session,
                    };
                    match protocol {
                        Protocol::TrainTest if subj.train.is_empty() || subj.test.is_empty() => {
                            skipped.push(format!(
                                "{protocol} on {:?} subject {:?}: it needs train and test runs",
                                m.name, subj.id
                            ))
                        }
                        Protocol::WithinSession => {
                            for session in subj.session_runs() {
                                units.push(unit(Some(session)));
                            }
                        }
                        _ => units.push(unit(None)),
                    }
                }
            }
        }
        if units.is_empty() {
            return Err(BenchmarkError::NothingToRun { skipped });
        }
        Ok(Plan { units, skipped })
    }
}

/// One preset's score on one subject under one protocol (the JSON row).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchmarkRow {
    pub dataset: String,
    pub subject: String,
    /// Within-session: the session's name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub session: Option<String>,
    pub protocol: Protocol,
    pub preset: String,
    /// Epoch ROC-AUC on the test data (mean over folds within a session).
    pub auc: f64,
    /// Epochs scored (test epochs; all epochs under cross-validation).
    pub n_epochs: usize,
    pub n_targets: usize,
    /// Speller characters scored (train → test and cross-subject on spellers).
    pub n_chars: Option<usize>,
    /// Cells of the speller's matrix (chance is one over this).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_choices: Option<usize>,
    /// Characters right after 1..N repetitions (`null` when not a speller).
    pub chars_by_reps: Option<Vec<usize>>,
    /// The best Wolpaw ITR over repetitions, bits/min, from the recording's own flash timing.
    pub itr_bits_per_min: Option<f64>,
    /// Seconds of one fit (mean over folds; unsupervised: the whole replay).
    pub fit_s: f64,
    /// Unsupervised: characters decided right online (each by the model of the characters so
    /// far).
    pub online_chars: Option<usize>,
}

/// A preset's scores over subjects under one protocol.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PresetSummary {
    pub protocol: Protocol,
    pub preset: String,
    /// Rows summarised (subjects; subject-sessions within session).
    pub n: usize,
    pub auc_mean: f64,
    /// Sample standard deviation (`None` for one row).
    pub auc_sd: Option<f64>,
    /// Mean over speller rows of the fraction of characters right after 1..N repetitions (N the
    /// fewest any row has).
    pub char_accuracy_by_reps: Option<Vec<f64>>,
}

/// Is preset `a` better than `b` across subjects? (one-sided Wilcoxon signed-rank test)
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    pub protocol: Protocol,
    pub a: String,
    pub b: String,
    /// Subjects (sessions) both presets scored.
    pub n: usize,
    /// Mean AUC of `a` minus that of `b`.
    pub mean_auc_diff: f64,
    /// `p` of "a's AUC tends to be larger than b's"; `None` when every difference is zero.
    pub pvalue: Option<f64>,
}

/// Everything a benchmark found.
#[derive(Debug, Clone, Serialize)]
pub struct BenchmarkReport {
    pub results: Vec<BenchmarkRow>,
    pub summary: Vec<PresetSummary>,
    pub comparisons: Vec<Comparison>,
    pub skipped: Vec<String>,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// Threads the evaluations ran on.
    pub threads: usize,
}

/// What a benchmark is doing, for a progress display. Called from several threads.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// Before anything: subjects to read and evaluations to make.
    Plan { subjects: usize, units: usize },
    /// A subject's runs were read and epoched.
    Loaded { dataset: &'a str, subject: &'a str },
    /// A run was resampled to its subject's first run's rate ([`Layout`]).
    Resampled {
        run: &'a std::path::Path,
        resampled: Resampled,
        of: &'a str,
    },
    /// One evaluation finished with these rows.
    Done { rows: &'a [BenchmarkRow] },
}

/// Runs the plan of `params` on `manifests`.
///
/// Subjects are streamed: a subject's runs are read and epoched, its evaluations made, and
/// its epochs dropped before the next subject is read, at most as many subjects at once as
/// the thread pool has threads, so memory stays about one subject per thread however many
/// subjects there are, and an error in the first subject is reported at once. Cross-subject
/// evaluations need every subject of their data set at once (each is scored by a model of all
/// the others): a data set's subjects are read together for them, then dropped.
pub fn run(
    params: &BenchmarkParams,
    manifests: &[Manifest],
    on: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<BenchmarkReport, BenchmarkError> {
    let t0 = Instant::now();
    let plan = params.plan(manifests)?;
    // Per-subject units, grouped by subject in plan order; cross-subject units by data set.
    let mut own: Vec<((usize, usize), Vec<usize>)> = Vec::new();
    let mut cross: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, u) in plan.units.iter().enumerate() {
        if u.protocol == Protocol::CrossSubject {
            match cross.iter_mut().find(|(d, _)| *d == u.dataset) {
                Some((_, units)) => units.push(i),
                None => cross.push((u.dataset, vec![i])),
            }
        } else {
            let key = (u.dataset, u.subject);
            match own.iter_mut().find(|(k, _)| *k == key) {
                Some((_, units)) => units.push(i),
                None => own.push((key, vec![i])),
            }
        }
    }
    let reads = own.len()
        + cross
            .iter()
            .map(|&(d, _)| manifests[d].subjects.len())
            .sum::<usize>();
    on(Progress::Plan {
        subjects: reads,
        units: plan.units.len(),
    });
    let mut unsupervised_sets: Vec<usize> = plan
        .units
        .iter()
        .filter(|u| u.protocol == Protocol::Unsupervised)
        .map(|u| u.dataset)
        .collect();
    unsupervised_sets.dedup();
    let starts = crate::pooled::starts_by_dataset(
        &params.transfer,
        manifests,
        &params.preprocess,
        &unsupervised_sets,
        on,
    )?;
    let rows = Mutex::new(Vec::new());
    let skipped = Mutex::new(plan.skipped);
    let load = |d: usize, s: usize| -> Result<_, BenchmarkError> {
        let recs = load_subject(&manifests[d], s, &params.preprocess, on)?;
        on(Progress::Loaded {
            dataset: &manifests[d].name,
            subject: &manifests[d].subjects[s].id,
        });
        Ok(((d, s), recs))
    };
    let run_units = |loaded: &BTreeMap<(usize, usize), Vec<EpochedRecording>>, units: &[usize]| {
        units.par_iter().try_for_each(|&i| {
            let (r, skip) = run_unit(params, manifests, loaded, &plan.units[i], &starts)?;
            if let Some(why) = skip {
                skipped.lock().expect("no panic holds the lock").push(why);
            }
            on(Progress::Done { rows: &r });
            rows.lock().expect("no panic holds the lock").push((i, r));
            Ok::<(), BenchmarkError>(())
        })
    };
    let threads = rayon::current_num_threads().max(1);
    for batch in own.chunks(threads) {
        batch.par_iter().try_for_each(|((d, s), units)| {
            let loaded: BTreeMap<_, _> = std::iter::once(load(*d, *s)?).collect();
            run_units(&loaded, units)
        })?;
    }
    for (d, units) in &cross {
        let loaded = (0..manifests[*d].subjects.len())
            .into_par_iter()
            .map(|s| load(*d, s))
            .collect::<Result<BTreeMap<_, _>, BenchmarkError>>()?;
        run_units(&loaded, units)?;
    }
    let mut rows = rows.into_inner().expect("no panic holds the lock");
    rows.sort_by_key(|(i, _)| *i);
    let results: Vec<BenchmarkRow> = rows.into_iter().flat_map(|(_, r)| r).collect();
    let names: Vec<String> = params.presets.iter().map(Preset::to_string).collect();
    Ok(BenchmarkReport {
        summary: summarise(&results, &names),
        comparisons: compare(&results, &names),
        results,
        skipped: skipped.into_inner().expect("no panic holds the lock"),
        wall_s: t0.elapsed().as_secs_f64(),
        threads: rayon::current_num_threads(),
    })
}

/// Every run of a subject, labelled (the manifest's event mapping, speller geometry and spelled
/// texts) and epoched, in the order train then test.
/// A subject's runs, read, labelled, matched to the first run's [`Layout`] (the one channel and
/// rate policy `evaluate` applies to its files too) and epoched.
pub(crate) fn load_subject(
    m: &Manifest,
    s: usize,
    pre: &Preprocess,
    on: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<Vec<EpochedRecording>, BenchmarkError> {
    let subj = &m.subjects[s];
    let runs = subj
        .runs()
        .map(|run| (run.as_path(), Labelling::of_run(m, subj, run)));
    dataset::load_epochs(runs, pre, None, None, &mut |run, resampled, of| {
        on(Progress::Resampled { run, resampled, of })
    })
    .map(|(recs, _)| recs)
    .map_err(|source| BenchmarkError::Dataset {
        dataset: m.name.clone(),
        subject: subj.id.clone(),
        source: Box::new(source),
    })
}

/// The recordings of `runs` among a subject's loaded runs.
fn pick(
    m: &Manifest,
    s: usize,
    recs: &[EpochedRecording],
    runs: &[PathBuf],
) -> Vec<EpochedRecording> {
    m.subjects[s]
        .runs()
        .zip(recs)
        .filter(|(r, _)| runs.contains(r))
        .map(|(_, rec)| rec.clone())
        .collect()
}

/// A unit's rows, or why it does not apply (found once the runs were read).
fn run_unit(
    params: &BenchmarkParams,
    manifests: &[Manifest],
    loaded: &BTreeMap<(usize, usize), Vec<EpochedRecording>>,
    u: &Unit,
    starts: &BTreeMap<usize, oddball_decode::unsupervised::PooledStart>,
) -> Result<(Vec<BenchmarkRow>, Option<String>), BenchmarkError> {
    let m = &manifests[u.dataset];
    let subj = &m.subjects[u.subject];
    let recs = &loaded[&(u.dataset, u.subject)];
    if u.protocol == Protocol::Unsupervised {
        return unsupervised_unit(params, m, &subj.id, recs, starts.get(&u.dataset));
    }
    // The subject's runs are loaded train runs first, so train → test borrows them.
    type Runs<'r> = Cow<'r, [EpochedRecording]>;
    let (train, test): (Runs<'_>, Runs<'_>) = match u.protocol {
        Protocol::TrainTest => {
            let (train, test) = recs.split_at(subj.train.len());
            (Cow::Borrowed(train), Cow::Borrowed(test))
        }
        Protocol::WithinSession => {
            let runs = &u
                .session
                .as_ref()
                .expect("within-session units name a session")
                .1;
            (
                Cow::Owned(pick(m, u.subject, recs, runs)),
                Cow::Owned(Vec::new()),
            )
        }
        Protocol::Unsupervised => unreachable!("replayed above"),
        Protocol::CrossSubject => {
            let mut train = Vec::new();
            for (o, other) in m
                .subjects
                .iter()
                .enumerate()
                .filter(|(o, _)| *o != u.subject)
            {
                let theirs = &loaded[&(u.dataset, o)];
                check_layout(m, &subj.id, &recs[0], &other.id, &theirs[0])?;
                train.extend(theirs.iter().cloned());
            }
            (Cow::Owned(train), Cow::Borrowed(&recs[..]))
        }
    };
    let eval = EvaluateParams {
        presets: params.presets.clone(),
        folds: params.folds,
        tune: false,
    };
    let session = u.session.as_ref().map(|(name, _)| name.clone());
    let scored = if test.is_empty() { &train } else { &test };
    let n_epochs: usize = scored.iter().map(|r| r.epochs.n_epochs()).sum();
    let n_targets: usize = scored
        .iter()
        .flat_map(|r| r.epochs.events())
        .filter(|e| e.target == Some(true))
        .count();
    let failed = |source| BenchmarkError::Evaluate {
        dataset: m.name.clone(),
        subject: subj.id.clone(),
        protocol: u.protocol,
        session: session.clone(),
        source: Box::new(source),
    };
    // Copies made for this unit (other subjects', a session's runs) are pooled as they are
    // freed; runs borrowed from the loaded ones are pooled by copy, the loaded ones kept.
    let set = match train {
        Cow::Borrowed(runs) => TrainingSet::of(runs),
        Cow::Owned(runs) => TrainingSet::pool(runs),
    }
    .map_err(&failed)?;
    let results = evaluate::evaluate(&eval, &set, &test, &mut |_| {}).map_err(failed)?;
    let rows = results
        .iter()
        .map(|r| {
            row(
                m,
                &subj.id,
                session.clone(),
                u.protocol,
                r,
                n_epochs,
                n_targets,
            )
        })
        .collect();
    Ok((rows, None))
}

/// [`Protocol::Unsupervised`] on a subject's runs: one row, or why it does not apply.
fn unsupervised_unit(
    params: &BenchmarkParams,
    m: &Manifest,
    subject: &str,
    recs: &[EpochedRecording],
    transfer: Option<&oddball_decode::unsupervised::PooledStart>,
) -> Result<(Vec<BenchmarkRow>, Option<String>), BenchmarkError> {
    let t0 = Instant::now();
    // From the P300 template (as `evaluate --unsupervised` and a session) and the pooled start
    // if any, the default covariance.
    let settings = crate::unsupervised::ReplaySettings {
        template: true,
        transfer,
        block_toeplitz: false,
    };
    let mut r = crate::unsupervised::replay(&params.preprocess, recs, &settings, &mut |_, _| {});
    let why = || format!("{UNSUPERVISED} on {:?} subject {subject:?}: ", m.name);
    if let Err(ReplayError::NotSpeller { recording }) = &r {
        return Ok((
            vec![],
            Some(why() + &format!("{recording} is not a speller")),
        ));
    }
    // A start that names none of the channels cannot start anything: without it, noted.
    let mut note = None;
    if let Err(ReplayError::Unsupervised(
        oddball_decode::unsupervised::UnsupervisedError::NoSharedChannels { .. },
    )) = &r
    {
        note = Some(why() + "replayed without the pooled start, which names none of its channels");
        let alone = crate::unsupervised::ReplaySettings {
            transfer: None,
            ..settings
        };
        r = crate::unsupervised::replay(&params.preprocess, recs, &alone, &mut |_, _| {});
    }
    let r = r.map_err(|e| BenchmarkError::Unsupervised {
        dataset: m.name.clone(),
        subject: subject.to_string(),
        source: Box::new(e),
    })?;
    let events = || recs.iter().flat_map(|r| r.epochs.events());
    let n = r.n_characters;
    Ok((
        vec![BenchmarkRow {
            dataset: m.name.clone(),
            subject: subject.to_string(),
            session: None,
            protocol: Protocol::Unsupervised,
            preset: UNSUPERVISED.to_string(),
            auc: r.auc,
            n_epochs: events().count(),
            n_targets: events().filter(|e| e.target == Some(true)).count(),
            n_chars: Some(n),
            n_choices: recs[0].speller.as_ref().map(|s| s.n_rows() * s.n_cols()),
            chars_by_reps: Some(
                r.posthoc_chars_by_reps
                    .iter()
                    .map(|a| (a * n as f64).round() as usize)
                    .collect(),
            ),
            itr_bits_per_min: None,
            fit_s: t0.elapsed().as_secs_f64(),
            online_chars: Some(r.online_correct.iter().map(|&c| usize::from(c)).sum()),
        }],
        note,
    ))
}

fn check_layout(
    m: &Manifest,
    subject: &str,
    a: &EpochedRecording,
    other: &str,
    b: &EpochedRecording,
) -> Result<(), BenchmarkError> {
    // A model of one subject scores the other's epochs as they are: no matching.
    let layout = |r: &EpochedRecording| Layout::of_epochs(&r.epochs, r.name.clone());
    match layout(a).differs(&layout(b)) {
        Some(what) => Err(BenchmarkError::Layout {
            dataset: m.name.clone(),
            subject: subject.to_string(),
            other: other.to_string(),
            what,
        }),
        None => Ok(()),
    }
}

fn row(
    m: &Manifest,
    subject: &str,
    session: Option<String>,
    protocol: Protocol,
    r: &PipelineResult,
    n_epochs: usize,
    n_targets: usize,
) -> BenchmarkRow {
    let chars_by_reps = r
        .speller_accuracy
        .as_ref()
        .zip(r.speller_n_chars)
        .map(|(acc, n)| {
            acc.iter()
                .map(|a| (a * n as f64).round() as usize)
                .collect()
        });
    BenchmarkRow {
        dataset: m.name.clone(),
        subject: subject.to_string(),
        session,
        protocol,
        preset: r.pipeline.clone(),
        auc: r.auc,
        n_epochs,
        n_targets,
        n_chars: r.speller_n_chars,
        n_choices: r.speller_choices,
        chars_by_reps,
        itr_bits_per_min: r.itr_at_best.map(|i| i.bits_per_minute),
        fit_s: r.fit_s,
        online_chars: None,
    }
}

/// Mean ± sd of the AUC and the mean character accuracy per protocol and preset.
pub fn summarise(rows: &[BenchmarkRow], presets: &[String]) -> Vec<PresetSummary> {
    let mut out = Vec::new();
    for protocol in Protocol::ALL {
        let unsupervised = [UNSUPERVISED.to_string()];
        let presets = match protocol {
            Protocol::Unsupervised => &unsupervised[..],
            _ => presets,
        };
        for preset in presets {
            let mine: Vec<&BenchmarkRow> = rows
                .iter()
                .filter(|r| r.protocol == protocol && &r.preset == preset)
                .collect();
            if mine.is_empty() {
                continue;
            }
            let n = mine.len();
            let mean = mine.iter().map(|r| r.auc).sum::<f64>() / n as f64;
            let sd = (n > 1).then(|| {
                (mine.iter().map(|r| (r.auc - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
            });
            let spellers: Vec<(&Vec<usize>, usize)> = mine
                .iter()
                .filter_map(|r| r.chars_by_reps.as_ref().zip(r.n_chars))
                .filter(|(_, n)| *n > 0)
                .collect();
            let char_accuracy_by_reps = (!spellers.is_empty()).then(|| {
                let reps = spellers.iter().map(|(c, _)| c.len()).min().unwrap_or(0);
                (0..reps)
                    .map(|k| {
                        spellers
                            .iter()
                            .map(|(c, n)| c[k] as f64 / *n as f64)
                            .sum::<f64>()
                            / spellers.len() as f64
                    })
                    .collect()
            });
            out.push(PresetSummary {
                protocol,
                preset: preset.clone(),
                n,
                auc_mean: mean,
                auc_sd: sd,
                char_accuracy_by_reps,
            });
        }
    }
    out
}

/// One-sided Wilcoxon signed-rank tests of every ordered pair of presets per protocol, paired by
/// data set, subject and session.
pub fn compare(rows: &[BenchmarkRow], presets: &[String]) -> Vec<Comparison> {
    let key = |r: &BenchmarkRow| (r.dataset.clone(), r.subject.clone(), r.session.clone());
    let mut out = Vec::new();
    for protocol in Protocol::ALL {
        let by_preset = |p: &String| -> BTreeMap<_, f64> {
            rows.iter()
                .filter(|r| r.protocol == protocol && &r.preset == p)
                .map(|r| (key(r), r.auc))
                .collect()
        };
        for a in presets {
            for b in presets.iter().filter(|b| *b != a) {
                let (xa, xb) = (by_preset(a), by_preset(b));
                let (x, y): (Vec<f64>, Vec<f64>) = xa
                    .iter()
                    .filter_map(|(k, &va)| xb.get(k).map(|&vb| (va, vb)))
                    .unzip();
                if x.is_empty() {
                    continue;
                }
                let mean_auc_diff =
                    x.iter().zip(&y).map(|(a, b)| a - b).sum::<f64>() / x.len() as f64;
                out.push(Comparison {
                    protocol,
                    a: a.clone(),
                    b: b.clone(),
                    n: x.len(),
                    mean_auc_diff,
                    pvalue: wilcoxon(&x, &y, Alternative::Greater)
                        .ok()
                        .map(|w| w.pvalue),
                });
            }
        }
    }
    out
}

/// The results as CSV, one line per row of [`BenchmarkReport::results`]; `chars_by_reps` is
/// `;`-separated and empty fields are nulls.
pub fn to_csv(rows: &[BenchmarkRow]) -> String {
    let mut s = String::from(
        "dataset,subject,session,protocol,preset,auc,n_epochs,n_targets,n_chars,chars_by_reps,\
         itr_bits_per_min,fit_s,online_chars\n",
    );
    let field = |t: &str| {
        if t.contains([',', '"', '\n']) {
            format!("\"{}\"", t.replace('"', "\"\""))
        } else {
            t.to_string()
        }
    };
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            field(&r.dataset),
            field(&r.subject),
            field(r.session.as_deref().unwrap_or("")),
            r.protocol,
            field(&r.preset),
            r.auc,
            r.n_epochs,
            r.n_targets,
            r.n_chars.map(|n| n.to_string()).unwrap_or_default(),
            r.chars_by_reps
                .as_ref()
                .map(|c| c
                    .iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(";"))
                .unwrap_or_default(),
            r.itr_bits_per_min
                .map(|v| v.to_string())
                .unwrap_or_default(),
            r.fit_s,
            r.online_chars.map(|n| n.to_string()).unwrap_or_default(),
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(subject: &str, preset: &str, auc: f64, chars: Option<Vec<usize>>) -> BenchmarkRow {
        BenchmarkRow {
            dataset: "d".into(),
            subject: subject.into(),
            session: None,
            protocol: Protocol::TrainTest,
            preset: preset.into(),
            auc,
            n_epochs: 10,
            n_targets: 2,
            n_chars: chars.as_ref().map(|_| 4),
            n_choices: chars.as_ref().map(|_| 36),
            chars_by_reps: chars,
            itr_bits_per_min: None,
            fit_s: 0.0,
            online_chars: None,
        }
    }

    #[test]
    fn protocols_parse_by_name() {
        for p in Protocol::ALL {
            assert_eq!(p.name().parse::<Protocol>().unwrap(), p);
        }
        assert!("loso"
            .parse::<Protocol>()
            .unwrap_err()
            .contains("cross-subject"));
    }

    #[test]
    fn summary_is_mean_and_sample_sd_and_mean_char_accuracy() {
        let presets = vec!["lda".to_string(), "mdm".to_string()];
        let rows = vec![
            row("1", "lda", 0.9, Some(vec![2, 4])),
            row("2", "lda", 0.7, Some(vec![0, 2, 4])),
            row("1", "mdm", 0.8, None),
        ];
        let s = summarise(&rows, &presets);
        assert_eq!(s.len(), 2);
        assert!((s[0].auc_mean - 0.8).abs() < 1e-12);
        // sample sd of 0.9 and 0.7
        assert!((s[0].auc_sd.unwrap() - 0.02f64.sqrt()).abs() < 1e-12);
        assert_eq!(
            s[0].char_accuracy_by_reps.as_deref(),
            Some(&[0.25, 0.75][..])
        );
        assert_eq!(s[1].auc_sd, None);
        assert_eq!(s[1].char_accuracy_by_reps, None);
    }

    #[test]
    fn comparisons_pair_subjects_and_test_one_sided() {
        let presets = vec!["a".to_string(), "b".to_string()];
        let mut rows = Vec::new();
        for (i, d) in [0.05, 0.02, 0.03, 0.04, 0.01, 0.06].iter().enumerate() {
            rows.push(row(&i.to_string(), "a", 0.8 + d, None));
            rows.push(row(&i.to_string(), "b", 0.8, None));
        }
        // a subject only one preset scored is left out of the pairs
        rows.push(row("x", "a", 0.1, None));
        let c = compare(&rows, &presets);
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].a.as_str(), c[0].n), ("a", 6));
        assert!((c[0].mean_auc_diff - 0.035).abs() < 1e-12);
        // all six differences positive: exact p = 1/64 (scipy.stats.wilcoxon, greater)
        assert!((c[0].pvalue.unwrap() - 1.0 / 64.0).abs() < 1e-12);
        assert!((c[1].pvalue.unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn csv_has_one_line_per_row_and_nulls_empty() {
        let csv = to_csv(&[
            row("s,1", "lda", 0.5, Some(vec![1, 2])),
            row("2", "lda", 0.5, None),
        ]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[1].starts_with("d,\"s,1\",,train-test,lda,0.5,10,2,4,1;2,,"));
        assert!(lines[2].contains(",lda,0.5,10,2,,,,"));
    }
}
