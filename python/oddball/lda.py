"""Linear discriminant analysis: scikit-learn's ``LinearDiscriminantAnalysis`` (lsqr solver),
``toeplitzlda``'s ``ToeplitzLDA``, and oddball's ``AdaptiveLDA`` (a calibrated LDA that keeps
learning from a session through ``partial_fit``), computed in Rust; binary (target vs
non-target)."""
from __future__ import annotations

import numbers

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from . import _oddball
from ._base import binary_labels, predict_from_decision, proba_columns

__all__ = ["AdaptiveLDA", "LinearDiscriminantAnalysis", "ToeplitzLDA"]


def _shrinkage(s, owner):
    """``(fixed weight or None, auto)`` from scikit-learn's ``shrinkage`` values."""
    if isinstance(s, str):
        if s != "auto":
            raise ValueError(f"{owner}(shrinkage={s!r}): expected None, 'auto' or a float in [0, 1]")
        return None, True
    if s is None:
        return None, False
    if isinstance(s, numbers.Real) and not isinstance(s, bool) and 0.0 <= s <= 1.0:
        return float(s), False
    raise ValueError(f"{owner}(shrinkage={s!r}): expected None, 'auto' or a float in [0, 1]")


class _LinearBinary(ClassifierMixin, BaseEstimator):
    """Shared prediction of the two binary linear discriminants."""

    def _rows(self, X, reset):
        return validate_data(self, X, reset=reset, dtype=np.float64, order="C")

    def decision_function(self, X):
        """Log-odds of ``classes_[1]`` per row ``(n_samples,)``."""
        check_is_fitted(self, "classes_")
        return self._model.decision_function(self._model_input(self._rows(X, reset=False)))

    def predict(self, X):
        return predict_from_decision(self, X)

    def predict_proba(self, X):
        check_is_fitted(self, "classes_")
        return proba_columns(self._model.predict_proba(self._model_input(self._rows(X, reset=False))))

    def predict_log_proba(self, X):
        with np.errstate(divide="ignore"):
            return np.log(self.predict_proba(X))

    def _model_input(self, X):
        return X

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.classifier_tags.multi_class = False
        return tags


class LinearDiscriminantAnalysis(_LinearBinary):
    """Binary shrinkage LDA, equal to scikit-learn's
    ``LinearDiscriminantAnalysis(solver="lsqr", shrinkage=...)``.

    ``solver`` must be ``"lsqr"`` (oddball's default, where scikit-learn's is ``"svd"``);
    ``shrinkage`` is None, ``"auto"`` (Ledoit–Wolf) or a float in [0, 1]; ``priors`` and
    ``covariance_estimator`` must be None (the class frequencies are the priors);
    ``n_components``, ``store_covariance`` and ``tol`` are accepted and unused (``n_components``
    is for ``transform``, which the lsqr solver does not have in scikit-learn either; the
    covariance is always stored; the lsqr solver has no tolerance).

    Fitted: ``classes_``, ``coef_`` ``(1, n_features)``, ``intercept_`` ``(1,)``, ``means_``,
    ``priors_``, ``covariance_``, ``n_features_in_``.
    """

    def __init__(self, solver="lsqr", shrinkage=None, priors=None, n_components=None,
                 store_covariance=False, tol=1e-4, covariance_estimator=None):
        self.solver = solver
        self.shrinkage = shrinkage
        self.priors = priors
        self.n_components = n_components
        self.store_covariance = store_covariance
        self.tol = tol
        self.covariance_estimator = covariance_estimator

    def fit(self, X, y):
        if self.solver != "lsqr":
            raise ValueError(
                f"LinearDiscriminantAnalysis(solver={self.solver!r}): oddball implements "
                "solver='lsqr' only"
            )
        for name in ("priors", "covariance_estimator"):
            if getattr(self, name) is not None:
                raise ValueError(f"LinearDiscriminantAnalysis({name}=...) is not implemented in oddball")
        shrink, auto = _shrinkage(self.shrinkage, type(self).__name__)
        X, y = validate_data(self, X, y, dtype=np.float64, order="C")
        classes, target = binary_labels(y, X.shape[0])
        self._model = _oddball.Lda.fit(X, target, shrink, auto)
        self.classes_ = classes
        self.coef_ = self._model.coef[np.newaxis, :]
        self.intercept_ = np.array([self._model.intercept])
        self.means_ = self._model.means
        self.priors_ = np.array(self._model.priors)
        self.covariance_ = self._model.covariance
        return self


