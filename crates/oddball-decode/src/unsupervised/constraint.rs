//! The paradigm's constraint: which codes compete in a trial, which flashes show groups of
//! choices, which codes are never attended ([`Constraint`]).

use std::collections::BTreeMap;

use oddball_io::Speller;
use serde::{Deserialize, Serialize};

use super::error::{Result, UnsupervisedError};

/// Which codes compete: in every trial exactly one code of each set is attended; and which
/// codes are never attended (decoys).
///
/// **Decoys** are flashes the paradigm shows but nobody is asked to attend: an extra symbol that
/// is never a target (Hübner et al. 2017's speller), a blank flash. Their target share is 0, so
/// they are the one group whose labels the paradigm gives away: the EM takes their epochs as
/// non-targets (responsibility 0, in no slot's evidence). The likelihood stays exact (the
/// model's non-target term of those epochs, as every other epoch's baseline), so the objective
/// still never decreases; and the non-target mean they anchor is what a labelling that turns a
/// non-attended code into the target has to fit too. This is how learning from label
/// proportions enters the EM here: its share-0 group as known labels (the [`super::Llp`] estimator fits
/// groups of any shares on its own).
///
/// **Group flashes** ([`Constraint::groups`]): a flash may show any group of the choices (a
/// checkerboard or region speller, Hübner et al.'s label-proportion speller). Then one choice
/// of `n_choices` is attended per trial, and a flash is a target exactly when its group holds
/// it: the choice's evidence is the sum of the LLRs of the flashes showing it, and an epoch's
/// responsibility the posterior of its group. Groups of different sizes have different target
/// shares; the EM uses that (and every flash's membership) exactly, so learning from label
/// proportions needs no separate estimator there.
///
/// Read back (a saved model, a pickled decoder) through the same checks as the constructors.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "ConstraintFields")]
pub struct Constraint {
    sets: Vec<Vec<u32>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    decoys: Vec<u32>,
    /// Code → the choices (indices into the one set, `0..n_choices`) its flash shows; empty
    /// for the code-per-choice forms.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    groups: BTreeMap<u32, Vec<usize>>,
}

/// A [`Constraint`] as saved, before its checks.
#[derive(Deserialize)]
struct ConstraintFields {
    sets: Vec<Vec<u32>>,
    #[serde(default)]
    decoys: Vec<u32>,
    #[serde(default)]
    groups: BTreeMap<u32, Vec<usize>>,
}

impl TryFrom<ConstraintFields> for Constraint {
    type Error = UnsupervisedError;

    fn try_from(f: ConstraintFields) -> Result<Self> {
        let c = if f.groups.is_empty() {
            Self::new(f.sets)?
        } else {
            let n = f.sets.first().map_or(0, Vec::len);
            if f.sets.len() != 1 || f.sets[0] != (0..n as u32).collect::<Vec<_>>() {
                return Err(UnsupervisedError::InvalidParameter {
                    name: "sets",
                    value: format!("{:?}", f.sets),
                    reason: "with groups, one set of the choices 0, 1, …".into(),
                });
            }
            Self::groups(n, f.groups)?
        };
        c.with_decoys(&f.decoys)
    }
}

impl Constraint {
    /// Sets of at least two codes each, no code in two sets.
    pub fn new(sets: Vec<Vec<u32>>) -> Result<Self> {
        let mut seen = std::collections::BTreeSet::new();
        for (set, codes) in sets.iter().enumerate() {
            if codes.len() < 2 {
                return Err(UnsupervisedError::TooFewChoices {
                    set,
                    n_codes: codes.len(),
                });
            }
            for &code in codes {
                if !seen.insert(code) {
                    return Err(UnsupervisedError::SharedCode { code });
                }
            }
        }
        if sets.is_empty() {
            return Err(UnsupervisedError::TooFewChoices { set: 0, n_codes: 0 });
        }
        Ok(Self {
            sets,
            decoys: Vec::new(),
            groups: BTreeMap::new(),
        })
    }

