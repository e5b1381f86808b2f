"""Learning while used: ``AdaptiveLDA.partial_fit`` (the engine of a session's ``--adapt``) and
the unsupervised decoder as a scikit-learn estimator (``evaluate --unsupervised``'s EM).

* ``partial_fit`` after each confident decision, replayed over real speller runs (eeg3; BCI
  Competition II IIb), gives the scores and AUC of a naive numpy adaptive LDA (scikit-learn's
  shrinkage LDA for the calibration, class means of every epoch taken in, the drift guard) to
  1e-9;
* ``UnsupervisedDecoder.partial_fit`` trial by trial on eeg3_1 + eeg3_2 decides online and post
  hoc the characters ``oddball evaluate --unsupervised`` prints, with its AUC;
* both pickle mid-session and go on as the original; ``clone`` gives an unfitted twin.
"""
from __future__ import annotations

import json
import os
import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis as SkLDA
from sklearn.metrics import roc_auc_score

import oddball
from oddball.lda import AdaptiveLDA
from oddball.unsupervised import UnsupervisedDecoder
from conftest import REPO, REQUIRE, data_file

EEG3 = "bci2000-samplefiles-p300/eeg3_{}.dat"
IIB = "bci-competition-ii-iib/AAS0{}.mat"


def oddball_bin() -> Path:
    """The command-line program: $ODDBALL_BIN, else the workspace's debug or release build."""
    for p in [os.environ.get("ODDBALL_BIN")] + [str(REPO / "target" / b / "oddball") for b in ("debug", "release")]:
        if p and Path(p).is_file():
            return Path(p)
    msg = "the oddball program is not built (cargo build) and ODDBALL_BIN is unset"
    if REQUIRE:
        pytest.fail(msg + " (ODDBALL_REQUIRE_DATA=1)")
    pytest.skip(msg)


def features(ep):
    """The ``lda`` preset's features: per channel, means of round(sfreq/25)-sample bins."""
    w = int(round(ep.sfreq / 25))
    n, c, t = ep.data.shape
    nb = t // w
    return ep.data[:, :, : nb * w].reshape(n, c, nb, w).mean(axis=3).reshape(n, c * nb)


def runs(names, texts=None):
    out = []
    for k, name in enumerate(names):
        ep = oddball.read_epochs(data_file(name), text=None if texts is None else texts[k])
        assert ep.trials is not None and (ep.targets >= 0).all()
        out.append((ep, features(ep)))
    return out


def decide(sets, codes, scores):
    """A character's (row, column) by its flashes' summed scores, and the smaller of the two
    posteriors (softmax of the sums)."""
    choice, conf = [], []
    for competing in sets:
        ev = np.array([scores[codes == c].sum() for c in competing])
        p = np.exp(ev - ev.max())
        p /= p.sum()
        choice.append(competing[int(np.argmax(p))])
        conf.append(p.max())
    return choice, min(conf)


class NaiveAdaptive:
    """The adaptive LDA written out: class means of every epoch taken in, the calibration's
    covariance (scikit-learn's), weights Σ⁻¹(μt − μn), an update undone below min_cosine."""

    def __init__(self, X, y, min_cosine=0.8):
        lda = SkLDA(solver="lsqr", shrinkage="auto").fit(X, y)
        self.P = np.linalg.inv(lda.covariance_)
        self.rows = [list(X[~y]), list(X[y])]
        self.lpr = np.log(y.mean() / (1 - y.mean()))
        self.min_cosine = min_cosine
        self.w0, _ = self.weights(self.rows)
        self.w, self.b = self.w0, self.weights(self.rows)[1]

    def weights(self, rows):
        mn, mt = (np.mean(r, axis=0) for r in rows)
        w = self.P @ (mt - mn)
        return w, -0.5 * (mt @ self.P @ mt - mn @ self.P @ mn) + self.lpr

    def update(self, X, y):
        rows = [self.rows[0] + list(X[~y]), self.rows[1] + list(X[y])]
        w, b = self.weights(rows)
        if w @ self.w0 / (np.linalg.norm(w) * np.linalg.norm(self.w0)) < self.min_cosine:
            return False
        self.rows, self.w, self.b = rows, w, b
        return True

    def decision_function(self, X):
        return X @ self.w + self.b


def replay(train, test, model, update, min_confidence=0.9):
    """Scores of every test epoch by the model of that moment; after each character whose
    decision is confident, its epochs are taken in labelled by the decision."""
    scores, truth, n_updates = [], [], 0
    for ep, x in test:
        for t in np.unique(ep.trials):
            idx = np.flatnonzero(ep.trials == t)
            s = model.decision_function(x[idx])
            choice, conf = decide(ep.sets, ep.codes[idx], s)
            scores.append(s)
            truth.append(ep.targets[idx] == 1)
            if conf >= min_confidence:
                update(x[idx], np.isin(ep.codes[idx], choice))
                n_updates += 1
    return np.concatenate(scores), np.concatenate(truth), n_updates


