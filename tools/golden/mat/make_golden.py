"""Golden values for the MAT reader (crates/oddball-io/src/mat), from scipy.io.loadmat.

Writes small MAT fixtures to crates/oddball-io/tests/fixtures/mat/ and, beside them, golden.json with
what scipy.io.loadmat reads from each; tests/mat_golden.rs compares the Rust reader with it.

    python tools/golden/mat/make_golden.py [--data DIR]

Fixtures:
* v5.mat — scipy.io.savemat, format 5, uncompressed: int8/int16/uint8/uint16/int32/uint32/int64/
  uint64/single/double arrays, a 2-D and a 3-D array, a complex array, a logical array, an empty
  array, char arrays (one row, two rows, non-ASCII), a struct (numeric, char and nested struct
  fields), a 1x2 struct array, a cell array.
* v7.mat — the same variables, compressed (each in a miCOMPRESSED zlib element).
* narrow.mat — written byte by byte here, as MATLAB writes: class double stored as miINT16 and
  miUINT8 (the BCI Competition files' layout), class single stored as miINT16, small data elements
  (4-byte name, 1x1 dims), a char array stored as miUTF8, and a big-endian twin narrow_be.mat.
* bci_small.mat — a tiny recording in the BCI Competition layout (compressed), spelling "BZ".
* v73.mat — the 512-byte user block of a v7.3 (HDF5) file and the HDF5 signature; scipy refuses it.

For each variable golden.json holds: class (the numpy dtype with mat_dtype=True, i.e. MATLAB's
class), stored (the dtype with mat_dtype=False, i.e. the element type in the file), shape, and the
values flattened column-major (order 'F'); complex values as [re, im]; char arrays as the list of
their characters (column-major); structs as field -> golden of the field value (per element for
struct arrays); cells as a list of goldens.

With --data (default ../shared/data beside the repository) it also stores checks of the real
BCI Competition II IIb files AAS010R01.mat and AAS012R03.mat as scipy reads them: shapes and stored
dtypes, signal sums, a few samples, state sums, onset count, target count and the text decoded from
the targets (codes 1-6 columns, 7-12 rows) — a handful of numbers, not the data.
"""
from __future__ import annotations

import argparse
import json
import struct
from pathlib import Path

import numpy as np
import scipy
import scipy.io as sio

REPO = Path(__file__).resolve().parents[3]
OUT = REPO / "crates/oddball-io/tests/fixtures/mat"


def variables():
    return {
        "i8": np.array([[-128, -1, 0, 127]], dtype=np.int8),
        "i16_2d": np.arange(-6, 6, dtype=np.int16).reshape(3, 4),
        "u8": np.array([0, 1, 200, 255], dtype=np.uint8).reshape(4, 1),
        "u16": np.array([[0, 65535], [1, 40000]], dtype=np.uint16),
        "i32": np.array([[-2147483648, 7, 2147483647]], dtype=np.int32),
        "u32": np.array([[4294967295, 3]], dtype=np.uint32),
        "i64": np.array([[-(2**40), 5]], dtype=np.int64),
        "u64": np.array([[2**40 + 1, 9]], dtype=np.uint64),
        "f32": np.array([[1.5, -2.25, 3.0e-3]], dtype=np.float32),
        "f64_3d": (np.arange(24, dtype=np.float64) * 0.5 - 3).reshape(2, 3, 4),
        "cplx": np.array([[1 + 2j, -3.5 - 0.25j]]),
        "logic": np.array([[True, False, True]]),
        "empty": np.zeros((0, 0)),
        "scalar": np.array(3.25),
        "text": "hello MAT",
        "text2": np.array(["ab", "cd"]),
        "umlaut": "µV über",
        "st": {"x": np.array([[1.0, 2.0, 3.0]]), "name": "Cz", "n": np.int32(42),
               "inner": {"k": np.array([[7]], dtype=np.uint8)}},
        "sa": np.array([[(1.0, "a"), (2.0, "bc")]], dtype=[("v", object), ("s", object)]),
        "cell": np.array([[np.array([[1.0, 2.0]]), "xy", np.array([[5]], dtype=np.int16)]],
                         dtype=object),
    }


# --- a hand-written MAT v5 file, the way MATLAB writes narrow types -------------------------------

MI = {"int8": 1, "uint8": 2, "int16": 3, "uint16": 4, "int32": 5, "uint32": 6, "single": 7,
      "double": 9, "utf8": 16}
CLASS = {"double": 6, "single": 7, "char": 4}


