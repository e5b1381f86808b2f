//! `oddball._oddball`: thin PyO3 bindings of oddball's fitted decoders and readers, for the pure
//! Python scikit-learn estimators of the `oddball` package (`python/oddball`).
//!
//! Every class here is a *fitted* model: a static `fit` builds it from numpy arrays by calling the
//! Rust crate's `XxxParams::fit`, its methods call the fitted type's own methods, and it pickles
//! through its serde JSON (`__reduce__` → `from_json`). No numerical code lives here: arrays are
//! passed through as `ndarray` views, the GIL is released (`Python::detach`, pyo3's new name for
//! `allow_threads`) while Rust computes, and errors become `ValueError` (decoders) or `OSError`
//! (readers) carrying the Rust error's message.
//!
//! Labels arrive as numpy `bool` arrays (`True` = target, scikit-learn's `classes_[1]`): the
//! Python side maps whatever labels the user gives.

use numpy::PyReadonlyArray3;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use oddball_decode::classifiers::lda::{LdaParams, Shrinkage};
use oddball_decode::classifiers::toeplitz_lda::ToeplitzLdaParams;
use oddball_decode::riemann::covariance::CovEstimator;
use oddball_decode::riemann::xdawn::{XdawnCovariancesParams, XdawnParams};
use oddball_decode::riemann::{MdmParams, TangentSpaceParams};
use oddball_decode::DecodeError;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

fn value_err(e: DecodeError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

fn json_err(e: serde_json::Error) -> PyErr {
    PyValueError::new_err(format!("saved oddball model: {e}"))
}

/// pyRiemann's covariance estimator names: `"scm"`, `"lwf"`, `"oas"`.
fn cov_estimator(name: &str) -> PyResult<CovEstimator> {
    match name {
        "scm" => Ok(CovEstimator::Scm),
        "lwf" => Ok(CovEstimator::LedoitWolf),
        "oas" => Ok(CovEstimator::Oas),
        other => Err(PyValueError::new_err(format!(
            "estimator {other:?} is not available in oddball; use \"scm\", \"lwf\" or \"oas\""
        ))),
    }
}

fn cov_estimator_name(e: CovEstimator) -> &'static str {
    match e {
        CovEstimator::Scm => "scm",
        CovEstimator::LedoitWolf => "lwf",
        CovEstimator::Oas => "oas",
    }
}

fn labels(y: &PyReadonlyArray1<'_, bool>) -> Vec<bool> {
    y.as_array().to_vec()
}

/// A class's `#[pymethods]` block, with `to_json`, `from_json` and pickling through them added
/// (one block per class: pyo3 without `multiple-pymethods`); the class keeps its model in `inner`
/// (frozen, or changed in place as `learning`'s are).
macro_rules! methods_with_json {
    ($py_type:ident, $inner:ty, { $($body:tt)* }) => {
        #[pymethods]
        impl $py_type {
            $($body)*

            /// The fitted model as oddball's JSON.
            fn to_json(&self) -> PyResult<String> {
                serde_json::to_string(&self.inner).map_err(json_err)
            }

            /// A fitted model from `to_json`'s text.
            #[staticmethod]
            fn from_json(text: &str) -> PyResult<Self> {
                let inner: $inner = serde_json::from_str(text).map_err(json_err)?;
                Ok(Self { inner })
            }

            fn __reduce__<'py>(
                slf: &Bound<'py, Self>,
            ) -> PyResult<(Bound<'py, PyAny>, (String,))> {
                let json = slf.borrow().to_json()?;
                Ok((slf.get_type().getattr("from_json")?, (json,)))
            }
        }
    };
}

// After the macro, which they use.
mod learning;
mod online;

/// Fitted xDAWN spatial filters (pyRiemann's `Xdawn`).
#[pyclass(module = "oddball._oddball", frozen)]
struct Xdawn {
    inner: oddball_decode::riemann::xdawn::Xdawn,
}

methods_with_json!(Xdawn, oddball_decode::riemann::xdawn::Xdawn, {
    #[staticmethod]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray3<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
        nfilter: usize,
        estimator: &str,
    ) -> PyResult<Self> {
        let params = XdawnParams {
            nfilter,
            estimator: cov_estimator(estimator)?,
        };
        let (x, y) = (x.as_array(), labels(&y));
        let inner = py.detach(|| params.fit(x, &y)).map_err(value_err)?;
        Ok(Self { inner })
    }

    /// Spatially filtered epochs `(n_epochs, 2k, n_times)`.
    fn transform<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let x = x.as_array();
        let out = py.detach(|| self.inner.transform(x)).map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    #[getter]
    fn filters<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.filters().to_owned().into_pyarray(py)
    }

    #[getter]
    fn patterns<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.patterns().to_owned().into_pyarray(py)
    }

    #[getter]
    fn evokeds<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.evokeds().to_owned().into_pyarray(py)
    }
});

