"""Tangent space, as ``pyriemann.tangentspace``: ``TangentSpace``."""
from __future__ import annotations

from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_matrices, as_rows

__all__ = ["TangentSpace"]


def check_metric(est, metric):
    """oddball implements the affine-invariant ("riemann") metric only."""
    ok = metric == "riemann" or (
        isinstance(metric, dict) and all(v == "riemann" for v in metric.values())
    )
    if not ok:
        raise ValueError(
            f"{type(est).__name__}(metric={metric!r}): oddball implements metric='riemann' only"
        )


class TangentSpace(TransformerMixin, BaseEstimator):
    """Tangent space at the Riemannian mean of the training matrices (pyRiemann's
    ``TangentSpace``), computed in Rust.

    ``transform``: SPD matrices ``(n, c, c)`` → vectors ``(n, c(c+1)/2)`` (upper triangle row by
    row, off-diagonal × √2, as pyRiemann). ``metric="riemann"`` and ``tsupdate=False`` only.

    Fitted: ``reference_``.
    """

    def __init__(self, metric="riemann", tsupdate=False):
        self.metric = metric
        self.tsupdate = tsupdate

    def fit(self, X, y=None):
        check_metric(self, self.metric)
        if self.tsupdate:
            raise ValueError("TangentSpace(tsupdate=True) is not implemented in oddball")
        X = as_matrices(X)
        self._model = _oddball.TangentSpace.fit(X)
        self.reference_ = self._model.reference
        return self

    def transform(self, X):
        check_is_fitted(self, "reference_")
        return self._model.transform(as_matrices(X))

    def inverse_transform(self, X):
        check_is_fitted(self, "reference_")
        return self._model.inverse_transform(as_rows(X))
