"""Shared fixtures: the real EEG in ../shared/data (or $ODDBALL_DATA) and its P300 epochs.

As the Rust tests (oddball-testkit): when the data is absent a test skips, unless
ODDBALL_REQUIRE_DATA=1 (CI), which makes it fail.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
DATA = Path(os.environ.get("ODDBALL_DATA", REPO.parent / "shared" / "data"))
FIXTURES = REPO / "crates" / "oddball-io" / "tests" / "fixtures"
REQUIRE = os.environ.get("ODDBALL_REQUIRE_DATA", "") == "1"

# peer_eval.py's pre-processing (../shared/peer): 4th-order Butterworth 0.5-20 Hz, zero-phase,
# epochs of round(0.8 sfreq) samples from each onset; Riemannian features every round(sfreq/64)-th
# sample, vector features the means of round(sfreq/25)-sample bins.
BAND = (0.5, 20.0)
EPOCH_S = 0.8


def need(path: Path) -> Path:
    if not path.exists():
        msg = f"{path} is absent"
        if REQUIRE:
            pytest.fail(msg + " (ODDBALL_REQUIRE_DATA=1)")
        pytest.skip(msg)
    return path


def data_file(rel: str) -> Path:
    return need(DATA / rel)


def need_module(name: str):
    """Imports an optional test dependency; fails instead of skipping under ODDBALL_REQUIRE_DATA=1."""
    try:
        return __import__(name)
    except ImportError as e:
        if REQUIRE:
            pytest.fail(f"{name} is not installed ({e}); ODDBALL_REQUIRE_DATA=1")
        pytest.skip(f"{name} is not installed")


def bandpass(data: np.ndarray, sfreq: float) -> np.ndarray:
    """(n_channels, n_times): mean removed, then zero-phase band-pass (peer_eval.bandpass)."""
    from scipy.signal import butter, sosfiltfilt

    sos = butter(4, BAND, btype="bandpass", fs=sfreq, output="sos")
    return sosfiltfilt(sos, data - data.mean(axis=1, keepdims=True), axis=1)


def epochs_of(raw) -> tuple[np.ndarray, np.ndarray]:
    """Labelled epochs (n_epochs, n_channels, n_times) of an oddball.Raw, and 0/1 labels."""
    x = bandpass(raw.data, raw.sfreq)
    n = int(round(EPOCH_S * raw.sfreq))
    keep = (raw.event_targets >= 0) & (raw.events[:, 0] + n <= x.shape[1])
    on = raw.events[keep, 0]
    idx = on[:, None] + np.arange(n)[None, :]
    X = np.ascontiguousarray(x[:, idx].transpose(1, 0, 2))
    return X, raw.event_targets[keep].astype(int)


def riem(X: np.ndarray, sfreq: float) -> np.ndarray:
    return np.ascontiguousarray(X[..., :: max(1, int(round(sfreq / 64.0)))])


def vec(X: np.ndarray, sfreq: float) -> np.ndarray:
    k = max(1, int(round(sfreq / 25.0)))
    nb = X.shape[-1] // k
    return X[..., : nb * k].reshape(*X.shape[:-1], nb, k).mean(-1).reshape(len(X), -1)


@pytest.fixture(scope="session")
def eeg3():
    """eeg3_1.dat (BCI2000 P300 speller): dict with X (band-passed epochs),
    y (1 = target), sfreq, riem and vec features."""
    import oddball

    raw = oddball.read_raw(data_file("bci2000-samplefiles-p300/eeg3_1.dat"))
    X, y = epochs_of(raw)
    return dict(X=X, y=y, sfreq=raw.sfreq, riem=riem(X, raw.sfreq), vec=vec(X, raw.sfreq))