def element(e: str, mi: int, data: bytes, small_ok: bool = True) -> bytes:
    if small_ok and len(data) <= 4:
        # Small data element: byte count in the upper 16 bits of the first word, type below.
        return struct.pack(e + "I", (len(data) << 16) | mi) + data.ljust(4, b"\0")
    pad = (-len(data)) % 8
    return struct.pack(e + "II", mi, len(data)) + data + b"\0" * pad


def matrix(e: str, name: str, cls: str, dims, mi_name: str, payload: bytes) -> bytes:
    body = element(e, MI["uint32"], struct.pack(e + "II", CLASS[cls], 0), small_ok=False)
    body += element(e, MI["int32"], struct.pack(e + "i" * len(dims), *dims), small_ok=False)
    body += element(e, MI["int8"], name.encode())
    body += element(e, MI[mi_name], payload)
    return struct.pack(e + "II", 14, len(body)) + body


def narrow_file(path: Path, big_endian: bool) -> None:
    e = ">" if big_endian else "<"
    header = b"MATLAB 5.0 MAT-file, written by tools/golden/mat/make_golden.py".ljust(116, b" ")
    header += b"\0" * 8 + (b"\x01\x00MI" if big_endian else b"\x00\x01IM")
    sig = np.array([[-128, 608], [64, -32], [160, 1000]], dtype=np.int16)  # 3 x 2, class double
    f = header
    f += matrix(e, "sig", "double", [3, 2], "int16",
                sig.flatten(order="F").astype(e + "i2").tobytes())
    f += matrix(e, "code", "double", [1, 5], "uint8", bytes([0, 1, 12, 0, 7]))
    f += matrix(e, "w", "single", [1, 1], "int16", struct.pack(e + "h", -7))
    f += matrix(e, "utf", "char", [1, 3], "utf8", "aµb".encode("utf-8"))  # 3 chars in 4 bytes
    path.write_bytes(f)


# --- golden values as scipy reads them ------------------------------------------------------------

def golden(cls_val, raw_val):
    """The golden of one value: cls_val read with mat_dtype=True, raw_val with mat_dtype=False."""
    if isinstance(cls_val, np.ndarray) and cls_val.dtype.names:
        fields = list(cls_val.dtype.names)
        return {
            "kind": "struct",
            "shape": list(cls_val.shape),
            "fields": fields,
            "elements": [
                {f: golden(c[f], r[f]) for f in fields}
                for c, r in zip(cls_val.flatten(order="F"), raw_val.flatten(order="F"))
            ],
        }
    if isinstance(cls_val, np.ndarray) and cls_val.dtype == object:
        return {
            "kind": "cell",
            "shape": list(cls_val.shape),
            "cells": [golden(c, r) for c, r in
                      zip(cls_val.flatten(order="F"), raw_val.flatten(order="F"))],
        }
    if isinstance(cls_val, np.ndarray) and cls_val.dtype.kind == "U":
        return {
            "kind": "char",
            "shape": list(cls_val.shape),
            "chars": [str(c) for c in cls_val.flatten(order="F")],
        }
    # Values as stored (mat_dtype=False): casting complex data to the class would drop the
    # imaginary part.
    flat = raw_val.flatten(order="F")
    if raw_val.dtype.kind == "c":
        values = [[float(v.real), float(v.imag)] for v in flat]
    elif raw_val.dtype.kind in "iub":
        values = [int(v) for v in flat]
    else:
        values = [float(v) for v in flat]
    return {
        "kind": "numeric",
        "class": cls_val.dtype.name,
        "stored": raw_val.dtype.name,
        "shape": list(cls_val.shape),
        "values": values,
    }


def read_golden(path: Path):
    kw = dict(chars_as_strings=False, squeeze_me=False, struct_as_record=True)
    cls = sio.loadmat(path, mat_dtype=True, **kw)
    raw = sio.loadmat(path, mat_dtype=False, **kw)
    whos = {name: (shape, c) for name, shape, c in sio.whosmat(path)}
    names = [k for k in cls if not k.startswith("__")]
    return {
        "header": cls["__header__"].decode("latin-1"),
        "variables": {
            k: {**golden(cls[k], raw[k]), "whos_class": whos[k][1]} for k in names
        },
        "order": names,
    }


