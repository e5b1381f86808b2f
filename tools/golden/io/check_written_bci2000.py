"""Cross-check of the Rust BCI2000 writer with the peer reader (run by hand; not part of cargo test).

    cargo test -p oddball-io --test bci2000_writer small_file_for_the_peer_reader
    /tmp/venv-golden/bin/python tools/golden/io/check_written_bci2000.py \
        [target/tmp/bci2000_written_small.dat] [--peer ../shared/peer]

The Rust test writes a small BCI2000 v1.1 float32 file (4 channels x 50 samples, channel names
that need URL-encoding, StimulusCode/StimulusType from `stimulus_states`, a 2-bit, a 32-bit and a
1-bit state, extra parameters: a string, a list, a labelled matrix, an empty value, a caller's
SampleBlockSize) and, beside it, a .json of the values it was given. This script reads the .dat
with the independent peer reader (shared/peer/bci2000.py) and checks against the .json: the first
line and HeaderLen (the header ends with CRLF CRLF), the file size, the channel names and rate,
every sample equal to float32(input) and the largest rounding equal to the writer's summary, gain 1
and offset 0, every state (a `Running` state that is 1 throughout comes first) packed bit by bit in
order, the stimulus onsets, codes and targets, and the parameters' decoded values.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[3]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dat", nargs="?", default=str(REPO / "target" / "tmp" / "bci2000_written_small.dat"))
    ap.add_argument("--peer", default=str(REPO.parent / "shared" / "peer"))
    args = ap.parse_args()
    sys.path.insert(0, args.peer)
    from bci2000 import read_dat, stimulus_onsets  # noqa: E402  (the peer's reader)

    dat = Path(args.dat)
    want = json.loads(dat.with_suffix(".json").read_text())
    blob = dat.read_bytes()
    f = read_dat(str(dat))
    n, c = f.data.shape

    # Header layout.
    first = blob[: blob.index(b"\r\n")].decode("ascii")
    m = re.fullmatch(r"BCI2000V= 1\.1 HeaderLen= (\d+) SourceCh= (\d+) StatevectorLen= (\d+) DataFormat= float32", first)
    assert m, first
    hlen, svlen = int(m.group(1)), int(m.group(3))
    assert blob.index(b"\r\n\r\n") + 4 == hlen, (blob.index(b"\r\n\r\n"), hlen)
    assert b"\n" not in blob[:hlen].replace(b"\r\n", b""), "bare LF in the header"
    assert len(blob) == want["bytes"] == hlen + n * (4 * c + svlen), (len(blob), want["bytes"])
    assert f.header["DataFormat"] == "float32"

    # Channels, rate, samples.
    assert f.ch_names == want["ch_names"], f.ch_names
    assert f.fs == want["sfreq"], f.fs
    x = np.asarray(want["samples_uv"], dtype=np.float64).T
    assert f.data.shape == x.shape, (f.data.shape, x.shape)
    assert np.array_equal(f.data, x.astype(np.float32).astype(np.float64)), "samples differ from float32(input)"
    rounding = float(np.abs(f.data - x).max())
    assert rounding == want["max_rounding_uv"], (rounding, want["max_rounding_uv"])
    assert f.params["SourceChGain"]["value"] == [1.0] * c
    assert f.params["SourceChOffset"]["value"] == [0.0] * c
    assert f.params["SamplingRate"]["value"] == f"{want['sfreq']:g}Hz"
    assert int(f.params["SourceCh"]["value"]) == c
    assert int(f.params["StateVectorLength"]["value"]) == svlen

    # States: Running first, then the given ones, bit by bit.
    given = {w["name"]: w for w in want["states"]}
    names = list(f.state_defs)
    assert names == ["Running", *given], names
    assert np.all(f.states["Running"] == 1)
    bit = 0
    for name in names:
        length, default, byte, bitloc = f.state_defs[name]
        assert (byte, bitloc) == divmod(bit, 8), (name, byte, bitloc, bit)
        assert default == f.states[name][0], (name, default)
        bit += length
        if name in given:
            w = given[name]
            assert length == w["bits"], (name, length)
            assert np.array_equal(f.states[name], np.asarray(w["values"], dtype=np.int64)), name
    assert svlen == (bit + 7) // 8, (svlen, bit)

    # Events.
    on = stimulus_onsets(f.states)
    got = [[int(t), int(f.states["StimulusCode"][t]), bool(f.states["StimulusType"][t])] for t in on]
    assert got == want["events"], got

    # Parameters.
    p = want["parameters"]
    assert f.params["Paradigm"]["value"] == p["Paradigm"]
    assert f.params["BulbNames"]["value"] == p["BulbNames"]
    assert f.params["BulbDirections"]["value"] == p["BulbDirections"]
    assert f.params["BulbDirections"]["labels"] == (["up", "down", "left", "right"], ["x", "y"])
    assert f.params["Note"]["value"] == p["Note"]
    assert f.params["SampleBlockSize"]["value"] == p["SampleBlockSize"]

    print(
        f"OK: {dat.name}: {c} channels x {n} samples = float32(input) (max rounding {rounding:.3g} uV), "
        f"{len(names)} states in {svlen} bytes, {len(on)} events ({sum(g[2] for g in got)} targets), "
        f"{len(f.params)} parameters, HeaderLen {hlen}"
    )


if __name__ == "__main__":
    main()
