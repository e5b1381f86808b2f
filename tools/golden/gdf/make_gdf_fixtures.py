"""GDF fixtures for oddball-io's GDF reader, and what MNE's reader finds in them.

MNE has no GDF writer, so this script writes small GDF files byte by byte with numpy (the GDF 2.x
layout of Schloegl's standard, arXiv:cs/0608052, and the GDF 1.25 layout), reads them back with
`mne.io.read_raw_gdf`, and stores what MNE read (samples in uV to full precision, channel names,
sampling rate, its annotations and raw event table) as JSON next to the fixtures:

MNE reads every channel of a file with the first channel's data type (`_check_dtype_byte`), so
each file MNE checks has one data type:

* `small_v2.gdf`: GDF 2.20, 4 int32 channels in uV, mV, V and uV (dimension codes 4275, 4274,
  4256) with different scalings, 128 Hz, 5 records of 32 samples, an event table of mode 3 (position, type, channel, duration) with
  BCI Competition IV style codes (0x0300 trial start, 0x0301/0x0302 cues, 0x7FFE new run).
* `small_v1.gdf`: GDF 1.25, 3 int16 channels in `uV`, 256 Hz, 16 records of
  16 samples, an event table of mode 1 (position, type) holding OpenViBE stimulation codes: row/
  column labels 0x8101.., target 0x8205 / non-target 0x8206 at or near them (a flag one sample
  after its label, one one sample before, flags listed before their labels), a duplicated label,
  a label without flag, a flag without label, trial start/stop, visual stimulation start/stop,
  and events outside the recording (1-based position 0, and past the end).
* `types/v2_<type>.gdf`: one GDF 2.20 file per data type MNE reads (int8 ... uint64, float32,
  float64), 2 channels (uV and mV) of 2 records of 8 samples at 32 Hz, and no event table.
* `mixed_types_v2.gdf`: GDF 2.20 with one channel of each data type (int8, uint8, int16,
  uint16, int32, uint32, int64, uint64, float32, float64, int24, uint24) and kV/V/mV/uV/nV and a
  non-voltage unit. MNE refuses it ("Reading multiple data types not supported"); its golden
  values are this script's own (digital -> physical -> uV, computed here with numpy).

For the OpenViBE fixture and the real file, the flashes a reader should make are computed here
from MNE's event table by the rule the Rust reader documents (a label 0x8101-0x81FF is a flash
of code label-0x8100; a 0x8205/0x8206 flag within 2 samples of it, nearest first, sets the target
flag; a label repeated at the same sample with the same code is one flash).

With `../shared/data/openvibe-p300-gdf/data_sample_8ch.gdf` present it also writes
`real_openvibe.json`: MNE's values of every channel on the first and last 32 samples, the event
table counts, and the flashes (values only, not the file).

Run from the workspace root: python tools/golden/gdf/make_gdf_fixtures.py
"""

import json
import os
import struct
import sys
from pathlib import Path

import mne
import numpy as np

OUT = Path("crates/oddball-io/tests/fixtures/gdf")
REAL = Path("../shared/data/openvibe-p300-gdf/data_sample_8ch.gdf")

# GDF type code -> (numpy dtype, bytes); 24-bit types written by hand.
GDFTYPES = {
    1: ("<i1", 1),
    2: ("<u1", 1),
    3: ("<i2", 2),
    4: ("<u2", 2),
    5: ("<i4", 4),
    6: ("<u4", 4),
    7: ("<i8", 8),
    8: ("<u8", 8),
    16: ("<f4", 4),
    17: ("<f8", 8),
    279: ("int24", 3),
    535: ("uint24", 3),
}
UNIT_FACTOR = {"kV": 1e9, "V": 1e6, "mV": 1e3, "uV": 1.0, "nV": 1e-3}
UNIT_CODE = {"kV": 4259, "V": 4256, "mV": 4274, "uV": 4275, "nV": 4276, "degC": 6048}


