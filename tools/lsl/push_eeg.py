"""A real LSL peer for oddball's tests: pushes a synthetic EEG stream with pylsl.

Channel c (0-based) carries a sine of (c + 1) Hz and 10 * (c + 1) µV peak; sample i is
stamped t0 + i / srate on LSL's clock and its value is the sine at i / srate, so a receiver
can check every value from its timestamp. Waits for a receiver, then prints one JSON line
({"t0", "srate", "channels", "unit", "freqs_hz", "amplitudes_uv", "gap"}) and pushes in real
time, 20 ms at a time. `--gap-at I --gap N` leaves samples I..I+N out (lost samples).
Values are sent in `--unit` (microvolts, millivolts, volts, nanovolts), labelled so.

    LSLAPICFG=tools/lsl/lsl_api.cfg python tools/lsl/push_eeg.py --name test-eeg --seconds 3
"""

import argparse
import json
import math
import sys
import time

import pylsl

UNITS = {"microvolts": 1.0, "millivolts": 1e-3, "volts": 1e-6, "nanovolts": 1e3}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--name", required=True)
    p.add_argument("--srate", type=float, default=500.0)
    p.add_argument("--channels", type=int, default=8)
    p.add_argument("--seconds", type=float, default=3.0)
    p.add_argument("--unit", choices=sorted(UNITS), default="microvolts")
    p.add_argument("--gap-at", type=int, default=-1)
    p.add_argument("--gap", type=int, default=0)
    p.add_argument("--wait", type=float, default=20.0, help="seconds to wait for a receiver")
    a = p.parse_args()

    labels = [f"EEG{c + 1}" for c in range(a.channels)]
    info = pylsl.StreamInfo(a.name, "EEG", a.channels, a.srate, "float32", f"pylsl-{a.name}")
    chans = info.desc().append_child("channels")
    for label in labels:
        chans.append_child("channel").append_child_value("label", label).append_child_value(
            "unit", a.unit
        ).append_child_value("type", "EEG")
    outlet = pylsl.StreamOutlet(info, 0, 360)
    if not outlet.wait_for_consumers(a.wait):
        print(json.dumps({"error": "no receiver"}), flush=True)
        return 2

    freqs = [float(c + 1) for c in range(a.channels)]
    amps = [10.0 * (c + 1) for c in range(a.channels)]
    scale = UNITS[a.unit]
    n = int(round(a.seconds * a.srate))
    skip = range(a.gap_at, a.gap_at + a.gap) if a.gap_at >= 0 else range(0)
    t0 = pylsl.local_clock() + 0.05
    print(
        json.dumps(
            {
                "t0": t0,
                "srate": a.srate,
                "channels": labels,
                "unit": a.unit,
                "freqs_hz": freqs,
                "amplitudes_uv": amps,
                "gap": [a.gap_at, a.gap] if a.gap else None,
                "samples": n - len(skip),
            }
        ),
        flush=True,
    )
    block = max(1, int(a.srate * 0.02))
    for start in range(0, n, block):
        due = t0 + start / a.srate
        delay = due - pylsl.local_clock()
        if delay > 0:
            time.sleep(delay)
        for i in range(start, min(n, start + block)):
            if i in skip:
                continue
            x = [
                scale * amps[c] * math.sin(2.0 * math.pi * freqs[c] * i / a.srate)
                for c in range(a.channels)
            ]
            outlet.push_sample(x, t0 + i / a.srate, pushthrough=(i == min(n, start + block) - 1))
    time.sleep(0.5)  # let the last samples reach the receiver before the outlet goes
    return 0


if __name__ == "__main__":
    sys.exit(main())
