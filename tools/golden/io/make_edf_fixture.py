"""A small EDF+ file written by pyedflib, and the values pyedflib reads back from it.

Writes crates/oddball-io/tests/fixtures/pyedflib_small.edf (about 3 KB) and
pyedflib_small.json; tests/edf_fixtures.rs reads the EDF+ file with the Rust reader and compares.

    python -m venv /tmp/venv-golden && /tmp/venv-golden/bin/pip install -r tools/golden/io/requirements.txt
    /tmp/venv-golden/bin/python tools/golden/io/make_edf_fixture.py [--out-dir DIR]

The file: 3 signals at 32 Hz for 3 s (data records of 1 s) with different units and ranges:
  Fz  uV, physical -200..200,     digital -32768..32767
  Cz  mV, physical -0.25..0.25,   digital -32768..32767  (the reader must multiply by 1000)
  Pz  uV, physical -100..300,     digital -2048..2047    (asymmetric, 12-bit range)
plus two "EDF Annotations" signals holding annotations with and without durations, numeric, free-text and "CODE target: LABEL" forms.

Expected values come from pyedflib's own reader (readSignal, physical units) times the unit
factor to microvolts, and from readAnnotations. The expected events follow the oddball-io
annotation rules (documented in crates/oddball-io/src/edf/mod.rs) and are written out by hand below.
"""
from __future__ import annotations

import argparse
import datetime
import json
from pathlib import Path

import numpy as np
import pyedflib

REPO = Path(__file__).resolve().parents[3]
FS = 32
SECONDS = 3
SIGNALS = [
    # label, dimension, phys_min, phys_max, dig_min, dig_max, to-uV factor
    ("Fz", "uV", -200.0, 200.0, -32768, 32767, 1.0),
    ("Cz", "mV", -0.25, 0.25, -32768, 32767, 1000.0),
    ("Pz", "uV", -100.0, 300.0, -2048, 2047, 1.0),
]
ANNOTATIONS = [  # onset s, duration s (-1 = none), text
    (0.5, -1, "1"),
    (1.0, 0.25, "2 target"),
    (1.25, -1, "stim"),
    (2.5, -1, "stim"),
    (2.75, -1, "7 nontarget: X"),
    (2.8125, -1, "blink"),
]
# What oddball-io must make of them at 32 Hz: onset sample = round(onset * 32); numeric codes
# as written; free texts get codes from 8 (one above the largest numeric code, 7) in order of
# first appearance: stim = 8, blink = 9.
EXPECTED_EVENTS = [
    {"onset": 16, "code": 1, "target": None, "label": None},
    {"onset": 32, "code": 2, "target": True, "label": None},
    {"onset": 40, "code": 8, "target": None, "label": "stim"},
    {"onset": 80, "code": 8, "target": None, "label": "stim"},
    {"onset": 88, "code": 7, "target": False, "label": "X"},
    {"onset": 90, "code": 9, "target": None, "label": "blink"},
]


def signals() -> list[np.ndarray]:
    t = np.arange(FS * SECONDS) / FS
    return [
        150.0 * np.sin(2 * np.pi * 3 * t) + 20.0 * t,
        0.2 * np.cos(2 * np.pi * 5 * t),
        100.0 + 150.0 * np.sin(2 * np.pi * 1 * t) * np.exp(-t),
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=str(REPO / "crates/oddball-io/tests/fixtures"))
    args = ap.parse_args()
    out = Path(args.out_dir)
    edf_path = out / "pyedflib_small.edf"

    w = pyedflib.EdfWriter(str(edf_path), len(SIGNALS), file_type=pyedflib.FILETYPE_EDFPLUS)
    w.setSignalHeaders([
        {"label": lab, "dimension": dim, "sample_frequency": FS, "physical_min": pmin,
         "physical_max": pmax, "digital_min": dmin, "digital_max": dmax,
         "transducer": "AgAgCl", "prefilter": "HP:0.1Hz"}
        for lab, dim, pmin, pmax, dmin, dmax, _ in SIGNALS
    ])
    # edflib stores at most one annotation per data record and annotation signal: two
    # annotation signals make room for the six annotations (and test that both are read).
    w.set_number_of_annotation_signals(2)
    w.setStartdatetime(datetime.datetime(2020, 1, 2, 3, 4, 5))
    w.setPatientCode("P001")
    w.setTechnician("golden")
    w.writeSamples(signals())
    for onset, dur, text in ANNOTATIONS:
        w.writeAnnotation(onset, dur, text)
    w.close()

    r = pyedflib.EdfReader(str(edf_path))
    try:
        assert len(r.readAnnotations()[0]) == len(ANNOTATIONS), r.readAnnotations()
        n = r.getNSamples()
        assert all(int(k) == FS * SECONDS for k in n), n
        data = [list(map(float, r.readSignal(i) * SIGNALS[i][6])) for i in range(len(SIGNALS))]
        onsets, durations, texts = r.readAnnotations()
        expected = {
            "generator": "tools/golden/io/make_edf_fixture.py",
            "pyedflib": pyedflib.__version__,
            "file": edf_path.name,
            "sfreq": float(r.getSampleFrequency(0)),
            "n_times": int(n[0]),
            "ch_names": [r.getLabel(i) for i in range(len(SIGNALS))],
            "dimensions": [r.getPhysicalDimension(i) for i in range(len(SIGNALS))],
            "data_uv": data,
            "annotations": [
                {"onset": float(o), "duration": (float(d) if d >= 0 else None), "text": str(t)}
                for o, d, t in zip(onsets, durations, texts)
            ],
            "events": EXPECTED_EVENTS,
            "patient_code": r.getPatientCode(),
        }
    finally:
        r.close()
    (out / "pyedflib_small.json").write_text(json.dumps(expected, separators=(",", ":")) + "\n")
    print("wrote", edf_path, edf_path.stat().st_size, "bytes and pyedflib_small.json")


if __name__ == "__main__":
    main()
