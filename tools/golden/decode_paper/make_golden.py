"""Reference values for oddball-decode's paper features and classifiers (pinned in requirements.txt).

Independent implementations: PyEMD (EMD-signal) for the first IMF, scipy.signal.hilbert for the analytic
signal, PyWavelets for the bior2.2 DWT, scikit-learn for StandardScaler, PCA, SVC, the sigmoid (Platt)
calibration, CalibratedClassifierCV, KNeighborsClassifier and the soft VotingClassifier. The `paper`
feature map is copied from the peer evaluation (shared/peer/peer_eval.py, `Features.paper`).

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/decode_paper/requirements.txt
    /tmp/golden/bin/python tools/golden/decode_paper/make_golden.py
Writes crates/oddball-decode/tests/fixtures/paper_golden.json.

Inputs are rounded to a few decimals before anything is computed from them, so the short decimal literals in
the fixture parse to exactly the doubles Python used.
"""
import json
import pathlib
import warnings
from importlib.metadata import version

import numpy as np
import pywt
from PyEMD import EMD
from scipy.signal import butter, hilbert, sosfiltfilt
from sklearn.calibration import CalibratedClassifierCV, _sigmoid_calibration
from sklearn.decomposition import PCA
from sklearn.ensemble import VotingClassifier
from sklearn.model_selection import StratifiedKFold
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

OUT = pathlib.Path(__file__).resolve().parents[3] / "crates/oddball-decode/tests/fixtures/paper_golden.json"
FS = 256.0
N_T = 205  # 0.8 s at 256 Hz, as the speller epochs
rng = np.random.default_rng(20260311)


def arr(a):
    return np.asarray(a, dtype=float).tolist()


def eeg_like(n, fs, seed_shift=0.0):
    """Band-passed (0.5-20 Hz) noise plus a P300-like bump: what a pre-processed EEG epoch looks like."""
    sos = butter(4, (0.5, 20.0), btype="bandpass", fs=fs, output="sos")
    x = sosfiltfilt(sos, rng.normal(0.0, 10.0, 4 * n))[n: 2 * n]
    t = np.arange(n) / fs
    return x + 6.0 * np.exp(-0.5 * ((t - 0.3 - seed_shift) / 0.05) ** 2)


# ------------------------------------------------------------------ EMD: first IMF (PyEMD defaults)
class CountingEMD(EMD):
    """PyEMD's EMD with a counter of envelope constructions (= sifting iterations of the first IMF)."""

    def __init__(self):
        super().__init__()
        self.n_sift = 0

    def extract_max_min_spline(self, T, S):
        self.n_sift += 1
        return super().extract_max_min_spline(T, S)


t205 = np.arange(N_T) / FS
emd_signals = {
    "sines_3_10_17hz": 20 * np.sin(2 * np.pi * 3 * t205) + 8 * np.sin(2 * np.pi * 10 * t205 + 0.4)
    + 3 * np.sin(2 * np.pi * 17 * t205 + 1.1),
    "eeg_like_a": eeg_like(N_T, FS),
    "eeg_like_b": eeg_like(N_T, FS, 0.1),
    "eeg_like_c": eeg_like(N_T, FS, -0.1),
    "noisy_chirp": 10 * np.sin(2 * np.pi * (2 + 20 * t205) * t205) + rng.normal(0, 2, N_T),
    "white_noise": rng.normal(0, 5, N_T),
    "eeg_like_410_at_512hz": eeg_like(410, 512.0),
    "few_extrema": 5 * np.sin(2 * np.pi * 1.7 * t205) + 0.5 * t205,
}
emd_out = []
for name, s in emd_signals.items():
    s = np.round(s, 6)
    e = CountingEMD()
    imfs = e.emd(s, max_imf=1)
    emd_out.append({"name": name, "signal": arr(s), "imf1": arr(imfs[0]), "n_sift": e.n_sift,
                    "n_rows": int(imfs.shape[0])})

# ------------------------------------------------------------------ Hilbert (scipy) + peer's inst. frequency
def inst_amp_freq(x, fs):
    z = hilbert(x)
    ph = np.unwrap(np.angle(z))
    f = np.diff(ph) * fs / (2 * np.pi)
    return z, np.abs(z), np.concatenate([f, f[-1:]])


