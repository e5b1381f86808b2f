#!/usr/bin/env python3
"""Write a small XDF file with Python's struct module (an independent XDF writer) and the values a
reader must find in it.

    python3 tools/golden/xdf/make_xdf_fixture.py

Standard library only. Writes, under crates/oddball-io/tests/fixtures/xdf/:

* python_small.xdf: XDF 1.0 with five streams and every chunk type:
  - stream 1 "TestAmp & Co", type EEG, 4 float32 channels at 250 Hz, units microvolts,
    microvolts, millivolts, volts; 60 samples in three Samples chunks (one with explicit
    timestamps, one whose samples after the first carry no timestamp (TimeStampBytes 0, so
    previous + 1/250 s), one with jittered timestamps); chunk lengths in 4 and 8 bytes,
    NumSamples in 1, 4 and 8 bytes;
  - stream 7 "Markers ü", one string channel, irregular: UTF-8 markers (one 300 bytes long, so a
    4-byte string length), one without timestamp, one before and one after the EEG; two
    ClockOffset chunks (0.002 s);
  - stream 3 "Acc", type ACC, 3 int16 channels at 50 Hz, timestamps deduced after the first;
  - stream 4 "Triggers", type Markers, one int32 channel, irregular;
  - stream 5 "Temp", type Misc, 2 double64 channels at 10 Hz (subnormal, huge, 1/3);
  - a Boundary chunk, a chunk with an unknown tag (99), and a StreamFooter per stream;
  the XML has a declaration, a comment, attributes, entities and indentation.
* python_small.json: the chunk table (offset, end, tag, stream id, samples), every stream's
  header values, timestamps and values, and what oddball-io's reader must make of it: the EEG in
  µV (float32 value × 1, 1e3, 1e6), marker samples after clock correction (t + 0.002) at the
  nearest EEG timestamp, and the event codes, targets and labels (written out by hand below).
"""

import json
import struct
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
OUT = ROOT / "crates" / "oddball-io" / "tests" / "fixtures" / "xdf"
BOUNDARY = bytes(
    [0x43, 0xA5, 0x46, 0xDC, 0xCB, 0xF5, 0x41, 0x0F,
     0xB3, 0x0E, 0xD5, 0x46, 0x73, 0x83, 0xCB, 0xE4]
)


def varlen(n, nbytes=None):
    if nbytes is None:
        nbytes = 1 if n < 256 else 4 if n < 2**32 else 8
    return bytes([nbytes]) + struct.pack({1: "<B", 4: "<I", 8: "<Q"}[nbytes], n)


class Writer:
    def __init__(self):
        self.b = bytearray(b"XDF:")
        self.chunks = []

    def chunk(self, tag, content, nlb=None, stream_id=None, n_samples=0):
        start = len(self.b)
        self.b += varlen(2 + len(content), nlb) + struct.pack("<H", tag) + content
        self.chunks.append(
            dict(offset=start, end=len(self.b), tag=tag, stream_id=stream_id,
                 n_samples=n_samples)
        )


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