def pad(text, n):
    b = text.encode("latin-1")
    assert len(b) <= n
    return b + b" " * (n - len(b))


def encode(values, typ):
    dtype, _ = GDFTYPES[typ]
    if dtype in ("int24", "uint24"):
        out = bytearray()
        for v in values:
            v = int(v)
            if dtype == "int24":
                assert -(1 << 23) <= v < (1 << 23)
                v &= 0xFFFFFF
            else:
                assert 0 <= v < (1 << 24)
            out += v.to_bytes(3, "little")
        return bytes(out)
    return np.asarray(values).astype(dtype).tobytes()


def records(channels, n_records):
    """Data records: for each record, channel after channel, its `spr` samples."""
    out = bytearray()
    for r in range(n_records):
        for ch in channels:
            spr = ch["spr"]
            out += encode(ch["digital"][r * spr : (r + 1) * spr], ch["type"])
    return bytes(out)


def microvolts(ch):
    dig = np.asarray(ch["digital"], dtype=np.float64)
    gain = (ch["pmax"] - ch["pmin"]) / (ch["dmax"] - ch["dmin"])
    return ((dig - ch["dmin"]) * gain + ch["pmin"]) * UNIT_FACTOR.get(ch["unit"], 1.0)


def gdf2(channels, n_records, duration, events, mode, event_sr, version=b"GDF 2.20"):
    ns = len(channels)
    h = bytearray()
    h += version
    h += pad("P01 Fixture_Subject", 66)
    h += bytes(10)
    h += bytes(4)  # smoking.., weight, height, gender..
    h += pad("oddball GDF 2 fixture", 64)
    h += bytes(16)  # location
    h += struct.pack("<Q", 0)  # start date (unknown)
    h += struct.pack("<Q", 0)  # birthday
    h += struct.pack("<H", ns + 1)  # header length in 256-byte blocks
    h += bytes(6)
    h += pad("oddball", 8)
    h += bytes(6)  # IP
    h += struct.pack("<3H", 0, 0, 0)
    h += struct.pack("<3f", 0, 0, 0)
    h += struct.pack("<3f", 0, 0, 0)
    h += struct.pack("<q", n_records)
    h += struct.pack("<2I", *duration)
    h += struct.pack("<H", ns)
    h += bytes(2)
    assert len(h) == 256
    v = bytearray()
    v += b"".join(pad(c["label"], 16) for c in channels)
    v += b"".join(pad("Ag/AgCl electrode", 80) for c in channels)
    v += b"".join(pad("", 6) for c in channels)
    v += b"".join(struct.pack("<H", UNIT_CODE[c["unit"]]) for c in channels)
    for key in ("pmin", "pmax", "dmin", "dmax"):
        v += b"".join(struct.pack("<d", c[key]) for c in channels)
    v += b"".join(pad("", 68) for c in channels)
    v += b"".join(struct.pack("<f", 30.0) for c in channels)  # lowpass
    v += b"".join(struct.pack("<f", 0.1) for c in channels)  # highpass
    v += b"".join(struct.pack("<f", 50.0) for c in channels)  # notch
    v += b"".join(struct.pack("<I", c["spr"]) for c in channels)
    v += b"".join(struct.pack("<I", c["type"]) for c in channels)
    v += b"".join(struct.pack("<3f", 0, 0, 0) for c in channels)
    v += b"".join(bytes(20) for c in channels)
    assert len(v) == 256 * ns
    et = bytearray([mode])
    et += len(events).to_bytes(3, "little")
    et += struct.pack("<f", event_sr)
    et += event_arrays(events, mode)
    return bytes(h + v) + records(channels, n_records) + bytes(et)


