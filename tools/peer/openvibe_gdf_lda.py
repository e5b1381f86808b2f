"""MNE + scikit-learn on the OpenViBE GDF run, beside `oddball benchmark datasets/openvibe-p300-gdf.toml
--protocol within-session --pipeline lda` (issue #33): the same epochs, the same folds, an independent stack.

MNE 1.13.2 reads the GDF (`mne.io.read_raw_gdf`) and its event table (`events_from_annotations`); a flash is a
row/column label code 33025-33038 (0x8101-0x810E; one per sample and code) with the target (33285) or non-target
(33286) flag nearest to it within 2 samples. Pre-processing is the peer stack's (`../shared/peer/peer_eval.py`):
each channel's mean removed, 4th-order Butterworth 0.5-20 Hz zero-phase (`sosfiltfilt`) on the continuous EEG,
epochs of round(0.8 fs) samples from each onset, features the means of round(fs/25)-sample bins. scikit-learn's
`LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto")` in 5 folds that keep characters whole (each fold one
of the 5 characters of 140 flashes), the AUC the mean over folds, as oddball's within-session protocol reports it.

    python3 -m venv /tmp/venv-peer-gdf && /tmp/venv-peer-gdf/bin/pip install -r tools/peer/requirements.txt
    /tmp/venv-peer-gdf/bin/python tools/peer/openvibe_gdf_lda.py ../shared/data/openvibe-p300-gdf/data_sample_8ch.gdf
"""
import sys

import mne
import numpy as np
import sklearn
from scipy.signal import butter, sosfiltfilt
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.metrics import roc_auc_score
from sklearn.model_selection import GroupKFold

LABELS = range(33025, 33039)
TARGET, NONTARGET = 33285, 33286


def flashes(raw):
    events, ids = mne.events_from_annotations(raw, verbose="error")
    code_of = {v: int(k) for k, v in ids.items() if k.isdigit()}
    ev = [(s, code_of.get(e)) for s, _, e in events]
    labels = sorted({(s, c - 33024) for s, c in ev if c in LABELS})
    flags = [(s, c == TARGET) for s, c in ev if c in (TARGET, NONTARGET)]
    used, out = set(), []
    for s, code in labels:
        near = [(abs(fs - s), i) for i, (fs, _) in enumerate(flags) if abs(fs - s) <= 2 and i not in used]
        if not near:
            continue
        _, i = min(near)
        used.add(i)
        out.append((s, code, flags[i][1]))
    return out


def main(path):
    raw = mne.io.read_raw_gdf(path, preload=True, verbose="error")
    fs = raw.info["sfreq"]
    x = raw.get_data() * 1e6  # µV
    fl = flashes(raw)
    sos = butter(4, (0.5, 20.0), btype="bandpass", fs=fs, output="sos")
    x = sosfiltfilt(sos, x - x.mean(axis=1, keepdims=True), axis=1)
    n = int(round(0.8 * fs))
    w = int(round(fs / 25))
    nb = n // w
    keep = [(s, c, t) for s, c, t in fl if s + n <= x.shape[1]]
    X = np.stack([x[:, s:s + n][:, : nb * w].reshape(x.shape[0], nb, w).mean(axis=2).reshape(-1)
                  for s, _, _ in keep])
    y = np.array([t for _, _, t in keep])
    char = np.arange(len(keep)) // 140
    aucs = []
    for train, test in GroupKFold(n_splits=5).split(X, y, char):
        lda = LinearDiscriminantAnalysis(solver="lsqr", shrinkage="auto").fit(X[train], y[train])
        aucs.append(roc_auc_score(y[test], lda.decision_function(X[test])))
    print(f"mne {mne.__version__}, scikit-learn {sklearn.__version__}: {len(keep)} flashes, {y.sum()} targets, "
          f"{len(set(c for _, c, _ in keep))} codes, {x.shape[0]} channels at {fs} Hz")
    print("AUC per fold (one character each): " + ", ".join(f"{a:.4f}" for a in aucs))
    print(f"shrinkage LDA, 5 folds keeping characters whole: AUC {np.mean(aucs):.4f}")


if __name__ == "__main__":
    main(sys.argv[1])
