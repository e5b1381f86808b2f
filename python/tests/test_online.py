"""oddball.online.OnlineDecoder: `oddball decode`'s engine fed from a Python loop.

A recording is fed as a stimulus loop would feed it: EEG in blocks with the time of each block's
last sample, the markers of `tools/lsl/play_recording.py` (TrialStart, Stim/{code}, Target or
NonTarget, TrialEnd) with their flashes' times. Blocks of random sizes and markers delivered late
and out of order within the epoch window must change no decision.
"""
from __future__ import annotations


import numpy as np
import pytest

import oddball
from conftest import REPO, data_file

PARADIGM = REPO / "paradigms" / "speller-6x6-rows-first.toml"


def markers(raw, per_trial=180):
    """(time s, text) of the recording's flashes as the reference program announces them."""
    sf = raw.sfreq
    onsets, codes = raw.events[:, 0], raw.events[:, 2]
    out = []
    for start in range(0, len(onsets), per_trial):
        idx = range(start, min(start + per_trial, len(onsets)))
        first, last = onsets[idx[0]] / sf, onsets[idx[-1]] / sf
        out.append((first - 0.001, "TrialStart"))
        for i in idx:
            t = onsets[i] / sf
            out.append((t, f"Stim/{codes[i]}"))
            out.append((t, "Target" if raw.event_targets[i] == 1 else "NonTarget"))
        out.append((last + 0.001, "TrialEnd"))
    return out


def feed(dec, raw, marks, block, delay):
    """Pushes the EEG `block(i)` samples at a time; each marker once the EEG has reached its
    time plus `delay(k)` s. Returns every message."""
    due = sorted(((t + delay(k), k) for k, (t, _) in enumerate(marks)))
    out, nxt, i, n = [], 0, 0, raw.n_times
    while i < n:
        m = max(1, min(block(i), n - i))
        last = (i + m - 1) / raw.sfreq
        while nxt < len(due) and due[nxt][0] <= last:
            t, text = marks[due[nxt][1]]
            out += dec.push_marker(text, t)
            nxt += 1
        out += dec.push_eeg(raw.data[:, i:i + m], last)
        i += m
    return out + dec.finish()


def decisions(msgs):
    return [m for m in msgs if m["type"] == "decision"]


@pytest.fixture(scope="module")
def eeg3():
    return oddball.read_raw(data_file("bci2000-samplefiles-p300/eeg3_2.dat"))


@pytest.mark.parametrize("calibration", [0, 2])
def test_random_blocks_and_late_markers_change_no_decision(eeg3, calibration):
    marks = markers(eeg3)
    make = lambda: oddball.online.OnlineDecoder(PARADIGM, eeg3.sfreq, eeg3.ch_names,
                                                calibration=calibration)
    reference = feed(make(), eeg3, marks, lambda i: 10, lambda k: 0.0)
    rng = np.random.default_rng(7)
    sizes = rng.integers(1, 200, size=eeg3.n_times)
    late = rng.uniform(0.0, 0.3, size=len(marks))
    shuffled = feed(make(), eeg3, marks, lambda i: int(sizes[i]), lambda k: float(late[k]))
    assert shuffled == reference
    ds = decisions(reference)
    assert len(ds) == 4 - calibration
    if calibration:
        assert [m for m in reference if m["type"] == "calibrated"][0]["trials"] == 2
        # Calibrated on 6M, it spells the rest of 6MK?.
        assert "".join(d["choice"] for d in ds) == "K?"
    for d in ds:
        assert abs(sum(d["posterior"].values()) - 1.0) < 1e-9
        assert d["flashes"] == 180


def test_dynamic_stopping_says_when_to_stop(eeg3):
    marks = markers(eeg3)
    dec = oddball.online.OnlineDecoder(PARADIGM, eeg3.sfreq, eeg3.ch_names, calibration=2,
                                       dynamic_stopping=True)
    msgs = feed(dec, eeg3, marks, lambda i: 32, lambda k: 0.0)
    stops = [m["trial"] for m in msgs if m["type"] == "stop"]
    assert stops, msgs
    for trial in stops:
        assert dec.stop_wanted(trial)
        d = [m for m in decisions(msgs) if m["trial"] == trial][0]
        assert d["early"] and d["flashes"] < 180
    assert dec.counts()["unknown"] == 0


def test_bad_input_is_refused_or_counted(eeg3):
    with pytest.raises(ValueError, match="choices.codes"):
        oddball.online.OnlineDecoder(
            'name = "x"\n[choices]\nlabels = ["a", "b"]\ncodes = [1, 1]\n'
            '[markers]\nflash = "{code}"\ntrial_end = "end"\n',
            250.0, ["Pz"], paradigm_text=True)
    dec = oddball.online.OnlineDecoder(PARADIGM, eeg3.sfreq, eeg3.ch_names)
    with pytest.raises(ValueError, match="channels"):
        dec.push_eeg(np.zeros((3, 10)), 0.1)
    dec.push_eeg(eeg3.data[:, :100], 99 / eeg3.sfreq)
    assert dec.push_marker("Hello", 0.2) == []
    assert dec.counts()["unknown"] == 1