/// Fitted xDAWN covariances (pyRiemann's `XdawnCovariances`).
#[pyclass(module = "oddball._oddball", frozen)]
struct XdawnCovariances {
    inner: oddball_decode::riemann::xdawn::XdawnCovariances,
}

methods_with_json!(
    XdawnCovariances,
    oddball_decode::riemann::xdawn::XdawnCovariances,
    {
        #[staticmethod]
        fn fit(
            py: Python<'_>,
            x: PyReadonlyArray3<'_, f64>,
            y: PyReadonlyArray1<'_, bool>,
            nfilter: usize,
            estimator: &str,
            xdawn_estimator: &str,
        ) -> PyResult<Self> {
            let params = XdawnCovariancesParams {
                nfilter,
                estimator: cov_estimator(estimator)?,
                xdawn_estimator: cov_estimator(xdawn_estimator)?,
            };
            let (x, y) = (x.as_array(), labels(&y));
            let inner = py.detach(|| params.fit(x, &y)).map_err(value_err)?;
            Ok(Self { inner })
        }

        /// SPD matrices `(n_epochs, 4k, 4k)`.
        fn transform<'py>(
            &self,
            py: Python<'py>,
            x: PyReadonlyArray3<'py, f64>,
        ) -> PyResult<Bound<'py, PyArray3<f64>>> {
            let x = x.as_array();
            let out = py.detach(|| self.inner.transform(x)).map_err(value_err)?;
            Ok(out.into_pyarray(py))
        }

        /// The xDAWN filters and prototypes inside.
        #[getter]
        fn xdawn(&self) -> Xdawn {
            Xdawn {
                inner: self.inner.xdawn().clone(),
            }
        }

        #[getter]
        fn estimator(&self) -> &'static str {
            cov_estimator_name(self.inner.estimator())
        }
    }
);

/// Covariance per epoch (pyRiemann's `Covariances`): `(n, c, t)` → `(n, c, c)`.
#[pyfunction]
fn covariances<'py>(
    py: Python<'py>,
    x: PyReadonlyArray3<'py, f64>,
    estimator: &str,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let est = cov_estimator(estimator)?;
    let x = x.as_array();
    let out = py.detach(|| est.estimate_epochs(x)).map_err(value_err)?;
    Ok(out.into_pyarray(py))
}

/// Fitted tangent space at the Riemannian mean (pyRiemann's `TangentSpace`).
#[pyclass(module = "oddball._oddball", frozen)]
struct TangentSpace {
    inner: oddball_decode::riemann::TangentSpace,
}

methods_with_json!(TangentSpace, oddball_decode::riemann::TangentSpace, {
    #[staticmethod]
    fn fit(py: Python<'_>, covs: PyReadonlyArray3<'_, f64>) -> PyResult<Self> {
        let covs = covs.as_array();
        let inner = py
            .detach(|| TangentSpaceParams::default().fit(covs))
            .map_err(value_err)?;
        Ok(Self { inner })
    }

    /// Tangent vectors `(n, c(c+1)/2)`.
    fn transform<'py>(
        &self,
        py: Python<'py>,
        covs: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let covs = covs.as_array();
        let out = py
            .detach(|| self.inner.transform(covs))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// SPD matrices `(n, c, c)` from tangent vectors.
    fn inverse_transform<'py>(
        &self,
        py: Python<'py>,
        v: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let v = v.as_array();
        let out = py
            .detach(|| self.inner.inverse_transform(v))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    #[getter]
    fn reference<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.reference().to_owned().into_pyarray(py)
    }
});

/// Fitted minimum distance to (Riemannian) mean (pyRiemann's `MDM`), binary.
#[pyclass(module = "oddball._oddball", frozen)]
struct Mdm {
    inner: oddball_decode::riemann::Mdm,
}

