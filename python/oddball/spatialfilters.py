"""Spatial filters, as ``pyriemann.spatialfilters``: ``Xdawn``."""
from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_array, as_epochs, binary_labels

__all__ = ["Xdawn"]


def _check_unsupported(est, classes):
    if est.classes is not None and set(np.asarray(est.classes).tolist()) != set(classes.tolist()):
        raise ValueError(
            f"{type(est).__name__}(classes={est.classes!r}): oddball filters both classes of a "
            "binary problem; leave classes=None"
        )
    if est.baseline_cov is not None:
        raise ValueError(f"{type(est).__name__}(baseline_cov=...) is not implemented in oddball")


class Xdawn(TransformerMixin, BaseEstimator):
    """xDAWN spatial filters (pyRiemann's ``Xdawn``), computed in Rust.

    ``transform`` gives the filtered epochs ``(n_epochs, 2·nfilter, n_times)`` (non-target
    filters first, as pyRiemann's ``classes_`` order). Each filter's sign is fixed (largest
    coefficient positive), where LAPACK's is arbitrary: outputs equal pyRiemann's up to one sign
    per filter. Binary labels only; ``classes`` None, ``baseline_cov`` None.

    Fitted: ``classes_``, ``filters_``, ``patterns_``, ``evokeds_``.
    """

    def __init__(self, nfilter=4, classes=None, estimator="scm", baseline_cov=None):
        self.nfilter = nfilter
        self.classes = classes
        self.estimator = estimator
        self.baseline_cov = baseline_cov

    def fit(self, X, y):
        X = as_array(X)
        classes, target = binary_labels(y, X.shape[0])
        X = as_epochs(X)
        _check_unsupported(self, classes)
        self._model = _oddball.Xdawn.fit(X, target, int(self.nfilter), self.estimator)
        self.classes_ = classes
        return self

    def transform(self, X):
        check_is_fitted(self, "classes_")
        return self._model.transform(as_epochs(X))

    @property
    def filters_(self):
        check_is_fitted(self, "classes_")
        return self._model.filters

    @property
    def patterns_(self):
        check_is_fitted(self, "classes_")
        return self._model.patterns

    @property
    def evokeds_(self):
        check_is_fitted(self, "classes_")
        return self._model.evokeds

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        return tags