def gdf1(channels, n_records, duration, events, mode, event_sr):
    ns = len(channels)
    h = bytearray()
    h += b"GDF 1.25"
    h += pad("P01 Fixture_Subject", 80)
    h += pad("oddball GDF 1 fixture", 80)
    h += b"2024010212304500"
    h += struct.pack("<q", 256 * (ns + 1))
    h += struct.pack("<QQQ", 0, 0, 0)
    h += bytes(20)
    h += struct.pack("<q", n_records)
    h += struct.pack("<2I", *duration)
    h += struct.pack("<I", ns)
    assert len(h) == 256
    v = bytearray()
    v += b"".join(pad(c["label"], 16) for c in channels)
    v += b"".join(pad("", 80) for c in channels)
    v += b"".join(pad(c["unit"], 8) for c in channels)
    v += b"".join(struct.pack("<d", c["pmin"]) for c in channels)
    v += b"".join(struct.pack("<d", c["pmax"]) for c in channels)
    v += b"".join(struct.pack("<q", int(c["dmin"])) for c in channels)
    v += b"".join(struct.pack("<q", int(c["dmax"])) for c in channels)
    v += b"".join(pad("HP:0.1Hz LP:40Hz", 80) for c in channels)
    v += b"".join(struct.pack("<I", c["spr"]) for c in channels)
    v += b"".join(struct.pack("<I", c["type"]) for c in channels)
    v += b"".join(bytes(32) for c in channels)
    assert len(v) == 256 * ns
    et = bytearray([mode])
    et += int(event_sr).to_bytes(3, "little")
    et += struct.pack("<I", len(events))
    et += event_arrays(events, mode)
    return bytes(h + v) + records(channels, n_records) + bytes(et)


def event_arrays(events, mode):
    """events: (1-based position, type, channel, duration)."""
    out = b"".join(struct.pack("<I", e[0]) for e in events)
    out += b"".join(struct.pack("<H", e[1]) for e in events)
    if mode == 3:
        out += b"".join(struct.pack("<H", e[2]) for e in events)
        out += b"".join(struct.pack("<I", e[3]) for e in events)
    return out


def openvibe_flashes(samples, types, n_times):
    """The flashes of an OpenViBE event table (0-based samples), by the reader's rule."""
    inside = [(int(s), int(t), i) for i, (s, t) in enumerate(zip(samples, types)) if 0 <= s < n_times]
    labels = sorted(
        [(s, t, i) for s, t, i in inside if 0x8101 <= t <= 0x81FF], key=lambda x: (x[0], x[2])
    )
    flags = [(s, t, i) for s, t, i in inside if t in (0x8205, 0x8206)]
    seen, unique = set(), []
    for s, t, i in labels:
        if (s, t) not in seen:
            seen.add((s, t))
            unique.append((s, t, i))
    used = set()
    flashes = []
    for s, t, _ in unique:
        near = [(abs(fs - s), fs, fi, ft) for fs, ft, fi in flags if fi not in used and abs(fs - s) <= 2]
        target = None
        if near:
            _, _, fi, ft = min(near)
            used.add(fi)
            target = ft == 0x8205
        flashes.append([s, t - 0x8100, target])
    orphans = len(flags) - len(used)
    return flashes, len(labels) - len(unique), orphans


def mne_read(path):
    raw = mne.io.read_raw_gdf(path, preload=True, verbose="error")
    extras = raw._raw_extras[0]
    ev = extras["events"]
    table = None
    if ev is not None:
        n, pos, typ, chn, dur = ev
        # MNE's pos is the file's 1-based position minus one; chn/dur as MNE filled them.
        table = {
            "pos0": [int(p) for p in np.asarray(pos, dtype=np.int64)],
            "type": [int(t) for t in typ],
            "channel": [int(c) for c in chn],
            "duration": [int(d) for d in dur],
        }
    ann = raw.annotations
    return raw, {
        "ch_names": list(raw.ch_names),
        "sfreq": float(raw.info["sfreq"]),
        "n_times": int(raw.n_times),
        "data_uV": [[float(x) for x in row] for row in raw.get_data() * 1e6],
        "annotations": {
            "onset_s": [float(x) for x in ann.onset],
            "duration_s": [float(x) for x in ann.duration],
            "description": [str(x) for x in ann.description],
        },
        "event_table": table,
    }


