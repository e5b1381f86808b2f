"""BrainVision fixtures and what MNE 1.13.2 reads from them.

Writes into crates/oddball-io/tests/fixtures/brainvision/ (run from the workspace root):

* mne_float32.{vhdr,vmrk,eeg}: mne.export.export_raw(fmt="brainvision") (pybv, IEEE_FLOAT_32,
  resolution 0.1 µV, MULTIPLEXED) of a 5-channel 500 Hz RawArray with Stimulus, Response and
  Comment annotations;
* pybv_int16.{vhdr,vmrk,eeg}: pybv.write_brainvision(fmt="binary_int16", resolution 0.5 µV and, for
  one channel in mV, 0.0005 mV) with Stimulus and Response events;
* hand_int32_vec.{vhdr,vmrk,eeg}: written byte by byte here: INT_32, VECTORIZED, DataPoints,
  Codepage=ANSI (cp1252 bytes µV, °C in the header; the marker file stays ASCII, since MNE
  reads it as UTF-8 when looking for the date), a `\\1` comma in a channel name, an empty
  resolution, a non-voltage channel (°C), a fractional sampling interval, text Stimulus
  descriptions, a New Segment with a date and a marker beyond the data.

Each gets a JSON with what mne.io.read_raw_brainvision reads: channel names, sfreq, the data
(µV for voltage channels, the file's own unit for the others), annotations (onset in samples,
description) and mne.events_from_annotations (sample, code).
"""

import json
import pathlib

import mne
import numpy as np
import pybv

OUT = pathlib.Path("crates/oddball-io/tests/fixtures/brainvision")
OUT.mkdir(parents=True, exist_ok=True)
VOLT_UNITS = ("V", "mV", "µV", "uV", "nV")


def describe(vhdr):
    raw = mne.io.read_raw_brainvision(OUT / vhdr, preload=True, verbose="error")
    units = raw._orig_units
    data = raw.get_data()
    rows = []
    for i, name in enumerate(raw.ch_names):
        scale = 1e6 if units[name] in VOLT_UNITS else 1.0
        rows.append([float(v) for v in data[i] * scale])
    sfreq = raw.info["sfreq"]
    ann = [
        {"sample": int(round(a["onset"] * sfreq)), "description": a["description"]}
        for a in raw.annotations
    ]
    events, event_id = mne.events_from_annotations(raw, verbose="error")
    return {
        "file": vhdr,
        "ch_names": raw.ch_names,
        "units": [units[n] for n in raw.ch_names],
        "sfreq": float(sfreq),
        "n_times": int(raw.n_times),
        "data": rows,
        "annotations": ann,
        "events": [[int(e[0]), int(e[2])] for e in events],
        "event_id": {k: int(v) for k, v in event_id.items()},
    }


def mne_float32(rng):
    names = ["Fp1", "Fz", "Cz", "Pz", "Oz"]
    info = mne.create_info(names, 500.0, "eeg")
    data = rng.normal(0, 30e-6, (5, 100))
    raw = mne.io.RawArray(data, info, verbose="error")
    raw.set_meas_date(1_700_000_000)
    raw.set_annotations(
        mne.Annotations(
            onset=[0.02, 0.05, 0.08, 0.11, 0.15],
            duration=[0.002] * 5,
            description=["Stimulus/S  1", "Stimulus/S 12", "Response/R  3", "Comment/note", "Stimulus/S  1"],
            orig_time=raw.info["meas_date"],
        )
    )
    mne.export.export_raw(OUT / "mne_float32.vhdr", raw, fmt="brainvision", overwrite=True, verbose="error")
    return describe("mne_float32.vhdr")


def pybv_int16(rng):
    data = rng.normal(0, 40e-6, (3, 80))
    data[0, 5] = 16000e-6  # near the int16 limit at 0.5 µV
    data[0, 6] = -16000e-6
    events = [
        {"onset": 3, "description": 2, "type": "Stimulus"},
        {"onset": 10, "description": 7, "type": "Response"},
        {"onset": 40, "description": 2, "type": "Stimulus", "duration": 4},
        {"onset": 79, "description": 255, "type": "Stimulus"},
    ]
    pybv.write_brainvision(
        data=data,
        sfreq=250.0,
        ch_names=["C3", "C4", "EOG"],
        fname_base="pybv_int16",
        folder_out=OUT,
        overwrite=True,
        events=events,
        resolution=np.array([0.5, 0.5, 0.0005]),
        unit=["µV", "µV", "mV"],
        fmt="binary_int16",
    )
    return describe("pybv_int16.vhdr")


