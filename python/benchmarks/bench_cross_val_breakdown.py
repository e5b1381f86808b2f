#!/usr/bin/env python
"""Where the time of bench_cross_val.py's oddball pipeline goes, and how many passes the mean needs.

Issue 23 asks for cross_val_score of XdawnCovariances → TangentSpace → LogisticRegression with
oddball's estimators ≥ 20× faster than with pyRiemann's. This splits oddball's time into the
parts that could still shrink and the part both pipelines share (scikit-learn's logistic
regression and cross-validation on the tangent vectors), and counts the passes of the Karcher
mean (one whitening, eigendecomposition and log of every matrix each) needed to reach
pyRiemann's tolerance, for its damped step and plain Karcher steps from two starts. Same data,
folds and thread settings as bench_cross_val.py; prints, asserts nothing.

    python python/benchmarks/bench_cross_val_breakdown.py [--reps 7]
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
# One thread each (set before numpy loads), the tests' pre-processing and the timer: the same
# settings as the benchmark this breaks down.
from bench_cross_val import DATA, epochs_of, median_time, riem  # noqa: E402

import numpy as np  # noqa: E402


def median_ms(fn, reps):
    return 1e3 * median_time(fn, reps)[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=7)
    ap.add_argument("--file", default=str(DATA / "bci2000-samplefiles-p300" / "eeg3_1.dat"))
    args = ap.parse_args()
    warnings.simplefilter("ignore")

    from pyriemann.utils.base import expm, invsqrtm, logm, sqrtm
    from pyriemann.utils.mean import mean_riemann
    from sklearn.base import BaseEstimator, TransformerMixin
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline

    import oddball
    from oddball.estimation import XdawnCovariances
    from oddball.tangentspace import TangentSpace

    raw = oddball.read_raw(args.file)
    X, y = epochs_of(raw)
    X = riem(X, raw.sfreq)
    cv = StratifiedKFold(n_splits=5, shuffle=True, random_state=0)
    full = make_pipeline(XdawnCovariances(nfilter=4, estimator="oas"), TangentSpace(),
                         LogisticRegression(max_iter=1000))
    vectors = full[:-1].fit_transform(X, y)

    class Rows(BaseEstimator, TransformerMixin):
        """Looks up precomputed rows by the epoch index stored in the input."""

        def __init__(self, rows=None):
            self.rows = rows

        def fit(self, X, y=None):
            return self

        def transform(self, X):
            return self.rows[X[:, 0, 0].astype(int)]

    index = np.arange(len(y), dtype=float).reshape(-1, 1, 1)
    t_full = median_ms(lambda: cross_val_score(full, X, y, cv=cv, scoring="roc_auc"), args.reps)
    t_lr = median_ms(lambda: cross_val_score(
        make_pipeline(Rows(vectors), LogisticRegression(max_iter=1000)), index, y, cv=cv,
        scoring="roc_auc"), args.reps)
    t_lr2 = median_ms(lambda: cross_val_score(
        make_pipeline(Rows(vectors[:, :2]), LogisticRegression()), index, y, cv=cv,
        scoring="roc_auc"), args.reps)

    class FirstTwo(BaseEstimator, TransformerMixin):
        def fit(self, X, y=None):
            return self

        def transform(self, X):
            return X.reshape(len(X), -1)[:, :2]

    t_xc = median_ms(lambda: cross_val_score(
        make_pipeline(XdawnCovariances(nfilter=4, estimator="oas"), FirstTwo(),
                      LogisticRegression()), X, y, cv=cv, scoring="roc_auc"), args.reps) - t_lr2
    tr, _ = next(cv.split(X, y))
    covs = XdawnCovariances(nfilter=4, estimator="oas").fit(X[tr], y[tr]).transform(X)
    ts = TangentSpace()
    t_ts_fit = median_ms(lambda: ts.fit(covs[tr]), args.reps)
    t_ts_tr = median_ms(lambda: ts.transform(covs), args.reps)
    print(f"{args.file}: {X.shape}, 5 folds, one thread, median of {args.reps}")
    print(f"oddball cross_val_score                      {t_full:7.1f} ms")
    print(f"  scikit-learn's share (LR + CV on vectors)  {t_lr:7.1f} ms  (the same for pyRiemann)")
    print(f"  XdawnCovariances fit + transform, 5 folds  {t_xc:7.1f} ms")
    print(f"  TangentSpace fit (mean of {len(tr)}) x 5      {5 * t_ts_fit:7.1f} ms")
    print(f"  TangentSpace transform ({len(y)}) x 5        {5 * t_ts_tr:7.1f} ms")

    C = covs[tr]
    converged = mean_riemann(C, tol=1e-14, maxiter=500)
    default = mean_riemann(C)

    def karcher(M, tol):
        for k in range(1, 200):
            m12, mm12 = sqrtm(M), invsqrtm(M)
            J = np.mean(logm(mm12 @ C @ mm12), axis=0)
            M = m12 @ expm(J) @ m12
            if np.linalg.norm(J) <= tol:
                return M, k
        return M, k

    def damped(M, tol=1e-8, maxiter=50):
        """pyRiemann's mean_riemann step by step (its step size nu shrinks), to count passes."""
        nu, tau = 1.0, np.finfo(np.float64).max
        for k in range(1, maxiter + 1):
            m12, mm12 = sqrtm(M), invsqrtm(M)
            J = np.mean(logm(mm12 @ C @ mm12), axis=0)
            M = m12 @ expm(nu * J) @ m12
            crit = np.linalg.norm(J)
            h = nu * crit
            if h < tau:
                nu, tau = 0.95 * nu, h
            else:
                nu *= 0.5
            if crit <= tol or nu <= tol:
                return M, k
        return M, maxiter

    rel = lambda a, b: np.abs(a - b).max() / np.abs(converged).max()  # noqa: E731
    print(f"pyRiemann's mean (tol 1e-8) vs converged (tol 1e-14): {rel(default, converged):.1e}")
    M, k = damped(C.mean(0))
    print(f"pyRiemann's damped iteration, re-run here: {k} passes, {rel(M, default):.1e} from "
          f"pyRiemann's own result")
    for name, start in (("arithmetic", C.mean(0)), ("log-Euclidean", expm(np.mean(logm(C), 0)))):
        for tol in (1e-8, 1e-10):
            M, k = karcher(start, tol)
            print(f"plain Karcher from the {name} mean to |J| <= {tol:.0e}: {k} passes, "
                  f"{rel(M, converged):.1e} from converged")


if __name__ == "__main__":
    main()
