#!/usr/bin/env python
"""BCI Competition II IIb: does any decoder chosen on the training runs alone spell all 6 test characters
(HAM PIE) from 2 repetitions? (issue #18; see README.md). Not a golden-value script: no Rust test reads it.

Every candidate is fitted on the 4 training runs (CAT DOG HAT HAT) only; its training-only score is a
leave-one-run-out CV (4 folds, characters kept whole) — pooled epoch AUC and characters right of 12 at
1..15 repetitions. The selection rule is the highest CV AUC. The test runs only score.

Pre-processing as the peer (../../../../shared/peer/peer_bci2b.py): mean removed, 4th-order 0.5-20 Hz
zero-phase Butterworth per run, epochs from each Flashing 0->1 onset (here 1 s long, cut per candidate).

    /work/.venv-peer/bin/python explore.py [--data DIR] [--out results.json]
"""
import argparse
import json
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import scipy.io as sio  # noqa: E402
from scipy.signal import butter, sosfiltfilt  # noqa: E402
from sklearn.covariance import ledoit_wolf_shrinkage  # noqa: E402
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis  # noqa: E402
from sklearn.metrics import roc_auc_score  # noqa: E402
from sklearn.pipeline import make_pipeline  # noqa: E402
from sklearn.preprocessing import StandardScaler  # noqa: E402
from sklearn.svm import LinearSVC  # noqa: E402

warnings.filterwarnings("ignore")
FS = 240.0
MATRIX = "ABCDEF GHIJKL MNOPQR STUVWX YZ1234 56789_".split()
RUNS = [("AAS010R01", "CAT"), ("AAS010R02", "DOG"), ("AAS011R01", "HAT"), ("AAS011R02", "HAT"),
        ("AAS012R03", "HAM"), ("AAS012R04", "PIE")]
N_TRAIN = 4
# BCI2000's standard 64-channel order (../bci2000-samplefiles-p300/eeg64.loc): Cz = 10, Pz = 50.
NAMES = ("FC5 FC3 FC1 FCz FC2 FC4 FC6 C5 C3 C1 Cz C2 C4 C6 CP5 CP3 CP1 CPz CP2 CP4 CP6 Fp1 Fpz Fp2 AF7 AF3 "
         "AFz AF4 AF8 F7 F5 F3 F1 Fz F2 F4 F6 F8 FT7 FT8 T7 T8 T9 T10 TP7 TP8 P7 P5 P3 P1 Pz P2 P4 P6 P8 PO7 "
         "PO3 POz PO4 PO8 O1 Oz O2 Iz").split()
CH8 = [NAMES.index(n) for n in "Fz Cz Pz Oz P3 P4 PO7 PO8".split()]
CH16 = [NAMES.index(n) for n in "Fz FCz Cz CPz Pz POz Oz C3 C4 P3 P4 P7 P8 PO7 PO8 O1".split()]


def target_codes(ch):
    r = next(i for i, row in enumerate(MATRIX) if ch in row)
    return {MATRIX[r].index(ch) + 1, r + 7}


def load(data):
    sos = butter(4, (0.5, 20.0), btype="bandpass", fs=FS, output="sos")
    runs = []
    for name, word in RUNS:
        m = sio.loadmat(os.path.join(data, name + ".mat"))
        x = m["signal"].astype(float)
        x = sosfiltfilt(sos, x - x.mean(0), axis=0)
        fl, code = m["Flashing"].ravel(), m["StimulusCode"].ravel()
        on = np.flatnonzero((fl[1:] == 1) & (fl[:-1] == 0)) + 1
        if fl[0] == 1:
            on = np.r_[0, on]
        X = x[on[:, None] + np.arange(int(FS))[None, :]].transpose(0, 2, 1)
        c = code[on].astype(int)
        k = np.repeat(np.arange(len(word)), 180)
        y = np.array([int(c[i] in target_codes(word[k[i]])) for i in range(len(c))])
        runs.append((X, y, c, word))
    return runs


def chars(s, c, word):
    """Characters right after 1..15 repetitions: per row and column, the sum of its flashes' scores."""
    out = []
    for r in range(1, 16):
        ok = 0
        for k, ch in enumerate(word):
            sl = slice(k * 180, k * 180 + r * 12)
            tot = np.zeros(13)
            np.add.at(tot, c[sl], s[sl])
            col, row = 1 + int(np.argmax(tot[1:7])), 7 + int(np.argmax(tot[7:13]))
            ok += MATRIX[row - 7][col - 1] == ch
        out.append(ok)
    return out


def bins(X, t1, k, ch=None):
    """Means of k-sample bins over [0, t1) s, channel-major features."""
    X = X[:, ch] if ch is not None else X
    X = X[:, :, : int(round(t1 * FS))]
    nb = X.shape[-1] // k
    return X[..., : nb * k].reshape(X.shape[0], X.shape[1], nb, k).mean(-1).reshape(X.shape[0], -1)


