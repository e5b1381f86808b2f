//! Feature rows of epochs filled one epoch at a time.

use ndarray::{Array2, ArrayView2, ArrayView3};

use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// Features of every epoch of `epochs` `(n_epochs, n_channels, n_times)`: a row of `width` values
/// each, filled by `fill(epoch, first, rest)` with its first `split` values and the rest.
pub(crate) fn two_block_rows(
    epochs: ArrayView3<f64>,
    width: usize,
    split: usize,
    mut fill: impl FnMut(ArrayView2<f64>, &mut [f64], &mut [f64]) -> Result<()>,
) -> Result<Array2<f64>> {
    let mut out = Array2::zeros((epochs.dim().0, width));
    for (epoch, mut row) in epochs.outer_iter().zip(out.rows_mut()) {
        let row = row
            .as_slice_mut()
            .expect("rows of a standard-layout array are contiguous");
        let (first, rest) = row.split_at_mut(split);
        fill(epoch, first, rest)?;
    }
    Ok(out)
}