hil_out = []
for name, x in {
    "eeg_like_205": np.round(eeg_like(N_T, FS), 6),
    "am_fm_256": np.round((1 + 0.5 * np.sin(2 * np.pi * 1.5 * np.arange(256) / FS))
                          * np.sin(2 * np.pi * (8 * np.arange(256) / FS + 0.3 * np.sin(2 * np.pi * np.arange(256) / FS))),
                          6),
    "imf1_sines": np.asarray(emd_out[0]["imf1"]),
}.items():
    z, a, f = inst_amp_freq(x, FS)
    entry = {"name": name, "x": arr(x), "amp": arr(a), "freq": arr(f)}
    if not hil_out:  # the analytic signal itself once; amplitude and frequency for all
        entry.update({"re": arr(z.real), "im": arr(z.imag)})
    hil_out.append(entry)

# ------------------------------------------------------------------ DWT: pywt.wavedec(bior2.2, symmetric)
dwt_out = []
for n, level in ((205, 5), (128, 4), (160, 4), (64, 3), (33, 2)):
    x = np.round(rng.normal(0, 10, n).cumsum() * 0.3 + rng.normal(0, 3, n), 6)
    coeffs = pywt.wavedec(x, "bior2.2", level=level, mode="symmetric")
    dwt_out.append({"x": arr(x), "level": level, "coeffs": [arr(c) for c in coeffs]})

# ------------------------------------------------------------------ StandardScaler
Xs = np.round(rng.normal(0, 1, (30, 5)) * [1.0, 50.0, 0.01, 1.0, 3.0] + [0.0, 1000.0, -5.0, 0.0, 2.0], 6)
Xs[:, 3] = 7.25  # constant feature -> scale 1
sc = StandardScaler().fit(Xs)
Xs_test = np.round(rng.normal(0, 1, (6, 5)) * 2, 6)
scaler_out = {"x": arr(Xs), "mean": arr(sc.mean_), "scale": arr(sc.scale_), "var": arr(sc.var_),
              "x_test": arr(Xs_test), "transform": arr(sc.transform(Xs_test))}

# ------------------------------------------------------------------ PCA (svd_solver='full')
mix = rng.normal(0, 1, (12, 12)) * np.exp(-0.4 * np.arange(12))[:, None]
Xp = np.round(rng.normal(0, 1, (50, 12)) @ mix + rng.normal(0, 0.05, (50, 12)) + 3.0, 6)
Xp_test = np.round(rng.normal(0, 1, (7, 12)) @ mix + 3.0, 6)
pca_out = {"x": arr(Xp), "x_test": arr(Xp_test), "cases": []}
for nc in (0.95, 0.5, 3):
    p = PCA(n_components=nc, svd_solver="full").fit(Xp)
    pca_out["cases"].append({"n_components": nc, "n_components_": int(p.n_components_), "mean": arr(p.mean_),
                             "components": arr(p.components_), "explained_variance": arr(p.explained_variance_),
                             "explained_variance_ratio": arr(p.explained_variance_ratio_),
                             "singular_values": arr(p.singular_values_), "transform": arr(p.transform(Xp_test))})
# wide case (n_samples < n_features), as the paper features are
Xw = np.round(rng.normal(0, 1, (15, 40)) @ rng.normal(0, 1, (40, 40)), 6)
pw = PCA(n_components=0.95, svd_solver="full").fit(Xw)
pca_out["wide"] = {"x": arr(Xw), "n_components_": int(pw.n_components_), "components": arr(pw.components_),
                   "explained_variance": arr(pw.explained_variance_), "transform": arr(pw.transform(Xw))}

# ------------------------------------------------------------------ SVM / kNN / calibration / vote
def two_class(n_pos, n_neg, d, shift):
    X = np.vstack([rng.normal(0, 1, (n_pos, d)) + shift, rng.normal(0, 1, (n_neg, d))])
    y = np.r_[np.ones(n_pos, int), np.zeros(n_neg, int)]
    perm = rng.permutation(len(y))
    return np.round(X[perm], 6), y[perm]


