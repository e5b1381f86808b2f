//! Cross-validation folds of epochs, the one home of every fold rule: groups (speller
//! characters) kept whole ([`cv_folds`]), or stratified by label as scikit-learn's
//! `StratifiedKFold` without shuffling ([`stratified_folds`]) or shuffled as with its
//! `random_state` ([`stratified_folds_shuffled`], the SVM's probability calibration), or groups
//! dealt round-robin ([`interleaved_folds`], a session's calibration); and each fold's two parts
//! ([`Split`], from [`Folds::splits`]).

use crate::linalg::check_labels;
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

    /// Fold `f`'s parts of the epochs labelled `y` (in `groups`, if given).
    pub fn split_of(&self, f: usize, y: &[bool], groups: Option<&[usize]>) -> Split {
        let (train, test) = self.split(f);
        Split {
            fold: f,
            y_train: train.iter().map(|&i| y[i]).collect(),
            y_test: test.iter().map(|&i| y[i]).collect(),
            groups_train: groups.map(|g| train.iter().map(|&i| g[i]).collect()),
            train,
            test,
        }
    }

    /// Every fold's parts, in fold order ([`Folds::split_of`]).
    pub fn splits<'a>(
        &'a self,
        y: &'a [bool],
        groups: Option<&'a [usize]>,
    ) -> impl Iterator<Item = Split> + 'a {
        (0..self.n_folds()).map(move |f| self.split_of(f, y, groups))
    }
}

/// One fold's two parts: indices into the epochs (each in increasing order), the labels of both
/// parts and the groups of the training part (a stack's inner folds keep them whole).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Split {
    /// The fold (0-based) whose test part this is.
    pub fold: usize,
    pub train: Vec<usize>,
    pub test: Vec<usize>,
    pub y_train: Vec<bool>,
    pub y_test: Vec<bool>,
    pub groups_train: Option<Vec<usize>>,
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
                fold_of: stratified_folds(y, n_folds)?,
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

/// Folds that deal groups round-robin, as a session's calibration is cross-validated: group `g`
/// (a trial: `groups[i]` is epoch `i`'s) falls in fold `g % k`, so consecutive trials land in
/// different folds and slow drift is spread over all of them. Residues no group falls on make no
/// fold (the others keep their order); with fewer than two, nothing can be held out and there is
/// no fold.
pub fn interleaved_folds(groups: &[usize], k: usize) -> Folds {
    let k = k.max(1);
    let mut used = vec![false; k];
    for &g in groups {
        used[g % k] = true;
    }
    let mut fold_index = vec![0; k];
    let mut n_folds = 0;
    for (r, &u) in used.iter().enumerate() {
        if u {
            fold_index[r] = n_folds;
            n_folds += 1;
        }
    }
    if n_folds < 2 {
        n_folds = 0;
    }
    Folds {
        fold_of: groups.iter().map(|&g| fold_index[g % k]).collect(),
        n_folds,
        grouped: true,
    }
}

/// Test-fold index of every sample, as scikit-learn's `StratifiedKFold(n_splits, shuffle=False)`:
/// each class (in order of first appearance) is dealt to folds in contiguous blocks whose sizes
/// follow scikit-learn's allocation. Every class needs at least `n_splits` samples.
pub fn stratified_folds(y: &[bool], n_splits: usize) -> Result<Vec<usize>> {
    stratified(y, n_splits, None)
}

/// Test-fold index of every sample, as scikit-learn's `StratifiedKFold(n_splits, shuffle=True,
/// random_state=seed)` (scikit-learn 1.x, numpy's legacy `RandomState`): the fold labels of each
/// class, in blocks as [`stratified_folds`] deals them, are shuffled in class order by one
/// MT19937 stream seeded with `seed` (`init_genrand`, from the `rand_mt` crate), each with
/// numpy's Fisher–Yates `shuffle` drawing `j ≤ i` by masked rejection of 32-bit outputs
/// (numpy's `random_interval`).
pub fn stratified_folds_shuffled(y: &[bool], n_splits: usize, seed: u32) -> Result<Vec<usize>> {
    stratified(y, n_splits, Some(seed))
}

