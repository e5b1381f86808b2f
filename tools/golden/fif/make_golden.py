#!/usr/bin/env python3
"""Write small FIF raw files with MNE's own writer (`Raw.save`) and what `mne.io.read_raw_fif` reads
from them, for the Rust FIF reader's golden test (crates/oddball-io/tests/fif_golden.rs).

    python3 -m venv /tmp/venv-fif && /tmp/venv-fif/bin/pip install -r tools/golden/fif/requirements.txt
    /tmp/venv-fif/bin/python tools/golden/fif/make_golden.py

Writes, under crates/oddball-io/tests/fixtures/fif/, each FIF file and a JSON file of the same stem:

* float_raw.fif: 3 EEG (one named with 20 characters, so MNE writes FIFFB_CH_INFO blocks with the
  full name), 1 EOG, 1 STIM (`STI 014`) at 256 Hz, 200 samples in buffers of 64 samples, saved
  as float32 (`fmt="single"`); meas_date set; annotations, one with a colon in its text (stored
  as `{COLON}`), one `CODE target` text (one after the end is dropped by MNE before saving);
* short_raw.fif / int_raw.fif / double_raw.fif: the same raw saved with `fmt="short"` (stored as
  FIFFT_DAU_PACK16), `"int"`, `"double"`; EEG `cal` set to 1e-8 and 2e-8 and one `range` of 2
  before saving, so the integers keep the signal;
* cropped_raw.fif: a 400-sample raw cropped from 0.5 s (first_samp 128), meas_date set, an
  annotation overlapping the crop start (MNE clips it to the first sample);
* nodate_raw.fif: the same crop with meas_date None (annotations without orig_time);
* skip_raw.fif: a `BAD_ACQ_SKIP` annotation on whole buffers, so MNE writes a FIFF_DATA_SKIP;
* split_raw.fif + split_raw-1.fif + split_raw-2.fif: `split_size` just over MNE's 1 MiB cushion,
  so each part holds one or two buffers; the JSON is for the whole recording.

The JSON holds: sfreq, every channel name and type, first_samp, n_times, meas_date, the EEG in µV
(`get_data(picks="eeg") * 1e6`, full precision), `find_events` on the stim channel with MNE's
defaults (consecutive="increasing") except shortest_event=1, the annotations as stored
(`mne.read_annotations`), and the data sample of every annotation MNE keeps
(`events_from_annotations(regexp=None)` minus first_samp), and the zero-filled skips.
FIF files hold the file id's time stamp, so a new run gives new bytes and the same values.
"""

import json
from pathlib import Path

import mne
import numpy as np

ROOT = Path(__file__).resolve().parents[3]
OUT = ROOT / "crates" / "oddball-io" / "tests" / "fixtures" / "fif"
SFREQ = 256.0
BUF = 0.25  # 64 samples per buffer
MEAS_DATE = 1_700_000_000.5

mne.set_log_level("ERROR")


def base_raw(n, seed=0):
    rng = np.random.default_rng(seed)
    names = ["Fz", "Cz", "Pz-long-channel-name", "EOG1", "STI 014"]
    info = mne.create_info(names, SFREQ, ["eeg", "eeg", "eeg", "eog", "stim"])
    data = rng.normal(0, 20e-6, (5, n))
    stim = np.zeros(n)
    # Rises 0 -> 1, 0 -> 2 (one sample), 0 -> 3 -> 5 (an increase: two events), 5 -> 4 (a
    # decrease: no event), 4 -> 0, and 9 at the last sample.
    stim[10:14] = 1
    stim[40] = 2
    stim[70:73] = 3
    stim[73:76] = 5
    stim[76:80] = 4
    stim[120:125] = 7
    stim[n - 1] = 9
    if n >= 400:
        stim[200:204] = 6
    data[4] = stim
    raw = mne.io.RawArray(data, info)
    raw.set_meas_date(MEAS_DATE)
    return raw


def annotate(raw, onsets, durations, texts):
    raw.set_annotations(
        mne.Annotations(onsets, durations, texts, orig_time=raw.info["meas_date"])
    )


