//! Scores of a decoder: epoch ROC-AUC, selection accuracy versus the number of repetitions (4-choice
//! panels and row/column spellers), and the Wolpaw information transfer rate.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::DecodeError;

/// Area under the ROC curve of `scores` for `labels` (`true` = positive), by the Mann–Whitney
/// statistic with tied scores given their average rank (as scikit-learn's `roc_auc_score`).
pub fn roc_auc(scores: &[f64], labels: &[bool]) -> Result<f64, DecodeError> {
    if scores.len() != labels.len() {
        return Err(DecodeError::LabelCount {
            n_samples: scores.len(),
            n_labels: labels.len(),
        });
    }
    if let Some(i) = scores.iter().position(|s| !s.is_finite()) {
        return Err(DecodeError::NonFinite {
            what: format!("score of epoch {i}"),
        });
    }
    let n_pos = labels.iter().filter(|&&l| l).count();
    let n_neg = labels.len() - n_pos;
    if n_pos == 0 || n_neg == 0 {
        return Err(DecodeError::NeedBothClasses {
            n_targets: n_pos,
            n_nontargets: n_neg,
        });
    }
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]));
    let mut rank_sum_pos = 0.0;
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && scores[order[j + 1]] == scores[order[i]] {
            j += 1;
        }
        // ranks i+1 ..= j+1 share their mean
        let mean_rank = (i + j + 2) as f64 / 2.0;
        for &k in &order[i..=j] {
            if labels[k] {
                rank_sum_pos += mean_rank;
            }
        }
        i = j + 1;
    }
    let u = rank_sum_pos - (n_pos * (n_pos + 1)) as f64 / 2.0;
    Ok(u / (n_pos as f64 * n_neg as f64))
}

/// Wolpaw's information transfer rate in bits per selection for `n_choices` equiprobable choices
/// picked with accuracy `p`: `log2 N + p log2 p + (1 − p) log2((1 − p)/(N − 1))`; 0 when `p ≤ 1/N`.
pub fn wolpaw_bits(n_choices: usize, p: f64) -> f64 {
    if n_choices < 2 || !p.is_finite() {
        return 0.0;
    }
    let n = n_choices as f64;
    let p = p.clamp(0.0, 1.0);
    if p <= 1.0 / n {
        return 0.0;
    }
    let mut bits = n.log2() + p * p.log2();
    if p < 1.0 {
        bits += (1.0 - p) * ((1.0 - p) / (n - 1.0)).log2();
    }
    bits
}

/// Information transfer rate of a paradigm: bits per selection and per minute.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Itr {
    pub n_choices: usize,
    pub accuracy: f64,
    /// Seconds one selection takes, pauses included.
    pub seconds_per_selection: f64,
    pub bits_per_selection: f64,
    pub bits_per_minute: f64,
}

impl Itr {
    pub fn new(n_choices: usize, accuracy: f64, seconds_per_selection: f64) -> Self {
        let bits = wolpaw_bits(n_choices, accuracy);
        let per_minute = if seconds_per_selection > 0.0 {
            bits * 60.0 / seconds_per_selection
        } else {
            0.0
        };
        Self {
            n_choices,
            accuracy,
            seconds_per_selection,
            bits_per_selection: bits,
            bits_per_minute: per_minute,
        }
    }
}

/// One flash as the selection scorers see it: its stimulus code, whether it was the attended
/// item (or contained it), and the decoder's score (larger = more target-like).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoredFlash {
    pub code: u32,
    pub target: bool,
    pub score: f64,
}

/// Sums of scores per code over the first `r` flashes of each code in a selection block.
fn cumulative_by_code(block: &[ScoredFlash], r: usize) -> BTreeMap<u32, f64> {
    let mut seen: BTreeMap<u32, usize> = BTreeMap::new();
    let mut sums: BTreeMap<u32, f64> = BTreeMap::new();
    for f in block {
        let k = seen.entry(f.code).or_insert(0);
        if *k < r {
            *sums.entry(f.code).or_insert(0.0) += f.score;
        }
        *k += 1;
    }
    sums
}

/// The code with the largest summed score among `codes` (ties to the lowest code).
fn best_of(sums: &BTreeMap<u32, f64>, codes: &[u32]) -> Option<u32> {
    let mut best: Option<(u32, f64)> = None;
    for &c in codes {
        if let Some(&s) = sums.get(&c) {
            if best.is_none_or(|(_, b)| s > b) {
                best = Some((c, s));
            }
        }
    }
    best.map(|(c, _)| c)
}

/// The attended code of a block: the code of its target flashes (`None` unless exactly one code
/// among `codes` is flagged target).
fn attended(block: &[ScoredFlash], codes: &[u32]) -> Option<u32> {
    let mut found: Option<u32> = None;
    for f in block.iter().filter(|f| f.target && codes.contains(&f.code)) {
        match found {
            None => found = Some(f.code),
            Some(c) if c == f.code => {}
            Some(_) => return None,
        }
    }
    found
}

/// Fraction of blocks whose attended code wins after summing the scores of the first
/// `1..=max_reps` repetitions: element `r − 1` is the accuracy with `r` repetitions.
/// Each block is one selection (e.g. one decision of the 4-bulb panel); the winner is the code
/// with the largest summed score.
pub fn choice_accuracy_by_repetitions(
    blocks: &[Vec<ScoredFlash>],
    max_reps: usize,
) -> Result<Vec<f64>, DecodeError> {
    if blocks.is_empty() {
        return Err(DecodeError::TooFewSamples {
            what: "no selection blocks to score".into(),
        });
    }
    let mut correct = vec![0usize; max_reps];
    for (b, block) in blocks.iter().enumerate() {
        let codes: Vec<u32> = {
            let mut c: Vec<u32> = block.iter().map(|f| f.code).collect();
            c.sort_unstable();
            c.dedup();
            c
        };
        let truth = attended(block, &codes).ok_or_else(|| DecodeError::TooFewSamples {
            what: format!("block {b} has no single attended code"),
        })?;
        for (r, hits) in correct.iter_mut().enumerate() {
            if best_of(&cumulative_by_code(block, r + 1), &codes) == Some(truth) {
                *hits += 1;
            }
        }
    }
    Ok(correct
        .into_iter()
        .map(|c| c as f64 / blocks.len() as f64)
        .collect())
}

