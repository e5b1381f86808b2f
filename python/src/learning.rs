//! Learning while used, from Python: the adaptive LDA (`oddball.lda.AdaptiveLDA`, the
//! incremental statistics and drift guard of a session's `--adapt`), the unsupervised decoder
//! (`oddball.unsupervised.UnsupervisedDecoder`, the EM of `evaluate --unsupervised` and of a
//! session without calibration), and the epochs both take (`oddball.read_epochs`, the one
//! preprocessing path of `oddball evaluate`). Both models change in place (`partial_fit`) and
//! pickle through their serde JSON.

use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
};
use oddball_decode::adaptive::{AdaptiveLdaParams, Update};
use oddball_decode::classifiers::lda::{LdaParams, Shrinkage};
use oddball_decode::pipeline::Preprocess;
use oddball_decode::unsupervised::{
    Constraint, P300Template, TrialPosterior, Unsupervised, UnsupervisedParams,
};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde::{Deserialize, Serialize};

use crate::{json_err, labels, value_err};

fn unsup_err(e: oddball_decode::unsupervised::UnsupervisedError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A calibrated shrinkage LDA whose class means follow the session
/// (`oddball_decode::adaptive::AdaptiveLda`).
#[pyclass(module = "oddball._oddball")]
pub(crate) struct AdaptiveLda {
    inner: oddball_decode::adaptive::AdaptiveLda,
}

methods_with_json!(AdaptiveLda, oddball_decode::adaptive::AdaptiveLda, {
    /// Calibrates on rows `x` with labels `y`; `shrinkage` as `Lda.fit`; updates that turn the
    /// weights below `min_cosine` with the calibrated weights are undone.
    #[staticmethod]
    #[pyo3(signature = (x, y, shrinkage, auto, min_cosine))]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
        shrinkage: Option<f64>,
        auto: bool,
        min_cosine: f64,
    ) -> PyResult<Self> {
        let params = AdaptiveLdaParams {
            lda: LdaParams {
                shrinkage: if auto {
                    Shrinkage::Auto
                } else {
                    Shrinkage::Fixed(shrinkage.unwrap_or(0.0))
                },
            },
            min_cosine,
        };
        let (x, y) = (x.as_array(), labels(&y));
        let inner = py.detach(|| params.fit(x, &y)).map_err(value_err)?;
        Ok(Self { inner })
    }

    /// Takes in labelled rows; `(accepted, cosine)`: an update the guard rejects is undone.
    fn partial_fit(
        &mut self,
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
    ) -> PyResult<(bool, f64)> {
        let (x, y) = (x.as_array(), labels(&y));
        let inner = &mut self.inner;
        let r = py.detach(|| inner.update(x, &y)).map_err(value_err)?;
        Ok(match r {
            Update::Accepted { cosine } => (true, cosine),
            Update::Rejected { cosine } => (false, cosine),
        })
    }

    /// Log-odds of the target class per row.
    fn decision_function<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array();
        let out = py
            .detach(|| self.inner.decision_function(x))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// P(target) per row.
    fn predict_proba<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array();
        let out = py
            .detach(|| self.inner.predict_proba(x))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    #[getter]
    fn coef<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.coef().into_pyarray(py)
    }

    #[getter]
    fn intercept(&self) -> f64 {
        self.inner.intercept()
    }

    /// Class means `(2, n_features)`: non-target, target.
    #[getter]
    fn means<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.means().into_pyarray(py)
    }

    /// Epochs taken in per class, calibration included: `(non-target, target)`.
    #[getter]
    fn counts(&self) -> (f64, f64) {
        let [n, t] = self.inner.counts();
        (n, t)
    }

    /// The weights' cosine with the calibrated weights.
    #[getter]
    fn cosine(&self) -> f64 {
        self.inner.cosine()
    }
});

/// What an unsupervised decoder holds between calls: its settings, the feature rows, codes and
/// trials of every epoch taken in, each epoch's P300-template score (where every refit starts,
/// as a session without calibration starts), and the latest fit.
#[derive(Serialize, Deserialize)]
struct UnsupervisedState {
    params: UnsupervisedParams,
    constraint: Constraint,
    /// The epochs' preprocessing, for the template's start; `None`: random starts only.
    template: Option<Preprocess>,
    sfreq: f64,
    rows: Vec<f64>,
    codes: Vec<u32>,
    trials: Vec<usize>,
    start: Vec<f64>,
    model: Option<Unsupervised>,
}

/// The unsupervised decoder (`oddball_decode::unsupervised`): no label is taken anywhere.
#[pyclass(module = "oddball._oddball")]
pub(crate) struct UnsupervisedDecoder {
    inner: UnsupervisedState,
}

fn preprocess_named(name: &str) -> PyResult<Preprocess> {
    match name {
        "peer" => Ok(Preprocess::peer()),
        "peer-causal" => Ok(Preprocess::peer().as_causal()),
        other => Err(PyValueError::new_err(format!(
            "preprocess {other:?}: expected \"peer\" (oddball evaluate's zero-phase band-pass) or \
             \"peer-causal\" (as a live session filters)"
        ))),
    }
}