@pytest.mark.parametrize("case", ["eeg3", "iib"])
def test_partial_fit_after_confident_decisions_is_the_naive_adaptive_lda(case):
    if case == "eeg3":
        train, test = runs([EEG3.format(1)]), runs([EEG3.format(2)])
    else:
        train = runs([IIB.format(f) for f in ("10R01", "10R02", "11R01", "11R02")])
        test = runs([IIB.format("12R03"), IIB.format("12R04")], texts=["HAM", "PIE"])
    X = np.concatenate([x for _, x in train])
    y = np.concatenate([ep.targets == 1 for ep, _ in train])
    ours = AdaptiveLDA().fit(X, y)
    ref = NaiveAdaptive(X, y)
    s_ours, truth, n_ours = replay(train, test, ours, lambda X, y: ours.partial_fit(X, y))
    s_ref, _, n_ref = replay(train, test, ref, ref.update)
    frozen = AdaptiveLDA().fit(X, y)
    s_frozen, _, _ = replay(train, test, frozen, lambda X, y: None)
    auc = [roc_auc_score(truth, s) for s in (s_ours, s_ref, s_frozen)]
    print(f"\n{case}: AUC partial_fit {auc[0]:.12f}, naive {auc[1]:.12f}, frozen {auc[2]:.12f}; "
          f"{n_ours} updates, {ours.n_rejected_} undone")
    assert n_ours == n_ref and ours.n_updates_ == n_ours > 0
    np.testing.assert_allclose(s_ours, s_ref, rtol=1e-9, atol=1e-9)
    assert abs(auc[0] - auc[1]) <= 1e-9
    assert ours.counts_[1] > y.sum()  # it took epochs in


def test_adaptive_lda_pickles_mid_session_and_goes_on_as_the_original():
    rng = np.random.default_rng(3)
    X = rng.normal(size=(120, 6))
    y = np.arange(120) % 4 == 1
    X[y] += 0.5
    a = AdaptiveLDA().fit(X, y)
    a.partial_fit(X[:30], y[:30])
    b = pickle.loads(pickle.dumps(a))
    for m in (a, b):
        m.partial_fit(X[30:60], y[30:60])
    np.testing.assert_array_equal(a.decision_function(X), b.decision_function(X))
    assert a.counts_ == b.counts_ and a.n_updates_ == b.n_updates_ == 2
    c = clone(a)
    assert not hasattr(c, "classes_") and c.get_params() == a.get_params()
    # The first partial_fit of an unfitted model calibrates it.
    d = AdaptiveLDA().partial_fit(X, y, classes=[False, True])
    np.testing.assert_array_equal(d.decision_function(X), AdaptiveLDA().fit(X, y).decision_function(X))
    with pytest.raises(ValueError, match="labels"):
        a.partial_fit(X[:4], np.array([0, 1, 2, 1]))
    # The guard: labels flipped many times over are undone.
    before = a.decision_function(X)
    for _ in range(5):
        a.partial_fit(np.repeat(X, 3, axis=0), np.repeat(~y, 3))
    assert a.n_rejected_ >= 1
    assert a.cosine_ >= 0.8


@pytest.fixture(scope="module")
def eeg3_epochs():
    return [oddball.read_epochs(data_file(EEG3.format(k))) for k in (1, 2)]


def session(eeg3_epochs):
    """eeg3_1 then eeg3_2 as one unlabelled session: (data, codes, trials) with characters
    numbered on across the two runs, as ``evaluate --unsupervised`` numbers them."""
    a, b = eeg3_epochs
    trials = np.r_[a.trials, b.trials + a.trials.max() + 1]
    return np.concatenate([a.data, b.data]), np.r_[a.codes, b.codes], trials


def test_unsupervised_estimator_decides_what_evaluate_unsupervised_decides(eeg3_epochs, tmp_path):
    out = tmp_path / "unsup.json"
    files = [str(data_file(EEG3.format(k))) for k in (1, 2)]
    subprocess.run([str(oddball_bin()), "evaluate", "--unsupervised", "--test", *files, "--out", str(out)],
                   check=True, capture_output=True)
    cli = json.loads(out.read_text())["unsupervised"]
    ep = eeg3_epochs[0]
    X, codes, trials = session(eeg3_epochs)
    dec = UnsupervisedDecoder(sets=ep.sets, sfreq=ep.sfreq)
    online = []
    for t in np.unique(trials):  # the session: after each character, refit on all so far
        i = trials == t
        dec.partial_fit(X[i], codes[i], trials[i])
        online.append(ep.symbol(dec.predict(X[i], codes[i], trials[i])[0]))
    posthoc = "".join(ep.symbol(c) for c in dec.predict(X, codes, trials))
    assert "".join(online) == cli["online_text"]
    assert posthoc == cli["posthoc_text"]
    np.testing.assert_array_equal(dec.choices_, dec.predict(X, codes, trials))
    truth = np.r_[eeg3_epochs[0].targets, eeg3_epochs[1].targets] == 1
    auc = roc_auc_score(truth, dec.decision_function(X))
    print(f"\nonline {''.join(online)!r}, post hoc {posthoc!r}, AUC {auc:.6f} (CLI: "
          f"{cli['online_text']!r}, {cli['posthoc_text']!r}, {cli['auc']:.6f})")
    assert abs(auc - cli["auc"]) < 1e-9


