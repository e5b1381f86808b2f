#!/usr/bin/env python3
"""Load an XDF file with pyxdf and print a JSON summary of it on stdout.

    python pyxdf_read.py FILE [--full]

Per stream (in pyxdf's order): id, name, type, channel count, nominal rate, channel format,
number of samples, first and last timestamp, first and last sample's values, the footer's
sample_count; with --full also every timestamp and every value (channel-major for numbers,
[sample][channel] for strings). Timestamps are the file's own: no clock synchronization and no
dejittering. Numbers are printed with Python's shortest round-trip repr, so they can be
compared bit for bit.
"""

import json
import sys

import numpy as np
import pyxdf


def first(info, key):
    v = info.get(key)
    if isinstance(v, list):
        v = v[0] if v else None
    return v


def main():
    args = sys.argv[1:]
    full = "--full" in args
    files = [a for a in args if a != "--full"]
    if len(files) != 1:
        sys.exit(__doc__)
    streams, header = pyxdf.load_xdf(
        files[0], synchronize_clocks=False, dejitter_timestamps=False
    )
    out = {
        "file": files[0],
        "pyxdf_version": pyxdf.__version__,
        "version": first(header["info"], "version") if header else None,
        "streams": [],
    }
    for s in streams:
        info = s["info"]
        fmt = first(info, "channel_format")
        ts = np.asarray(s["time_stamps"], dtype=np.float64)
        d = {
            "stream_id": int(info["stream_id"]),
            "name": first(info, "name") or "",
            "type": first(info, "type") or "",
            "channel_count": int(first(info, "channel_count")),
            "nominal_srate": float(first(info, "nominal_srate")),
            "channel_format": fmt,
            "n_samples": int(ts.size),
            "first_timestamp": float(ts[0]) if ts.size else None,
            "last_timestamp": float(ts[-1]) if ts.size else None,
        }
        footer = s.get("footer")
        d["footer_sample_count"] = (
            int(first(footer["info"], "sample_count")) if footer else None
        )
        if fmt == "string":
            values = [list(v) for v in s["time_series"]]
            d["first_values"] = values[0] if values else None
            d["last_values"] = values[-1] if values else None
            if full:
                d["values"] = values
        else:
            arr = np.asarray(s["time_series"], dtype=np.float64).reshape(
                ts.size, d["channel_count"]
            )
            d["first_values"] = [float(x) for x in arr[0]] if ts.size else None
            d["last_values"] = [float(x) for x in arr[-1]] if ts.size else None
            if full:
                d["values"] = [[float(x) for x in row] for row in arr.T]
        if full:
            d["time_stamps"] = [float(t) for t in ts]
        out["streams"].append(d)
    json.dump(out, sys.stdout, ensure_ascii=False, allow_nan=False)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
