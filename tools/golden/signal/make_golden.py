"""Reference values for oddball-signal from scipy (see requirements.txt for the pinned versions).

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/signal/requirements.txt
    /tmp/golden/bin/python tools/golden/signal/make_golden.py
Writes crates/oddball-signal/tests/fixtures/signal_golden.json.
"""
import json
import pathlib

import numpy as np
import scipy
from scipy import signal

OUT = pathlib.Path(__file__).resolve().parents[3] / "crates/oddball-signal/tests/fixtures/signal_golden.json"

rng = np.random.default_rng(20261122)
n_channels, n_times, fs = 2, 300, 256.0
t = np.arange(n_times) / fs
x = np.empty((n_channels, n_times))
for c in range(n_channels):
    x[c] = (
        30.0 * np.sin(2 * np.pi * (2.0 + 3 * c) * t)
        + 8.0 * np.sin(2 * np.pi * 50.0 * t + c)
        + 40.0 * (c + 1)            # DC offset, as amplifiers have
        + 15.0 * t * (c - 1)        # slow drift
        + rng.normal(0.0, 5.0, n_times)
    )
x = np.round(x, 6)  # short decimal literals in the fixture, exactly representable enough


def arr(a):
    return np.asarray(a, dtype=float).tolist()


designs = {
    "band_1_15_fs256_o4": dict(N=4, Wn=[1.0, 15.0], btype="bandpass", fs=256.0),
    "band_1_15_fs500_o4": dict(N=4, Wn=[1.0, 15.0], btype="bandpass", fs=500.0),
    "band_05_20_fs160_o4": dict(N=4, Wn=[0.5, 20.0], btype="bandpass", fs=160.0),
    "low_30_fs160_o2": dict(N=2, Wn=30.0, btype="lowpass", fs=160.0),
    "low_40_fs256_o5": dict(N=5, Wn=40.0, btype="lowpass", fs=256.0),
    "high_05_fs256_o3": dict(N=3, Wn=0.5, btype="highpass", fs=256.0),
    "stop_48_52_fs500_o2": dict(N=2, Wn=[48.0, 52.0], btype="bandstop", fs=500.0),
}

out = {
    "versions": {"numpy": np.__version__, "scipy": scipy.__version__},
    "x": arr(x),
    "butter": [],
    "cheby1": [],
    "detrend": {
        "constant": arr(signal.detrend(x, axis=-1, type="constant")),
        "linear": arr(signal.detrend(x, axis=-1, type="linear")),
    },
    "decimate": [],
}
for name, d in designs.items():
    sos = signal.butter(d["N"], d["Wn"], btype=d["btype"], fs=d["fs"], output="sos")
    zi = signal.sosfilt_zi(sos)
    entry = {
        "name": name,
        "order": d["N"],
        "btype": d["btype"],
        "wn": d["Wn"] if isinstance(d["Wn"], list) else [d["Wn"]],
        "fs": d["fs"],
        "sos": arr(sos),
        "zi": arr(zi),
        "sosfiltfilt": arr(signal.sosfiltfilt(sos, x, axis=-1)),
    }
    if name in ("band_1_15_fs256_o4", "low_40_fs256_o5"):
        entry["sosfilt_rest"] = arr(signal.sosfilt(sos, x, axis=-1))
        entry["sosfilt_steady"] = arr(
            np.stack([signal.sosfilt(sos, x[c], zi=zi * x[c, 0])[0] for c in range(n_channels)])
        )
    out["butter"].append(entry)

for q in (2, 3, 4, 5):
    sos = signal.cheby1(8, 0.05, 0.8 / q, output="sos")
    out["cheby1"].append({"q": q, "sos": arr(sos)})
for q in (2, 4, 5):
    out["decimate"].append({"q": q, "y": arr(signal.decimate(x, q, axis=-1))})

OUT.parent.mkdir(parents=True, exist_ok=True)
OUT.write_text(json.dumps(out, separators=(",", ":"), default=float))
print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
