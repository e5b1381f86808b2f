//! Channel names from a montage file: EEGLAB's `.loc` (`index theta radius label` per line, the
//! label padded with dots to four characters: `Fc5.`, `Cz..`), as BCI2000 ships `eeg64.loc`
//! for its 64-channel recordings (whose `.dat` files hold no channel names). The names name a
//! file's channels in order ([`crate::ReadOptions::montage`], `--montage`); positions are not
//! used (nothing in oddball draws a scalp map).

use std::path::Path;

use crate::IoError;

/// The channel labels of an EEGLAB `.loc` file, in file order, trailing dots removed.
pub fn read_montage(path: impl AsRef<Path>) -> Result<Vec<String>, IoError> {
    let path = path.as_ref();
    crate::check_file(path)?;
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Io {
        path: path.to_path_buf(),
        action: "read",
        source,
    })?;
    parse_montage(&text, path)
}

/// [`read_montage`] of text already read (`path` names it in errors).
pub fn parse_montage(text: &str, path: &Path) -> Result<Vec<String>, IoError> {
    let mut names = Vec::new();
    let mut offset = 0u64;
    for (i, line) in text.split_inclusive('\n').enumerate() {
        let start = offset;
        let bad = |expected: &str, found: &str| IoError::InvalidField {
            path: path.to_path_buf(),
            field: format!("line {}", i + 1),
            offset: start,
            expected: expected.to_string(),
            found: crate::bounded(found),
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        offset += line.len() as u64;
        if fields.is_empty() {
            continue;
        }
        if fields.len() != 4 {
            return Err(bad("index, theta, radius and label", line.trim_end()));
        }
        if fields[0].parse::<u32>().is_err() {
            return Err(bad("a channel index", fields[0]));
        }
        for f in &fields[1..3] {
            if !f.parse::<f64>().is_ok_and(f64::is_finite) {
                return Err(bad("a number (theta, radius)", f));
            }
        }
        let label = fields[3].trim_end_matches('.');
        if label.is_empty() {
            return Err(bad("a channel label", fields[3]));
        }
        names.push(label.to_string());
    }
    if names.is_empty() {
        return Err(IoError::InvalidField {
            path: path.to_path_buf(),
            field: "montage".into(),
            offset: 0,
            expected: "at least one channel line".into(),
            found: String::new(),
        });
    }
    oddball_signal::check_unique_names(&names).map_err(|source| IoError::Signal {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_lose_their_padding_and_bad_lines_are_named() {
        let p = Path::new("m.loc");
        let names = parse_montage(
            "1\t-68\t0.3\tFc5.\n2\t0\t0.1\tCz..\n\n3\t90\t0.2\tT10.\n",
            p,
        )
        .unwrap();
        assert_eq!(names, ["Fc5", "Cz", "T10"]);
        let e = parse_montage("1\t0\t0.1\tCz..\n2\tx\t0.1\tPz..\n", p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2") && e.contains("byte offset 13"), "{e}");
        let e = parse_montage("1 0 0.1 Cz\n2 0 0.1 Cz..\n", p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("Cz"), "{e}");
    }
}
