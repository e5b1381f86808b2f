//! Cross-validation folds of epochs: groups (speller characters) kept whole, or stratified by
//! label as scikit-learn's `StratifiedKFold` without shuffling.

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Cross-validation folds: the test fold of every epoch.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Folds {
    fold_of: Vec<usize>,
    n_folds: usize,
    grouped: bool,
}

impl Folds {
    /// Number of folds (the `k` asked for, or fewer when there are fewer groups).
    pub fn n_folds(&self) -> usize {
        self.n_folds
    }

    /// Test fold of each epoch.
    pub fn fold_of(&self) -> &[usize] {
        &self.fold_of
    }

    /// Whether the folds keep groups together (rather than being stratified by label).
    pub fn grouped(&self) -> bool {
        self.grouped
    }

    /// (training indices, test indices) of fold `f`, each in increasing order.
    pub fn split(&self, f: usize) -> (Vec<usize>, Vec<usize>) {
        (0..self.fold_of.len()).partition(|&i| self.fold_of[i] != f)
    }
}

/// `k` folds of epochs labelled `y`: groups (e.g. speller characters; `groups[i]` is epoch `i`'s)
/// kept whole, `min(k, n_groups)` folds of contiguous runs of groups (in order of first
/// appearance); without groups, stratified by label (`min(k, smaller class)` folds). Every fold
/// must leave both classes in its training and its test part.
pub fn cv_folds(y: &[bool], groups: Option<&[usize]>, k: usize) -> Result<Folds> {
    if k < 2 {
        return Err(DecodeError::InvalidParameter {
            name: "folds",
            value: k.to_string(),
            reason: "cross-validation needs at least 2 folds".into(),
        });
    }
    let n_targets = y.iter().filter(|&&t| t).count();
    let n_nontargets = y.len() - n_targets;
    if n_targets < 2 || n_nontargets < 2 {
        return Err(DecodeError::NeedBothClasses {
            n_targets,
            n_nontargets,
        });
    }
    let folds = match groups {
        Some(g) => {
            if g.len() != y.len() {
                return Err(DecodeError::LabelCount {
                    n_samples: g.len(),
                    n_labels: y.len(),
                });
            }
            let mut order: Vec<usize> = Vec::new();
            let index: Vec<usize> = g
                .iter()
                .map(|id| match order.iter().position(|o| o == id) {
                    Some(p) => p,
                    None => {
                        order.push(*id);
                        order.len() - 1
                    }
                })
                .collect();
            let n_groups = order.len();
            let n_folds = k.min(n_groups);
            if n_folds < 2 {
                return Err(DecodeError::TooFewSamples {
                    what: format!(
                        "cross-validation kept by group needs at least 2 groups, got {n_groups}"
                    ),
                });
            }
            Folds {
                fold_of: index.iter().map(|&gi| gi * n_folds / n_groups).collect(),
                n_folds,
                grouped: true,
            }
        }
        None => {
            let n_folds = k.min(n_targets).min(n_nontargets);
            Folds {
                fold_of: crate::svm::stratified_folds(y, n_folds)?,
                n_folds,
                grouped: false,
            }
        }
    };
    for f in 0..folds.n_folds {
        let (tr, te) = folds.split(f);
        for (part, idx) in [("training", &tr), ("test", &te)] {
            let t = idx.iter().filter(|&&i| y[i]).count();
            if t == 0 || t == idx.len() {
                return Err(DecodeError::TooFewSamples {
                    what: format!(
                        "the {part} part of fold {} of {} has {t} targets among {} epochs: \
                         it needs both classes",
                        f + 1,
                        folds.n_folds,
                        idx.len()
                    ),
                });
            }
        }
    }
    Ok(folds)
}
