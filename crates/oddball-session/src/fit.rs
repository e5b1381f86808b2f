//! Fitting a session's model on labelled epochs: the preset on every epoch, its score model on
//! cross-validated scores ([`fit_session_model_oof`]), and the calibration epochs a session keeps
//! for it ([`Calibration`]).

use ndarray::{Array2, Array3, Axis};
use oddball_decode::decision::{DecisionModel, ScoreModelParams};
use oddball_decode::metrics::roc_auc;
use oddball_decode::model_selection::{cross_val_predict, interleaved_folds};
use oddball_decode::pipeline::{EpochSource, FrontCache, Model};

use crate::decoder::DecoderParams;
use crate::SessionError;

/// Calibration epochs kept for training.
#[derive(Debug, Default)]
pub(crate) struct Calibration {
    pub(crate) epochs: Vec<Array2<f64>>,
    pub(crate) labels: Vec<bool>,
    pub(crate) trials: Vec<usize>,
    /// Index of each epoch's flash.
    pub(crate) flashes: Vec<usize>,
    pub(crate) rejected: usize,
}

impl Calibration {
    /// The epochs as one `(n_epochs, n_channels, n_times)` array (`n_channels` when there are
    /// none).
    pub(crate) fn stacked(&self, n_channels: usize) -> Array3<f64> {
        let (n_ch, n_t) = self.epochs.first().map_or((n_channels, 0), |e| e.dim());
        let mut x = Array3::zeros((self.epochs.len(), n_ch, n_t));
        for (i, e) in self.epochs.iter().enumerate() {
            x.index_axis_mut(Axis(0), i).assign(e);
        }
        x
    }
}

/// Fits the preset on labelled epochs `x` and its score model on out-of-fold scores
/// ([`interleaved_folds`]: fold `g % k` holds the epochs of group `g`, a trial or a spelled
/// character, so overlapping epochs of one group never straddle a split). Returns the model with its decision rule, the cross-validated
/// AUC, the scores' d′ and the out-of-fold scores themselves (what stopping is chosen from).
pub(crate) fn fit_session_model_oof(
    decoder: &DecoderParams,
    sfreq: f64,
    ch_names: &[String],
    x: EpochSource<'_>,
    y: &[bool],
    groups: &[usize],
) -> Result<(Model, f64, f64, Vec<f64>), SessionError> {
    let params = decoder.pipeline.params(sfreq)?;
    let k = decoder.cv_folds.max(2);
    // A front that learns nothing is computed once for every fold and the final fit; epochs
    // held as windows are read a part at a time (the scores are those of fitting on copies).
    let mut cache = FrontCache::new(x);
    let folds = interleaved_folds(groups, k);
    let oof = cross_val_predict(&params, &mut cache, y, Some(groups), &folds, || {})?;
    let cv_auc = roc_auc(&oof, y)?;
    let scores = ScoreModelParams::default().fit(&oof, y)?;
    let mut model = Model::new(
        decoder.preprocess,
        sfreq,
        ch_names.to_vec(),
        params.fit_cached(&mut cache, y, Some(groups))?,
    );
    model.decision = Some(DecisionModel {
        scores,
        rule: decoder.rule,
    });
    Ok((model, cv_auc, scores.d_prime(), oof))
}
