"""Riemannian classifiers, as ``pyriemann.classification``: ``MDM``."""
from __future__ import annotations

from sklearn.base import BaseEstimator, ClassifierMixin, TransformerMixin
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_array, as_matrices, binary_labels, predict_from_decision, proba_columns
from .tangentspace import check_metric

__all__ = ["MDM"]


class MDM(ClassifierMixin, TransformerMixin, BaseEstimator):
    """Minimum distance to (Riemannian) mean (pyRiemann's ``MDM``), computed in Rust; binary.

    ``transform`` gives the distances ``(n, 2)`` to the class means (``classes_`` order),
    ``predict_proba`` pyRiemann's softmax of ``-d²``, and ``decision_function`` (not in
    pyRiemann) ``d²(C, M_0) − d²(C, M_1)``, positive for ``classes_[1]``.
    ``metric="riemann"`` only; ``n_jobs`` is accepted for pyRiemann compatibility (oddball's
    distances run on Rust threads; set ``RAYON_NUM_THREADS`` to bound them).

    Fitted: ``classes_``, ``covmeans_``.
    """

    def __init__(self, metric="riemann", n_jobs=1):
        self.metric = metric
        self.n_jobs = n_jobs

    def fit(self, X, y):
        check_metric(self, self.metric)
        X = as_array(X)
        classes, target = binary_labels(y, X.shape[0])
        X = as_matrices(X)
        self._model = _oddball.Mdm.fit(X, target)
        self.classes_ = classes
        self.covmeans_ = self._model.covmeans
        return self

    def transform(self, X):
        check_is_fitted(self, "classes_")
        return self._model.distances(as_matrices(X))

    def decision_function(self, X):
        check_is_fitted(self, "classes_")
        return self._model.decision_function(as_matrices(X))

    def predict(self, X):
        return predict_from_decision(self, X)

    def predict_proba(self, X):
        check_is_fitted(self, "classes_")
        return proba_columns(self._model.predict_proba(as_matrices(X)))

    def fit_predict(self, X, y):
        return self.fit(X, y).predict(X)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.classifier_tags.multi_class = False
        return tags
