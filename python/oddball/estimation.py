"""Covariance estimators, as ``pyriemann.estimation``: ``XdawnCovariances`` and ``Covariances``."""
from __future__ import annotations

from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_array, as_epochs, binary_labels
from .spatialfilters import Xdawn, _check_unsupported

__all__ = ["Covariances", "XdawnCovariances"]


class XdawnCovariances(TransformerMixin, BaseEstimator):
    """xDAWN covariance matrices (pyRiemann's ``XdawnCovariances``), computed in Rust.

    Per epoch, the covariance of the super-trial ``[evoked prototypes ; xDAWN-filtered epoch]``:
    ``(n_epochs, 4·nfilter, 4·nfilter)`` for the two classes.

    Parameters as pyRiemann's: ``nfilter``; ``estimator`` and ``xdawn_estimator`` in ``"scm"``,
    ``"lwf"``, ``"oas"``; ``applyfilters`` must be True, ``classes`` None (or both classes) and
    ``baseline_cov`` None (oddball does not implement the others). Binary labels only.

    Fitted: ``classes_``, ``Xd_`` (an :class:`oddball.spatialfilters.Xdawn`).
    """

    def __init__(self, nfilter=4, applyfilters=True, classes=None, estimator="scm",
                 xdawn_estimator="scm", baseline_cov=None):
        self.nfilter = nfilter
        self.applyfilters = applyfilters
        self.classes = classes
        self.estimator = estimator
        self.xdawn_estimator = xdawn_estimator
        self.baseline_cov = baseline_cov

    def fit(self, X, y):
        """Fits xDAWN on epochs ``X`` ``(n_epochs, n_channels, n_times)`` labelled ``y``."""
        X = as_array(X)
        classes, target = binary_labels(y, X.shape[0])
        X = as_epochs(X)
        _check_unsupported(self, classes)
        if not self.applyfilters:
            raise ValueError("XdawnCovariances(applyfilters=False) is not implemented in oddball")
        self._model = _oddball.XdawnCovariances.fit(
            X, target, int(self.nfilter), self.estimator, self.xdawn_estimator
        )
        self.classes_ = classes
        self.n_channels_in_ = X.shape[1]
        return self

    def transform(self, X):
        """SPD matrices ``(n_epochs, 4·nfilter, 4·nfilter)`` of epochs ``X``."""
        check_is_fitted(self, "classes_")
        return self._model.transform(as_epochs(X))

    @property
    def Xd_(self):
        check_is_fitted(self, "classes_")
        xd = Xdawn(nfilter=self.nfilter, estimator=self.xdawn_estimator)
        xd._model = self._model.xdawn
        xd.classes_ = self.classes_
        return xd

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.required = True
        return tags


class Covariances(TransformerMixin, BaseEstimator):
    """One covariance matrix per epoch (pyRiemann's ``Covariances``), estimator ``"scm"``,
    ``"lwf"`` or ``"oas"``. Stateless: ``fit`` only checks its input."""

    def __init__(self, estimator="scm"):
        self.estimator = estimator

    def fit(self, X, y=None):
        X = as_epochs(X)
        self.n_channels_in_ = X.shape[1]
        return self

    def transform(self, X):
        check_is_fitted(self, "n_channels_in_")
        return _oddball.covariances(as_epochs(X), self.estimator)