fn trial_dicts<'py>(py: Python<'py>, t: &[TrialPosterior]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for tp in t {
        let d = PyDict::new(py);
        d.set_item("trial", tp.trial)?;
        d.set_item("posterior", tp.sets.clone())?;
        out.append(d)?;
    }
    Ok(out)
}

impl UnsupervisedDecoder {
    fn features(&self, epochs: &PyReadonlyArray3<'_, f64>) -> PyResult<ndarray::Array2<f64>> {
        self.inner
            .params
            .features
            .transform(epochs.as_array())
            .map_err(value_err)
    }

    fn model(&self) -> PyResult<&Unsupervised> {
        self.inner
            .model
            .as_ref()
            .ok_or_else(|| PyValueError::new_err("the unsupervised decoder is not fitted yet"))
    }
}

methods_with_json!(UnsupervisedDecoder, UnsupervisedState, {
    /// `sets`: the codes that compete (one attended per set and trial: a speller's rows and
    /// columns, or the bulbs); epochs at `sfreq` Hz cut by `preprocess` (`"peer"`,
    /// `"peer-causal"`), whose P300 template starts every refit, or `None` for random starts;
    /// `decoys`: codes flashed that nobody attends (known non-targets, `Constraint::with_decoys`);
    /// `groups` (code → the choices `0..K` its flash shows) instead of `sets` for flashes of
    /// groups of choices (`Constraint::groups`; `sets` is then ignored).
    #[new]
    #[pyo3(signature = (sets, sfreq, preprocess=Some("peer"), mean_prior=0.0, n_inits=None, max_iter=200, tol=1e-6, seed=0, decoys=Vec::new(), groups=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        sets: Vec<Vec<u32>>,
        sfreq: f64,
        preprocess: Option<&str>,
        mean_prior: f64,
        n_inits: Option<usize>,
        max_iter: usize,
        tol: f64,
        seed: u32,
        decoys: Vec<u32>,
        groups: Option<std::collections::BTreeMap<u32, Vec<usize>>>,
    ) -> PyResult<Self> {
        let constraint = match groups {
            Some(g) => {
                let n_choices = g.values().flatten().max().map_or(0, |m| m + 1);
                Constraint::groups(n_choices, g)
            }
            None => Constraint::new(sets),
        }
        .and_then(|c| c.with_decoys(&decoys))
        .map_err(unsup_err)?;
        let defaults = UnsupervisedParams::for_sfreq(sfreq).map_err(value_err)?;
        let params = UnsupervisedParams {
            mean_prior,
            n_inits: n_inits.unwrap_or(defaults.n_inits),
            max_iter,
            tol,
            seed,
            ..defaults
        };
        let template = preprocess.map(preprocess_named).transpose()?;
        if let Some(pre) = &template {
            P300Template::default()
                .matched(pre, sfreq)
                .map_err(unsup_err)?;
        }
        Ok(Self {
            inner: UnsupervisedState {
                params,
                constraint,
                template,
                sfreq,
                rows: Vec::new(),
                codes: Vec::new(),
                trials: Vec::new(),
                start: Vec::new(),
                model: None,
            },
        })
    }

    /// Takes in epochs `(n, n_channels, n_times)` with their stimulus `codes` and `trials` and
    /// refits on every epoch so far, warm-started from the last fit (a session's refit after
    /// each trial); with `reset`, forgets what came before and fits from scratch.
    fn partial_fit(
        &mut self,
        py: Python<'_>,
        epochs: PyReadonlyArray3<'_, f64>,
        codes: Vec<u32>,
        trials: Vec<usize>,
        reset: bool,
    ) -> PyResult<()> {
        let x = self.features(&epochs)?;
        let start = match &self.inner.template {
            Some(pre) => {
                let t = P300Template::default()
                    .matched(pre, self.inner.sfreq)
                    .map_err(unsup_err)?;
                epochs
                    .as_array()
                    .outer_iter()
                    .map(|e| t.score(e))
                    .collect::<Result<Vec<f64>, _>>()
                    .map_err(unsup_err)?
            }
            None => Vec::new(),
        };
        if codes.len() != x.nrows() || trials.len() != x.nrows() {
            return Err(PyValueError::new_err(format!(
                "{} epochs, {} codes and {} trials: give one code and one trial per epoch",
                x.nrows(),
                codes.len(),
                trials.len()
            )));
        }
        let s = &mut self.inner;
        if reset {
            s.rows.clear();
            s.codes.clear();
            s.trials.clear();
            s.start.clear();
            s.model = None;
        }
        let p = x.ncols();
        s.rows.extend(x.iter().copied());
        s.codes.extend(codes);
        s.trials.extend(trials);
        s.start.extend(start);
        let all = ndarray::ArrayView2::from_shape((s.codes.len(), p), &s.rows)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let prior = s.template.as_ref().map(|_| s.start.as_slice());
        let fitted = py
            .detach(|| {
                s.params.fit_features_from(
                    all,
                    &s.codes,
                    &s.trials,
                    &s.constraint,
                    s.model.as_ref(),
                    prior,
                )
            })
            .map_err(unsup_err);
        match fitted {
            Ok(m) => {
                s.model = Some(m);
                Ok(())
            }
            Err(e) => {
                // What was taken in is given back: the decoder stays as before the call.
                let n = s.rows.len() / p.max(1) - x.nrows();
                s.rows.truncate(n * p);
                s.codes.truncate(n);
                s.trials.truncate(n);
                s.start.truncate(if s.template.is_some() { n } else { 0 });
                Err(e)
            }
        }
    }

    /// The most probable code of each set, per trial of the given epochs (in order of first
    /// appearance), under the current model.
    fn predict(
        &self,
        epochs: PyReadonlyArray3<'_, f64>,
        codes: Vec<u32>,
        trials: Vec<usize>,
    ) -> PyResult<Vec<Vec<u32>>> {
        let x = self.features(&epochs)?;
        let m = self.model()?;
        let post = m
            .posteriors_features(x.view(), &codes, &trials)
            .map_err(unsup_err)?;
        Ok(m.choices_of(&post))
    }

    /// Each trial's posterior per set, for the given epochs.
    fn posteriors<'py>(
        &self,
        py: Python<'py>,
        epochs: PyReadonlyArray3<'py, f64>,
        codes: Vec<u32>,
        trials: Vec<usize>,
    ) -> PyResult<Bound<'py, PyList>> {
        let x = self.features(&epochs)?;
        let post = self
            .model()?
            .posteriors_features(x.view(), &codes, &trials)
            .map_err(unsup_err)?;
        trial_dicts(py, &post)
    }

    /// The fitted trials' posteriors and choices (the epochs taken in).
    fn fitted<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyList>, Vec<Vec<u32>>)> {
        let m = self.model()?;
        Ok((trial_dicts(py, m.trials())?, m.choices()))
    }

    /// LLR (target vs non-target) per epoch.
    fn decision_function<'py>(
        &self,
        py: Python<'py>,
        epochs: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = self.features(&epochs)?;
        let out = self
            .model()?
            .decision_function_features(x.view())
            .map_err(unsup_err)?;
        Ok(out.into_pyarray(py))
    }

    /// Epochs taken in so far.
    #[getter]
    fn n_epochs(&self) -> usize {
        self.inner.codes.len()
    }

    #[getter]
    fn is_fitted(&self) -> bool {
        self.inner.model.is_some()
    }
});

