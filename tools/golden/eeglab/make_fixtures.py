"""EEGLAB fixtures and what MNE 1.13.2 reads from them.

Writes into crates/oddball-io/tests/fixtures/eeglab/ (run from the workspace root):

* mne_export.set: mne.export.export_raw(fmt="eeglab") (eeglabio 0.1.4: top-level variables,
  single-precision data inside the .set) of a 4-channel 256 Hz RawArray with annotations
  (texts, a numeric text, an onset between samples, one outside the data);
* struct_fdt.set + struct_fdt.fdt: scipy.io.savemat of a struct variable `EEG` (the older
  EEGLAB layout) whose `data` names the .fdt, written here as float32 channels x points
  column-major; numeric and text event types, a fractional latency, a `boundary` event;
* epoched.set: trials = 2, which read_raw_eeglab refuses (as the Rust reader must).

Each readable file gets what mne.io.read_raw_eeglab(preload=True) reads: channel names, sfreq,
the data in µV, the annotations (sample = onset × sfreq, description) and
mne.events_from_annotations's samples.
"""

import json
import pathlib

import mne
import numpy as np
import scipy
import scipy.io

OUT = pathlib.Path("crates/oddball-io/tests/fixtures/eeglab")
OUT.mkdir(parents=True, exist_ok=True)


def describe(name):
    raw = mne.io.read_raw_eeglab(OUT / name, preload=True, verbose="error")
    sfreq = raw.info["sfreq"]
    events, event_id = mne.events_from_annotations(raw, verbose="error")
    by_code = {v: k for k, v in event_id.items()}
    return {
        "file": name,
        "ch_names": raw.ch_names,
        "sfreq": float(sfreq),
        "n_times": int(raw.n_times),
        "data": [[float(v) for v in row] for row in raw.get_data() * 1e6],
        "annotations": [
            {"onset_s": float(a["onset"]), "description": a["description"]}
            for a in raw.annotations
        ],
        "events": [[int(e[0]), by_code[int(e[2])]] for e in events],
    }


def mne_export(rng):
    names = ["Fz", "Cz", "Pz", "Oz"]
    raw = mne.io.RawArray(
        rng.normal(0, 20e-6, (4, 120)), mne.create_info(names, 256.0, "eeg"), verbose="error"
    )
    raw.set_annotations(
        mne.Annotations(
            onset=[10 / 256, 20 / 256, 30.3 / 256, 50 / 256, 80 / 256, 119 / 256],
            duration=[0.0] * 6,
            description=["stim", "7", "target", "stim", "3 nontarget: A", "last"],
        )
    )
    mne.export.export_raw(OUT / "mne_export.set", raw, fmt="eeglab", overwrite=True, verbose="error")
    return describe("mne_export.set")


def struct_fdt(rng):
    n_ch, n_times = 3, 50
    data = rng.normal(0, 25, (n_ch, n_times)).astype(np.float32)  # µV
    # channels x points column-major: all channels of sample 0, then of sample 1, ...
    data.astype("<f4").ravel(order="F").tofile(OUT / "struct_fdt.fdt")
    chanlocs = np.array(
        [("C3",), ("C4",), ("EOG",)], dtype=[("labels", object)]
    ).reshape(1, -1)
    events = np.zeros((1, 5), dtype=[("type", object), ("latency", object), ("duration", object)])
    for i, (t, lat) in enumerate(
        [(1.0, 5.0), ("target", 12.7), (2.0, 20.0), ("boundary", 30.5), ("target", 41.0)]
    ):
        events[0, i] = (t, float(lat), 0.0)
    eeg = {
        "setname": "struct layout",
        "nbchan": float(n_ch),
        "pnts": float(n_times),
        "trials": 1.0,
        "srate": 200.0,
        "xmin": 0.0,
        "data": "struct_fdt.fdt",
        "chanlocs": chanlocs,
        "event": events,
        "ref": "common",
    }
    scipy.io.savemat(OUT / "struct_fdt.set", {"EEG": eeg}, appendmat=False)
    return describe("struct_fdt.set")


def epoched(rng):
    eeg = {
        "nbchan": 2.0,
        "pnts": 10.0,
        "trials": 2.0,
        "srate": 100.0,
        "data": rng.normal(0, 10, (2, 10, 2)),
        "chanlocs": np.array([("A",), ("B",)], dtype=[("labels", object)]).reshape(1, -1),
    }
    scipy.io.savemat(OUT / "epoched.set", eeg, appendmat=False)
    try:
        mne.io.read_raw_eeglab(OUT / "epoched.set", verbose="error")
        return "read"
    except Exception as e:  # noqa: BLE001
        return f"{type(e).__name__}: {e}"


def main():
    rng = np.random.default_rng(20260302)
    gold = {
        "mne": mne.__version__,
        "scipy": scipy.__version__,
        "fixtures": [mne_export(rng), struct_fdt(rng)],
        "epoched_mne": epoched(rng),
    }
    path = OUT / "golden.json"
    path.write_text(json.dumps(gold, indent=1))
    for f in gold["fixtures"]:
        print(f"{f['file']}: {len(f['ch_names'])} ch x {f['n_times']} at {f['sfreq']} Hz, "
              f"events {f['events']}")
    print(f"epoched.set: MNE says {gold['epoched_mne']}")
    print(f"wrote {path} ({path.stat().st_size} B)")


if __name__ == "__main__":
    main()
