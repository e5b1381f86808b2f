"""A small file in BCI Competition III data set II's layout (one block per character) and what a
reader must make of it, by scipy.io.loadmat and numpy: the blocks one after the other.

Writes crates/oddball-io/tests/fixtures/mat/competition3_small.mat (+ .json). Three characters
("C", "A", "T" of the competition's 6×6 matrix, codes 1-6 columns, 7-12 rows) of 120 samples and
4 channels; each block flashes the 12 codes once (4 samples on, 4 off) after 8 blank samples, in
a shuffled order; Signal is single, as in the competition files.
"""
import json
from pathlib import Path

import numpy as np
import scipy
import scipy.io

OUT = Path(__file__).resolve().parents[3] / "crates/oddball-io/tests/fixtures/mat"
MATRIX = ["ABCDEF", "GHIJKL", "MNOPQR", "STUVWX", "YZ1234", "56789_"]
TEXT = "CAT"
N_CHARS, N_TIMES, N_CH = len(TEXT), 120, 4

rng = np.random.default_rng(2005)
signal = rng.normal(scale=20.0, size=(N_CHARS, N_TIMES, N_CH)).astype(np.float32)
flashing = np.zeros((N_CHARS, N_TIMES))
code = np.zeros((N_CHARS, N_TIMES))
stype = np.zeros((N_CHARS, N_TIMES))
for i, ch in enumerate(TEXT):
    row = next(r for r, s in enumerate(MATRIX) if ch in s)
    col = MATRIX[row].index(ch)
    targets = {col + 1, row + 7}
    for k, c in enumerate(rng.permutation(np.arange(1, 13))):
        on = 8 + 8 * k
        flashing[i, on:on + 4] = 1
        code[i, on:on + 4] = c
        stype[i, on:on + 4] = 1 if c in targets else 0

path = OUT / "competition3_small.mat"
scipy.io.savemat(path, {"Signal": signal, "Flashing": flashing, "StimulusCode": code,
                        "StimulusType": stype, "TargetChar": TEXT}, do_compression=False)

back = scipy.io.loadmat(path)
assert back["Signal"].shape == (N_CHARS, N_TIMES, N_CH)
# The blocks one after the other: sample j of character i is sample i*N_TIMES + j.
data = back["Signal"].astype(np.float64).reshape(N_CHARS * N_TIMES, N_CH).T  # (n_channels, n_times)
fl = back["Flashing"].reshape(-1)
codes = back["StimulusCode"].reshape(-1)
types = back["StimulusType"].reshape(-1)
onsets = [t for t in range(len(fl)) if fl[t] != 0 and (t == 0 or fl[t - 1] == 0)]
golden = {
    "versions": {"numpy": np.__version__, "scipy": scipy.__version__},
    "sfreq": 240.0,
    "data": data.tolist(),
    "events": [[t, int(codes[t]), bool(types[t])] for t in onsets],
    "text": str(back["TargetChar"][0]),
    "flashes_per_character": 12,
}
(OUT / "competition3_small.json").write_text(json.dumps(golden))
print(f"wrote {path.name}: {N_CHARS} characters x {N_TIMES} samples x {N_CH} channels, "
      f"{len(onsets)} flashes, text {golden['text']!r}")
