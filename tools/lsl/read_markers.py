"""A real LSL peer for oddball's tests: receives an oddball marker stream with pylsl.

Resolves the stream by name, connects, prints {"ready": true} on a line, then prints each
marker as a JSON line {"marker": TEXT, "timestamp": T} (T on this machine's LSL clock,
time-corrected) until `end` arrives or nothing came for --idle seconds, and finally
{"count": N, "correction": C}.

    LSLAPICFG=tools/lsl/lsl_api.cfg python tools/lsl/read_markers.py --name oddball-markers
"""

import argparse
import json
import sys

import pylsl


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--name", required=True)
    p.add_argument("--type", default=None, help="also require this stream type")
    p.add_argument("--timeout", type=float, default=20.0, help="seconds to find the stream")
    p.add_argument("--idle", type=float, default=20.0, help="give up after this long silent")
    a = p.parse_args()

    found = pylsl.resolve_byprop("name", a.name, 1, a.timeout)
    if a.type is not None:
        found = [s for s in found if s.type() == a.type]
    if not found:
        print(json.dumps({"error": f"no stream named {a.name}"}), flush=True)
        return 2
    inlet = pylsl.StreamInlet(found[0], 360, 0, True)
    inlet.open_stream(a.timeout)
    correction = inlet.time_correction(5.0)
    print(json.dumps({"ready": True, "type": found[0].type()}), flush=True)
    count = 0
    while True:
        sample, ts = inlet.pull_sample(a.idle)
        if ts is None:
            break
        count += 1
        marker = " ".join(str(v) for v in sample)
        print(json.dumps({"marker": marker, "timestamp": ts + correction}), flush=True)
        if marker == "end":
            break
    print(json.dumps({"count": count, "correction": correction}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