def real_checks(data: Path):
    out = {}
    matrix6 = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"]
    for name in ["AAS010R01.mat", "AAS012R03.mat"]:
        p = data / "bci-competition-ii-iib" / name
        if not p.exists():
            print(f"skipping {p}: not found")
            continue
        m = sio.loadmat(p)
        sig = m["signal"]
        f = m["Flashing"].ravel().astype(int)
        code = m["StimulusCode"].ravel().astype(int)
        on = [t for t in range(len(f)) if f[t] and (t == 0 or not f[t - 1])]
        c = {
            "variables": sorted(k for k in m if not k.startswith("__")),
            "signal_shape": list(sig.shape),
            "signal_stored": str(sig.dtype),
            "signal_class": sio.whosmat(p) and dict((n, cl) for n, _, cl in sio.whosmat(p))["signal"],
            "signal_sum": int(sig.astype(np.int64).sum()),
            "signal_abs_sum": int(np.abs(sig.astype(np.int64)).sum()),
            "signal_channel_sums": [int(s) for s in sig.astype(np.int64).sum(axis=0)[:4]],
            "signal_first_row": [int(v) for v in sig[0, :5]],
            "signal_last_row": [int(v) for v in sig[-1, -5:]],
            "signal_at": [[t, ch, int(sig[t, ch])] for t, ch in [(1000, 10), (20000, 50), (5, 63)]],
            "state_sums": {k: int(m[k].astype(np.int64).sum()) for k in
                           ["StimulusCode", "Flashing", "PhaseInSequence", "trialnr"]
                           + (["StimulusType"] if "StimulusType" in m else [])},
            "n_onsets": len(on),
            "first_onsets": [[t, int(code[t])] for t in on[:3]],
            "strings": {k: str(m[k][0]) for k in m if not k.startswith("__") and m[k].dtype.kind == "U"},
        }
        if "StimulusType" in m:
            st = m["StimulusType"].ravel()
            c["n_targets"] = int(sum(1 for t in on if st[t]))
            text = ""
            for b in range(0, len(on), 180):
                block = on[b:b + 180]
                cols = np.bincount([code[t] for t in block if st[t] and code[t] <= 6], minlength=13)
                rows = np.bincount([code[t] for t in block if st[t] and code[t] > 6], minlength=13)
                text += matrix6[int(rows.argmax()) - 7][int(cols.argmax()) - 1]
            c["text"] = text
        out[name] = c
    return out


def bci_small(path: Path) -> None:
    """A tiny file in the BCI Competition layout: 3 channels, 2 characters ("B", "Z") of two
    sequences of 12 flashes (5 samples on, 10 apart), a 60-sample pause between characters,
    codes 1-6 columns and 7-12 rows, StimulusType 1 on the target's row and column."""
    matrix6 = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"]
    rng = np.random.default_rng(0)
    n = 700
    code = np.zeros((n, 1), dtype=np.uint8)
    flashing = np.zeros((n, 1), dtype=np.uint8)
    stype = np.zeros((n, 1), dtype=np.uint8)
    t = 20
    for ch in "BZ":
        r = next(i for i, row in enumerate(matrix6) if ch in row)
        c = matrix6[r].index(ch)
        for _ in range(2):
            for k in rng.permutation(12) + 1:
                code[t:t + 5] = k
                flashing[t:t + 5] = 1
                stype[t:t + 5] = int(k == c + 1 or k == r + 7)
                t += 10
        t += 60
    signal = rng.integers(-500, 500, size=(n, 3)).astype(np.int16)
    sio.savemat(path, {"signal": signal, "StimulusCode": code, "Flashing": flashing,
                       "StimulusType": stype, "filename": "bci_small.mat"},
                format="5", do_compression=True)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=REPO.parent / "shared/data")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    v = variables()
    sio.savemat(OUT / "v5.mat", v, format="5", do_compression=False)
    sio.savemat(OUT / "v7.mat", v, format="5", do_compression=True)
    narrow_file(OUT / "narrow.mat", big_endian=False)
    narrow_file(OUT / "narrow_be.mat", big_endian=True)
    bci_small(OUT / "bci_small.mat")
    v73 = (b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Wed Nov 25 12:00:00 2026 HDF5 schema 1.00 ."
           .ljust(116, b" ") + b"\0" * 8 + b"\x00\x02IM").ljust(512, b"\0") + b"\x89HDF\r\n\x1a\n"
    (OUT / "v73.mat").write_bytes(v73)
    try:
        sio.loadmat(OUT / "v73.mat")
        v73_scipy = "read"
    except NotImplementedError as e:
        v73_scipy = f"NotImplementedError: {e}"
    gold = {
        "versions": {"scipy": scipy.__version__, "numpy": np.__version__},
        "files": {n: read_golden(OUT / n) for n in
                  ["v5.mat", "v7.mat", "narrow.mat", "narrow_be.mat", "bci_small.mat"]},
        "v73_scipy": v73_scipy,
        "real": real_checks(args.data),
    }
    (OUT / "golden.json").write_text(json.dumps(gold, ensure_ascii=False) + "\n")
    for p in sorted(OUT.iterdir()):
        print(f"{p.stat().st_size:8d}  {p.relative_to(REPO)}")


if __name__ == "__main__":
    main()
