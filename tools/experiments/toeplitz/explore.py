#!/usr/bin/env python
"""Pre-registered block-Toeplitz LDA experiment (see README.md). Reuses ../fusion/explore.py's folds,
nested CV and report; adds the member TLDA and the designs TLDA, zT2, zT3, stackT3. Deterministic, 1 thread."""
import contextlib
import io
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fusion"))
import explore as fx  # noqa: E402  (sets the thread limits, data paths and the peer's pipelines)
import numpy as np  # noqa: E402
from sklearn.linear_model import LogisticRegression  # noqa: E402
from sklearn.preprocessing import StandardScaler  # noqa: E402
from toeplitzlda.classification import ToeplitzLDA  # noqa: E402


class TLDA:
    """toeplitzlda's ToeplitzLDA; its fit returns None and its decision_function calls an sklearn API
    that sklearn 1.9 removed, so the score is computed from coef_/intercept_ exactly as it would."""

    def __init__(self, n_channels):
        self.n_channels = n_channels

    def fit(self, X, y):
        self.m = ToeplitzLDA(n_channels=self.n_channels)
        with contextlib.redirect_stdout(io.StringIO()):  # its "forcing gamma" prints
            self.m.fit(X, y)
        return self

    def score(self, X):
        s = X @ self.m.coef_.T + self.m.intercept_
        return s[:, 1] - s[:, 0]


OLD = ["LDA-shrink", "XdawnCov+TS+LR", "XdawnCov+MDM"]
fx.MEMBERS = OLD + ["TLDA"]
fx.DESIGNS = fx.DESIGNS + ["TLDA", "zT2", "zT3", "stackT3"]
_N_CH = {}


def feats(fe, X):
    _N_CH["n"] = X.shape[1]
    vt = fx.pe.bin_mean(X, fe.k_vec).transpose(0, 2, 1).reshape(len(X), -1)  # time-major
    return {"vec": fe.vec(X), "riem": fe.riem(X), "vecT": np.ascontiguousarray(vt)}


def stack(oof, S, ytr):
    sc = StandardScaler().fit(oof)
    lr = LogisticRegression().fit(sc.transform(oof), ytr)
    return lr.decision_function(sc.transform(S)), lr.coef_[0].tolist()


def fit_designs(F, y, tr, te, groups):
    fx.PIPES["TLDA"] = ("vecT", lambda: TLDA(_N_CH["n"]))
    ytr = y[tr]
    sd, S = fx.member_scores(F, y, tr, te)
    Z = S / sd
    out = {"LDA": S[:, 0], "TSLR": S[:, 1], "MDM": S[:, 2], "TLDA": S[:, 3],
           "z2": Z[:, 0] + Z[:, 1], "z3": Z[:, :3].sum(1), "z2rm": Z[:, 1] + Z[:, 2],
           "zT2": Z[:, 3] + Z[:, 1], "zT3": Z[:, 1:].sum(1)}
    g = None if groups is None else groups[tr]
    oof = np.zeros((len(tr), 4))
    for itr, ite in fx.folds(ytr, g):
        _, oof[ite] = fx.member_scores(F, y, tr[itr], tr[ite])
    out["stack3"], c3 = stack(oof[:, :3], S[:, :3], ytr)
    out["stackT3"], cT3 = stack(oof[:, 1:], S[:, 1:], ytr)
    w = np.clip([fx.dprime(oof[:, k], ytr) for k in range(3)], 0, None)
    out["cvw3"] = Z[:, :3] @ w
    return out, {"stack_coef": c3, "stackT3_coef [TSLR,MDM,TLDA]": cT3, "cvw_dprime": w.tolist(),
                 "train_sd": sd.tolist()}


fx.feats = feats
fx.fit_designs = fit_designs

if __name__ == "__main__":
    os.environ.setdefault("FUSION_OUT", os.environ.get("TOEPLITZ_OUT", "toeplitz_results.json"))
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1):
        fx.main()