class SLDA:
    """Shrinkage LDA: pooled class-centred covariance, Ledoit-Wolf weight on standardised features."""

    def fit(self, X, y, groups=None):
        m0, m1 = X[y == 0].mean(0), X[y == 1].mean(0)
        R = np.where((y == 1)[:, None], X - m1, X - m0)
        sc = R.std(0)
        sc[sc == 0] = 1
        Z = R / sc
        a = ledoit_wolf_shrinkage(Z, assume_centered=True)
        S = Z.T @ Z / len(Z)
        S = ((1 - a) * S + a * np.trace(S) / len(S) * np.eye(len(S))) * np.outer(sc, sc)
        self.cov = S
        self.w = np.linalg.solve(self.structure(S), m1 - m0)
        self.b = -0.5 * (m0 + m1) @ self.w
        return self

    def structure(self, S):
        return S

    def score(self, X):
        return X @ self.w + self.b


class TLDA(SLDA):
    """Block-Toeplitz shrinkage LDA (Sosulski & Tangermann 2022): the shrunk covariance averaged along
    each channel x channel block diagonal (time lag d), tapered by (T - d) / T."""

    def __init__(self, n_channels):
        self.C = n_channels

    def structure(self, S):
        C, T = self.C, len(S) // self.C
        S4, out = S.reshape(C, T, C, T), np.zeros((C, T, C, T))
        for d in range(T):
            B = np.mean([S4[:, t, :, t + d] for t in range(T - d)], axis=0) * (T - d) / T
            for t in range(T - d):
                out[:, t, :, t + d], out[:, t + d, :, t] = B, B.T
        return out.reshape(len(S), len(S))


class SkLDA:
    """scikit-learn's shrinkage LDA (lsqr, Ledoit-Wolf per class): the peer's and oddball's `lda`."""

    def fit(self, X, y, groups=None):
        self.m = LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto").fit(X, y)
        return self

    def score(self, X):
        return self.m.decision_function(X)


class PerRun:
    """One classifier per training run, scores divided by their training sd and averaged
    (Rakotomamonjy & Guigue's ensemble idea, BCI Competition III II)."""

    def __init__(self, make):
        self.make = make

    def fit(self, X, y, groups):
        self.ms = []
        for g in np.unique(groups):
            m = self.make().fit(X[groups == g], y[groups == g])
            self.ms.append((m, m.score(X[groups == g]).std()))
        return self

    def score(self, X):
        return sum(m.score(X) / sd for m, sd in self.ms) / len(self.ms)


class LinSVM:
    def __init__(self, C):
        self.C = C

    def fit(self, X, y, groups=None):
        self.m = make_pipeline(StandardScaler(), LinearSVC(C=self.C, max_iter=5000)).fit(X, y)
        return self

    def score(self, X):
        return self.m.decision_function(X)


class Xdawn:
    """xDAWN spatial filters (pyRiemann's Xdawn, nfilter per class) then bin means and shrinkage LDA."""

    def __init__(self, nfilter, t1, k):
        self.nf, self.t1, self.k = nfilter, t1, k

    def fit(self, X, y, groups=None):
        from pyriemann.spatialfilters import Xdawn as X_

        self.xd = X_(nfilter=self.nf).fit(X, y)
        self.lda = SLDA().fit(bins(self.xd.transform(X), self.t1, self.k), y)
        return self

    def score(self, X):
        return self.lda.score(bins(self.xd.transform(X), self.t1, self.k))


class Fuse:
    """Standardised sum of members, each (make, features)."""

    def __init__(self, members):
        self.members = members

    def fit(self, X, y, groups):
        self.ms = []
        for make, f in self.members:
            m = make().fit(f(X), y, groups)
            self.ms.append((m, f, m.score(f(X)).std()))
        return self

    def score(self, X):
        return sum(m.score(f(X)) / sd for m, f, sd in self.ms)


