"""Reference values for oddball-decode's linear and Riemannian decoders (lda, logistic, covariance,
xdawn, riemann) from scikit-learn and pyRiemann (see requirements.txt for the pinned versions).

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/decode_linear/requirements.txt
    /tmp/golden/bin/python tools/golden/decode_linear/make_golden.py
Writes crates/oddball-decode/tests/fixtures/linear_riemann_golden.json (read by
crates/oddball-decode/tests/linear_riemann_golden.rs).

The data set is synthetic and P300-like: 60 epochs x 6 channels x 32 samples in uV, every fifth epoch
(index % 5 == 2) a target carrying a positive Gaussian bump on channels 2..5; spatially correlated,
temporally smoothed noise from a seeded generator. Epochs 0..40 train, 40..60 test. The epochs are
rounded to 3 decimals before anything is computed from them, so the fixture holds the exact input.
"""
import json
import pathlib
import warnings

import numpy as np
import pyriemann
import scipy
import sklearn
from pyriemann.classification import MDM
from pyriemann.estimation import XdawnCovariances
from pyriemann.geometry.covariance import covariance_scm, covariances
from pyriemann.geometry.mean import mean_riemann
from pyriemann.spatialfilters import Xdawn
from pyriemann.tangentspace import TangentSpace
from sklearn.covariance import ledoit_wolf, oas
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.linear_model import LogisticRegression

OUT = (
    pathlib.Path(__file__).resolve().parents[3]
    / "crates/oddball-decode/tests/fixtures/linear_riemann_golden.json"
)

rng = np.random.default_rng(20261123)
n_epochs, n_channels, n_times, fs = 60, 6, 32, 64.0
n_train = 40
y = np.array([i % 5 == 2 for i in range(n_epochs)])

t = np.arange(n_times) / fs
mixing = np.eye(n_channels) + 0.4 * rng.normal(size=(n_channels, n_channels))
bump = np.exp(-0.5 * ((t - 0.3) / 0.06) ** 2)  # P300-like peak at 300 ms
topography = np.array([0.0, 0.5, 1.0, 1.5, 1.2, 0.8])
kernel = np.array([0.25, 0.5, 1.0, 0.5, 0.25])
X = np.empty((n_epochs, n_channels, n_times))
for e in range(n_epochs):
    white = rng.normal(0.0, 4.0, size=(n_channels, n_times + len(kernel) - 1))
    smooth = np.stack([np.convolve(w, kernel, mode="valid") for w in white])
    X[e] = mixing @ smooth + rng.normal(0.0, 1.0, size=(n_channels, 1))  # per-epoch offsets
    if y[e]:
        X[e] += 6.0 * topography[:, None] * bump[None, :]
X = np.round(X, 3)

Xtr, ytr, Xte = X[:n_train], y[:n_train], X[n_train:]


def arr(a):
    return np.asarray(a, dtype=float).tolist()


