"""Cross-check of the Rust EDF+ writer with pyedflib (run by hand; not part of cargo test).

    cargo run --release -p oddball-io --example to_edf_plus -- ../shared/data/bci2000-samplefiles-p300/eeg3_1.dat /tmp/eeg3_1.edf
    /tmp/venv-golden/bin/python tools/golden/io/check_written_edf.py /tmp/eeg3_1.edf \
        ../shared/data/bci2000-samplefiles-p300/eeg3_1.dat [--peer ../shared/peer]

Reads the EDF+ file with pyedflib and the .dat file with the independent peer reader
(shared/peer/bci2000.py) and checks: the channel labels and rate, every sample within half a
quantisation step ((physical max - physical min) / 65535 / 2 per channel), and one annotation per
stimulus onset at the same sample, with "target" exactly on the StimulusType = 1 onsets.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pyedflib

REPO = Path(__file__).resolve().parents[3]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("edf")
    ap.add_argument("dat")
    ap.add_argument("--peer", default=str(REPO.parent / "shared" / "peer"))
    args = ap.parse_args()
    sys.path.insert(0, args.peer)
    from bci2000 import read_dat, stimulus_onsets  # noqa: E402  (the peer's reader)

    f = read_dat(args.dat)
    n, c = f.data.shape
    r = pyedflib.EdfReader(args.edf)
    try:
        assert r.getSignalLabels() == list(f.ch_names), r.getSignalLabels()
        assert all(fs == f.fs for fs in r.getSampleFrequencies()), r.getSampleFrequencies()
        for i in range(c):
            step = (r.getPhysicalMaximum(i) - r.getPhysicalMinimum(i)) / 65535
            err = np.abs(r.readSignal(i)[:n] - f.data[:, i]).max()
            assert err <= step / 2 + 1e-9, (f.ch_names[i], err, step)
        onsets, _d, texts = r.readAnnotations()
    finally:
        r.close()
    on = stimulus_onsets(f.states)
    assert np.array_equal(np.round(onsets * f.fs).astype(int), on)
    codes = [int(t.split()[0]) for t in texts]
    assert codes == [int(x) for x in f.states["StimulusCode"][on]]
    is_target = [t.split()[1] == "target" for t in texts]
    assert is_target == [bool(x) for x in f.states["StimulusType"][on] > 0]
    print(f"ok: {c} channels x {n} samples within half a step, {len(on)} annotations ({sum(is_target)} targets)")


if __name__ == "__main__":
    main()
