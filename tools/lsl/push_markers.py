"""A real LSL peer for oddball's tests: pushes a numeric marker stream with pylsl.

Stimulus programs send markers as numbers as often as strings. This one makes an
irregular-rate, one-channel stream of type Markers in --format (int32, float32, …), waits for a
receiver, prints one JSON line {"t0": T, "markers": [...], "hostname": H}, pushes the markers
(the k-th stamped t0 + 0.1 k on LSL's clock), then stays until its standard input closes (or
--linger seconds pass), so that the receiver sees the stream go away when the test decides.

    LSLAPICFG=tools/lsl/lsl_api.cfg python tools/lsl/push_markers.py --name m --format int32
"""

import argparse
import json
import socket
import sys
import threading

import pylsl

FORMATS = {
    "int8": pylsl.cf_int8,
    "int16": pylsl.cf_int16,
    "int32": pylsl.cf_int32,
    "int64": pylsl.cf_int64,
    "float32": pylsl.cf_float32,
    "double64": pylsl.cf_double64,
}
MARKERS = {
    "float32": [3.0, 0.25, -1.5, 12.0, 100.0],
    "double64": [3.0, 0.1, -1.5, 12.0, 1e6],
}
INTEGERS = [1, 2, 3, -4, 100]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--name", required=True)
    p.add_argument("--format", choices=sorted(FORMATS), default="int32")
    p.add_argument("--timeout", type=float, default=20.0, help="seconds to wait for a receiver")
    p.add_argument("--linger", type=float, default=30.0, help="seconds to stay at most")
    a = p.parse_args()

    info = pylsl.StreamInfo(a.name, "Markers", 1, pylsl.IRREGULAR_RATE, FORMATS[a.format], a.name)
    outlet = pylsl.StreamOutlet(info)
    if not outlet.wait_for_consumers(a.timeout):
        print(json.dumps({"error": "no receiver"}), flush=True)
        return 2
    markers = MARKERS.get(a.format, INTEGERS)
    t0 = pylsl.local_clock()
    print(
        json.dumps({"t0": t0, "markers": markers, "hostname": socket.gethostname()}),
        flush=True,
    )
    for k, m in enumerate(markers):
        outlet.push_sample([m], t0 + 0.1 * k)
    closed = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), closed.set()), daemon=True).start()
    closed.wait(a.linger)
    return 0


if __name__ == "__main__":
    sys.exit(main())
