#!/usr/bin/env python
"""Speed of oddball's estimators against pyRiemann's, one thread each, on eeg3_1.dat.

The Done-when measure of issue 23: cross_val_score (5 stratified folds, ROC AUC) of
XdawnCovariances(4, "oas") → TangentSpace("riemann") → LogisticRegression on peer_eval.py's
`riem` epochs, with pyRiemann's estimators and with oddball's (only the imports differ), then
each stage alone. Prints median wall times of --reps runs and the ratios; asserts nothing.

    python python/benchmarks/bench_cross_val.py [--reps 5]
"""
from __future__ import annotations

import os

# One thread each: BLAS/OpenMP for numpy/scipy/pyRiemann, rayon for oddball. Set before imports.
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"):
    os.environ[var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
from conftest import DATA, epochs_of, riem  # noqa: E402  (the tests' pre-processing)


def median_time(fn, reps):
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--file", default=str(DATA / "bci2000-samplefiles-p300" / "eeg3_1.dat"))
    args = ap.parse_args()

    import pyriemann
    import pyriemann.estimation
    import pyriemann.tangentspace
    import sklearn
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline

    import oddball
    import oddball.estimation
    import oddball.tangentspace

    raw = oddball.read_raw(args.file)
    X, y = epochs_of(raw)
    X = riem(X, raw.sfreq)
    print(f"{args.file}: {X.shape[0]} epochs x {X.shape[1]} channels x {X.shape[2]} samples, "
          f"{y.sum()} targets; numpy {np.__version__}, scikit-learn {sklearn.__version__}, "
          f"pyRiemann {pyriemann.__version__}, oddball {oddball.__version__}; one thread each, "
          f"median of {args.reps}")

    def pipeline(est, ts):
        return make_pipeline(est.XdawnCovariances(nfilter=4, estimator="oas"),
                             ts.TangentSpace(metric="riemann"), LogisticRegression(max_iter=1000))

    cv = StratifiedKFold(n_splits=5, shuffle=True, random_state=0)
    rows = []
    for name, est, ts in (("pyRiemann", pyriemann.estimation, pyriemann.tangentspace),
                          ("oddball", oddball.estimation, oddball.tangentspace)):
        t, scores = median_time(lambda: cross_val_score(pipeline(est, ts), X, y, cv=cv, scoring="roc_auc"),
                                args.reps)
        xc = est.XdawnCovariances(nfilter=4, estimator="oas")
        t_xc_fit, _ = median_time(lambda: xc.fit(X, y), args.reps)
        t_xc_tr, covs = median_time(lambda: xc.transform(X), args.reps)
        tsp = ts.TangentSpace(metric="riemann")
        t_ts_fit, _ = median_time(lambda: tsp.fit(covs), args.reps)
        t_ts_tr, _ = median_time(lambda: tsp.transform(covs), args.reps)
        rows.append((name, t, scores, t_xc_fit, t_xc_tr, t_ts_fit, t_ts_tr))

    print(f"{'':10} {'cross_val_score':>16} {'mean AUC':>9} {'XC fit':>9} {'XC transform':>13} "
          f"{'TS fit':>9} {'TS transform':>13}")
    for name, t, scores, a, b, c, d in rows:
        print(f"{name:10} {t * 1e3:13.1f} ms {scores.mean():9.6f} {a * 1e3:6.1f} ms {b * 1e3:10.1f} ms "
              f"{c * 1e3:6.1f} ms {d * 1e3:10.1f} ms")
    (_, t0, s0, *r0), (_, t1, s1, *r1) = rows
    print(f"{'ratio':10} {t0 / t1:13.1f} x {'':9} " + " ".join(
        f"{a / b:{w}.1f} x" for a, b, w in zip(r0, r1, (6, 10, 6, 10))))
    print(f"max |AUC difference| over the folds: {np.max(np.abs(s0 - s1)):.1e}")
    # The LogisticRegression on the tangent vectors is scikit-learn's in both pipelines.
    lr = LogisticRegression(max_iter=1000)
    F = pipeline(oddball.estimation, oddball.tangentspace)[:-1].fit_transform(X, y)
    t_lr, _ = median_time(lambda: lr.fit(F, y), args.reps)
    print(f"(scikit-learn's LogisticRegression fit on all {len(y)} tangent vectors, common to both: "
          f"{t_lr * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
