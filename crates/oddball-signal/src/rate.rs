//! When two sampling rates are the same rate, and the nominal rate behind one estimated from
//! timestamps: the one home of both rules (readers, models, layouts and live sources ask here).
//!
//! A rate estimated from a recording's timestamps (a CSV's time column, NIC's `.easy`
//! timestamps) is never exactly the amplifier's nominal rate: clocks drift by tens of parts
//! per million and timestamps are rounded (`240.00000729` Hz from a real CSV). Stored as it is,
//! such a rate made every other file and stream of the same amplifier "another rate".
//! [`nominal_sfreq`] rounds an estimate to the nearest common amplifier rate, or failing that to
//! the nearest whole hertz, when it is within [`RATE_TOLERANCE`] of it; [`same_sfreq`] treats
//! two rates within that tolerance as one. 0.1 % is ten times a cheap crystal's error and well
//! under the 2.3 % between the closest common rates (250 and 256 Hz), so two nominal rates are
//! never merged.

/// Relative difference within which two rates are one (0.1 %).
pub const RATE_TOLERANCE: f64 = 1e-3;

/// Sampling rates amplifiers are built for (Hz), besides whole hertz.
pub const COMMON_SFREQS: [f64; 24] = [
    100.0, 125.0, 128.0, 160.0, 200.0, 220.0, 240.0, 250.0, 256.0, 300.0, 400.0, 500.0, 512.0,
    600.0, 1000.0, 1024.0, 1200.0, 2000.0, 2048.0, 4000.0, 4096.0, 8000.0, 8192.0, 16384.0,
];

/// Whether `a` and `b` are one rate: within [`RATE_TOLERANCE`] of each other (relative).
pub fn same_sfreq(a: f64, b: f64) -> bool {
    (a - b).abs() <= RATE_TOLERANCE * a.abs().max(b.abs())
}

/// The nominal rate behind `estimate` (Hz, from timestamps): the nearest of [`COMMON_SFREQS`],
/// else the nearest whole hertz, when within [`RATE_TOLERANCE`]; otherwise the estimate itself.
pub fn nominal_sfreq(estimate: f64) -> f64 {
    if !estimate.is_finite() || estimate <= 0.0 {
        return estimate;
    }
    let nearest = COMMON_SFREQS
        .iter()
        .copied()
        .min_by(|a, b| (a - estimate).abs().total_cmp(&(b - estimate).abs()))
        .expect("a non-empty list");
    if same_sfreq(nearest, estimate) {
        return nearest;
    }
    let whole = estimate.round();
    if whole >= 1.0 && same_sfreq(whole, estimate) {
        whole
    } else {
        estimate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_round_to_the_nominal_rate_and_nominal_rates_stay_apart() {
        assert_eq!(nominal_sfreq(240.000_007_292_893_46), 240.0);
        assert_eq!(nominal_sfreq(255.9), 256.0);
        assert_eq!(nominal_sfreq(250.1), 250.0);
        assert_eq!(nominal_sfreq(333.33), 333.0);
        assert_eq!(nominal_sfreq(97.3), 97.3);
        assert_eq!(nominal_sfreq(0.5), 0.5);
        assert!(nominal_sfreq(f64::NAN).is_nan());
        assert!(same_sfreq(240.000_007_3, 240.0) && same_sfreq(240.0, 240.000_007_3));
        assert!(!same_sfreq(250.0, 256.0));
        for w in COMMON_SFREQS.windows(2) {
            assert!(!same_sfreq(w[0], w[1]), "{w:?}");
            assert_eq!(nominal_sfreq(w[0]), w[0]);
        }
    }
}