    /// One of `n_choices` choices attended per trial, each code's flash showing the choices
    /// of its group (type doc). The one set's "codes" are then the choice indices `0..n_choices`
    /// ([`Self::sets`], [`super::Unsupervised::choices`]). Every group non-empty, within range and
    /// without repeats; every choice in some group.
    pub fn groups(n_choices: usize, groups: BTreeMap<u32, Vec<usize>>) -> Result<Self> {
        if n_choices < 2 {
            return Err(UnsupervisedError::TooFewChoices {
                set: 0,
                n_codes: n_choices,
            });
        }
        let mut shown = vec![false; n_choices];
        for (&code, members) in &groups {
            let mut seen = std::collections::BTreeSet::new();
            if members.is_empty() || members.iter().any(|&c| c >= n_choices || !seen.insert(c)) {
                return Err(UnsupervisedError::InvalidParameter {
                    name: "groups",
                    value: format!("code {code}: {members:?}"),
                    reason: format!(
                        "a group lists choices below {n_choices}, at least one, each once"
                    ),
                });
            }
            for &c in members {
                shown[c] = true;
            }
        }
        if let Some(c) = shown.iter().position(|s| !s) {
            return Err(UnsupervisedError::InvalidParameter {
                name: "groups",
                value: format!("choice {c}"),
                reason: "no code flashes it".into(),
            });
        }
        let mut c = Self::new(vec![(0..n_choices as u32).collect()])?;
        c.groups = groups;
        Ok(c)
    }

    /// These sets with `decoys`, codes flashed but never attended (type doc): none in a set,
    /// none twice.
    pub fn with_decoys(mut self, decoys: &[u32]) -> Result<Self> {
        let mut seen = std::collections::BTreeSet::new();
        for &code in decoys {
            if self.targets_of(code).is_some() {
                let what = "is in a choice set";
                return Err(UnsupervisedError::Decoy { code, what });
            }
            if !seen.insert(code) {
                let what = "is listed twice";
                return Err(UnsupervisedError::Decoy { code, what });
            }
        }
        self.decoys = decoys.to_vec();
        Ok(self)
    }

    /// One attended code among `codes` per trial (the four-bulb panel: codes 1–4).
    pub fn one_of(codes: &[u32]) -> Result<Self> {
        Self::new(vec![codes.to_vec()])
    }

    /// One attended row and one attended column per character of `speller`.
    pub fn speller(speller: &Speller) -> Result<Self> {
        Self::new(vec![
            (0..speller.n_rows())
                .map(|r| speller.code_of_row(r))
                .collect(),
            (0..speller.n_cols())
                .map(|c| speller.code_of_col(c))
                .collect(),
        ])
    }

    /// The sets of competing codes.
    pub fn sets(&self) -> &[Vec<u32>] {
        &self.sets
    }

    /// Whether flashes show groups of choices ([`Self::groups`]): the one set is the choices.
    pub fn is_grouped(&self) -> bool {
        !self.groups.is_empty()
    }

    /// The codes flashed but never attended.
    pub fn decoys(&self) -> &[u32] {
        &self.decoys
    }

    /// Whether `code` is a decoy.
    pub fn is_decoy(&self, code: u32) -> bool {
        self.decoys.contains(&code)
    }

    /// (set, index within the set) of `code`, where a code is one choice (not under
    /// [`Self::groups`]: see [`Self::targets_of`]).
    pub fn locate(&self, code: u32) -> Option<(usize, usize)> {
        if !self.groups.is_empty() {
            return None;
        }
        self.sets
            .iter()
            .enumerate()
            .find_map(|(s, codes)| codes.iter().position(|&c| c == code).map(|i| (s, i)))
    }

    /// The set of `code` and the choices (indices within the set) whose being attended makes
    /// its flash a target: one for a code per choice, its group under [`Self::groups`]; `None`
    /// for a decoy or an unknown code.
    pub fn targets_of(&self, code: u32) -> Option<(usize, Vec<usize>)> {
        if self.groups.is_empty() {
            return self.locate(code).map(|(s, i)| (s, vec![i]));
        }
        self.groups.get(&code).map(|g| (0, g.clone()))
    }

    /// The responsibility of an epoch of `code`: the summed posterior of the choices that make
    /// it a target, from its trial's posterior per set (0 for a decoy or an unknown code).
    pub fn attended_weight(&self, code: u32, sets: &[Vec<f64>]) -> f64 {
        match self.targets_of(code) {
            Some((s, choices)) => choices.iter().map(|&c| sets[s][c]).sum(),
            None => 0.0,
        }
    }
}
