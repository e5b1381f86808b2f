//! Numbers with unit suffixes (`256Hz`, `0.033muV`, `-100uV`) and voltage units to µV factors.

/// Splits `s` (trimmed) into its leading decimal number and the unit text after it.
///
/// Accepts an optional sign, digits with an optional fraction, and an optional exponent
/// (`e`/`E`, only when digits follow, so `2e` is the number 2 with unit `e`). Returns `None`
/// when `s` does not start with a number.
pub(crate) fn split_number_unit(s: &str) -> Option<(f64, &str)> {
    let s = s.trim();
    let b = s.as_bytes();
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let int_start = i;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
    }
    let mut n_digits = i - int_start;
    if i < b.len() && b[i] == b'.' {
        let frac_start = i + 1;
        let mut j = frac_start;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        n_digits += j - frac_start;
        i = j;
    }
    if n_digits == 0 {
        return None;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        let exp_start = j;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        if j > exp_start {
            i = j;
        }
    }
    let value: f64 = s[..i].parse().ok()?;
    Some((value, s[i..].trim()))
}

/// The factor that turns a value in `unit` into microvolts, for the voltage units written by
/// BCI2000 (`muV`) and EDF (`uV`, `µV`, `mV`, `V`, `nV`). Case matters (`mV` vs `MV`), except
/// that the `V` may be either case. Returns `None` for anything else, including an empty unit.
pub(crate) fn volt_factor_to_uv(unit: &str) -> Option<f64> {
    let unit = unit.trim();
    let prefix = unit.strip_suffix('V').or_else(|| unit.strip_suffix('v'))?;
    match prefix {
        "u" | "mu" | "µ" | "μ" | "U" => Some(1.0),
        "m" => Some(1e3),
        "" => Some(1e6),
        "n" => Some(1e-3),
        "k" => Some(1e9),
        _ => None,
    }
}

/// The factor that turns a frequency in `unit` into Hz (`""`, `Hz`, `kHz`).
pub(crate) fn hz_factor(unit: &str) -> Option<f64> {
    match unit.trim() {
        "" | "Hz" | "hz" => Some(1.0),
        "kHz" | "khz" => Some(1e3),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_units() {
        assert_eq!(split_number_unit("256Hz"), Some((256.0, "Hz")));
        assert_eq!(split_number_unit(" 0.033muV "), Some((0.033, "muV")));
        assert_eq!(split_number_unit("-100uV"), Some((-100.0, "uV")));
        assert_eq!(split_number_unit("1e-3mV"), Some((1e-3, "mV")));
        assert_eq!(split_number_unit("2e"), Some((2.0, "e")));
        assert_eq!(split_number_unit(".5"), Some((0.5, "")));
        assert_eq!(split_number_unit("5."), Some((5.0, "")));
        assert_eq!(split_number_unit("+7"), Some((7.0, "")));
        assert_eq!(split_number_unit("abc"), None);
        assert_eq!(split_number_unit("-"), None);
        assert_eq!(split_number_unit("."), None);
        assert_eq!(split_number_unit(""), None);
    }

    #[test]
    fn voltage_units() {
        assert_eq!(volt_factor_to_uv("muV"), Some(1.0));
        assert_eq!(volt_factor_to_uv("uV"), Some(1.0));
        assert_eq!(volt_factor_to_uv("µV"), Some(1.0));
        assert_eq!(volt_factor_to_uv("mV"), Some(1e3));
        assert_eq!(volt_factor_to_uv("V"), Some(1e6));
        assert_eq!(volt_factor_to_uv("nV"), Some(1e-3));
        assert_eq!(volt_factor_to_uv(""), None);
        assert_eq!(volt_factor_to_uv("degC"), None);
        assert_eq!(volt_factor_to_uv("Boolean"), None);
        assert_eq!(volt_factor_to_uv("mV\u{a7}"), None);
        assert_eq!(volt_factor_to_uv("\u{b3}"), None);
        assert_eq!(volt_factor_to_uv("\u{b3}V"), None);
        assert_eq!(hz_factor("Hz"), Some(1.0));
        assert_eq!(hz_factor("kHz"), Some(1e3));
        assert_eq!(hz_factor("s"), None);
    }
}