methods_with_json!(Mdm, oddball_decode::riemann::Mdm, {
    #[staticmethod]
    fn fit(
        py: Python<'_>,
        covs: PyReadonlyArray3<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
    ) -> PyResult<Self> {
        let (covs, y) = (covs.as_array(), labels(&y));
        let inner = py
            .detach(|| MdmParams::default().fit(covs, &y))
            .map_err(value_err)?;
        Ok(Self { inner })
    }

    /// Riemannian distances `(n, 2)` to the non-target and target means.
    fn distances<'py>(
        &self,
        py: Python<'py>,
        covs: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let covs = covs.as_array();
        let out = py
            .detach(|| self.inner.distances(covs))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// `d²(C, M_non-target) − d²(C, M_target)` per matrix.
    fn decision_function<'py>(
        &self,
        py: Python<'py>,
        covs: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let covs = covs.as_array();
        let out = py
            .detach(|| self.inner.decision_function(covs))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// P(target) per matrix.
    fn predict_proba<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array();
        let out = py
            .detach(|| self.inner.predict_proba(x))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// The class means `(2, c, c)`: non-target, target.
    #[getter]
    fn covmeans<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let both = ndarray::stack(
            ndarray::Axis(0),
            &[self.inner.mean_nontarget(), self.inner.mean_target()],
        )
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(both.into_pyarray(py))
    }
});

/// Fitted binary shrinkage LDA (scikit-learn's `LinearDiscriminantAnalysis(solver="lsqr")`).
#[pyclass(module = "oddball._oddball", frozen)]
struct Lda {
    inner: oddball_decode::classifiers::lda::Lda,
}

methods_with_json!(Lda, oddball_decode::classifiers::lda::Lda, {
    /// `shrinkage`: `None` (none), a weight in `[0, 1]`, or `auto` = `True` (Ledoit–Wolf).
    #[staticmethod]
    #[pyo3(signature = (x, y, shrinkage, auto))]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
        shrinkage: Option<f64>,
        auto: bool,
    ) -> PyResult<Self> {
        let params = LdaParams {
            shrinkage: if auto {
                Shrinkage::Auto
            } else {
                Shrinkage::Fixed(shrinkage.unwrap_or(0.0))
            },
        };
        let (x, y) = (x.as_array(), labels(&y));
        let inner = py.detach(|| params.fit(x, &y)).map_err(value_err)?;
        Ok(Self { inner })
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
        self.inner.coef().to_owned().into_pyarray(py)
    }

    #[getter]
    fn intercept(&self) -> f64 {
        self.inner.intercept()
    }

    #[getter]
    fn priors(&self) -> [f64; 2] {
        self.inner.priors()
    }

    #[getter]
    fn means<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.means().to_owned().into_pyarray(py)
    }

    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.covariance().to_owned().into_pyarray(py)
    }
});

/// Fitted block-Toeplitz LDA (`toeplitzlda`'s `ToeplitzLDA`), on channel-major features.
#[pyclass(module = "oddball._oddball", frozen)]
struct ToeplitzLda {
    inner: oddball_decode::classifiers::toeplitz_lda::ToeplitzLda,
}

methods_with_json!(
    ToeplitzLda,
    oddball_decode::classifiers::toeplitz_lda::ToeplitzLda,
    {
        /// `x` `(n, n_channels · n_times)`, feature `ch · n_times + t`.
        #[staticmethod]
        fn fit(
            py: Python<'_>,
            x: PyReadonlyArray2<'_, f64>,
            y: PyReadonlyArray1<'_, bool>,
            n_channels: usize,
        ) -> PyResult<Self> {
            let (x, y) = (x.as_array(), labels(&y));
            let inner = py
                .detach(|| ToeplitzLdaParams::default().fit(x, &y, n_channels))
                .map_err(value_err)?;
            Ok(Self { inner })
        }

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

        /// Channel-major weights (feature `ch · n_times + t`).
        #[getter]
        fn coef<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
            self.inner.coef().to_owned().into_pyarray(py)
        }

        #[getter]
        fn intercept(&self) -> f64 {
            self.inner.intercept()
        }

        #[getter]
        fn shrinkage(&self) -> f64 {
            self.inner.shrinkage()
        }
    }
);

/// A fitted preset pipeline (`oddball train --pipeline NAME`) on band-passed epochs.
#[pyclass(module = "oddball._oddball", frozen)]
struct Pipeline {
    inner: oddball_decode::pipeline::Pipeline,
}

methods_with_json!(Pipeline, oddball_decode::pipeline::Pipeline, {
    /// Fits the preset `name` for epochs sampled at `sfreq` Hz.
    #[staticmethod]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray3<'_, f64>,
        y: PyReadonlyArray1<'_, bool>,
        name: &str,
        sfreq: f64,
    ) -> PyResult<Self> {
        let preset: oddball_decode::preset::Preset = name.parse().map_err(value_err)?;
        let params = preset.params(sfreq).map_err(value_err)?;
        let (x, y) = (x.as_array(), labels(&y));
        let inner = py.detach(|| params.fit(x, &y)).map_err(value_err)?;
        Ok(Self { inner })
    }

    /// Target evidence per epoch (larger = more target-like).
    fn decision_function<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array();
        let out = py
            .detach(|| self.inner.decision_function(x))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// P(target) per epoch.
    fn predict_proba<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray3<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = x.as_array();
        let out = py
            .detach(|| self.inner.predict_proba(x))
            .map_err(value_err)?;
        Ok(out.into_pyarray(py))
    }

    /// `(n_channels, n_times)` of the epochs it was fitted on.
    #[getter]
    fn epoch_shape(&self) -> (usize, usize) {
        self.inner.epoch_shape()
    }
});