def small_v2(rng):
    spr, n_rec = 32, 5
    n = spr * n_rec
    chans = [
        dict(label="Fz", type=5, unit="uV", pmin=-1000.0, pmax=1000.0, dmin=-1e6, dmax=1e6, spr=spr,
             digital=rng.integers(-1_000_000, 1_000_001, n)),
        dict(label="Cz", type=5, unit="mV", pmin=-2.0, pmax=2.0, dmin=0.0, dmax=2e9, spr=spr,
             digital=rng.integers(0, 2_000_000_001, n)),
        dict(label="Pz", type=5, unit="V", pmin=-0.001, pmax=0.001, dmin=-2**31, dmax=2**31 - 1,
             spr=spr, digital=rng.integers(-2**31, 2**31, n)),
        dict(label="Oz", type=5, unit="uV", pmin=-250.0, pmax=750.0, dmin=-50000.0, dmax=150000.0,
             spr=spr, digital=rng.integers(-50000, 150001, n)),
    ]
    events = [
        (1, 0x7FFE, 0, 0),
        (11, 0x0300, 0, 48),
        (19, 0x0301, 0, 16),
        (75, 0x0300, 2, 48),
        (83, 0x0302, 0, 16),
        (160, 0x0114, 1, 1),
    ]
    return chans, gdf2(chans, n_rec, (1, 4), events, 3, 128.0), events


def small_v1(rng):
    spr, n_rec = 16, 16
    n = spr * n_rec
    chans = [
        dict(label="Cz", type=3, unit="uV", pmin=-3276.8, pmax=3276.7, dmin=-32768, dmax=32767,
             spr=spr, digital=rng.integers(-32768, 32768, n)),
        dict(label="Pz", type=3, unit="uV", pmin=-500.0, pmax=500.0, dmin=-32768, dmax=32767,
             spr=spr, digital=rng.integers(-32768, 32768, n)),
        dict(label="Oz", type=3, unit="uV", pmin=-100.0, pmax=100.0, dmin=-2000, dmax=2000,
             spr=spr, digital=rng.integers(-2000, 2001, n)),
    ]
    ev = [
        (0, 0x8001),  # position 0: before the first sample (1-based positions)
        (1, 0x8001),  # experiment start
        (11, 0x8005),  # trial start
        (21, 0x8101), (21, 0x8206), (25, 0x800B), (33, 0x800C),
        (42, 0x8205), (41, 0x8103), (45, 0x800B),  # flag 1 sample after, listed first
        (60, 0x8206), (61, 0x8102),  # flag 1 sample before
        (81, 0x8205), (81, 0x8108),
        (101, 0x8102), (101, 0x8206), (101, 0x8102), (101, 0x8206),  # duplicated
        (121, 0x8104),  # no flag
        (141, 0x8205),  # no label
        (161, 0x8109), (163, 0x8205),  # flag 2 samples after
        (181, 0x810E), (184, 0x8206),  # flag 3 samples after: not paired
        (201, 0x8006),  # trial stop
        (300, 0x8101), (300, 0x8205),  # past the end (256 samples)
    ]
    events = [(p, t, 0, 0) for p, t in ev]
    return chans, gdf1(chans, n_rec, (1, 16), events, 1, 256), events


TYPE_NAMES = {1: "int8", 2: "uint8", 3: "int16", 4: "uint16", 5: "int32", 6: "uint32",
              7: "int64", 8: "uint64", 16: "float32", 17: "float64"}


