//! Voltage units to µV factors ([`microvolts_per`], the one rule of every reader and of live
//! streams) and numbers with unit suffixes (`256Hz`, `0.033muV`, `-100uV`).

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

/// Microvolts per `unit`: the factor that turns a value in `unit` into µV, or `None` when
/// `unit` is not a voltage unit (an empty unit included: each reader says what it does then).
///
/// The one rule for every reader (EDF, BCI2000, EASY, XDF) and for live LSL streams: a volt
/// with an optional metric prefix, short or spelled out, in any letter case, whitespace
/// ignored:
///
/// | factor | short                             | spelled out                 |
/// |--------|-----------------------------------|-----------------------------|
/// | 1e9    | `kV`                              | `kilovolt`, `kilovolts`     |
/// | 1e6    | `V`                               | `volt`, `volts`             |
/// | 1e3    | `mV`                              | `millivolt`, `millivolts`   |
/// | 1      | `uV`, `µV` (U+00B5), `μV` (U+03BC), `muV` (BCI2000) | `microvolt`, `microvolts` |
/// | 1e-3   | `nV`                              | `nanovolt`, `nanovolts`     |
///
/// Case never matters: no EEG is recorded in megavolts, so `MV` from a careless writer is
/// millivolts (as `UV` is microvolts and `NV` nanovolts). A short prefix goes with `V` and a
/// spelled-out one with `volt(s)` (`mvolts` and `milliV` are not units).
///
/// What the readers do with a unit that is empty or not a voltage:
/// * EDF: the signal is read unscaled and named in `non_voltage_signals`.
/// * BCI2000 `SourceChGain`: an empty unit means µV per A/D unit; any other unit is an error.
/// * EASY `EEG units`: an error.
/// * XDF and live LSL streams ([`stream_microvolts_per`]): an empty unit is µV; the XDF reader
///   keeps the values of any other non-voltage unit unscaled (the unit stays in `eeg_units`),
///   a live LSL inlet refuses the stream.
pub fn microvolts_per(unit: &str) -> Option<f64> {
    let u: String = unit
        .chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect();
    let (prefix, spelled) = match u.strip_suffix("volts").or_else(|| u.strip_suffix("volt")) {
        Some(p) => (p, true),
        None => (u.strip_suffix('v')?, false),
    };
    Some(match (prefix, spelled) {
        ("", _) => 1e6,
        ("kilo", true) | ("k", false) => 1e9,
        ("milli", true) | ("m", false) => 1e3,
        ("micro", true) | ("u" | "µ" | "μ" | "mu", false) => 1.0,
        ("nano", true) | ("n", false) => 1e-3,
        _ => return None,
    })
}

/// Microvolts per unit of an LSL stream's channel, live or in its XDF recording: an empty (or
/// missing) unit is µV, anything else as [`microvolts_per`].
pub fn stream_microvolts_per(unit: &str) -> Option<f64> {
    if unit.trim().is_empty() {
        Some(1.0)
    } else {
        microvolts_per(unit)
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
        for (unit, f) in [
            ("muV", 1.0),
            ("uV", 1.0),
            ("µV", 1.0),
            ("μV", 1.0),
            ("UV", 1.0),
            (" microvolts ", 1.0),
            ("micro volt", 1.0),
            ("mV", 1e3),
            ("MV", 1e3),
            ("Millivolts", 1e3),
            ("V", 1e6),
            ("v", 1e6),
            ("Volts", 1e6),
            ("nV", 1e-3),
            ("NV", 1e-3),
            ("nanovolt", 1e-3),
            ("kV", 1e9),
            ("kilovolts", 1e9),
        ] {
            assert_eq!(microvolts_per(unit), Some(f), "{unit:?}");
        }
        for unit in [
            "",
            " ",
            "degC",
            "Boolean",
            "counts",
            "mV\u{a7}",
            "\u{b3}",
            "\u{b3}V",
            "mvolts",
            "milliv",
            "uvs",
            "vv",
            "voltss",
            "pV",
            "megavolts",
        ] {
            assert_eq!(microvolts_per(unit), None, "{unit:?}");
        }
        assert_eq!(stream_microvolts_per(""), Some(1.0));
        assert_eq!(stream_microvolts_per("  "), Some(1.0));
        assert_eq!(stream_microvolts_per("MV"), Some(1e3));
        assert_eq!(stream_microvolts_per("counts"), None);
        assert_eq!(hz_factor("Hz"), Some(1.0));
        assert_eq!(hz_factor("kHz"), Some(1e3));
        assert_eq!(hz_factor("s"), None);
    }

    mod spelling {
        use super::super::microvolts_per;
        use proptest::prelude::*;

        /// (short prefix, spelled-out prefix, factor).
        const PREFIXES: [(&[&str], &str, f64); 5] = [
            (&["k"], "kilo", 1e9),
            (&[""], "", 1e6),
            (&["m"], "milli", 1e3),
            (&["u", "µ", "μ", "mu"], "micro", 1.0),
            (&["n"], "nano", 1e-3),
        ];

        /// `s` with the letters whose bit in `mask` is set in upper case.
        fn recase(s: &str, mask: u64) -> String {
            s.chars()
                .enumerate()
                .flat_map(|(i, c)| {
                    let upper = mask >> (i % 64) & 1 == 1;
                    let v: Vec<char> = if upper {
                        c.to_uppercase().collect()
                    } else {
                        vec![c]
                    };
                    v
                })
                .collect()
        }

        proptest! {
            /// Every spelling of every prefix, in any case, with spaces around and (spelled
            /// out) between prefix and volt, gives the prefix's factor.
            #[test]
            fn spellings_in_any_case(
                p in 0usize..5,
                which in 0usize..4,
                spelled in any::<bool>(),
                plural in any::<bool>(),
                space in any::<bool>(),
                mask in any::<u64>(),
                pad in "[ \t]{0,2}",
            ) {
                let (short, long, factor) = PREFIXES[p];
                let unit = if spelled {
                    format!("{long}{}volt{}", if space { " " } else { "" }, if plural { "s" } else { "" })
                } else {
                    format!("{}V", short[which % short.len()])
                };
                let unit = format!("{pad}{}{pad}", recase(&unit, mask));
                prop_assert_eq!(microvolts_per(&unit), Some(factor), "{:?}", unit);
            }

            /// Case never changes the answer, for any text over the letters of the units.
            #[test]
            fn case_never_matters(s in "[vVoOlLtTsSmMuUnNkKiIcCrRaA µμ]{0,12}", mask in any::<u64>()) {
                prop_assert_eq!(microvolts_per(&recase(&s, mask)), microvolts_per(&s.to_lowercase()));
            }
        }
    }
}