/// The preset names `Pipeline.fit` takes.
#[pyfunction]
fn presets() -> Vec<&'static str> {
    oddball_decode::preset::PRESETS.to_vec()
}

/// Reads a recording with `oddball_io::read_with` (format by extension; the reader options the
/// command line has: `sfreq`, `channels`, `montage`, `time_column`, `events_from`, `data_from`),
/// labels its events by `target`/`nontarget` keys (codes such as `"2"` or marker texts,
/// comma-separated) when given, and returns a dict: `data` `(n_channels, n_times)` µV, `sfreq`, `ch_names`, `format`, and the
/// events as `onsets` (samples), `codes`, `targets` (`1` target, `0` non-target, `-1` unknown) and
/// `labels` (text or `None`).
#[pyfunction]
#[pyo3(signature = (path, target=None, nontarget=None, text=None, sfreq=None, channels=None, montage=None, time_column=None, events_from=None, data_from=None))]
#[allow(clippy::too_many_arguments)]
fn read_raw<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    target: Option<&str>,
    nontarget: Option<&str>,
    text: Option<&str>,
    sfreq: Option<f64>,
    channels: Option<Vec<String>>,
    montage: Option<std::path::PathBuf>,
    time_column: Option<String>,
    events_from: Option<String>,
    data_from: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let options = oddball_io::ReadOptions {
        sfreq,
        channels,
        montage,
        time_column,
        events: events_from,
        data: data_from,
    };
    options.check().map_err(PyValueError::new_err)?;
    let mapping = match (target, nontarget) {
        (Some(t), Some(n)) => Some(
            oddball_io::EventMapping::parse(t, n)
                .map_err(|e| PyValueError::new_err(e.to_string()))?,
        ),
        (None, None) => None,
        _ => {
            return Err(PyValueError::new_err(
                "events: give both target and non-target keys, or neither",
            ))
        }
    };
    let text = text.map(str::to_owned);
    let rec = py.detach(move || -> PyResult<oddball_io::Recording> {
        let mut rec = oddball_io::read_with(&path, &options)
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        if let Some(m) = &mapping {
            rec.map_events(m)
                .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        }
        if let Some(t) = &text {
            rec.label_from_text(t)
                .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?;
        }
        Ok(rec)
    })?;
    let format = format!("{:?}", rec.format);
    let (data, sfreq, ch_names, events) = rec.raw.into_parts();
    let events = events.into_vec();
    let onsets: Vec<i64> = events.iter().map(|e| e.onset as i64).collect();
    let codes: Vec<i64> = events.iter().map(|e| i64::from(e.code)).collect();
    let targets: Vec<i8> = events
        .iter()
        .map(|e| e.target.map_or(-1, i8::from))
        .collect();
    let labels: Vec<Option<String>> = events.into_iter().map(|e| e.label).collect();
    let out = PyDict::new(py);
    out.set_item("data", data.into_pyarray(py))?;
    out.set_item("sfreq", sfreq)?;
    out.set_item("ch_names", PyList::new(py, ch_names)?)?;
    out.set_item("format", format)?;
    out.set_item("onsets", onsets.into_pyarray(py))?;
    out.set_item("codes", codes.into_pyarray(py))?;
    out.set_item("targets", targets.into_pyarray(py))?;
    out.set_item("labels", PyList::new(py, labels)?)?;
    Ok(out)
}

#[pymodule]
fn _oddball(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Xdawn>()?;
    m.add_class::<XdawnCovariances>()?;
    m.add_class::<TangentSpace>()?;
    m.add_class::<Mdm>()?;
    m.add_class::<Lda>()?;
    m.add_class::<ToeplitzLda>()?;
    m.add_class::<Pipeline>()?;
    m.add_function(wrap_pyfunction!(covariances, m)?)?;
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(read_raw, m)?)?;
    m.add_class::<online::OnlineDecoder>()?;
    m.add_class::<learning::AdaptiveLda>()?;
    m.add_class::<learning::UnsupervisedDecoder>()?;
    m.add_function(wrap_pyfunction!(learning::read_epochs, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
