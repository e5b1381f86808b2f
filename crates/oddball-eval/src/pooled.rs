//! Pooled starts for the unsupervised decoder built from labelled data sets
//! (`oddball_decode::unsupervised::PooledStart`): every subject's effect-size pattern (its runs,
//! labelled by the manifest), pooled by channel name over subjects. What a benchmark measures
//! with one is leave-one-data-set-out ([`Transfer::LeaveOneDataSetOut`]): a data set's subjects
//! are replayed from a start built without any of that data set's recordings.

use std::collections::BTreeMap;

use oddball_decode::pipeline::Preprocess;
use oddball_decode::unsupervised::{PooledPattern, PooledStart, POOLED_VERSION};
use oddball_io::Manifest;
use rayon::prelude::*;

use crate::benchmark::{load_subject, BenchmarkError, Progress};
use crate::unsupervised::{labelled_pattern, ReplayError};
use oddball_decode::unsupervised::UnsupervisedError;

/// Which pooled start an unsupervised replay adds to its refits' starts.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Transfer {
    /// None: the template (and the last fit, the random starts) only.
    #[default]
    None,
    /// This one, for every subject (e.g. the shipped start, or a file).
    Given(PooledStart),
    /// Built per data set from every other data set of the benchmark (labelled by their
    /// manifests): no recording of the replayed data set is in its start.
    LeaveOneDataSetOut,
}

/// Every subject's pattern, per data set (index into `manifests`), under `pre`; subjects whose
/// channels are only numbered (`Channel 1`, `ch3`) have none.
pub fn subject_patterns(
    manifests: &[Manifest],
    pre: &Preprocess,
    on: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<Vec<(usize, PooledPattern)>, BenchmarkError> {
    let jobs: Vec<(usize, usize)> = manifests
        .iter()
        .enumerate()
        .flat_map(|(d, m)| (0..m.subjects.len()).map(move |s| (d, s)))
        .collect();
    jobs.par_iter()
        .map(|&(d, s)| {
            let m = &manifests[d];
            let recs = load_subject(m, s, pre, on)?;
            let source = format!("{}/{}", m.name, m.subjects[s].id);
            match labelled_pattern(&recs, pre.causal, &source) {
                Ok(p) => Ok(Some((d, p))),
                // Channels numbered, not named (e.g. `Channel 1`…): nothing to pool.
                Err(ReplayError::Unsupervised(UnsupervisedError::NoNamedChannels { .. })) => {
                    Ok(None)
                }
                Err(e) => Err(BenchmarkError::Unsupervised {
                    dataset: m.name.clone(),
                    subject: m.subjects[s].id.clone(),
                    source: Box::new(e),
                }),
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.into_iter().flatten().collect())
}

/// The patterns of every data set but `left_out`, pooled (`None` when no other data set has
/// one).
pub fn pool_without(
    patterns: &[(usize, PooledPattern)],
    left_out: Option<usize>,
) -> Result<Option<PooledPattern>, BenchmarkError> {
    let parts: Vec<PooledPattern> = patterns
        .iter()
        .filter(|(d, _)| Some(*d) != left_out)
        .map(|(_, p)| p.clone())
        .collect();
    if parts.is_empty() {
        return Ok(None);
    }
    PooledPattern::pool(&parts)
        .map(Some)
        .map_err(|e| BenchmarkError::Pooled(Box::new(e)))
}

/// The pooled start of every subject of `manifests`, zero-phase (`pre`) and causal (`pre`
/// made causal): what `oddball benchmark … --write-pooled FILE` writes and the library ships.
pub fn build(
    manifests: &[Manifest],
    pre: &Preprocess,
    on: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<PooledStart, BenchmarkError> {
    let mut patterns = Vec::new();
    for p in [
        Preprocess {
            causal: false,
            ..*pre
        },
        pre.as_causal(),
    ] {
        let parts = subject_patterns(manifests, &p, on)?;
        patterns.extend(pool_without(&parts, None)?);
    }
    let start = PooledStart {
        version: POOLED_VERSION,
        patterns,
    };
    start
        .check()
        .map_err(|e| BenchmarkError::Pooled(Box::new(e)))?;
    Ok(start)
}

/// Per data set, the start its subjects' unsupervised replays add: `transfer`'s.
pub(crate) fn starts_by_dataset(
    transfer: &Transfer,
    manifests: &[Manifest],
    pre: &Preprocess,
    needed: &[usize],
    on: &(dyn Fn(Progress<'_>) + Sync),
) -> Result<BTreeMap<usize, PooledStart>, BenchmarkError> {
    let mut out = BTreeMap::new();
    match transfer {
        Transfer::None => {}
        Transfer::Given(s) => {
            for &d in needed {
                out.insert(d, s.clone());
            }
        }
        Transfer::LeaveOneDataSetOut => {
            if needed.is_empty() {
                return Ok(out);
            }
            let parts = subject_patterns(manifests, pre, on)?;
            for &d in needed {
                if let Some(p) = pool_without(&parts, Some(d))? {
                    out.insert(
                        d,
                        PooledStart {
                            version: POOLED_VERSION,
                            patterns: vec![p],
                        },
                    );
                }
            }
        }
    }
    Ok(out)
}