/// Accuracy for `r = 1..=max_reps`, and the (row code, column code) picked per character.
pub type SpellerScores = (Vec<f64>, Vec<(u32, u32)>);

/// Row/column speller: per block (one character), the best row code among `row_codes` and the
/// best column code among `col_codes` after `r` repetitions; correct when both are the target's.
/// Returns the accuracy for `r = 1..=max_reps` and the (row, column) picked at `max_reps`.
pub fn speller_accuracy_by_repetitions(
    blocks: &[Vec<ScoredFlash>],
    row_codes: &[u32],
    col_codes: &[u32],
    max_reps: usize,
) -> Result<SpellerScores, DecodeError> {
    if blocks.is_empty() {
        return Err(DecodeError::TooFewSamples {
            what: "no characters to score".into(),
        });
    }
    let mut correct = vec![0usize; max_reps];
    let mut picks = Vec::with_capacity(blocks.len());
    for (b, block) in blocks.iter().enumerate() {
        let (Some(row), Some(col)) = (attended(block, row_codes), attended(block, col_codes))
        else {
            return Err(DecodeError::TooFewSamples {
                what: format!("character {b} has no single target row and column"),
            });
        };
        let mut last = (0, 0);
        for (r, hits) in correct.iter_mut().enumerate() {
            let sums = cumulative_by_code(block, r + 1);
            let pick = (
                best_of(&sums, row_codes).unwrap_or(0),
                best_of(&sums, col_codes).unwrap_or(0),
            );
            if pick == (row, col) {
                *hits += 1;
            }
            last = pick;
        }
        picks.push(last);
    }
    Ok((
        correct
            .into_iter()
            .map(|c| c as f64 / blocks.len() as f64)
            .collect(),
        picks,
    ))
}

/// The speller character each of `n_flashes` consecutive flashes of one recording belongs to
/// (0-based): blocks of the speller's flashes per character (the last may be shorter), as
/// [`oddball_io::Speller::character_blocks`] cuts them, or one character of all the flashes when
/// that is unknown. The one rule for cross-validation groups, character scoring and replays.
pub fn character_of_flashes(speller: &oddball_io::Speller, n_flashes: usize) -> Vec<usize> {
    match speller.flashes_per_character {
        Some(per) if per > 0 => (0..n_flashes).map(|i| i / per).collect(),
        _ => vec![0; n_flashes],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive_auc(scores: &[f64], labels: &[bool]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for (i, &li) in labels.iter().enumerate() {
            for (j, &lj) in labels.iter().enumerate() {
                if li && !lj {
                    den += 1.0;
                    num += if scores[i] > scores[j] {
                        1.0
                    } else if scores[i] == scores[j] {
                        0.5
                    } else {
                        0.0
                    };
                }
            }
        }
        num / den
    }

    #[test]
    fn auc_equals_the_pairwise_definition_with_ties() {
        let scores = [0.1, 0.4, 0.35, 0.8, 0.4, 0.4, -1.0, 2.0];
        let labels = [false, true, false, true, false, true, false, false];
        let a = roc_auc(&scores, &labels).unwrap();
        assert!((a - naive_auc(&scores, &labels)).abs() < 1e-12);
        assert_eq!(roc_auc(&[1.0, 2.0], &[false, true]).unwrap(), 1.0);
        assert!(roc_auc(&[1.0, 2.0], &[true, true]).is_err());
    }

    #[test]
    fn wolpaw_known_values() {
        assert!((wolpaw_bits(4, 1.0) - 2.0).abs() < 1e-12);
        assert_eq!(wolpaw_bits(4, 0.25), 0.0);
        // N = 36, P = 0.9: log2 36 + 0.9 log2 0.9 + 0.1 log2(0.1/35)
        let expect = 36f64.log2() + 0.9 * 0.9f64.log2() + 0.1 * (0.1f64 / 35.0).log2();
        assert!((wolpaw_bits(36, 0.9) - expect).abs() < 1e-12);
        let itr = Itr::new(4, 1.0, 10.0);
        assert!((itr.bits_per_minute - 12.0).abs() < 1e-12);
    }

    #[test]
    fn repetitions_accumulate_evidence() {
        // Code 2 attended; first repetition favours code 1, the second tips it to code 2.
        let f = |code, target, score| ScoredFlash {
            code,
            target,
            score,
        };
        let block = vec![
            f(1, false, 1.0),
            f(2, true, 0.5),
            f(3, false, 0.0),
            f(1, false, 0.0),
            f(2, true, 1.0),
            f(3, false, 0.0),
        ];
        let acc = choice_accuracy_by_repetitions(&[block], 2).unwrap();
        assert_eq!(acc, vec![0.0, 1.0]);
    }

    #[test]
    fn flashes_belong_to_blocks_of_a_character() {
        let mut speller = oddball_io::Speller::from_rows(&["AB", "CD"]).unwrap();
        assert_eq!(character_of_flashes(&speller, 3), [0, 0, 0]);
        speller.flashes_per_character = Some(2);
        assert_eq!(character_of_flashes(&speller, 5), [0, 0, 1, 1, 2]);
    }
}