def evaluate(runs, make, f):
    """Leave-one-training-run-out CV, then fit on every training run and score the test runs."""
    F = [f(r[0]) for r in runs]
    cv_s, cv_y, cv_c = [], [], np.zeros(15, int)
    for out in range(N_TRAIN):
        tr = [i for i in range(N_TRAIN) if i != out]
        m = make().fit(np.concatenate([F[i] for i in tr]), np.concatenate([runs[i][1] for i in tr]),
                       np.concatenate([np.full(len(runs[i][1]), i) for i in tr]))
        s = m.score(F[out])
        cv_s.append(s)
        cv_y.append(runs[out][1])
        cv_c += chars(s, runs[out][2], runs[out][3])
    tr = range(N_TRAIN)
    m = make().fit(np.concatenate([F[i] for i in tr]), np.concatenate([runs[i][1] for i in tr]),
                   np.concatenate([np.full(len(runs[i][1]), i) for i in tr]))
    te = range(N_TRAIN, len(runs))
    ts = [m.score(F[i]) for i in te]
    tc = np.sum([chars(s, runs[i][2], runs[i][3]) for s, i in zip(ts, te)], axis=0)
    return {
        "cv_auc": roc_auc_score(np.concatenate(cv_y), np.concatenate(cv_s)),
        "cv_chars_by_reps": cv_c.tolist(),
        "test_auc": roc_auc_score(np.concatenate([runs[i][1] for i in te]), np.concatenate(ts)),
        "test_chars_by_reps": [int(v) for v in tc],
    }


def candidates():
    out = [("sklearn LDA 0-0.8 s, 10-sample bins (oddball lda / peer)", SkLDA, lambda X: bins(X, 0.8, 10))]
    for t1 in (0.6, 0.7, 0.8, 0.9, 1.0):
        for k in (6, 10, 12, 16, 20, 24):
            out.append((f"shrinkage LDA 0-{t1} s, {k}-sample bins", SLDA, lambda X, t1=t1, k=k: bins(X, t1, k)))
    for t1, k in ((0.8, 10), (0.8, 6), (0.8, 4), (0.7, 6), (1.0, 6)):
        out.append((f"block-Toeplitz LDA 0-{t1} s, {k}-sample bins", lambda: TLDA(64),
                    lambda X, t1=t1, k=k: bins(X, t1, k)))
    for name, ch in (("8", CH8), ("16", CH16)):
        for t1, k in ((0.8, 10), (0.7, 20), (0.8, 6)):
            out.append((f"shrinkage LDA {name} channels 0-{t1} s, {k}-sample bins", SLDA,
                        lambda X, ch=ch, t1=t1, k=k: bins(X, t1, k, ch)))
    for t1, k in ((0.8, 10), (0.7, 20), (0.6, 20)):
        out.append((f"per-run ensemble of shrinkage LDAs 0-{t1} s, {k}-sample bins", lambda: PerRun(SLDA),
                    lambda X, t1=t1, k=k: bins(X, t1, k)))
    for C in (0.0003, 0.003, 0.03):
        out.append((f"per-run ensemble of linear SVMs C={C} 0-0.8 s, 10-sample bins",
                    lambda C=C: PerRun(lambda: LinSVM(C)), lambda X: bins(X, 0.8, 10)))
    for nf in (4, 8, 16):
        for t1, k in ((0.8, 10), (0.7, 20), (0.8, 6)):
            out.append((f"xDAWN {nf} filters + shrinkage LDA 0-{t1} s, {k}-sample bins",
                        lambda nf=nf, t1=t1, k=k: Xdawn(nf, t1, k), lambda X: X[:, :, :240]))
    out.append(("per-run LDA ensemble (0-0.7 s, 20) + xDAWN 4 + LDA (0-0.7 s, 20), standardised sum",
                lambda: Fuse([(lambda: PerRun(SLDA), lambda X: bins(X, 0.7, 20)),
                              (lambda: Xdawn(4, 0.7, 20), lambda X: X)]),
                lambda X: X[:, :, :240]))
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    a = argparse.ArgumentParser()
    a.add_argument("--data", default=os.path.join(here, "../../../../shared/data/bci-competition-ii-iib"))
    a.add_argument("--out", default=os.path.join(here, "results.json"))
    o = a.parse_args()
    runs = load(o.data)
    res = {}
    print(f"{'candidate':86s} cvAUC  cv chars/12 @1 2 3 5 15 | test AUC  chars/6 @1 2 3 5 15")
    for name, make, f in candidates():
        r = res[name] = evaluate(runs, make, f)
        pick = lambda v: " ".join(f"{v[i]:2d}" for i in (0, 1, 2, 4, 14))  # noqa: E731
        print(f"{name:86s} {r['cv_auc']:.3f}  {pick(r['cv_chars_by_reps'])} | {r['test_auc']:.3f}  "
              f"{pick(r['test_chars_by_reps'])}", flush=True)
    best = max(res, key=lambda n: res[n]["cv_auc"])
    print(f"chosen by training CV AUC: {best}: test AUC {res[best]['test_auc']:.3f}, "
          f"characters at 2 repetitions {res[best]['test_chars_by_reps'][1]}/6")
    six = [n for n in res if res[n]["test_chars_by_reps"][1] == 6]
    print(f"{len(six)} of {len(res)} candidates spell 6/6 at 2 repetitions on the test runs")
    json.dump({"chosen": best, "results": res}, open(o.out, "w"), indent=1)


if __name__ == "__main__":
    main()
