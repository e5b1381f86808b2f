"""The unsupervised decoder as a scikit-learn estimator: a P300 classifier learnt without labels.

In every trial the person attends one choice of each set of competing stimulus codes (one of
the bulbs; a speller's row and column); which one is unknown. ``UnsupervisedDecoder`` fits
oddball's EM over that constraint (Kindermans et al. 2012; ``oddball evaluate --unsupervised``
and a session with ``--calibration none``) from epochs, their stimulus codes and their trials —
``fit`` takes no labels at all — and ``predict`` gives the attended code of each set per trial::

    ep = oddball.read_epochs("eeg3_2.dat")          # epochs as oddball evaluate cuts them
    dec = UnsupervisedDecoder(ep.sets, ep.sfreq)
    for trial in np.unique(ep.trials):              # a session: refit after each trial
        i = ep.trials == trial
        dec.partial_fit(ep.data[i], ep.codes[i], ep.trials[i])
        online = dec.predict(ep.data[i], ep.codes[i], ep.trials[i])[0]
    posthoc = dec.predict(ep.data, ep.codes, ep.trials)

``partial_fit`` takes in more epochs and refits on all of them, warm-started from the last fit
(what a session does after each trial); ``fit`` forgets and fits from scratch. Every fit starts
EM from the P300 template's score of each epoch as ``preprocess`` cut it, plus random
initialisations once there are as many epochs as features, and keeps the likeliest.
"""
from __future__ import annotations

import numbers

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from . import _oddball
from ._base import as_array, as_epochs

__all__ = ["UnsupervisedDecoder"]


def _ints(v, n, what, dtype):
    a = np.asarray(v)
    if a.ndim != 1 or a.shape[0] != n:
        raise ValueError(f"{what}: expected one per epoch ({n}), got shape {a.shape}")
    if a.size and (not np.issubdtype(a.dtype, np.integer) or a.min() < 0):
        raise ValueError(f"{what}: expected non-negative integers, got {a.dtype}")
    return [int(x) for x in a.astype(dtype)]


class UnsupervisedDecoder(BaseEstimator):
    """``sets``: the competing stimulus codes, one list per set (e.g. ``[[1..6], [7..12]]`` for a
    6×6 speller's rows and columns, ``[[1, 2, 3, 4]]`` for four bulbs); epochs
    ``(n_epochs, n_channels, n_times)`` at ``sfreq`` Hz, cut by ``preprocess`` (``"peer"``:
    ``oddball evaluate``'s zero-phase band-pass, ``"peer-causal"``: as a live session filters;
    ``None``: no template start, random initialisations only). ``mean_prior``, ``n_inits``,
    ``max_iter``, ``tol``, ``seed``: the EM's settings (``oddball_decode::unsupervised``;
    ``n_inits=None``: the library's number of random starts, as ``oddball evaluate --unsupervised``).
    ``decoys``: codes the paradigm flashes but nobody attends (a blank, a symbol never spelled):
    the EM takes their epochs as known non-targets, the one group whose labels a paradigm gives
    away; they are in no set and never predicted. ``groups``: for flashes that show groups of
    choices (a checkerboard or region speller), ``{code: [choice, …]}`` with choices numbered from
    0, in place of ``sets``: one choice is attended per trial, and ``predict`` gives its number.

    Fitted: ``coef_`` is not exposed (features are the ``lda`` preset's bin means inside Rust);
    ``trial_posteriors_`` (per fitted trial, each set's posterior), ``choices_`` (per fitted
    trial, the attended codes), ``n_epochs_`` (epochs taken in).
    """

    def __init__(self, sets=((1, 2, 3, 4),), sfreq=None, preprocess="peer", mean_prior=0.0, n_inits=None,
                 max_iter=200, tol=1e-6, seed=0, decoys=(), groups=None):
        self.sets = sets
        self.sfreq = sfreq
        self.preprocess = preprocess
        self.mean_prior = mean_prior
        self.n_inits = n_inits
        self.max_iter = max_iter
        self.tol = tol
        self.seed = seed
        self.decoys = decoys
        self.groups = groups

    def _new_model(self):
        if self.sfreq is None or not isinstance(self.sfreq, numbers.Real) or not float(self.sfreq) > 0:
            raise ValueError(f"UnsupervisedDecoder(sfreq={self.sfreq!r}): give the epochs' rate in Hz")
        sets = [[int(c) for c in s] for s in self.sets]
        return _oddball.UnsupervisedDecoder(
            sets, float(self.sfreq), self.preprocess, float(self.mean_prior),
            None if self.n_inits is None else int(self.n_inits),
            int(self.max_iter), float(self.tol), int(self.seed), [int(c) for c in self.decoys],
            None if self.groups is None
            else {int(c): [int(m) for m in g] for c, g in dict(self.groups).items()})

    def _args(self, X, stimuli, trials):
        X = as_epochs(as_array(X))
        n = X.shape[0]
        return X, _ints(stimuli, n, "stimuli", np.uint32), _ints(trials, n, "trials", np.uint64)

    def _sync(self):
        posts, choices = self._model.fitted()
        self.trial_posteriors_ = posts
        self.choices_ = np.asarray(choices, dtype=np.int64)
        self.n_epochs_ = self._model.n_epochs

    def fit(self, X, stimuli, trials, y=None):
        """Fits from scratch on epochs ``X``, each epoch's stimulus code and trial number (epochs
        with one number form one trial). ``y`` is refused: the decoder never sees labels."""
        if y is not None:
            raise ValueError("UnsupervisedDecoder.fit takes no labels (y must be None)")
        X, codes, trials = self._args(X, stimuli, trials)
        self._model = self._new_model()
        self._model.partial_fit(X, codes, trials, True)
        self._sync()
        return self

    def partial_fit(self, X, stimuli, trials, y=None):
        """Takes in more epochs (e.g. the trial that just ended) and refits on all epochs so far,
        warm-started from the last fit."""
        if y is not None:
            raise ValueError("UnsupervisedDecoder.partial_fit takes no labels (y must be None)")
        X, codes, trials = self._args(X, stimuli, trials)
        if not hasattr(self, "_model"):
            self._model = self._new_model()
        self._model.partial_fit(X, codes, trials, False)
        self._sync()
        return self

    def predict(self, X, stimuli, trials):
        """The attended code of each set, per trial of ``X`` (in order of first appearance):
        ``(n_trials, n_sets)``."""
        check_is_fitted(self, "choices_")
        X, codes, trials = self._args(X, stimuli, trials)
        return np.asarray(self._model.predict(X, codes, trials), dtype=np.int64)

    def predict_proba(self, X, stimuli, trials):
        """Per trial of ``X``, each set's posterior over its codes (in ``sets`` order)."""
        check_is_fitted(self, "choices_")
        X, codes, trials = self._args(X, stimuli, trials)
        return [p["posterior"] for p in self._model.posteriors(X, codes, trials)]

    def decision_function(self, X):
        """Log-likelihood ratio (attended vs not, nats) per epoch."""
        check_is_fitted(self, "choices_")
        return self._model.decision_function(as_epochs(as_array(X)))
