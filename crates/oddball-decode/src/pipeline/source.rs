//! Where a pipeline reads its epochs: an array, or [`Epochs`] that may be windows into their
//! recording, read a part at a time.

use ndarray::{s, Array1, Array3, ArrayView3, Axis};
use oddball_signal::{Epochs, EPOCH_CHUNK};

use crate::traits::FeatureData;
use crate::DecodeError;

type Result<T> = std::result::Result<T, DecodeError>;

/// The epochs a pipeline's front cache serves: an array `(n_epochs, n_channels, n_times)`, or
/// [`Epochs`] (perhaps windows into their recording, whose samples are made a part at a time
/// and never all at once where a pipeline allows).
#[derive(Debug, Clone, Copy)]
pub enum EpochSource<'a> {
    Array(ArrayView3<'a, f64>),
    Epochs(&'a Epochs),
}

impl<'a> From<ArrayView3<'a, f64>> for EpochSource<'a> {
    fn from(v: ArrayView3<'a, f64>) -> Self {
        EpochSource::Array(v)
    }
}

impl<'a> From<&'a Epochs> for EpochSource<'a> {
    fn from(e: &'a Epochs) -> Self {
        EpochSource::Epochs(e)
    }
}

impl<'a> EpochSource<'a> {
    /// `(n_epochs, n_channels, n_times)`.
    pub fn dim(&self) -> (usize, usize, usize) {
        match self {
            EpochSource::Array(v) => v.dim(),
            EpochSource::Epochs(e) => e.dim(),
        }
    }

    /// A copy of the epochs at `indices`, every `step`-th sample (see [`Epochs::gather`]).
    pub fn gather(&self, indices: &[usize], step: usize) -> Array3<f64> {
        match self {
            EpochSource::Array(v) => v.slice(s![.., .., ..;step]).select(Axis(0), indices),
            EpochSource::Epochs(e) => e.gather(indices, step),
        }
    }

    /// Every epoch as one view when the samples are held as an array (nothing to copy).
    pub(crate) fn as_view(&self) -> Option<ArrayView3<'a, f64>> {
        match self {
            EpochSource::Array(v) => Some(*v),
            EpochSource::Epochs(e) => e.preloaded(),
        }
    }

    /// `f` of every epoch: of all at once when they are held as an array, otherwise of
    /// [`EPOCH_CHUNK`] at a time (copies made one at a time), the rows concatenated. Only for
    /// maps of each epoch alone, which give the same rows either way.
    pub(crate) fn map_chunks(
        &self,
        f: &mut dyn FnMut(ArrayView3<f64>) -> Result<FeatureData>,
    ) -> Result<FeatureData> {
        if let Some(v) = self.as_view() {
            return f(v);
        }
        let EpochSource::Epochs(e) = self else {
            unreachable!("an array is a view")
        };
        let mut parts = Vec::new();
        for (_, chunk) in e.chunks(EPOCH_CHUNK) {
            parts.push(f(chunk.view())?);
        }
        if parts.is_empty() {
            return f(e.gather(&[], 1).view());
        }
        FeatureData::concatenate(parts)
    }

    /// A score per epoch by `f`, read a part at a time (windows are never all copied at once).
    pub fn map_scores<E>(
        &self,
        mut f: impl FnMut(ArrayView3<f64>) -> std::result::Result<Array1<f64>, E>,
    ) -> std::result::Result<Array1<f64>, E> {
        match self {
            EpochSource::Epochs(e) if !e.is_preloaded() && !e.is_empty() => {
                let mut scores = Vec::with_capacity(e.n_epochs());
                for (_, chunk) in e.chunks(EPOCH_CHUNK) {
                    scores.extend(f(chunk.view())?);
                }
                Ok(Array1::from(scores))
            }
            _ => match self.as_view() {
                Some(all) => f(all),
                None => f(self.gather(&[], 1).view()),
            },
        }
    }

    /// The epochs at `indices`, every `step`-th sample, as a source of their own: windows read
    /// at every sample stay windows (no samples copied); otherwise a copy.
    pub(crate) fn subset(&self, indices: &[usize], step: usize) -> Subset {
        match self {
            EpochSource::Epochs(e) if !e.is_preloaded() && step == 1 => {
                Subset::Epochs(e.select(indices))
            }
            _ => Subset::Array(self.gather(indices, step)),
        }
    }
}

/// Some epochs of an [`EpochSource`], held as a source ([`EpochSource::subset`]).
pub(crate) enum Subset {
    Array(Array3<f64>),
    Epochs(Epochs),
}

impl Subset {
    pub(crate) fn source(&self) -> EpochSource<'_> {
        match self {
            Subset::Array(a) => EpochSource::Array(a.view()),
            Subset::Epochs(e) => EpochSource::Epochs(e),
        }
    }
}