def one_type(rng, typ):
    spr, n_rec = 8, 2
    n = spr * n_rec
    if typ in (16, 17):
        lo, hi = -1000.0, 1000.0
        dig = rng.uniform(lo, hi, n)
        dig2 = rng.uniform(lo, hi, n)
        if typ == 16:
            dig, dig2 = (d.astype("<f4").astype(np.float64) for d in (dig, dig2))
    else:
        info = np.iinfo(GDFTYPES[typ][0])
        # MNE scales in float64: keep the integers exact there (|x| < 2**53).
        lo, hi = max(int(info.min), -(2**40)), min(int(info.max), 2**40)
        dt = np.uint64 if typ == 8 else np.int64
        dig = rng.integers(lo, hi, n, endpoint=True, dtype=dt)
        dig2 = rng.integers(lo, hi, n, endpoint=True, dtype=dt)
    chans = [
        dict(label="C3", type=typ, unit="uV", pmin=-100.0, pmax=100.0, dmin=float(lo), dmax=float(hi),
             spr=spr, digital=dig),
        dict(label="C4", type=typ, unit="mV", pmin=-0.5, pmax=1.5, dmin=float(lo), dmax=float(hi),
             spr=spr, digital=dig2),
    ]
    data = gdf2(chans, n_rec, (1, 4), [], 1, 32.0)
    # No event table: the file ends with the data.
    data = data[: len(data) - 8]
    return chans, data