/// numpy's legacy `RandomState.shuffle` of a 1-D array.
fn numpy_shuffle(v: &mut [usize], rng: &mut rand_mt::Mt) {
    for i in (1..v.len()).rev() {
        // numpy's random_interval(i): the smallest all-ones mask covering i, redrawn until ≤ i
        let max = i as u64;
        let mask = u64::MAX >> max.leading_zeros();
        let j = loop {
            let value = u64::from(rng.next_u32()) & mask;
            if value <= max {
                break value as usize;
            }
        };
        v.swap(i, j);
    }
}

/// [`stratified_folds`], shuffled as [`stratified_folds_shuffled`] when `shuffle_seed` is given.
pub(crate) fn stratified(
    y: &[bool],
    n_splits: usize,
    shuffle_seed: Option<u32>,
) -> Result<Vec<usize>> {
    if n_splits < 2 {
        return Err(DecodeError::InvalidParameter {
            name: "n_folds",
            value: n_splits.to_string(),
            reason: "cross-validation needs at least 2 folds".into(),
        });
    }
    let (n_t, n_n) = check_labels(y.len(), y)?;
    if n_t.min(n_n) < n_splits {
        return Err(DecodeError::TooFewSamples {
            what: format!(
                "{n_splits} stratified folds need {n_splits} samples of each class, got {n_t} \
                 targets and {n_n} non-targets"
            ),
        });
    }
    // classes encoded by first appearance; y_order = sorted codes
    let first = y[0];
    let counts = [
        y.iter().filter(|&&v| v == first).count(),
        y.iter().filter(|&&v| v != first).count(),
    ];
    // allocation[i][k] = number of code-k entries among y_order[i::n_splits]
    let mut alloc = vec![[0usize; 2]; n_splits];
    for pos in 0..y.len() {
        let code = usize::from(pos >= counts[0]);
        alloc[pos % n_splits][code] += 1;
    }
    // per class, its fold labels in blocks (numpy's arange(n_splits).repeat(allocation[:, k]))
    let mut rng = shuffle_seed.map(rand_mt::Mt::new);
    let per_class: Vec<Vec<usize>> = (0..2)
        .map(|code| {
            let mut labels: Vec<usize> = (0..n_splits)
                .flat_map(|fold| std::iter::repeat_n(fold, alloc[fold][code]))
                .collect();
            if let Some(rng) = rng.as_mut() {
                numpy_shuffle(&mut labels, rng);
            }
            labels
        })
        .collect();
    let mut next = [0usize; 2];
    let folds = y
        .iter()
        .map(|&v| {
            let code = usize::from(v != first);
            next[code] += 1;
            per_class[code][next[code] - 1]
        })
        .collect();
    Ok(folds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_follow_sklearn_allocation() {
        // 3 targets first seen, 7 non-targets; 3 folds
        let y = [
            true, false, false, true, false, false, true, false, false, false,
        ];
        let f = stratified_folds(&y, 3).unwrap();
        // class "true" (first seen) gets one per fold; non-targets 3/2/2 in order
        assert_eq!(f, vec![0, 0, 0, 1, 0, 1, 2, 1, 2, 2]);
        assert!(stratified_folds(&y, 4).is_err());
        assert!(stratified_folds(&y, 1).is_err());
    }

    /// Every epoch of group `g` is tested in the fold of residue `g % k`; residues no group
    /// falls on make no fold; a single residue leaves nothing to train on, so no fold.
    #[test]
    fn interleaved_folds_deal_groups_round_robin() {
        let groups: Vec<usize> = (0..24).map(|i| i / 4).collect(); // 6 trials of 4 epochs
        let f = interleaved_folds(&groups, 4);
        assert_eq!(f.n_folds(), 4);
        for (i, &g) in groups.iter().enumerate() {
            assert_eq!(f.fold_of()[i], g % 4);
        }
        // Groups 0, 2, 4 with k = 4: residues 0 and 2 only, renumbered 0 and 1 in order.
        let sparse = [0, 0, 2, 2, 4, 4];
        let f = interleaved_folds(&sparse, 4);
        assert_eq!(f.n_folds(), 2);
        assert_eq!(f.fold_of(), &[0, 0, 1, 1, 0, 0]);
        let (train, test) = f.split(1);
        assert_eq!((train, test), (vec![0, 1, 4, 5], vec![2, 3]));
        assert_eq!(interleaved_folds(&[3, 3, 7], 4).n_folds(), 0);
    }
}
