//! BCI Competition III data set II's layout, one block per character, made the continuous
//! layout of data set IIb (`signal` + one state value per sample) that [`super::bci`] reads.
//!
//! Its files hold `Signal` as `n_characters × n_times × n_channels` (single) and `Flashing`,
//! `StimulusCode`, `StimulusType` as `n_characters × n_times`, each row one character's
//! recording, and the training files `TargetChar`, the spelled text (`1 × n_characters` char).
//! The blocks are put one after the other in character order (the data set's own MATLAB
//! examples do the same), so sample `j` of character `i` becomes sample `i · n_times + j`; the
//! number of flashes per character and the spelled text come from the blocks and `TargetChar`
//! (unless the options give them). Memory: the samples are converted once, to the `f64` the
//! recording holds anyway.

use std::path::Path;

use super::file::{MatArray, MatClass, MatFile, MatNumbers, MatValue};
use crate::IoError;

/// What the per-character layout said about the characters.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct PerCharacter {
    /// Flashes (`Flashing` 0 → 1) in every character's block, when all have the same number.
    pub flashes_per_character: Option<usize>,
    /// `TargetChar`, when the file has it.
    pub text: Option<String>,
}

/// When `file` has no variable `signal` but a 3-D variable of that name in another letter case
/// (`Signal`), rewrites it and every `n_characters × n_times` numeric variable in the continuous
/// layout, in place; `None` when the file is not in the per-character layout.
pub(super) fn flatten(
    file: &mut MatFile,
    signal: &str,
    path: &Path,
) -> Result<Option<PerCharacter>, IoError> {
    if file.get(signal).is_some() {
        return Ok(None);
    }
    let Some(k) = file
        .variables
        .iter()
        .position(|v| v.name.eq_ignore_ascii_case(signal) && v.array.dims.len() == 3)
    else {
        return Ok(None);
    };
    let (n_chars, n_times, n_channels) = match file.variables[k].array.dims[..] {
        [a, b, c] => (a, b, c),
        _ => unreachable!("three dimensions checked"),
    };
    let v = &mut file.variables[k];
    let MatValue::Numeric {
        real, imag: None, ..
    } = &v.array.value
    else {
        return Err(IoError::InvalidField {
            path: path.to_path_buf(),
            field: format!("variable {:?}: type", v.name),
            offset: v.offset,
            expected: "a real numeric array (characters × samples × channels)".into(),
            found: "another class".into(),
        });
    };
    // Column-major [i, j, c] is at i + n_chars·(j + n_times·c); the continuous
    // (n_chars·n_times) × n_channels array has (i·n_times + j, c) at (i·n_times + j) + T·c.
    let values = real.to_f64();
    let total = n_chars * n_times;
    let mut out = vec![0.0; values.len()];
    for c in 0..n_channels {
        for j in 0..n_times {
            for i in 0..n_chars {
                out[i * n_times + j + total * c] = values[i + n_chars * (j + n_times * c)];
            }
        }
    }
    drop(values);
    v.name = signal.to_string();
    v.array = MatArray {
        dims: vec![total, n_channels],
        value: MatValue::Numeric {
            class: MatClass::Double,
            real: MatNumbers::F64(out),
            imag: None,
        },
    };
    let mut per_char = PerCharacter {
        flashes_per_character: None,
        text: None,
    };
    for v in &mut file.variables {
        match &v.array.value {
            MatValue::Numeric {
                real, imag: None, ..
            } if v.array.dims == [n_chars, n_times] => {
                let values = real.to_f64();
                let flat: Vec<f64> = (0..n_chars)
                    .flat_map(|i| (0..n_times).map(move |j| (i, j)))
                    .map(|(i, j)| values[i + n_chars * j])
                    .collect();
                if v.name == "Flashing" {
                    let counts: Vec<usize> = flat
                        .chunks(n_times.max(1))
                        .map(|row| {
                            (0..row.len())
                                .filter(|&t| row[t] != 0.0 && (t == 0 || row[t - 1] == 0.0))
                                .count()
                        })
                        .collect();
                    if counts.windows(2).all(|w| w[0] == w[1]) && counts.first() > Some(&0) {
                        per_char.flashes_per_character = counts.first().copied();
                    }
                }
                v.array = MatArray {
                    dims: vec![total, 1],
                    value: MatValue::Numeric {
                        class: MatClass::Double,
                        real: MatNumbers::F64(flat),
                        imag: None,
                    },
                };
            }
            MatValue::Char(_) if v.name == "TargetChar" => {
                per_char.text = v.array.char_rows().map(|rows| rows.concat());
            }
            _ => {}
        }
    }
    Ok(Some(per_char))
}