def hand_int32_vec(rng):
    n_times = 40
    stored = rng.integers(-2_000_000, 2_000_000, (4, n_times), dtype=np.int32)
    stored[0, 0] = np.iinfo(np.int32).max
    stored[1, 1] = np.iinfo(np.int32).min
    # VECTORIZED: channel after channel.
    (OUT / "hand_int32_vec.eeg").write_bytes(stored.astype("<i4").tobytes(order="C"))
    vhdr = (
        "Brain Vision Data Exchange Header File Version 1.0\r\n"
        "; Written byte by byte by tools/golden/brainvision/make_fixtures.py\r\n"
        "\r\n"
        "[Common Infos]\r\n"
        "Codepage=ANSI\r\n"
        "DataFile=hand_int32_vec.eeg\r\n"
        "MarkerFile=hand_int32_vec.vmrk\r\n"
        "DataFormat=BINARY\r\n"
        "DataOrientation=VECTORIZED\r\n"
        "NumberOfChannels=4\r\n"
        f"DataPoints={n_times}\r\n"
        "SamplingInterval=1953.125\r\n"
        "\r\n"
        "[Binary Infos]\r\n"
        "BinaryFormat=INT_32\r\n"
        "\r\n"
        "[Channel Infos]\r\n"
        "; Each entry: Ch<Channel number>=<Name>,<Reference channel name>,\r\n"
        "; <Resolution in \"Unit\">,<Unit>, Future extensions..\r\n"
        "Ch1=Fz\\1a,Cz,0.25,µV\r\n"
        "Ch2=Pz,,,mV\r\n"
        "Ch3=Oz,,0.001\r\n"
        "Ch4=Temp,,0.01,°C\r\n"
        "\r\n"
        "[Comment]\r\n"
        "A free text line without an equals sign\r\n"
    )
    (OUT / "hand_int32_vec.vhdr").write_bytes(vhdr.encode("cp1252"))
    vmrk = (
        "Brain Vision Data Exchange Marker File, Version 1.0\r\n"
        "\r\n"
        "[Common Infos]\r\n"
        "Codepage=ANSI\r\n"
        "DataFile=hand_int32_vec.eeg\r\n"
        "\r\n"
        "[Marker Infos]\r\n"
        "; Each entry: Mk<Marker number>=<Type>,<Description>,<Position in data points>,\r\n"
        "; <Size in data points>, <Channel number (0 = marker is related to all channels)>\r\n"
        "Mk1=New Segment,,1,1,0,20240102030405678901\r\n"
        "Mk2=Stimulus,S  1,3,1,0\r\n"
        "Mk3=Stimulus,Target,8,1,0\r\n"
        "Mk4=Response,R  2,12,1,0\r\n"
        "Mk5=Comment,a\\1b,15,1,0\r\n"
        "Mk6=Stimulus,S  1,20,1,0\r\n"
        "Mk7=Stimulus,Target,25,1,0\r\n"
        "Mk8=Stimulus,Non target,30,1,0\r\n"
        "Mk9=Stimulus,S  4,41,1,0\r\n"
    )
    (OUT / "hand_int32_vec.vmrk").write_bytes(vmrk.encode("cp1252"))
    return describe("hand_int32_vec.vhdr")


def main():
    rng = np.random.default_rng(20260301)
    gold = {
        "mne": mne.__version__,
        "pybv": pybv.__version__,
        "fixtures": [mne_float32(rng), pybv_int16(rng), hand_int32_vec(rng)],
    }
    path = OUT / "golden.json"
    path.write_text(json.dumps(gold, indent=1, ensure_ascii=False))
    for f in gold["fixtures"]:
        print(f"{f['file']}: {len(f['ch_names'])} ch x {f['n_times']} at {f['sfreq']} Hz, "
              f"{len(f['annotations'])} annotations, events {f['events']}")
    print(f"wrote {path} ({path.stat().st_size} B)")


if __name__ == "__main__":
    main()