def describe(fname, raw, dedupe=False):
    """What read_raw_fif reads from `raw`'s file (raw is the re-read object)."""
    first = int(raw.first_samp)
    eeg = raw.get_data(picks="eeg") * 1e6
    events = mne.find_events(raw, shortest_event=1, verbose="ERROR")
    stored = mne.read_annotations(fname)
    ann_events = []
    if len(raw.annotations):
        ev, ids = mne.events_from_annotations(raw, regexp=None, verbose="ERROR")
        names = {v: k for k, v in ids.items()}
        rows = [(int(s) - first, names[int(c)]) for s, _, c in ev]
        if dedupe:  # the skip's annotation: stored once, and added again by MNE
            rows = sorted(set(rows))
        ann_events = [list(r) for r in rows]
    skips = []
    for extra in raw._raw_extras:
        b = extra["bounds"]
        for i, ent in enumerate(extra["ent"]):
            if ent is None:
                skips.append([int(b[i]) - first, int(b[i + 1] - b[i])])
    md = raw.info["meas_date"]
    return {
        "file": Path(fname).name,
        "sfreq": raw.info["sfreq"],
        "ch_names": raw.ch_names,
        "ch_types": raw.get_channel_types(),
        "eeg_names": [raw.ch_names[i] for i in mne.pick_types(raw.info, eeg=True)],
        "first_samp": first,
        "n_times": int(raw.n_times),
        "meas_date": None if md is None else [int(md.timestamp() // 1), md.microsecond],
        "orig_format": raw.orig_format,
        "cals": [float(c) for c in raw._cals],
        "eeg_uv": eeg.tolist(),
        "stim_events": [[int(s) - first, int(c)] for s, _, c in events],
        "annotations": {
            "onset": [float(x) for x in stored.onset],
            "duration": [float(x) for x in stored.duration],
            "description": [str(x) for x in stored.description],
            "orig_time": None if stored.orig_time is None else stored.orig_time.timestamp(),
        },
        "annotation_events": ann_events,
        "skips": skips,
    }


def save_and_describe(raw, name, dedupe=False, **kw):
    fname = OUT / name
    raw.save(fname, overwrite=True, buffer_size_sec=BUF, **kw)
    back = mne.io.read_raw_fif(fname, preload=True)
    gold = describe(fname, back, dedupe)
    (OUT / (fname.name[: -len(".fif")] + ".json")).write_text(json.dumps(gold))
    size = sum(p.stat().st_size for p in OUT.glob(fname.name[: -len(".fif")] + "*.fif"))
    print(
        f"{name} ({size} B): {len(gold['eeg_names'])} EEG x {gold['n_times']} samples, "
        f"first_samp {gold['first_samp']}, {gold['orig_format']}, "
        f"stim events {gold['stim_events']}, annotation events {gold['annotation_events']}, "
        f"skips {gold['skips']}"
    )


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    for old in OUT.glob("*"):
        old.unlink()

    raw = base_raw(200)
    annotate(
        raw,
        [0.1, 0.3, 0.5, 0.62, 5.0],
        [0.0, 0.1, 0.0, 0.05, 0.0],
        ["Target", "NonTarget", "7 target", "a: b", "after the end"],
    )
    save_and_describe(raw, "float_raw.fif")

    for i, (cal, rng) in enumerate([(1e-8, 1.0), (2e-8, 1.0), (1e-8, 2.0)]):
        raw.info["chs"][i]["cal"] = cal
        raw.info["chs"][i]["range"] = rng
    for fmt in ("short", "int", "double"):
        save_and_describe(raw, f"{fmt}_raw.fif", fmt=fmt)

    long = base_raw(400, seed=1)
    annotate(
        long,
        [0.2, 0.4, 0.75, 1.0],
        [0.0, 0.2, 0.0, 0.0],
        ["before the crop", "across the crop", "Target", "NonTarget"],
    )
    cropped = long.copy().crop(tmin=0.5, tmax=(128 + 199) / SFREQ)
    save_and_describe(cropped, "cropped_raw.fif")

    nodate = long.copy().set_meas_date(None)
    nodate.set_annotations(
        mne.Annotations([0.2, 0.4, 0.75, 1.0], [0.0, 0.2, 0.0, 0.0],
                        ["before the crop", "across the crop", "Target", "NonTarget"])
    )
    nodate.crop(tmin=0.5, tmax=(128 + 199) / SFREQ)
    save_and_describe(nodate, "nodate_raw.fif")

    skip = base_raw(256, seed=2)
    annotate(skip, [64 / SFREQ, 0.1], [128 / SFREQ, 0.0], ["BAD_ACQ_SKIP", "x"])
    save_and_describe(skip, "skip_raw.fif", dedupe=True)

    split = base_raw(256, seed=3)
    annotate(split, [0.1, 0.9], [0.0, 0.0], ["Target", "NonTarget"])
    save_and_describe(split, "split_raw.fif", split_size=2**20 + 4500)


if __name__ == "__main__":
    main()