def test_unsupervised_estimator_takes_no_labels_pickles_and_clones(eeg3_epochs):
    ep = eeg3_epochs[1]
    X, codes, trials = ep.data, ep.codes, ep.trials
    with pytest.raises(ValueError, match="no labels"):
        UnsupervisedDecoder(sets=ep.sets, sfreq=ep.sfreq).fit(X, codes, trials, y=ep.targets)
    first = trials < 2
    a = UnsupervisedDecoder(sets=ep.sets, sfreq=ep.sfreq).partial_fit(X[first], codes[first], trials[first])
    b = pickle.loads(pickle.dumps(a))
    for m in (a, b):
        m.partial_fit(X[~first], codes[~first], trials[~first])
    np.testing.assert_array_equal(a.predict(X, codes, trials), b.predict(X, codes, trials))
    np.testing.assert_array_equal(a.decision_function(X), b.decision_function(X))
    assert a.n_epochs_ == len(codes)
    c = clone(a)
    assert not hasattr(c, "choices_") and c.get_params() == a.get_params()
    # fit forgets: one fit from scratch on all epochs.
    f = clone(a).fit(X, codes, trials)
    assert f.n_epochs_ == len(codes) and f.choices_.shape == (len(np.unique(trials)), 2)
    with pytest.raises(ValueError, match="one per epoch"):
        a.predict(X, codes[:-1], trials)
    with pytest.raises(ValueError):
        a.predict(X, codes + 100, trials)  # codes outside the sets


def test_unsupervised_estimator_takes_decoys_as_known_non_targets():
    """Decoys (codes flashed that nobody attends) reach the EM: on weak synthetic four-bulb trials
    with a decoy each round, the decoder with ``decoys=[5]`` finds more trials than one that never
    sees the decoys' epochs; a decoy inside a set, or listed twice, is refused."""
    right = {"decoys": 0, "dropped": 0}
    total = 0
    for seed in range(12):
        rng = np.random.default_rng(100 + seed)
        n_trials, reps = 6, 5
        stim = np.concatenate([rng.permutation([1, 2, 3, 4, 5]) for _ in range(n_trials * reps)])
        trials = np.repeat(np.arange(n_trials), reps * 5)
        attended = rng.integers(1, 5, size=n_trials)
        X = rng.normal(size=(len(stim), 2, 20))
        X[stim == attended[trials], :, 8:12] += 0.35
        kw = dict(sets=[[1, 2, 3, 4]], sfreq=50.0, preprocess=None, n_inits=4)
        a = UnsupervisedDecoder(decoys=[5], **kw).fit(X, stim, trials)
        keep = stim != 5
        b = UnsupervisedDecoder(**kw).fit(X[keep], stim[keep], trials[keep])
        right["decoys"] += int((a.choices_[:, 0] == attended).sum())
        right["dropped"] += int((b.choices_[:, 0] == attended).sum())
        total += n_trials
    print(f"\nright of {total}: {right}")
    assert right["decoys"] > right["dropped"], right
    assert clone(UnsupervisedDecoder(decoys=[5])).get_params()["decoys"] == [5]
    for bad, why in (([4], "in a choice set"), ([5, 5], "listed twice")):
        with pytest.raises(ValueError, match=why):
            UnsupervisedDecoder(sets=[[1, 2, 3, 4]], sfreq=50.0, decoys=bad).fit(X, stim, trials)


def test_unsupervised_estimator_decodes_group_flashes():
    """Flashes of groups of choices (``groups``): the decoder finds the attended choice, as a number
    from 0, on synthetic trials where no code is a single choice."""
    groups = {1: [0, 1], 2: [2, 3], 3: [0, 2], 4: [1, 3], 5: [0]}
    rng = np.random.default_rng(7)
    n_trials, reps = 10, 5
    stim = np.concatenate([rng.permutation([1, 2, 3, 4, 5]) for _ in range(n_trials * reps)])
    trials = np.repeat(np.arange(n_trials), reps * 5)
    attended = rng.integers(0, 4, size=n_trials)
    target = np.array([attended[t] in groups[c] for c, t in zip(stim, trials)])
    X = rng.normal(size=(len(stim), 2, 20))
    X[target, :, 8:12] += 1.0
    dec = UnsupervisedDecoder(groups=groups, sfreq=50.0, preprocess=None, n_inits=4).fit(X, stim, trials)
    right = int((dec.choices_[:, 0] == attended).sum())
    print(f"\ngroup flashes: {right}/{n_trials}")
    assert right >= 9
    assert clone(dec).get_params()["groups"] == groups
    with pytest.raises(ValueError, match="no code flashes"):
        UnsupervisedDecoder(groups={1: [0], 2: [2]}, sfreq=50.0).fit(X, stim, trials)
