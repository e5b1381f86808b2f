//! Issue #19, defect 4 and the duplicate-name part of defect 9: values from outside are
//! checked where they enter, before any filter is designed or buffer sized by them allocated.

use ndarray::Array2;
use oddball_signal::epochs::EpochsParams;
use oddball_signal::filter::{Band, ButterworthParams};
use oddball_signal::{Event, Events, Raw, SignalError, MAX_WINDOW_S, SFREQ_MAX};

fn names(n: usize) -> Vec<String> {
    (0..n).map(|c| format!("E{c}")).collect()
}

/// 1e300 Hz made the Butterworth design panic; 1e9 Hz made epoching allocate gigabytes.
#[test]
fn implausible_sampling_rates_are_refused_before_design_or_allocation() {
    for sfreq in [
        1e300,
        1e9,
        SFREQ_MAX * 1.01,
        0.0,
        -256.0,
        0.01,
        f64::NAN,
        f64::INFINITY,
    ] {
        let err = Raw::new(Array2::zeros((2, 10)), sfreq, names(2), Events::default()).unwrap_err();
        assert!(
            matches!(err, SignalError::InvalidSfreq { .. }),
            "{sfreq}: {err}"
        );
        assert!(err.to_string().contains("plausible"), "{err}");
        let err = ButterworthParams::paper().design(sfreq).unwrap_err();
        assert!(
            matches!(err, SignalError::InvalidSfreq { .. }),
            "{sfreq}: {err}"
        );
    }
    for sfreq in [1.0, 128.0, 256.0, 16_384.0, SFREQ_MAX] {
        Raw::new(Array2::zeros((1, 4)), sfreq, names(1), Events::default()).unwrap();
    }
}

/// A band above Nyquist is refused by the design, before any filtering.
#[test]
fn a_band_beyond_nyquist_is_refused() {
    let p = ButterworthParams {
        order: 4,
        band: Band::Bandpass {
            l_freq: 1.0,
            h_freq: 40.0,
        },
    };
    let e = p.design(64.0).unwrap_err();
    assert!(matches!(e, SignalError::InvalidBand { .. }));
    // As a person writes a band, not Rust's Option (it said "Some(1.0)–Some(40.0) Hz").
    assert_eq!(
        e.to_string(),
        "band 1–40 Hz does not fit between 0 and the Nyquist frequency 32 Hz (half the sampling rate)"
    );
    assert!(p.design(128.0).is_ok());
}

/// A window of ±1e9 s is refused; a window longer than the recording allocates nothing and
/// drops every epoch as out of bounds.
#[test]
fn windows_are_bounded_and_allocation_follows_the_data() {
    let raw = Raw::new(
        Array2::zeros((2, 1000)),
        100.0,
        names(2),
        Events::new(vec![Event::new(10, 1), Event::new(500, 1)]),
    )
    .unwrap();
    for (tmin, tmax) in [(-1e9, 1e9), (0.0, 1e9), (0.0, MAX_WINDOW_S * 1.5)] {
        let err = EpochsParams::new(tmin, tmax).cut(&raw).unwrap_err();
        assert!(matches!(err, SignalError::InvalidWindow { .. }), "{err}");
    }
    // 90 s at 100 Hz is 9001 samples: longer than the 1000-sample recording.
    let (ep, log) = EpochsParams::new(0.0, 90.0).cut(&raw).unwrap();
    assert_eq!(ep.n_epochs(), 0);
    assert_eq!(log.dropped.len(), 2);
}

/// Channels are matched by name; two channels of one name cannot be.
#[test]
fn duplicate_channel_names_are_refused() {
    let n = vec!["Cz".to_string(), "Pz".to_string(), "Cz".to_string()];
    let err = Raw::new(Array2::zeros((3, 4)), 256.0, n, Events::default()).unwrap_err();
    assert!(
        matches!(&err, SignalError::DuplicateChannel { name, first: 0, second: 2 } if name == "Cz"),
        "{err}"
    );
}

/// Issue #19, defect 7: a CSV with an event on every sample made 205-sample epochs of all of
/// them (7.9 GB from 15 MB). Epochs holding more than MAX_EPOCH_OVERLAP times the recording
/// are refused before they are allocated.
#[test]
fn an_event_on_every_sample_is_refused_before_allocation() {
    use oddball_signal::MAX_EPOCH_OVERLAP;
    let n = 200_000;
    let events = Events::new((0..n).map(|t| Event::new(t, 1)).collect());
    let raw = Raw::new(Array2::zeros((2, n)), 256.0, names(2), events).unwrap();
    let err = EpochsParams::new(0.0, 0.8).cut(&raw).unwrap_err();
    assert!(
        matches!(
            err,
            SignalError::TooManyEpochs {
                max_overlap: MAX_EPOCH_OVERLAP,
                ..
            }
        ),
        "{err}"
    );
    // A speller's density (an event every 42 samples) is fine.
    let events = Events::new((0..n / 42).map(|k| Event::new(k * 42, 1)).collect());
    let raw = Raw::new(Array2::zeros((2, n)), 240.0, names(2), events).unwrap();
    assert!(EpochsParams::new(0.0, 0.8).cut(&raw).is_ok());
}
