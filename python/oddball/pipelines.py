"""oddball's named pipelines (``oddball train --pipeline NAME``) as scikit-learn pipelines.

``make("stack", sfreq=240)`` gives a ``sklearn.pipeline.Pipeline`` whose one step, a
:class:`PresetClassifier`, fits the Rust preset on band-passed epochs
``(n_epochs, n_channels, n_times)`` sampled at ``sfreq`` Hz (the preset's own feature steps —
decimation, bin means, xDAWN, tangent space, fusion — run inside Rust, as in ``oddball train``).
"""
from __future__ import annotations

from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.pipeline import Pipeline
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_array, as_epochs, binary_labels, predict_from_decision, proba_columns

__all__ = ["PRESETS", "PresetClassifier", "make"]

#: The preset names, as the command line takes them.
PRESETS = tuple(_oddball.presets())


class PresetClassifier(ClassifierMixin, BaseEstimator):
    """The oddball preset ``name`` for epochs sampled at ``sfreq`` Hz; binary.

    ``decision_function`` is the preset's target evidence (positive leans to ``classes_[1]``;
    for score fusions — ``lda+riemann``, ``stack`` — the fused score), ``predict_proba`` its
    P(target).
    """

    def __init__(self, name="lda", sfreq=None):
        self.name = name
        self.sfreq = sfreq

    def fit(self, X, y):
        if self.name not in PRESETS:
            raise ValueError(f"unknown preset {self.name!r}; known: {', '.join(PRESETS)}")
        if self.sfreq is None or not float(self.sfreq) > 0:
            raise ValueError(f"PresetClassifier(sfreq={self.sfreq!r}): give the epochs' sampling rate in Hz")
        X = as_array(X)
        classes, target = binary_labels(y, X.shape[0])
        X = as_epochs(X)
        self._model = _oddball.Pipeline.fit(X, target, self.name, float(self.sfreq))
        self.classes_ = classes
        return self

    def decision_function(self, X):
        check_is_fitted(self, "classes_")
        return self._model.decision_function(as_epochs(X))

    def predict(self, X):
        return predict_from_decision(self, X)

    def predict_proba(self, X):
        check_is_fitted(self, "classes_")
        return proba_columns(self._model.predict_proba(as_epochs(X)))

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.classifier_tags.multi_class = False
        return tags


def make(name: str, sfreq: float) -> Pipeline:
    """The preset ``name`` (one of :data:`PRESETS`) as a scikit-learn ``Pipeline`` for band-passed
    epochs sampled at ``sfreq`` Hz."""
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; known: {', '.join(PRESETS)}")
    return Pipeline([(name, PresetClassifier(name=name, sfreq=sfreq))])
