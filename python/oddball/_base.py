"""Shared helpers of oddball's scikit-learn estimators: input checks and binary labels.

The estimators are thin: a pure-Python scikit-learn ``BaseEstimator`` holds the constructor
parameters; ``fit`` hands numpy arrays to a fitted Rust model (``oddball._oddball``), which
pickles through its JSON. No numerical code lives on the Python side.
"""
from __future__ import annotations

import numpy as np
from sklearn.utils import check_array
from sklearn.utils.multiclass import check_classification_targets, type_of_target

__all__ = ["as_array", "as_epochs", "as_matrices", "as_rows", "binary_labels", "predict_from_decision",
           "proba_columns"]


def _as_float_array(X, ndim: int, what: str) -> np.ndarray:
    X = as_array(X)  # scikit-learn's own checks and messages first, then the shape
    if X.ndim != ndim:
        raise ValueError(f"{what}: expected a {ndim}-D array, got shape {X.shape}")
    return X


def as_array(X) -> np.ndarray:
    """scikit-learn's input checks (sparse, complex, object dtype, NaN/inf, empty input) without
    the shape's: C-contiguous float64 of any dimension, for a fit to check labels next."""
    return check_array(X, allow_nd=True, dtype=np.float64, order="C", ensure_all_finite=True)


def as_epochs(X) -> np.ndarray:
    """Epochs ``(n_epochs, n_channels, n_times)`` as C-contiguous float64."""
    return _as_float_array(X, 3, "epochs (n_epochs, n_channels, n_times)")


def as_matrices(X) -> np.ndarray:
    """SPD matrices ``(n_matrices, n, n)`` as C-contiguous float64."""
    X = _as_float_array(X, 3, "SPD matrices (n_matrices, n_channels, n_channels)")
    if X.shape[1] != X.shape[2]:
        raise ValueError(f"SPD matrices: expected square matrices, got shape {X.shape}")
    return X


def as_rows(X) -> np.ndarray:
    """Rows ``(n_samples, n_features)`` as C-contiguous float64."""
    return _as_float_array(X, 2, "rows (n_samples, n_features)")


def binary_labels(y, n_samples: int):
    """``(classes_, is_target)``: the sorted two classes and a bool array, True for classes_[1]
    (scikit-learn's positive class). oddball's decoders are target vs non-target."""
    if y is None:
        raise ValueError("this estimator requires y to be passed, but the target y is None")
    y = np.asarray(y)
    if y.ndim != 1:
        y = np.ravel(y) if y.ndim == 2 and y.shape[1] == 1 else y
    if y.ndim != 1 or y.shape[0] != n_samples:
        raise ValueError(f"y: expected {n_samples} labels, got shape {np.shape(y)}")
    check_classification_targets(y)
    y_type = type_of_target(y, input_name="y", raise_unknown=True)
    if y_type != "binary":
        raise ValueError(
            "Only binary classification is supported (oddball's decoders are target vs "
            f"non-target). The type of the target is {y_type}."
        )
    classes = np.unique(y)
    if len(classes) != 2:
        raise ValueError(f"oddball's decoders need both classes; y has 1 class: {classes.tolist()}")
    return classes, np.ascontiguousarray(y == classes[1])


def predict_from_decision(est, X):
    """scikit-learn's binary rule: classes_[1] where ``est.decision_function`` is positive."""
    decision = est.decision_function(X)  # checks that est is fitted first
    return est.classes_[(np.asarray(decision) > 0).astype(int)]


def proba_columns(p_target):
    """``(n, 2)``: P(classes_[0]), P(classes_[1]) from P(target)."""
    p = np.asarray(p_target)
    return np.column_stack([1.0 - p, p])