class ToeplitzLDA(_LinearBinary):
    """Block-Toeplitz shrinkage LDA (Sosulski & Tangermann 2022), equal to
    ``toeplitzlda.classification.ToeplitzLDA(n_channels)`` 0.4.0.

    Features as ``toeplitzlda`` takes them: ``(n_samples, n_times · n_channels)``, time-major
    (feature ``t · n_channels + ch``, i.e. epochs ``(n, n_channels, n_times)`` passed as
    ``X.transpose(0, 2, 1).reshape(n, -1)``).

    Fitted: ``classes_``, ``coef_`` ``(1, n_features)`` (time-major), ``intercept_``,
    ``shrinkage_``, ``n_features_in_``.
    """

    def __init__(self, n_channels=1):
        self.n_channels = n_channels

    def _layout(self, n_features):
        nc = self.n_channels
        if not isinstance(nc, numbers.Integral) or nc < 1 or n_features % nc:
            raise ValueError(
                f"ToeplitzLDA(n_channels={nc!r}): n_features={n_features} must be a multiple of "
                "a positive n_channels"
            )
        return int(nc), n_features // int(nc)

    def _model_input(self, X):
        nc, nt = self._layout(X.shape[1])
        return np.ascontiguousarray(X.reshape(X.shape[0], nt, nc).transpose(0, 2, 1)).reshape(X.shape[0], -1)

    def fit(self, X, y):
        X, y = validate_data(self, X, y, dtype=np.float64, order="C")
        nc, nt = self._layout(X.shape[1])
        classes, target = binary_labels(y, X.shape[0])
        self._model = _oddball.ToeplitzLda.fit(self._model_input(X), target, nc)
        self.classes_ = classes
        coef = self._model.coef.reshape(nc, nt).T.reshape(-1)
        self.coef_ = coef[np.newaxis, :]
        self.intercept_ = np.array([self._model.intercept])
        self.shrinkage_ = self._model.shrinkage
        return self


class AdaptiveLDA(_LinearBinary):
    """A shrinkage LDA calibrated by ``fit`` whose class means keep learning from the session:
    ``partial_fit(X, y)`` takes in labelled rows (e.g. a decision's epochs, labelled by the
    decision) through incremental statistics, with the calibration's covariance — the engine of
    ``oddball demo/online --adapt``. An update that would turn the weights below ``min_cosine``
    with the calibrated weights (a run of wrong labels) is undone.

    The first ``partial_fit`` of an unfitted model calibrates it (as ``fit``); ``classes`` is
    accepted as scikit-learn's ``partial_fit`` takes it, and must match the labels.

    Fitted: ``classes_``, ``coef_``, ``intercept_``, ``means_`` ``(2, n_features)``,
    ``counts_`` (epochs per class taken in), ``cosine_`` (weights vs calibrated),
    ``n_updates_``, ``n_rejected_``, ``n_features_in_``.
    """

    def __init__(self, shrinkage="auto", min_cosine=0.8):
        self.shrinkage = shrinkage
        self.min_cosine = min_cosine

    def _sync(self):
        m = self._model
        self.coef_ = m.coef[np.newaxis, :]
        self.intercept_ = np.array([m.intercept])
        self.means_ = m.means
        self.counts_ = m.counts
        self.cosine_ = m.cosine

    def fit(self, X, y):
        shrink, auto = _shrinkage(self.shrinkage, "AdaptiveLDA")
        mc = self.min_cosine
        if not isinstance(mc, numbers.Real) or isinstance(mc, bool) or not -1.0 <= mc <= 1.0:
            raise ValueError(f"AdaptiveLDA(min_cosine={mc!r}): expected a cosine in [-1, 1]")
        X, y = validate_data(self, X, y, dtype=np.float64, order="C")
        classes, target = binary_labels(y, X.shape[0])
        self._model = _oddball.AdaptiveLda.fit(X, target, shrink, auto, float(mc))
        self.classes_ = classes
        self.n_updates_ = 0
        self.n_rejected_ = 0
        self._sync()
        return self

    def partial_fit(self, X, y, classes=None):
        if not hasattr(self, "classes_"):
            return self.fit(X, y)
        if classes is not None and not np.array_equal(np.unique(classes), self.classes_):
            raise ValueError(f"classes={list(classes)}: the model was fitted on {list(self.classes_)}")
        X = self._rows(X, reset=False)
        y = np.asarray(y)
        if y.ndim != 1 or y.shape[0] != X.shape[0]:
            raise ValueError(f"y: expected {X.shape[0]} labels, got shape {y.shape}")
        unknown = set(np.unique(y).tolist()) - set(self.classes_.tolist())
        if unknown:
            raise ValueError(f"y has labels {sorted(unknown)} the model was not fitted on {list(self.classes_)}")
        accepted, _ = self._model.partial_fit(X, np.ascontiguousarray(y == self.classes_[1]))
        self.n_updates_ += 1
        self.n_rejected_ += int(not accepted)
        self._sync()
        return self
