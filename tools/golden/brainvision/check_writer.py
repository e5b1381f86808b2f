"""What MNE 1.13.2 reads from a BrainVision recording written by oddball's writer, and how
pybv 0.8.1 writes the same data.

Reads crates/oddball-io/tests/fixtures/brainvision/oddball_written.vhdr (written by
`oddball_io::write_brainvision` from the recording of `fixture_raw` in
crates/oddball-io/tests/brainvision_writer.rs; `ODDBALL_WRITE_FIXTURES=1 cargo test -p oddball-io
--test brainvision_writer committed` writes it again) and writes oddball_written.json beside it:

* "mne": what `mne.io.read_raw_brainvision` (preload) reads: channel names, units, sfreq,
  n_times, the data in µV, the annotations (onset sample, description) and
  `mne.events_from_annotations` (sample, code);
* "pybv": `pybv.write_brainvision` of MNE's data (fmt="binary_float32", resolution 1, unit µV,
  MULTIPLEXED) with the same markers (type and code from our .vmrk, size 1) into a temporary
  folder: whether its .eeg bytes equal ours, and the header and marker lines (comments, blank
  lines and the lines naming the files left out) that only one of the two writers writes.

Run from the workspace root:  python tools/golden/brainvision/check_writer.py
"""

import json
import pathlib
import tempfile

import mne
import numpy as np
import pybv

DIR = pathlib.Path("crates/oddball-io/tests/fixtures/brainvision")
STEM = "oddball_written"


def mne_reading():
    raw = mne.io.read_raw_brainvision(DIR / f"{STEM}.vhdr", preload=True, verbose="error")
    sfreq = raw.info["sfreq"]
    ann = [
        {"sample": int(round(a["onset"] * sfreq)), "description": a["description"]}
        for a in raw.annotations
    ]
    events, _ = mne.events_from_annotations(raw, verbose="error")
    return raw, {
        "ch_names": raw.ch_names,
        "units": [raw._orig_units[n] for n in raw.ch_names],
        "sfreq": float(sfreq),
        "n_times": int(raw.n_times),
        "data": [[float(v) for v in row] for row in raw.get_data() * 1e6],
        "annotations": ann,
        "events": [[int(e[0]), int(e[2])] for e in events],
    }


def markers(vmrk):
    """(type, code, 0-based onset) of each Stimulus/Response marker of a .vmrk."""
    out = []
    for line in vmrk.read_text(encoding="utf-8").splitlines():
        if line.startswith("Mk"):
            kind, desc, pos = line.split("=", 1)[1].split(",")[:3]
            if kind in ("Stimulus", "Response"):
                out.append((kind, int(desc[1:]), int(pos) - 1))
    return out


def lines(path):
    """The setting lines of a header or marker file: no comments, blank lines or file names."""
    keep = []
    for line in path.read_text(encoding="utf-8").splitlines():
        s = line.strip()
        if not s or s.startswith(";") or s.split("=")[0] in ("DataFile", "MarkerFile"):
            continue
        keep.append(s)
    return keep


def only(a, b):
    return [x for x in a if x not in b]


def pybv_comparison(raw):
    ours = {ext: DIR / f"{STEM}.{ext}" for ext in ("vhdr", "vmrk", "eeg")}
    events = [
        {"onset": onset, "description": code, "type": kind, "duration": 1}
        for kind, code, onset in markers(ours["vmrk"])
    ]
    with tempfile.TemporaryDirectory() as tmp:
        pybv.write_brainvision(
            data=raw.get_data(),
            sfreq=raw.info["sfreq"],
            ch_names=raw.ch_names,
            fname_base=STEM,
            folder_out=tmp,
            events=events,
            resolution=1,
            unit="µV",
            fmt="binary_float32",
            overwrite=True,
        )
        theirs = {ext: pathlib.Path(tmp) / f"{STEM}.{ext}" for ext in ("vhdr", "vmrk", "eeg")}
        a = np.frombuffer(ours["eeg"].read_bytes(), "<f4")
        b = np.frombuffer(theirs["eeg"].read_bytes(), "<f4")
        out = {
            "pybv": pybv.__version__,
            "data_bytes_equal": ours["eeg"].read_bytes() == theirs["eeg"].read_bytes(),
            "data_values_differing": int(np.sum(a != b)) if a.shape == b.shape else -1,
            "vhdr_only_ours": only(lines(ours["vhdr"]), lines(theirs["vhdr"])),
            "vhdr_only_pybv": only(lines(theirs["vhdr"]), lines(ours["vhdr"])),
            "vmrk_only_ours": only(lines(ours["vmrk"]), lines(theirs["vmrk"])),
            "vmrk_only_pybv": only(lines(theirs["vmrk"]), lines(ours["vmrk"])),
        }
    return out


def main():
    raw, reading = mne_reading()
    gold = {"mne_version": mne.__version__, "mne": reading, "pybv": pybv_comparison(raw)}
    path = DIR / f"{STEM}.json"
    path.write_text(json.dumps(gold, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    p = gold["pybv"]
    print(
        f"MNE {mne.__version__}: {len(reading['ch_names'])} ch x {reading['n_times']} at "
        f"{reading['sfreq']!r} Hz, events {reading['events']}"
    )
    print(
        f"pybv {p['pybv']}: data bytes equal {p['data_bytes_equal']} "
        f"({p['data_values_differing']} values differ); header lines only ours "
        f"{p['vhdr_only_ours']}, only pybv's {p['vhdr_only_pybv']}; marker lines only ours "
        f"{p['vmrk_only_ours']}, only pybv's {p['vmrk_only_pybv']}"
    )
    print(f"wrote {path} ({path.stat().st_size} B)")


if __name__ == "__main__":
    main()