Xtr, ytr = two_class(30, 70, 4, 0.9)
Xte, yte = two_class(15, 25, 4, 0.9)
clf_out = {"x_train": arr(Xtr), "y_train": ytr.tolist(), "x_test": arr(Xte)}
for kernel in ("rbf", "linear"):
    m = SVC(kernel=kernel, C=1.0, gamma="scale").fit(Xtr, ytr)
    clf_out[f"svm_{kernel}"] = {
        "decision_test": arr(m.decision_function(Xte)), "decision_train": arr(m.decision_function(Xtr)),
        "n_support": int(m.n_support_.sum()), "support": m.support_.tolist(), "intercept": float(m.intercept_[0]),
        "gamma": float(m._gamma)}
# Platt sigmoid on given decision values (sklearn's _sigmoid_calibration): P = 1 / (1 + exp(a f + b))
dec = np.asarray(clf_out["svm_rbf"]["decision_train"])
a, b = _sigmoid_calibration(dec, ytr)
clf_out["sigmoid_train_decisions"] = {"a": float(a), "b": float(b)}
big = dec * 40.0  # exercises sklearn's rescaling of |f| >= 30
a2, b2 = _sigmoid_calibration(big, ytr)
clf_out["sigmoid_scaled_decisions"] = {"f": arr(big), "a": float(a2), "b": float(b2)}
# CalibratedClassifierCV with an unshuffled StratifiedKFold (deterministic folds; the peer shuffles with seed 0)
cv = StratifiedKFold(5)
clf_out["stratified_folds"] = np.concatenate(
    [np.full(len(te), i) for i, (_, te) in enumerate(cv.split(Xtr, ytr))])[
    np.argsort(np.concatenate([te for _, te in cv.split(Xtr, ytr)]))].tolist()
cal = CalibratedClassifierCV(SVC(kernel="rbf", C=1.0, gamma="scale"), method="sigmoid", cv=cv, ensemble=False)
cal.fit(Xtr, ytr)
clf_out["calibrated_svm_proba_test"] = arr(cal.predict_proba(Xte)[:, 1])
knn = KNeighborsClassifier(n_neighbors=3).fit(Xtr, ytr)
clf_out["knn3_proba_test"] = arr(knn.predict_proba(Xte)[:, 1])
knn5 = KNeighborsClassifier(n_neighbors=5).fit(Xtr, ytr)
clf_out["knn5_proba_test"] = arr(knn5.predict_proba(Xte)[:, 1])
vote = VotingClassifier([("svm", CalibratedClassifierCV(SVC(kernel="rbf", C=1.0, gamma="scale"), method="sigmoid",
                                                        cv=StratifiedKFold(5), ensemble=False)),
                         ("knn", KNeighborsClassifier(n_neighbors=3))], voting="soft").fit(Xtr, ytr)
clf_out["vote_proba_test"] = arr(vote.predict_proba(Xte)[:, 1])
# The peer's folds: StratifiedKFold(5, shuffle=True, random_state=seed) (numpy's legacy MT19937 stream)
def fold_of_each(cv, X, y):
    tests = [te for _, te in cv.split(X, y)]
    return np.concatenate([np.full(len(te), i) for i, te in enumerate(tests)])[
        np.argsort(np.concatenate(tests))].tolist()
rng = np.random.RandomState(7)
y_mixed = (rng.rand(53) < 0.3).astype(int)  # targets first seen second, odd sizes
clf_out["shuffled_folds"] = [
    {"y": yy.tolist(), "n_splits": k, "seed": seed,
     "folds": fold_of_each(StratifiedKFold(k, shuffle=True, random_state=seed), np.zeros((len(yy), 1)), yy)}
    for yy, k, seed in [(ytr, 5, 0), (ytr, 5, 1), (ytr, 3, 42), (y_mixed, 5, 0), (y_mixed, 4, 4294967295)]]
cv0 = StratifiedKFold(5, shuffle=True, random_state=0)
cal0 = CalibratedClassifierCV(SVC(kernel="rbf", C=1.0, gamma="scale"), method="sigmoid", cv=cv0, ensemble=False)
clf_out["calibrated_svm_shuffled_proba_test"] = arr(cal0.fit(Xtr, ytr).predict_proba(Xte)[:, 1])
vote0 = VotingClassifier([("svm", CalibratedClassifierCV(SVC(kernel="rbf", C=1.0, gamma="scale"), method="sigmoid",
                                                         cv=cv0, ensemble=False)),
                          ("knn", KNeighborsClassifier(n_neighbors=3))], voting="soft").fit(Xtr, ytr)
