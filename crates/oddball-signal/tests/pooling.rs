//! `Epochs::pool` (moving several recordings' epochs into one set) gives exactly what
//! `Epochs::concatenate` (copying them) gives, and refuses what it refuses.

use ndarray::{Array3, ShapeBuilder};
use oddball_signal::{Epochs, Event, SignalError};

/// `n` epochs of `n_ch` channels × `n_t` samples whose values say where they come from.
fn epochs(first: usize, n: usize, n_ch: usize, n_t: usize, sfreq: f64) -> Epochs {
    let data = Array3::from_shape_fn((n, n_ch, n_t), |(e, c, t)| {
        ((first + e) * 1000 + c * 100 + t) as f64 * 0.5
    });
    let events = (0..n)
        .map(|e| Event::new(10 * (first + e), 1 + (e % 2) as u32).with_target(e % 2 == 1))
        .collect();
    let names = (0..n_ch).map(|c| format!("C{c}")).collect();
    Epochs::new(data, sfreq, -0.1, names, events).unwrap()
}

#[test]
fn pooling_gives_the_concatenation() {
    let parts = vec![
        epochs(0, 3, 4, 7, 250.0),
        epochs(3, 1, 4, 7, 250.0),
        epochs(4, 5, 4, 7, 250.0),
    ];
    let copied = Epochs::concatenate(&parts).unwrap();
    let pooled = Epochs::pool(parts).unwrap();
    assert_eq!(pooled, copied);
    assert_eq!(pooled.n_epochs(), 9);
    assert_eq!(pooled.epoch(4)[[2, 3]], (4000 + 200 + 3) as f64 * 0.5);
    assert!(pooled.data().is_standard_layout());
}

#[test]
fn a_part_in_another_memory_order_pools_in_epoch_channel_time_order() {
    let a = epochs(0, 2, 3, 5, 100.0);
    // The same numbers, stored time-major.
    let (data, sfreq, tmin, names, events) = epochs(2, 2, 3, 5, 100.0).into_parts();
    let mut fortran = Array3::zeros(data.raw_dim().f());
    fortran.assign(&data);
    let b = Epochs::new(fortran, sfreq, tmin, names, events).unwrap();
    let copied = Epochs::concatenate(&[a.clone(), b.clone()]).unwrap();
    assert_eq!(Epochs::pool(vec![a, b]).unwrap(), copied);
}

#[test]
fn pooling_refuses_no_parts_and_mismatched_layouts() {
    assert!(matches!(
        Epochs::pool(Vec::new()),
        Err(SignalError::NoEpochs)
    ));
    for other in [
        epochs(3, 2, 5, 7, 250.0), // channels
        epochs(3, 2, 4, 8, 250.0), // window length
        epochs(3, 2, 4, 7, 500.0), // rate
    ] {
        let err = Epochs::pool(vec![epochs(0, 3, 4, 7, 250.0), other]).unwrap_err();
        assert!(matches!(err, SignalError::LayoutMismatch { .. }), "{err:?}");
        assert!(err.to_string().contains("4 channels at 250 Hz"), "{err}");
    }
}
