"""Two small Neuroelectrics NIC .easy recordings (one with its .info) and their expected values.

Writes into crates/oddball-io/tests/fixtures/:
  nic_small.easy + nic_small.info  8 EEG channels + accelerometer (13 cells per line), 500 Hz,
                                   40 samples, CRLF line ends, a NIC 1 style .info (device class,
                                   channel counts, record count, rate, "Channel k:" then
                                   " Position: X" lines, a trigger table)
  nic_small_noinfo.easy            8 EEG channels + accelerometer + AddSensor (14 cells), no
                                   .info, LF line ends, 30 samples at 2 ms with one 8 ms gap
                                   (3 lost samples, flagged with NIC's lost-packet trigger 255)
  nic_small.json                   what a reader must find in them
tests/easy.rs reads both with the Rust reader and compares.

    python3 tools/golden/io/make_easy_fixture.py [--out-dir DIR]

Standard library only. The layout follows Neuroelectrics' description of the format (one line
per sample, TAB-separated: EEG in nV, [aX aY aZ], [AddSensor], trigger, Unix time in ms); the
expected values are computed here from the integers written, independently of the Rust code:
  * microvolts = nanovolts / 1000 (a correctly rounded float division, as the reader does)
  * channel names from the .info positions; Ch1..Ch8 without a .info (NIC's own names for
    electrodes without a position)
  * sampling rate: the .info's "EEG sampling rate"; without a .info, 1000 / median interval
  * events: at each sample whose trigger is non-zero and differs from the previous sample's,
    except trigger 255 (lost packets); code = trigger value
  * the .info entries: every line with a colon, split at the first colon, both sides stripped.
"""
from __future__ import annotations

import argparse
import json
import math
import random
import statistics
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
SEED = 20240611
PACKET_LOSS = 255
INT32_MAX = 2**31 - 1


def events_from(triggers: list[int]) -> list[dict]:
    out, prev = [], 0
    for i, code in enumerate(triggers):
        if code != 0 and code != prev and code != PACKET_LOSS:
            out.append({"onset": i, "code": code})
        prev = code
    return out


def eeg_nv(rng: random.Random, n_ch: int, n: int, fs: float) -> list[list[int]]:
    rows = []
    for c in range(n_ch):
        amp = 10_000 * (c + 1)  # 10 .. 80 uV
        f = 2.0 + 1.5 * c
        rows.append(
            [
                int(round(amp * math.sin(2 * math.pi * f * i / fs) + rng.gauss(0.0, 3_000.0)))
                for i in range(n)
            ]
        )
    return rows


def accel(rng: random.Random, n: int) -> list[list[int]]:
    g = [0, 0, 9_810]  # mm/s^2, the device lying flat
    return [[g[k] + rng.randint(-150, 150) for _ in range(n)] for k in range(3)]


def write_lines(path: Path, rows: list[list[int]], eol: str) -> None:
    text = "".join("\t".join(str(v) for v in row) + eol for row in rows)
    path.write_bytes(text.encode("ascii"))


def info_entries(lines: list[str]) -> list[list[str]]:
    out = []
    for line in lines:
        if ":" in line:
            k, v = line.split(":", 1)
            out.append([k.strip(), v.strip()])
    return out