clf_out["vote_shuffled_proba_test"] = arr(vote0.predict_proba(Xte)[:, 1])

# ------------------------------------------------------------------ the peer's `paper` features, end to end
def bin_mean(X, k):
    nb = X.shape[-1] // k
    return X[..., : nb * k].reshape(*X.shape[:-1], nb, k).mean(-1)


def paper_features(X, fs):
    """Copied from shared/peer/peer_eval.py Features.paper (EMD-signal, scipy hilbert, pywt)."""
    k_vec = max(1, int(round(fs / 25.0)))
    wlevel = int(round(np.log2(fs / 8.0)))
    emd = EMD()
    n, nch, nt = X.shape
    amp = bin_mean(X, k_vec)
    ia = np.empty_like(X)
    ifr = np.empty_like(X)
    for i in range(n):
        for c in range(nch):
            imf1 = emd.emd(X[i, c], max_imf=1)[0]
            z = hilbert(imf1)
            ia[i, c] = np.abs(z)
            ph = np.unwrap(np.angle(z))
            f = np.diff(ph) * fs / (2 * np.pi)
            ifr[i, c, :-1] = f
            ifr[i, c, -1] = f[-1]
    coeffs = pywt.wavedec(X, "bior2.2", level=wlevel, axis=-1, mode="symmetric")
    a, d = coeffs[0], coeffs[1]
    parts = [amp, bin_mean(ia, k_vec), bin_mean(ifr, k_vec), a, d]
    return np.concatenate([p.reshape(n, -1) for p in parts], axis=1)


n_ep, n_ch = 22, 2
ep_y = np.r_[np.ones(7, int), np.zeros(15, int)][rng.permutation(n_ep)]
epochs = np.empty((n_ep, n_ch, N_T))
for i in range(n_ep):
    for c in range(n_ch):
        base = eeg_like(N_T, FS, 0.0) if ep_y[i] else eeg_like(N_T, FS, 0.0) - 6.0 * np.exp(
            -0.5 * ((t205 - 0.3) / 0.05) ** 2)
        epochs[i, c] = base
epochs = np.round(epochs, 3)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    F = paper_features(epochs, FS)
tr, te = np.arange(15), np.arange(15, n_ep)
pipe = make_pipeline(StandardScaler(), PCA(n_components=0.95, svd_solver="full"),
                     SVC(kernel="rbf", C=1.0, gamma="scale")).fit(F[tr], ep_y[tr])
pipe_knn = make_pipeline(StandardScaler(), PCA(n_components=0.95, svd_solver="full"),
                         KNeighborsClassifier(3)).fit(F[tr], ep_y[tr])
paper_out = {"fs": FS, "epochs": arr(epochs), "y": ep_y.tolist(), "features": arr(F), "n_train": len(tr),
             "pca_n_components": int(pipe.named_steps["pca"].n_components_),
             "svm_decision_test": arr(pipe.decision_function(F[te])),
             "knn3_proba_test": arr(pipe_knn.predict_proba(F[te])[:, 1])}

out = {
    "versions": {d: version(d) for d in ("numpy", "scipy", "scikit-learn", "PyWavelets", "EMD-signal")},
    "emd": emd_out,
    "hilbert": {"fs": FS, "signals": hil_out},
    "dwt": dwt_out,
    "scaler": scaler_out,
    "pca": pca_out,
    "classifiers": clf_out,
    "paper": paper_out,
}
OUT.parent.mkdir(parents=True, exist_ok=True)
OUT.write_text(json.dumps(out, separators=(",", ":")) + "\n")
print(f"wrote {OUT} ({OUT.stat().st_size / 1024:.0f} KiB)")
for e in emd_out:
    print(f"emd {e['name']}: {e['n_sift']} siftings, {e['n_rows']} rows")
print("paper features", F.shape, "pca components", paper_out["pca_n_components"])