def features(epochs):
    """Mean of 4-sample bins per channel, flattened channel-major: (n_epochs, 6 * 8)."""
    n = epochs.shape[0]
    return epochs.reshape(n, n_channels, n_times // 4, 4).mean(axis=-1).reshape(n, -1)


out = {
    "versions": {
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "scikit-learn": sklearn.__version__,
        "pyriemann": pyriemann.__version__,
    },
    "n_train": n_train,
    "epochs": arr(X),
    "y": [bool(v) for v in y],
}

# --- covariance estimators on single epochs (n_channels, n_times) ---------------------------------
cov = {"epochs": [0, 2, 7], "scm": [], "lwf": [], "lwf_shrinkage": [], "oas": [], "oas_shrinkage": []}
for e in cov["epochs"]:
    cov["scm"].append(arr(covariance_scm(X[e])))
    c, s = ledoit_wolf(X[e].T)
    cov["lwf"].append(arr(c))
    cov["lwf_shrinkage"].append(float(s))
    c, s = oas(X[e].T)
    cov["oas"].append(arr(c))
    cov["oas_shrinkage"].append(float(s))
    # pyriemann's batch estimators apply sklearn's per epoch on the transposed epoch
    for est, key in (("oas", "oas"), ("lwf", "lwf"), ("scm", "scm")):
        batch = covariances(X[e : e + 1], estimator=est)[0]
        assert np.allclose(batch, np.array(cov[key][-1]), rtol=0, atol=1e-12), est
out["covariance"] = cov

# --- shrinkage LDA and logistic regression on binned amplitudes -----------------------------------
Ftr, Fte = features(Xtr), features(Xte)
lda = {}
for name, shrinkage in (("auto", "auto"), ("fixed_0.3", 0.3)):
    clf = LinearDiscriminantAnalysis(solver="lsqr", shrinkage=shrinkage).fit(Ftr, ytr)
    lda[name] = {
        "coef": arr(clf.coef_[0]),
        "intercept": float(clf.intercept_[0]),
        "decision": arr(clf.decision_function(Fte)),
        "proba": arr(clf.predict_proba(Fte)[:, 1]),
    }
out["lda"] = lda


def logistic(Ftrain, Ftest):
    clf = LogisticRegression(C=1.0, tol=1e-10, max_iter=10000).fit(Ftrain, ytr)
    # lbfgs stops on its ftol (64 eps) before gtol=1e-10, a few 1e-7 short of the optimum; sklearn's
    # second-order newton-cholesky solver reaches the same optimum to ~1e-12 and is the reference
    nc = LogisticRegression(C=1.0, solver="newton-cholesky", tol=1e-12, max_iter=1000).fit(Ftrain, ytr)
    gap = np.max(np.abs(clf.coef_ - nc.coef_)) / np.max(np.abs(nc.coef_))
    print(f"logistic: lbfgs vs newton-cholesky relative gap {gap:.2e}")
    assert gap < 1e-5, gap
    return {
        "coef": arr(nc.coef_[0]),
        "intercept": float(nc.intercept_[0]),
        "lbfgs_coef": arr(clf.coef_[0]),
        "lbfgs_intercept": float(clf.intercept_[0]),
        "proba": arr(nc.predict_proba(Ftest)[:, 1]),
        "decision": arr(nc.decision_function(Ftest)),
    }


out["logistic"] = logistic(Ftr, Fte)

# --- xDAWN ------------------------------------------------------------------------------------------
xd = Xdawn(nfilter=2).fit(Xtr, ytr)
out["xdawn"] = {
    "nfilter": 2,
    "classes": [bool(c) for c in xd.classes_],
    "filters": arr(xd.filters_),
    "patterns": arr(xd.patterns_),
    "evokeds": arr(xd.evokeds_),
}

xc = XdawnCovariances(nfilter=2, estimator="oas").fit(Xtr, ytr)
covs = xc.transform(X)
out["xdawn_covariances"] = {"nfilter": 2, "estimator": "oas", "covs": arr(covs)}

xc4 = XdawnCovariances(nfilter=4, estimator="oas").fit(Xtr, ytr)
out["xdawn_covariances_4"] = {
    "nfilter": 4,
    "estimator": "oas",
    "epochs": [40, 41, 42],
    "filters": arr(xc4.Xd_.filters_),
    "covs": arr(xc4.transform(X[40:43])),
}

# --- Riemannian geometry on the (pyRiemann) xDAWN covariances ---------------------------------------
Ctr, Cte = covs[:n_train], covs[n_train:]
with warnings.catch_warnings():
    warnings.simplefilter("error")  # a "Convergence not reached" warning would make the reference loose
    M = mean_riemann(Ctr)
out["mean_riemann"] = arr(M)

ts = TangentSpace(metric="riemann").fit(Ctr)
assert np.allclose(ts.reference_, M, rtol=0, atol=1e-13)
Ttr, Tte = ts.transform(Ctr), ts.transform(Cte)
out["tangent_space"] = {"vectors_test": arr(Tte)}

mdm = MDM(metric="riemann").fit(Ctr, ytr)
dist = mdm.transform(Cte)  # columns in classes_ order: [False, True]
out["mdm"] = {
    "classes": [bool(c) for c in mdm.classes_],
    "means": arr(mdm.covmeans_),
    "distances": arr(dist),
    "scores": arr(dist[:, 0] ** 2 - dist[:, 1] ** 2),
    "proba": arr(mdm.predict_proba(Cte)[:, 1]),
}

out["logistic_tangent"] = logistic(Ttr, Tte)

OUT.parent.mkdir(parents=True, exist_ok=True)
OUT.write_text(json.dumps(out, separators=(",", ":")))
print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
