//! The online decoder behind a Python experiment's own stimuli (`oddball.online`).

use numpy::PyReadonlyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::{json_err, value_err};

/// The online decoder behind a Python experiment's own stimuli: `oddball decode`'s listener
/// (`oddball_session::listener`), fed from Python instead of Lab Streaming Layer. The paradigm
/// file says what the markers mean; EEG blocks come with the time of their last sample, markers
/// with their time, on one clock; each call returns the messages it produced as JSON text
/// (decisions, stops, the in-stream calibration), `oddball decode`'s very messages.
#[pyclass(module = "oddball._oddball")]
pub(crate) struct OnlineDecoder {
    inner: std::sync::Mutex<oddball_session::listener::Listener>,
    labels: Vec<String>,
}

impl OnlineDecoder {
    fn run<F>(&self, py: Python<'_>, f: F) -> PyResult<Vec<String>>
    where
        F: FnOnce(
                &mut oddball_session::listener::Listener,
            )
                -> Result<Vec<oddball_session::listener::Output>, oddball_session::SessionError>
            + Send,
    {
        let inner = &self.inner;
        let labels = &self.labels;
        py.detach(|| {
            let mut l = inner
                .lock()
                .map_err(|_| PyValueError::new_err("the decoder failed in an earlier call"))?;
            let outs = f(&mut l).map_err(|e| PyValueError::new_err(e.to_string()))?;
            Ok(outs.iter().map(|o| o.to_json(labels, f64::NAN)).collect())
        })
    }
}

#[pymethods]
impl OnlineDecoder {
    /// `paradigm`: a paradigm file's path, or its TOML text when `paradigm_text` is true;
    /// `model`: a saved model's JSON text (from `oddball train`), or `calibration`: the number
    /// of first trials to calibrate on, or `0` for none (the unsupervised decoder).
    #[new]
    #[pyo3(signature = (paradigm, sfreq, ch_names, model=None, calibration=0, dynamic_stopping=false, threshold=0.95, paradigm_text=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        paradigm: &str,
        sfreq: f64,
        ch_names: Vec<String>,
        model: Option<&str>,
        calibration: usize,
        dynamic_stopping: bool,
        threshold: f64,
        paradigm_text: bool,
    ) -> PyResult<Self> {
        use oddball_session::listener::{Listener, ListenerParams, ListenerStart};
        let paradigm = if paradigm_text {
            oddball_io::Paradigm::parse(paradigm, std::path::Path::new("<paradigm text>"))
        } else {
            oddball_io::Paradigm::load(paradigm)
        }
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let start = match (model, calibration) {
            (Some(m), 0) => ListenerStart::Model(Box::new(
                oddball_decode::pipeline::Model::from_json(m).map_err(value_err)?,
            )),
            (Some(_), _) => {
                return Err(PyValueError::new_err(
                    "give a model or a calibration, not both",
                ))
            }
            (None, 0) => ListenerStart::Uncalibrated { params: None },
            (None, trials) => ListenerStart::Calibrate { trials },
        };
        let labels = paradigm.labels.clone();
        let params = ListenerParams::new(
            paradigm,
            start,
            oddball_decode::preset::Preset::Lda,
            dynamic_stopping.then_some(threshold),
        );
        let inner = Listener::new(params, sfreq, &ch_names)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Self {
            inner: std::sync::Mutex::new(inner),
            labels,
        })
    }

    /// A block of EEG `(n_channels, n)` in µV whose last sample is at `last_time` (s); the
    /// messages it completed, as JSON text.
    fn push_eeg(
        &self,
        py: Python<'_>,
        samples: PyReadonlyArray2<'_, f64>,
        last_time: f64,
    ) -> PyResult<Vec<String>> {
        let x = samples.as_array().to_owned();
        self.run(py, move |l| l.push_eeg(x.view(), last_time))
    }

    /// One marker of the stimulus program, `time` on the EEG's clock (s).
    fn push_marker(&self, py: Python<'_>, text: &str, time: f64) -> PyResult<Vec<String>> {
        let text = text.to_string();
        self.run(py, move |l| l.push_marker(&text, time))
    }

    /// The streams ended: the trials still open are decided on what arrived.
    fn finish(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.run(py, |l| l.finish())
    }

    /// The markers read and those the decoder could not use, by reason (JSON text).
    fn counts(&self) -> PyResult<String> {
        let l = self
            .inner
            .lock()
            .map_err(|_| PyValueError::new_err("the decoder failed in an earlier call"))?;
        serde_json::to_string(l.counts()).map_err(json_err)
    }

    /// The choices' labels, in the order of the posteriors.
    #[getter]
    fn labels(&self) -> Vec<String> {
        self.labels.clone()
    }
}