/// A recording's flashes epoched as `oddball evaluate` epochs them (`oddball_eval::dataset`:
/// read, labelled, band-passed by `preprocess`, cut): a dict of `data`
/// `(n_epochs, n_channels, n_times)` µV, `sfreq`, `tmin`, `ch_names`, `codes`, `targets` (1, 0,
/// -1 unknown), and for a speller recording `trials` (each flash's character, from 0) and
/// `sets` (its rows' and columns' codes), else `None` for both.
#[pyfunction]
#[pyo3(signature = (path, preprocess="peer", text=None))]
pub(crate) fn read_epochs<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    preprocess: &str,
    text: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    use oddball_eval::dataset::{epoch, read_labelled, Labelling};
    let pre = preprocess_named(preprocess)?;
    let how = Labelling {
        mapping: None,
        text,
        speller: None,
        read: None,
    };
    let rec = py
        .detach(|| read_labelled(&path, how).and_then(|r| epoch(r, &pre)))
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
    let epochs = &rec.epochs;
    let events = epochs.events();
    let out = PyDict::new(py);
    out.set_item("data", epochs.data().into_owned().into_pyarray(py))?;
    out.set_item("sfreq", epochs.sfreq())?;
    out.set_item("tmin", epochs.tmin())?;
    out.set_item("ch_names", PyList::new(py, epochs.ch_names())?)?;
    out.set_item("codes", events.iter().map(|e| e.code).collect::<Vec<u32>>())?;
    let targets: Vec<i8> = events
        .iter()
        .map(|e| e.target.map_or(-1, i8::from))
        .collect();
    out.set_item("targets", targets.into_pyarray(py))?;
    match &rec.speller {
        Some(sp) if epochs.n_epochs() == rec.n_events => {
            let trials = oddball_decode::metrics::character_of_flashes(sp, events.len());
            let sets = Constraint::speller(sp).map_err(unsup_err)?;
            out.set_item("trials", trials)?;
            out.set_item("sets", sets.sets().to_vec())?;
            out.set_item("matrix", sp.matrix().to_vec())?;
        }
        _ => {
            out.set_item("trials", py.None())?;
            out.set_item("sets", py.None())?;
            out.set_item("matrix", py.None())?;
        }
    }
    Ok(out)
}
