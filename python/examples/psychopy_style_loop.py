"""A PsychoPy-style stimulus loop that asks oddball's online decoder for its decisions.

The shape of a real experiment script, runnable without a display or an amplifier: a recording
stands in for both. Its flashes are the "stimuli" the loop presents (``win.flip()`` would draw
them), its EEG arrives in blocks as an amplifier delivers them, and each flash's marker goes to
the decoder with the time its frame appeared. After every flash the loop asks ``stop_wanted()``:
with dynamic stopping the decoder says when it is sure, and the loop ends the trial early and
goes on to the next character. Run it as::

    python examples/psychopy_style_loop.py ../shared/data/bci2000-samplefiles-p300/eeg3_2.dat \\
        --paradigm paradigms/speller-6x6-rows-first.toml --calibration 2 --dynamic-stopping

or with a model from ``oddball train`` (``--model eeg3_1.json``). In a real script, replace
``Amplifier`` by your EEG source (pylsl's ``StreamInlet.pull_chunk``) and ``Screen.flip`` by
PsychoPy's ``win.flip()`` (its return value is the flip's time).
"""
from __future__ import annotations

import argparse

import numpy as np

import oddball


class Amplifier:
    """The recording's EEG, handed out in blocks up to a time (as an amplifier's buffer)."""

    def __init__(self, raw, block=20):
        self.raw, self.block, self.sent = raw, block, 0

    def pull_until(self, t):
        """Blocks ``(samples, time of the last)`` whose samples are all at or before ``t``."""
        out = []
        end = min(self.raw.n_times, int(np.floor(t * self.raw.sfreq)) + 1)
        while self.sent < end:
            n = min(self.block, end - self.sent)
            out.append((self.raw.data[:, self.sent:self.sent + n], (self.sent + n - 1) / self.raw.sfreq))
            self.sent += n
        return out


class Screen:
    """Stands in for ``psychopy.visual.Window``: ``flip`` returns when the frame appeared."""

    def flip(self, t):
        return t


def trials_of(raw, per_trial):
    """The recording's flashes grouped by trial: (onset s, code, target flag) lists."""
    fl = [(o / raw.sfreq, int(c), int(t)) for (o, _, c), t in zip(raw.events, raw.event_targets)]
    return [fl[i:i + per_trial] for i in range(0, len(fl), per_trial)]


def run(path, paradigm, model=None, calibration=0, dynamic_stopping=False, per_trial=180):
    raw = oddball.read_raw(path)
    dec = oddball.online.OnlineDecoder(paradigm, raw.sfreq, raw.ch_names, model=model,
                                       calibration=calibration, dynamic_stopping=dynamic_stopping)
    amp, win = Amplifier(raw), Screen()
    messages, shown = [], 0
    for n, trial in enumerate(trials_of(raw, per_trial), start=1):
        messages += dec.push_marker("TrialStart", trial[0][0] - 0.001)
        for onset, code, target in trial:
            t = win.flip(onset)  # the flash appears
            messages += dec.push_marker(f"Stim/{code}", t)
            if n <= calibration:  # a calibration trial says which flashes were the target
                messages += dec.push_marker("Target" if target == 1 else "NonTarget", t)
            shown += 1
            for block, last in amp.pull_until(t):
                messages += dec.push_eeg(block, last)
            if dec.stop_wanted(n):
                break
        # The epochs of the last flashes need 0.8 s more EEG; then the trial ends.
        messages += dec.push_marker("TrialEnd", t + 0.001)
        for block, last in amp.pull_until(t + 1.0):
            messages += dec.push_eeg(block, last)
    for block, last in amp.pull_until(raw.n_times / raw.sfreq):
        messages += dec.push_eeg(block, last)
    messages += dec.finish()
    decisions = [m for m in messages if m["type"] == "decision"]
    return decisions, shown


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording")
    ap.add_argument("--paradigm", required=True)
    ap.add_argument("--model", help="a model file from `oddball train`")
    ap.add_argument("--calibration", type=int, default=0, help="first trials that calibrate (0: none)")
    ap.add_argument("--dynamic-stopping", action="store_true")
    a = ap.parse_args(argv)
    model = open(a.model).read() if a.model else None
    decisions, shown = run(a.recording, a.paradigm, model, a.calibration, a.dynamic_stopping)
    for d in decisions:
        print(f"trial {d['trial']}: {d['choice'] or '(abstains)'} after {d['flashes']} flashes, "
              f"posterior {max(d['posterior'].values()):.3f}")
    print(f"spelled {''.join(d['choice'] or '-' for d in decisions)!r} with {shown} flashes shown")


if __name__ == "__main__":
    main()
