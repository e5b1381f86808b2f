//! The `--pipeline` argument: preset names checked when the command line is parsed, one default
//! for every command.

use std::str::FromStr;

use oddball_decode::pipeline::PRESETS;

/// The pipeline every command uses when none is named.
pub const DEFAULT_PIPELINE: &str = "lda";

/// One preset name, checked against [`PRESETS`].
pub fn parse_preset(name: &str) -> Result<String, String> {
    if PRESETS.contains(&name) {
        Ok(name.to_string())
    } else {
        Err(format!(
            "unknown pipeline {name:?}; known: {}",
            PRESETS.join(", ")
        ))
    }
}

/// `--pipeline a,b,c` or `--pipeline all`: presets in the order given, each once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PipelineList(pub Vec<String>);

impl FromStr for PipelineList {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim() == "all" {
            return Ok(Self(PRESETS.iter().map(|p| p.to_string()).collect()));
        }
        let mut names: Vec<String> = Vec::new();
        for name in s.split(',').map(str::trim) {
            let name = parse_preset(name).map_err(|e| format!("{e}, or all"))?;
            if !names.contains(&name) {
                names.push(name);
            }
        }
        Ok(Self(names))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_all_and_unknown_names() {
        let l: PipelineList = "lda, riemann,lda".parse().unwrap();
        assert_eq!(l.0, ["lda", "riemann"]);
        assert_eq!(
            "all".parse::<PipelineList>().unwrap().0.len(),
            PRESETS.len()
        );
        let err = "lda,nope".parse::<PipelineList>().unwrap_err();
        assert!(err.contains("\"nope\"") && err.contains("stack"), "{err}");
        assert!(parse_preset(DEFAULT_PIPELINE).is_ok());
    }
}
