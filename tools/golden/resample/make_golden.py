"""Reference values for oddball-signal's polyphase resampling from scipy.signal.resample_poly
(see requirements.txt for the pinned versions).

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/resample/requirements.txt
    /tmp/golden/bin/python tools/golden/resample/make_golden.py
Writes crates/oddball-signal/tests/fixtures/resample_golden.json.
"""
import json
import pathlib

import numpy as np
import scipy
from scipy import signal

OUT = pathlib.Path(__file__).resolve().parents[3] / "crates/oddball-signal/tests/fixtures/resample_golden.json"

rng = np.random.default_rng(20261126)
n_channels, n_times, fs = 2, 97, 160.0
t = np.arange(n_times) / fs
x = np.empty((n_channels, n_times))
for c in range(n_channels):
    x[c] = (
        20.0 * np.sin(2 * np.pi * (3.0 + 4 * c) * t)
        + 60.0 * (c + 1)  # a DC offset, as amplifiers have
        + rng.normal(0.0, 5.0, n_times)
    )
x = np.round(x, 6)

cases = []
# 160 -> 256 Hz (eeg2 to eeg3's rate), 256 -> 160, 500 -> 256, a plain downsampling by 2.
for up, down in [(8, 5), (5, 8), (64, 125), (1, 2), (3, 1)]:
    for padtype in ["constant", "mean"]:
        y = signal.resample_poly(x, up, down, axis=1, padtype=padtype)
        cases.append({"up": up, "down": down, "padtype": padtype, "y": y.tolist()})

OUT.write_text(json.dumps({
    "scipy": scipy.__version__,
    "numpy": np.__version__,
    "x": x.tolist(),
    "cases": cases,
}) + "\n")
print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
