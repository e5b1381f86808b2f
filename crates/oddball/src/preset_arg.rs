//! The `--pipeline` argument: presets parsed (by [`Preset`]'s one `FromStr`) when the command
//! line is parsed, one default for every command, and the help text listing them; [`list`]
//! parses it (and `--protocol`) as `all` or a comma-separated list.

use std::str::FromStr;

use oddball_decode::preset::Preset;

/// The pipeline every command uses when none is named.
pub const DEFAULT_PIPELINE: &str = "lda";

/// One preset, by name.
pub fn preset(name: &str) -> Result<Preset, String> {
    name.parse::<Preset>()
        .map_err(|_| format!("unknown pipeline {name:?}; known: {}", Preset::names()))
}

/// The help of a `--pipeline` taking one preset.
pub fn one_help() -> String {
    format!("Pipeline preset: {}", Preset::described())
}

/// The help of a `--pipeline` taking a list.
pub fn list_help() -> String {
    format!(
        "Pipeline presets, comma-separated ({}), or `all`",
        Preset::described()
    )
}

/// `--pipeline a,b,c` or `--pipeline all`: presets in the order given, each once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PipelineList(pub Vec<Preset>);

impl FromStr for PipelineList {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        list(s, Preset::ALL, |name| preset(name.trim())).map(Self)
    }
}

/// `all`, or names comma-separated (each parsed by `one`): the items in the order given, each
/// once.
pub fn list<T: Copy + PartialEq>(
    s: &str,
    all: &[T],
    one: impl Fn(&str) -> Result<T, String>,
) -> Result<Vec<T>, String> {
    if s.trim() == "all" {
        return Ok(all.to_vec());
    }
    let mut items: Vec<T> = Vec::new();
    for name in s.split(',') {
        let p = one(name).map_err(|e| format!("{e}, or all"))?;
        if !items.contains(&p) {
            items.push(p);
        }
    }
    Ok(items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_all_and_unknown_names() {
        let l: PipelineList = "lda, riemann,lda".parse().unwrap();
        assert_eq!(l.0, [Preset::Lda, Preset::Riemann]);
        assert_eq!(
            "all".parse::<PipelineList>().unwrap().0.len(),
            Preset::ALL.len()
        );
        let err = "lda,nope".parse::<PipelineList>().unwrap_err();
        assert!(err.contains("\"nope\"") && err.contains("stack"), "{err}");
        assert_eq!(preset(DEFAULT_PIPELINE), Ok(Preset::Lda));
        assert_eq!(preset("mdm"), Ok(Preset::Mdm));
        assert!(one_help().contains("paper-knn") && list_help().contains("lda+riemann"));
    }
}
