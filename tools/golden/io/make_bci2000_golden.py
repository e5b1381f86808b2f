"""Golden values for the BCI2000 reader, from the independent Python reader shared/peer/bci2000.py.

Writes crates/oddball-io/tests/fixtures/bci2000_golden.json, which tests/bci2000_golden.rs compares
with the Rust reader (relative tolerance 1e-9).

The peer reader is imported from --peer (default: ../shared/peer beside the repository, i.e.
/work/shared/peer), which is put on sys.path; the data from --data (default
../shared/data/bci2000-samplefiles-p300). Only numpy is needed (see requirements.txt):

    python tools/golden/io/make_bci2000_golden.py [--peer DIR] [--data DIR] [--out FILE]

For each file it stores: shape, sampling rate, channel names, header fields, the first and last 5
samples of every channel, the samples at 16 fixed pseudo-random indices (numpy seed 0), per-channel
sums and sums of absolute values, every stimulus onset with code and target flag, every state's sum
and values at the fixed indices, a few parameters, TextToSpell and, for speller files, the text
decoded from the target codes of each character (NumberOfSequences x 12 flashes per character,
StimulusCode 1-6 = rows, 7-12 = columns of TargetDefinitions).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[3]
FILES = ["eeg3_1.dat", "eeg2_1.dat"]
PARAMS = ["SamplingRate", "SampleBlockSize", "NumberOfSequences", "TextToSpell", "SubjectName",
          "StorageTime", "NumMatrixRows", "NumMatrixColumns"]


def speller_text(f, onsets) -> str | None:
    p = f.params
    if "TargetDefinitions" not in p:
        return None
    symbols = [row[0] for row in p["TargetDefinitions"]["value"]]
    n_rows = int(p["NumMatrixRows"]["value"][0])
    n_cols = int(p["NumMatrixColumns"]["value"][0])
    per_char = int(float(p["NumberOfSequences"]["value"])) * (n_rows + n_cols)
    codes = f.states["StimulusCode"][onsets]
    targets = f.states["StimulusType"][onsets] > 0
    out = []
    for start in range(0, len(onsets), per_char):
        tc = codes[start:start + per_char][targets[start:start + per_char]]
        rows = np.bincount(tc[(tc >= 1) & (tc <= n_rows)], minlength=n_rows + 1)
        cols = np.bincount(tc[tc > n_rows] - n_rows, minlength=n_cols + 1)
        r, c = int(np.argmax(rows[1:])), int(np.argmax(cols[1:]))
        out.append(symbols[r * n_cols + c])
    return "".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--peer", default=str(REPO.parent / "shared" / "peer"))
    ap.add_argument("--data", default=str(REPO.parent / "shared" / "data" / "bci2000-samplefiles-p300"))
    ap.add_argument("--out", default=str(REPO / "crates/oddball-io/tests/fixtures/bci2000_golden.json"))
    args = ap.parse_args()
    sys.path.insert(0, args.peer)
    from bci2000 import read_dat, stimulus_onsets  # noqa: E402  (the peer's reader)

    out = {"generator": "tools/golden/io/make_bci2000_golden.py", "peer": "shared/peer/bci2000.py", "files": {}}
    for name in FILES:
        f = read_dat(str(Path(args.data) / name))
        n, c = f.data.shape
        idx = np.sort(np.random.default_rng(0).integers(0, n, 16))
        on = stimulus_onsets(f.states)
        rec = {
            "n_channels": int(c),
            "n_times": int(n),
            "sfreq": float(f.fs),
            "ch_names": list(f.ch_names),
            "header": {k: (v if isinstance(v, str) else int(v)) for k, v in f.header.items()},
            "first5": [[float(x) for x in f.data[:5, ch]] for ch in range(c)],
            "last5": [[float(x) for x in f.data[-5:, ch]] for ch in range(c)],
            "indices": [int(i) for i in idx],
            "at_indices": [[float(x) for x in f.data[idx, ch]] for ch in range(c)],
            "sums": [float(x) for x in f.data.sum(axis=0)],
            "abs_sums": [float(x) for x in np.abs(f.data).sum(axis=0)],
            "events": {
                "onset": [int(i) for i in on],
                "code": [int(x) for x in f.states["StimulusCode"][on]],
                "target": [bool(x) for x in (f.states["StimulusType"][on] > 0)],
            },
            "states": {
                k: {"sum": int(v.sum()), "at_indices": [int(x) for x in v[idx]]} for k, v in f.states.items()
            },
            "params": {k: f.params[k]["value"] for k in PARAMS if k in f.params},
            "text_to_spell": f.params.get("TextToSpell", {}).get("value"),
            "decoded_text": speller_text(f, on),
        }
        out["files"][name] = rec
        print(f"{name}: {n} samples x {c} channels, {len(on)} events, text {rec['decoded_text']!r}")
    Path(args.out).write_text(json.dumps(out, indent=None, separators=(",", ":")) + "\n")
    print("wrote", args.out, Path(args.out).stat().st_size, "bytes")


if __name__ == "__main__":
    main()