def mixed_types(rng):
    spr, n_rec = 8, 3
    n = spr * n_rec
    spec = [
        (1, "uV", -128, 127, -12.8, 12.7),
        (2, "mV", 0, 255, -0.5, 0.5),
        (3, "uV", -32768, 32767, -327.68, 327.67),
        (4, "nV", 0, 65535, -65535.0, 65535.0),
        (5, "V", -(2**31), 2**31 - 1, -0.002, 0.002),
        (6, "kV", 0, 2**32 - 1, -1e-6, 1e-6),
        (7, "uV", -(2**40), 2**40, -1000.0, 1000.0),
        (8, "uV", 0, 2**40, 0.0, 100.0),
        (16, "uV", -1000.0, 1000.0, -1000.0, 1000.0),
        (17, "mV", -1.0, 1.0, -1.0, 1.0),
        (279, "uV", -(2**23), 2**23 - 1, -8388.608, 8388.607),
        (535, "degC", 0, 2**24 - 1, 20.0, 45.0),
    ]
    chans = []
    for k, (typ, unit, dmin, dmax, pmin, pmax) in enumerate(spec):
        if typ in (16, 17):
            dig = rng.uniform(dmin, dmax, n)
            if typ == 16:
                dig = dig.astype("<f4").astype(np.float64)
        else:
            dig = rng.integers(int(dmin), int(dmax), n, endpoint=True, dtype=np.int64 if typ != 8 else np.uint64)
        chans.append(dict(label=f"T{typ}", type=typ, unit=unit, pmin=pmin, pmax=pmax,
                          dmin=float(dmin), dmax=float(dmax), spr=spr, digital=dig))
    events = [(3, 0x0300, 0, 0), (20, 0x0301, 0, 0)]
    return chans, gdf2(chans, n_rec, (1, 8), events, 1, 64.0), events


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(20261128)
    golden = {}
    worst = 0.0

    for name, make in (("small_v2.gdf", small_v2), ("small_v1.gdf", small_v1)):
        chans, data, events = make(rng)
        (OUT / name).write_bytes(data)
        raw, got = mne_read(OUT / name)
        want = np.array([microvolts(c) for c in chans])
        diff = float(np.max(np.abs(np.array(got["data_uV"]) - want)))
        worst = max(worst, diff)
        got["intended_max_abs_diff_uV"] = diff
        got["written_events"] = [list(e) for e in events]
        if name == "small_v1.gdf":
            samples = np.array(got["event_table"]["pos0"])
            flashes, dups, orphans = openvibe_flashes(samples, got["event_table"]["type"], got["n_times"])
            got["openvibe"] = {"flashes": flashes, "duplicate_labels": dups, "orphan_flags": orphans}
        golden[name] = got
        print(f"{name}: {len(data)} B, {len(chans)} ch x {got['n_times']} @ {got['sfreq']} Hz, "
              f"MNE vs intended max |diff| {diff:.3g} uV, {len(got['annotations']['onset_s'])} annotations")

    (OUT / "types").mkdir(exist_ok=True)
    for typ, tname in TYPE_NAMES.items():
        chans, data = one_type(rng, typ)
        name = f"types/v2_{tname}.gdf"
        (OUT / name).write_bytes(data)
        raw, got = mne_read(OUT / name)
        want = np.array([microvolts(c) for c in chans])
        diff = float(np.max(np.abs(np.array(got["data_uV"]) - want)))
        worst = max(worst, diff)
        got["intended_max_abs_diff_uV"] = diff
        got["type"] = typ
        golden[name] = got
        print(f"{name}: {len(data)} B, MNE vs intended max |diff| {diff:.3g} uV, events {got['event_table']}")

    chans, data, events = mixed_types(rng)
    name = "mixed_types_v2.gdf"
    (OUT / name).write_bytes(data)
    try:
        mne.io.read_raw_gdf(OUT / name, preload=True, verbose="error")
        refused = None
    except Exception as e:  # MNE reads one sample width per file
        refused = f"{type(e).__name__}: {e}"
    golden[name] = {
        "mne_refused": refused,
        "ch_names": [c["label"] for c in chans],
        "sfreq": 64.0,
        "n_times": 24,
        "types": [c["type"] for c in chans],
        "units": [c["unit"] for c in chans],
        "data_uV": [[float(x) for x in microvolts(c)] for c in chans],
        "written_events": [list(e) for e in events],
    }
    print(f"{name}: {len(data)} B, {len(chans)} types; MNE: {refused}")

    (OUT / "golden.json").write_text(json.dumps(golden, indent=1) + "\n")
    print(f"wrote {OUT / 'golden.json'}; worst MNE vs intended {worst:.3g} uV")

    if REAL.exists():
        raw, got = mne_read(REAL)
        data = np.array(got["data_uV"])
        table = got["event_table"]
        flashes, dups, orphans = openvibe_flashes(np.array(table["pos0"]), table["type"], got["n_times"])
        counts = {}
        for t in table["type"]:
            counts[str(t)] = counts.get(str(t), 0) + 1
        trial_starts = [p for p, t in zip(table["pos0"], table["type"]) if t == 0x8005]
        pairs = []
        for k, start in enumerate(trial_starts):
            end = trial_starts[k + 1] if k + 1 < len(trial_starts) else got["n_times"]
            pairs.append(sorted({c for s, c, tg in flashes if start <= s < end and tg}))
        real = {
            "sha256_of_source": "23b72098934b394371de778a1f65ac0113103ef144bf7662f00ad2d557610eb2",
            "ch_names": got["ch_names"],
            "sfreq": got["sfreq"],
            "n_times": got["n_times"],
            "first_uV": [[float(x) for x in row[:32]] for row in data],
            "last_uV": [[float(x) for x in row[-32:]] for row in data],
            "event_type_counts": counts,
            "n_table_events": len(table["type"]),
            "flashes": flashes,
            "duplicate_labels": dups,
            "orphan_flags": orphans,
            "trial_starts": trial_starts,
            "target_pairs_per_trial": pairs,
        }
        (OUT / "real_openvibe.json").write_text(json.dumps(real) + "\n")
        n_t = sum(1 for f in flashes if f[2])
        print(f"real: {len(flashes)} flashes, {n_t} targets, {len({f[1] for f in flashes})} codes, "
              f"{dups} duplicate labels, {orphans} orphan flags, target pairs {pairs}")
    else:
        print(f"{REAL} not found: real_openvibe.json not written", file=sys.stderr)


if __name__ == "__main__":
    os.environ.setdefault("MNE_LOGGING_LEVEL", "ERROR")
    main()
