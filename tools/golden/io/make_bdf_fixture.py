"""A small BDF+ file written with numpy and struct only, and its expected values.

Writes crates/oddball-io/tests/fixtures/numpy_small.bdf (about 3 KB) and numpy_small.json;
tests/edf_fixtures.rs reads the BDF+ file with the Rust reader and compares.

    /tmp/venv-golden/bin/python tools/golden/io/make_bdf_fixture.py [--out-dir DIR]

The writer below follows the EDF/BDF specification directly (it shares no code with the Rust
reader): version "\\xFFBIOSEMI", reserved "BDF+C", 24-bit little-endian two's-complement samples,
a "BDF Annotations" signal with TALs. Signals, 64 Hz, 2 data records of 1 s:
  Fp1     uV, physical -262144..262143, digital -8388608..8388607 (BioSemi: 1/32 uV per step)
  Oz      mV, physical -1..1,           digital -1000000..1000000 (the reader multiplies by 1000)
  Status  Boolean, physical/digital -8388608..8388607 (not a voltage: kept unscaled)
Expected microvolts are computed here with numpy from the digital values:
  (dig - dig_min) * (phys_max - phys_min) / (dig_max - dig_min) + phys_min, times the unit factor.
If pyedflib is installed, the file is also read back with it and the values checked.
"""
from __future__ import annotations

import argparse
import json
import struct
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[3]
FS = 64
N_RECORDS = 2
SIGNALS = [
    # label, dimension, phys_min, phys_max, dig_min, dig_max, to-uV factor (None: not a voltage)
    ("Fp1", "uV", -262144.0, 262143.0, -8388608, 8388607, 1.0),
    ("Oz", "mV", -1.0, 1.0, -1000000, 1000000, 1000.0),
    ("Status", "Boolean", -8388608.0, 8388607.0, -8388608, 8388607, None),
]
ANN_BYTES = 60  # bytes of the annotation signal per record (20 samples x 3 bytes)
# (record, TAL bytes after the time stamp)
TALS = {
    0: [b"+0.5\x14stim\x14\x00", b"+0.75\x150.1\x143 target\x14\x00"],
    1: [b"+1.5\x14stim\x14\x00"],
}
EXPECTED_EVENTS = [  # at 64 Hz; "stim" gets code 4 (one above the numeric code 3)
    {"onset": 32, "code": 4, "target": None, "label": "stim"},
    {"onset": 48, "code": 3, "target": True, "label": None},
    {"onset": 96, "code": 4, "target": None, "label": "stim"},
]


def field(text: str, width: int) -> bytes:
    b = text.encode("ascii")
    assert len(b) <= width, (text, width)
    return b.ljust(width, b" ")


def digital_values() -> list[np.ndarray]:
    n = FS * N_RECORDS
    k = np.arange(n)
    fp1 = np.round(np.sin(2 * np.pi * 2 * k / FS) * 3_000_000 + k * 1000).astype(np.int64)
    fp1[5] = -8388608  # the extremes of the 24-bit range
    fp1[6] = 8388607
    oz = np.round(np.cos(2 * np.pi * 7 * k / FS) * 900_000).astype(np.int64)
    status = (k % 16 == 0).astype(np.int64) * 255 - 8388608 * (k % 32 == 0)
    return [fp1, oz, status]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=str(REPO / "crates/oddball-io/tests/fixtures"))
    args = ap.parse_args()
    out = Path(args.out_dir)
    path = out / "numpy_small.bdf"

    labels = [s[0] for s in SIGNALS] + ["BDF Annotations"]
    ns = len(labels)
    spr = [FS] * len(SIGNALS) + [ANN_BYTES // 3]
    h = b"\xffBIOSEMI"
    h += field("X M 01-JAN-1990 Golden", 80)
    h += field("Startdate 02-JAN-2020 X X numpy", 80)
    h += field("02.01.20", 8) + field("03.04.05", 8)
    h += field(str(256 * (ns + 1)), 8)
    h += field("BDF+C", 44)
    h += field(str(N_RECORDS), 8) + field("1", 8) + field(str(ns), 4)
    h += b"".join(field(lab, 16) for lab in labels)
    h += b"".join(field("active electrode" if s[1] != "Boolean" else "", 80) for s in SIGNALS) + field("", 80)
    h += b"".join(field(s[1], 8) for s in SIGNALS) + field("", 8)
    h += b"".join(field(f"{s[2]:.10g}", 8) for s in SIGNALS) + field("-1", 8)
    h += b"".join(field(f"{s[3]:.10g}", 8) for s in SIGNALS) + field("1", 8)
    h += b"".join(field(str(s[4]), 8) for s in SIGNALS) + field("-8388608", 8)
    h += b"".join(field(str(s[5]), 8) for s in SIGNALS) + field("8388607", 8)
    h += b"".join(field("HP:DC; LP:410", 80) for _ in SIGNALS) + field("", 80)
    h += b"".join(field(str(k), 8) for k in spr)
    h += b"".join(field("", 32) for _ in labels)
    assert len(h) == 256 * (ns + 1)

    dig = digital_values()
    body = b""
    for r in range(N_RECORDS):
        for x in dig:
            for v in x[r * FS:(r + 1) * FS]:
                body += struct.pack("<i", int(v))[:3]
        tal = f"+{r}\x14\x14\x00".encode() + b"".join(TALS.get(r, []))
        assert len(tal) <= ANN_BYTES
        body += tal.ljust(ANN_BYTES, b"\x00")
    path.write_bytes(h + body)

    data_uv, names = [], []
    for (lab, _dim, pmin, pmax, dmin, dmax, f), x in zip(SIGNALS, dig):
        phys = (x.astype(np.float64) - dmin) * (pmax - pmin) / (dmax - dmin) + pmin
        data_uv.append([float(v) for v in phys * (f if f is not None else 1.0)])
        names.append(lab)
    expected = {
        "generator": "tools/golden/io/make_bdf_fixture.py",
        "file": path.name,
        "sfreq": float(FS),
        "n_times": FS * N_RECORDS,
        "ch_names": names,
        "non_voltage": [s[0] for s in SIGNALS if s[6] is None],
        "digital": [[int(v) for v in x] for x in dig],
        "data_uv": data_uv,
        "events": EXPECTED_EVENTS,
    }
    (out / "numpy_small.json").write_text(json.dumps(expected, separators=(",", ":")) + "\n")
    print("wrote", path, path.stat().st_size, "bytes and numpy_small.json")

    try:
        import pyedflib
    except ImportError:
        print("pyedflib not installed: skipped the cross-check")
        return
    r = pyedflib.EdfReader(str(path))
    try:
        for i, (_lab, _d, _a, _b, _c, _e, f) in enumerate(SIGNALS):
            got = r.readSignal(i) * (f if f is not None else 1.0)
            np.testing.assert_allclose(got, data_uv[i], rtol=1e-9, atol=1e-9 * np.abs(data_uv[i]).max())
        onsets, _durs, texts = r.readAnnotations()
        assert list(texts) == ["stim", "3 target", "stim"], texts
        assert np.allclose(onsets, [0.5, 0.75, 1.5]), onsets
    finally:
        r.close()
    print("pyedflib reads the same values and annotations")


if __name__ == "__main__":
    main()