def small_with_info(out: Path, rng: random.Random) -> dict:
    fs, n, n_ch = 500.0, 40, 8
    names = ["Fz", "Cz", "Pz", "Oz", "P3", "P4", "PO7", "PO8"]
    start = 1_361_377_909_087
    nv = eeg_nv(rng, n_ch, n, fs)
    nv[0][5], nv[0][6], nv[1][7], nv[2][8] = INT32_MAX, -INT32_MAX, 0, -1  # the extremes
    acc = accel(rng, n)
    trig = [0] * n
    for i, code in {3: 1, 10: 2, 11: 2, 15: 3, 16: 4, 20: PACKET_LOSS, 25: 1, 30: 70_000, 39: 5}.items():
        trig[i] = code
    ts = [start + 2 * i for i in range(n)]
    rows = [[nv[c][i] for c in range(n_ch)] + [acc[k][i] for k in range(3)] + [trig[i], ts[i]] for i in range(n)]
    write_lines(out / "nic_small.easy", rows, "\r\n")

    info = [
        f"StartDate (first EEG timestamp): {start}",
        "Device class: STARSTIM",
        "Device Mac: 00:07:80:58:9C:1A",
        "NIC version: v1.1.9",
        "Firmware version: 699",
        "Line filter status: OFF",
        "Additional channel status: OFF",
        f"Total number of channels: {n_ch}",
        f"Number of EEG channels: {n_ch}",
        f"Number of records of EEG: {n}",
        "EEG sampling rate: 500 Samples/second",
        "Accelerometer data: ON",
    ]
    for k, name in enumerate(names, 1):
        info += [f"Channel {k}: ", f" Position: {name}", " Type: EEG Recording"]
    info += ["Trigger information:", "Code Description", "1 Subject moved", "2 Eyes opened"]
    (out / "nic_small.info").write_bytes(("\r\n".join(info) + "\r\n").encode("ascii"))

    return {
        "easy": "nic_small.easy",
        "info": "nic_small.info",
        "n_columns": len(rows[0]),
        "n_eeg": n_ch,
        "accelerometer_present": True,
        "add_sensor_present": False,
        "ch_names": names,
        "sfreq": fs,
        "n_times": n,
        "data_nv": nv,
        "data_uv": [[v / 1000 for v in row] for row in nv],
        "accelerometer": [[float(v) for v in row] for row in acc],
        "add_sensor": None,
        "triggers": trig,
        "timestamps_ms": ts,
        "events": events_from(trig),
        "device_class": "STARSTIM",
        "info_entries": info_entries(info),
    }


def small_without_info(out: Path, rng: random.Random) -> dict:
    n, n_ch = 30, 8
    start = 1_700_000_000_000
    steps = [2] * (n - 1)
    steps[11] = 8  # sample 12 comes 8 ms after sample 11: three samples lost
    ts = [start]
    for s in steps:
        ts.append(ts[-1] + s)
    fs = 1000 / statistics.median(b - a for a, b in zip(ts, ts[1:]))
    nv = eeg_nv(rng, n_ch, n, fs)
    acc = accel(rng, n)
    add = [rng.randint(-5_000, 5_000) for _ in range(n)]
    trig = [0] * n
    for i, code in {0: 7, 12: PACKET_LOSS, 20: 9, 21: 9, 22: 9}.items():
        trig[i] = code
    rows = [
        [nv[c][i] for c in range(n_ch)] + [acc[k][i] for k in range(3)] + [add[i], trig[i], ts[i]]
        for i in range(n)
    ]
    write_lines(out / "nic_small_noinfo.easy", rows, "\n")
    return {
        "easy": "nic_small_noinfo.easy",
        "info": None,
        "n_columns": len(rows[0]),
        "n_eeg": n_ch,
        "accelerometer_present": True,
        "add_sensor_present": True,
        "ch_names": [f"Ch{k}" for k in range(1, n_ch + 1)],
        "sfreq": fs,
        "n_times": n,
        "data_nv": nv,
        "data_uv": [[v / 1000 for v in row] for row in nv],
        "accelerometer": [[float(v) for v in row] for row in acc],
        "add_sensor": [float(v) for v in add],
        "triggers": trig,
        "timestamps_ms": ts,
        "events": events_from(trig),
        "device_class": None,
        "info_entries": [],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=str(REPO / "crates/oddball-io/tests/fixtures"))
    args = ap.parse_args()
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = random.Random(SEED)
    golden = {
        "generator": "tools/golden/io/make_easy_fixture.py (Python standard library only)",
        "seed": SEED,
        "with_info": small_with_info(out, rng),
        "without_info": small_without_info(out, rng),
    }
    (out / "nic_small.json").write_text(json.dumps(golden, indent=1) + "\n")
    for key in ["with_info", "without_info"]:
        g = golden[key]
        size = (out / g["easy"]).stat().st_size
        print(
            f"{g['easy']} ({size} B{', + ' + g['info'] if g['info'] else ''}): "
            f"{g['n_eeg']} EEG x {g['n_times']} samples, {g['n_columns']} cells/line, "
            f"{g['sfreq']:g} Hz, events {[(e['onset'], e['code']) for e in g['events']]}"
        )
    js = out / "nic_small.json"
    shown = js.resolve().relative_to(REPO) if js.resolve().is_relative_to(REPO) else js
    print(f"wrote {shown} ({js.stat().st_size} B)")


if __name__ == "__main__":
    main()