class Lcg:
    def __init__(self, seed):
        self.s = seed

    def next(self):
        self.s = (self.s * 6364136223846793005 + 1442695040888963407) % 2**64
        return (self.s >> 11) / 2**53


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    w = Writer()
    w.chunk(1, b'<?xml version="1.0"?>\n<info>\n  <version>1.0</version>\n'
               b'  <datetime>2024-01-01T12:00:00+0000</datetime>\n</info>\n', nlb=4)

    # ---- stream headers
    eeg_labels = ["Fz", "Cz", "Pz", "Oz"]
    eeg_units = ["microvolts", "microvolts", "millivolts", "volts"]
    eeg_xml = (
        '<?xml version="1.0" encoding="utf-8"?>\n<!-- written by make_xdf_fixture.py -->\n'
        "<info>\n  <name>TestAmp &amp; Co</name>\n  <type>EEG</type>\n"
        "  <channel_count>4</channel_count>\n  <nominal_srate>250.0000000000000</nominal_srate>\n"
        "  <channel_format>float32</channel_format>\n  <source_id>amp-1234</source_id>\n"
        "  <version>1.100000000000000</version>\n  <created_at>999.5</created_at>\n"
        '  <uid kind="random">0f8b2c</uid>\n  <v4address />\n  <desc>\n    <channels>\n'
        + "".join(
            f'      <channel><label>{l}</label><unit>{u}</unit><type>EEG</type></channel>\n'
            for l, u in zip(eeg_labels, eeg_units)
        )
        + "    </channels>\n    <manufacturer>Python struct</manufacturer>\n  </desc>\n</info>\n"
    )
    mk_xml = (
        "<?xml version=\"1.0\"?>\n<info><name>Markers \u00fc</name><type>Markers</type>"
        "<channel_count>1</channel_count><nominal_srate>0</nominal_srate>"
        "<channel_format>string</channel_format><source_id></source_id><desc/></info>"
    )
    acc_xml = (
        "<info><name>Acc</name><type>ACC</type><channel_count>3</channel_count>"
        "<nominal_srate>50</nominal_srate><channel_format>int16</channel_format></info>"
    )
    trig_xml = (
        "<info><name>Triggers</name><type>Markers</type><channel_count>1</channel_count>"
        "<nominal_srate>0.0</nominal_srate><channel_format>int32</channel_format></info>"
    )
    temp_xml = (
        "<info><name>Temp</name><type>Misc</type><channel_count>2</channel_count>"
        "<nominal_srate>10</nominal_srate><channel_format>double64</channel_format>"
        "<desc><channels><channel><label>a</label></channel><channel><label>b</label>"
        "</channel></channels></desc></info>"
    )
    for sid, xml in [(1, eeg_xml), (7, mk_xml), (3, acc_xml), (4, trig_xml), (5, temp_xml)]:
        w.chunk(2, struct.pack("<I", sid) + xml.encode("utf-8"), stream_id=sid)

    # ---- EEG samples (float32)
    rng = Lcg(20240101)
    scale = [40.0, 40.0, 0.04, 4e-5]  # µV, µV, mV, V
    eeg_ts, eeg_vals = [], []  # eeg_vals[sample][channel] (float32 values as Python floats)

    def eeg_chunk(first, n, mode, nlb, ns_bytes):
        body = bytearray(struct.pack("<I", 1) + varlen(n, ns_bytes))
        for k in range(first, first + n):
            vals = [f32((rng.next() - 0.5) * s) for s in scale]
            if mode == "explicit" or (mode == "deduced" and k == first):
                t = 1000.0 + k / 250.0
                body += b"\x08" + struct.pack("<d", t)
            elif mode == "jitter":
                t = 1000.0 + k / 250.0 + (1e-5 if k % 3 == 0 else -2e-6)
                body += b"\x08" + struct.pack("<d", t)
            else:
                t = eeg_ts[-1] + 1.0 / 250.0
                body += b"\x00"
            eeg_ts.append(t)
            eeg_vals.append(vals)
            body += struct.pack("<4f", *vals)
        w.chunk(3, bytes(body), nlb=nlb, stream_id=1, n_samples=n)

    # ---- markers: (timestamp or None = deduced, text, code, target, label)
    text_code = {  # one above the largest numeric code (70000), in order of first appearance
        "before start": 70001, "Grüße 🎉": 70002, "start": 70003, "x" * 300: 70004,
        "after end": 70005,
    }
    mk = lambda k: 1000.0 + k / 250.0 - 0.002  # noqa: E731 (EEG sample k after correction)
    m1 = [(999.0, "before start", 70001, None, "before start"),
          (mk(3.3), "flash 3", 3, None, "flash 3"),
          (mk(10.4), "3 target: Ä", 3, True, "Ä")]
    m2 = [(mk(25.2), "Grüße 🎉", 70002, None, "Grüße 🎉"),
          (mk(30.1), "12", 12, None, None),
          (mk(33.3), "S  5", 5, None, "S  5"),
          (mk(36.2), "start", 70003, None, "start"),
          (None, "start", 70003, None, "start"),
          (mk(38.2), "x" * 300, 70004, None, "x" * 300)]
    m3 = [(mk(45.3), "flash 3", 3, None, "flash 3"),
          (mk(50.2), "start", 70003, None, "start"),
          (mk(59.4), "end 7", 7, None, "end 7"),
          (1001.0, "after end", 70005, None, "after end")]
    for t, text, code, _, _ in m1 + m2 + m3:
        assert text not in text_code or text_code[text] == code
    mk_ts, mk_rows = [], []

    def marker_chunk(rows):
        body = bytearray(struct.pack("<I", 7) + varlen(len(rows)))
        for t, text, code, target, label in rows:
            if t is None:
                t = mk_ts[-1]  # irregular stream: previous + 0
                body += b"\x00"
            else:
                body += b"\x08" + struct.pack("<d", t)
            raw = text.encode("utf-8")
            body += varlen(len(raw)) + raw
            mk_ts.append(t)
            mk_rows.append((t, text, code, target, label))
        w.chunk(3, bytes(body), stream_id=7, n_samples=len(rows))

    # ---- the chunk sequence
    eeg_chunk(0, 20, "explicit", nlb=4, ns_bytes=1)
    marker_chunk(m1)
    clock = [(1000.1, 0.002), (1000.2, 0.002)]
    w.chunk(4, struct.pack("<Idd", 7, *clock[0]), stream_id=7)

    acc_ts, acc_vals = [], []
    body = bytearray(struct.pack("<I", 3) + varlen(10))
    for k in range(10):
        v = [-32768, 32767, k * 1000 - 4321] if k == 4 else [k, -k * 7, k * 1000 - 4321]
        if k == 0:
            t = 1000.0
            body += b"\x08" + struct.pack("<d", t)
        else:
            t = acc_ts[-1] + 1.0 / 50.0
            body += b"\x00"
        acc_ts.append(t)
        acc_vals.append(v)
        body += struct.pack("<3h", *v)
    w.chunk(3, bytes(body), nlb=1, stream_id=3, n_samples=10)

    eeg_chunk(20, 20, "deduced", nlb=8, ns_bytes=4)
    w.chunk(5, BOUNDARY)
    marker_chunk(m2)

    trig = [(1000.0 + 15.2 / 250.0, 5), (1000.0 + 44.1 / 250.0, 70000)]
    body = bytearray(struct.pack("<I", 4) + varlen(len(trig)))
    for t, v in trig:
        body += b"\x08" + struct.pack("<d", t) + struct.pack("<i", v)
    w.chunk(3, bytes(body), nlb=1, stream_id=4, n_samples=len(trig))

    w.chunk(99, b"unknown chunk, skipped")
    eeg_chunk(40, 20, "jitter", nlb=4, ns_bytes=8)
    marker_chunk(m3)

    temp_ts = [1000.0, 1000.1, 1000.2]
    temp_vals = [[0.1, 5e-324], [-1e300, 1.0 / 3.0], [2.0**-1074 * 3, -0.0]]
    body = bytearray(struct.pack("<I", 5) + varlen(3))
    for t, v in zip(temp_ts, temp_vals):
        body += b"\x08" + struct.pack("<d", t) + struct.pack("<2d", *v)
    w.chunk(3, bytes(body), stream_id=5, n_samples=3)
    w.chunk(4, struct.pack("<Idd", 7, *clock[1]), stream_id=7)

    streams = {
        1: (eeg_ts, 60), 7: (mk_ts, len(mk_ts)), 3: (acc_ts, 10), 4: ([t for t, _ in trig], 2),
        5: (temp_ts, 3),
    }
    for i, (sid, (ts, n)) in enumerate(streams.items()):
        xml = (
            f"<?xml version=\"1.0\"?>\n<info><writer>make_xdf_fixture.py</writer>"
            f"<first_timestamp>{ts[0]!r}</first_timestamp><last_timestamp>{ts[-1]!r}"
            f"</last_timestamp><sample_count>{n}</sample_count><clock_offsets>"
            + "".join(f"<offset><time>{a!r}</time><value>{b!r}</value></offset>"
                      for a, b in (clock if sid == 7 else []))
            + "</clock_offsets></info>"
        )
        w.chunk(6, struct.pack("<I", sid) + xml.encode("utf-8"), nlb=8 if i == 0 else None,
                stream_id=sid)

    # ---- what the reader must make of it
    factor = [1.0, 1.0, 1e3, 1e6]
    data_uv = [[eeg_vals[k][c] * factor[c] for k in range(60)] for c in range(4)]
    half = 0.5 / 250.0
    markers = []
    for t, text, code, target, label in mk_rows:
        ts = t + 0.002 + 0.0 * t  # clock fit: a = 0.002, b = 0
        if ts < eeg_ts[0] - half or ts > eeg_ts[-1] + half:
            sample = None
        else:
            sample = min(range(60), key=lambda k: (abs(eeg_ts[k] - ts), k))
        markers.append(dict(stream_id=7, timestamp=t, text=text, code=code, target=target,
                            label=label, sample=sample))
    for t, v in trig:
        sample = min(range(60), key=lambda k: (abs(eeg_ts[k] - t), k))
        markers.append(dict(stream_id=4, timestamp=t, text=str(v), code=v, target=None,
                            label=None, sample=sample))
    events = sorted(
        (dict(onset=m["sample"], code=m["code"], target=m["target"], label=m["label"])
         for m in markers if m["sample"] is not None),
        key=lambda e: e["onset"],
    )

    def stream(sid, name, typ, fmt, srate, n_ch, ts, values, labels, units):
        return dict(id=sid, name=name, type=typ, format=fmt, nominal_srate=srate,
                    channel_count=n_ch, n_samples=len(ts), timestamps=ts, values=values,
                    labels=labels, units=units)

    expected = dict(
        file="python_small.xdf",
        version="1.0",
        file_len=len(w.b),
        chunks=w.chunks,
        n_boundaries=1,
        n_unknown_chunks=1,
        streams=[
            stream(1, "TestAmp & Co", "EEG", "float32", 250.0, 4, eeg_ts,
                   [[v[c] for v in eeg_vals] for c in range(4)], eeg_labels, eeg_units),
            stream(7, "Markers \u00fc", "Markers", "string", 0.0, 1, mk_ts,
                   [[r[1]] for r in mk_rows], [], []),
            stream(3, "Acc", "ACC", "int16", 50.0, 3, acc_ts,
                   [[float(v[c]) for v in acc_vals] for c in range(3)], [], []),
            stream(4, "Triggers", "Markers", "int32", 0.0, 1, [t for t, _ in trig],
                   [[float(v) for _, v in trig]], [], []),
            stream(5, "Temp", "Misc", "double64", 10.0, 2, temp_ts,
                   [[v[c] for v in temp_vals] for c in range(2)], ["a", "b"], ["", ""]),
        ],
        clock_offsets={"7": clock},
        eeg=dict(stream_index=0, ch_names=eeg_labels, sfreq=250.0, scale_to_uv=factor,
                 data_uv=data_uv, source_id="amp-1234", created_at=999.5),
        markers=markers,
        events=events,
    )
    (OUT / "python_small.xdf").write_bytes(bytes(w.b))
    (OUT / "python_small.json").write_text(json.dumps(expected, ensure_ascii=False, indent=1))
    print(f"python_small.xdf ({len(w.b)} B): {len(w.chunks)} chunks, streams "
          f"{[(s['id'], s['n_samples']) for s in expected['streams']]}, "
          f"{len(events)} events of {len(markers)} markers")


if __name__ == "__main__":
    main()
