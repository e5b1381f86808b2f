"""Tests of play_recording.py on its own (no oddball decode): a tiny synthetic BCI2000 recording
played at --speed 10, both outlets read here with pylsl.

    LSLAPICFG=$PWD/tools/lsl/lsl_api.cfg /tmp/venv-play/bin/python -m pytest tools/lsl/test_play_recording.py
    (or run the file with that Python: it runs every test_* function)

Needs pylsl, numpy and oddball's Python package in the running Python. Channel 0 of the recording
holds the sample index itself (exact in float32), so every EEG sample received says which sample
of the file it is, and each Stim marker can be checked against the EEG sample of its onset.
"""

import json
import os
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
os.environ.setdefault("LSLAPICFG", str(HERE / "lsl_api.cfg"))

import numpy as np  # noqa: E402
import pylsl  # noqa: E402

SFREQ = 250.0
SOA = 50  # samples between flashes (0.2 s)
ON = 25  # samples a flash lasts
TRIAL_STARTS = [250, 1100, 1950]  # first flash of each trial (samples)
CODES = [1, 3, 2, 4, 2, 1, 4, 3]  # one trial's codes; code 2 is the target
N_TIMES = 2750


def flashes():
    """(onset, code, target) of every flash of the synthetic recording."""
    out = []
    for start in TRIAL_STARTS:
        for j, code in enumerate(CODES):
            out.append((start + j * SOA, code, code == 2))
    return out


def write_bci2000(path):
    """A BCI2000 v1.1 float32 file: channels Cz (= the sample index) and Pz (= -index / 8), states
    Running, StimulusCode (8 bits) and StimulusType (1 bit)."""
    n_ch = 2
    i = np.arange(N_TIMES, dtype=np.float64)
    data = np.stack([i, -i / 8.0]).astype(np.float32)
    code = np.zeros(N_TIMES, dtype=np.uint32)
    typ = np.zeros(N_TIMES, dtype=np.uint32)
    for onset, c, target in flashes():
        code[onset:onset + ON] = c
        typ[onset:onset + ON] = 1 if target else 0
    # State vector: Running bit 0, StimulusCode bits 1..8, StimulusType bit 9 -> 2 bytes.
    sv = (1 | (code << 1) | (typ << 9)).astype("<u2")
    props = "Source:Signal%20Properties:DataIOFilter"
    rest = (
        "[ State Vector Definition ]\r\n"
        "Running 1 1 0 0\r\n"
        "StimulusCode 8 0 0 1\r\n"
        "StimulusType 1 0 1 1\r\n"
        "[ Parameter Definition ]\r\n"
        f"{props} int SourceCh= {n_ch} // channels\r\n"
        f"{props} int SampleBlockSize= 5 // block\r\n"
        f"{props} float SamplingRate= {SFREQ:g}Hz // rate\r\n"
        f"{props} list ChannelNames= {n_ch} Cz Pz // names\r\n"
        f"{props} floatlist SourceChOffset= {n_ch} 0 0 // offsets\r\n"
        f"{props} floatlist SourceChGain= {n_ch} 1 1 // gains\r\n"
        "System:State%20Vector int StateVectorLength= 2 // bytes\r\n"
        "\r\n"
    )

    def first(n):
        return f"BCI2000V= 1.1 HeaderLen= {n} SourceCh= {n_ch} StatevectorLen= 2 DataFormat= float32\r\n"

    n = len(rest)
    while len(first(n)) + len(rest) != n:
        n = len(first(n)) + len(rest)
    body = bytearray()
    for t in range(N_TIMES):
        body += struct.pack("<2f", data[0, t], data[1, t])
        body += struct.pack("<H", int(sv[t]))
    Path(path).write_bytes((first(n) + rest).encode("ascii") + bytes(body))


_RUN = [0]


def play(path, extra=(), on_marker=None, decisions_name=None, timeout=60.0):
    """Runs play_recording.py on `path` at --speed 10 and reads both outlets. `on_marker(text, ts,
    markers_so_far)` is called for each marker as it arrives. Returns a dict: markers [(text, ts)],
    stamps (n,), values (n, 2), lead (first EEG stamp minus the local clock when it arrived),
    summary (the --json-summary), rc, out."""
    _RUN[0] += 1
    tag = f"{os.getpid()}-{_RUN[0]}"
    eeg_name, mk_name = f"test-play-eeg-{tag}", f"test-play-markers-{tag}"
    tmp = tempfile.mkdtemp(prefix="play-test-")
    summary_path = os.path.join(tmp, "summary.json")
    cmd = [sys.executable, str(HERE / "play_recording.py"), str(path), "--eeg", eeg_name,
           "--markers", mk_name, "--speed", "10", "--wait", "20", "--json-summary", summary_path, *extra]
    if decisions_name:
        cmd += ["--listen", decisions_name, "--final-wait", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=os.environ.copy())
    try:
        inlets = {}
        deadline = time.monotonic() + 20
        for name in (eeg_name, mk_name):
            while True:
                found = pylsl.resolve_byprop("name", name, 1, 0.5)
                if found:
                    inlet = pylsl.StreamInlet(found[0], max_buflen=60, processing_flags=0)
                    inlet.open_stream(timeout=5)
                    inlets[name] = inlet
                    break
                assert proc.poll() is None, proc.stdout.read()
                assert time.monotonic() < deadline, "play_recording.py's outlets never appeared"
        markers, stamps, values = [], [], []
        lead = None
        end = time.monotonic() + timeout
        done_at = None
        while time.monotonic() < end:
            got = False
            try:
                chunk, ts = inlets[eeg_name].pull_chunk(timeout=0.0)
                if ts:
                    if lead is None:
                        lead = ts[0] - pylsl.local_clock()
                    stamps += ts
                    values += chunk
                    got = True
                while True:
                    s, t = inlets[mk_name].pull_sample(timeout=0.0)
                    if s is None:
                        break
                    markers.append((s[0], t))
                    got = True
                    if on_marker:
                        on_marker(s[0], t, markers)
            except pylsl.LostError:
                break
            if proc.poll() is not None:
                done_at = done_at or time.monotonic()
                if time.monotonic() - done_at > 0.5:
                    break
            if not got:
                time.sleep(0.002)
        out = proc.communicate(timeout=10)[0] if proc.poll() is not None else ""
        assert proc.returncode is not None, "play_recording.py did not finish"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    summary = json.loads(Path(summary_path).read_text()) if os.path.exists(summary_path) else None
    return {
        "markers": markers,
        "stamps": np.asarray(stamps, dtype=np.float64),
        "values": np.asarray(values, dtype=np.float64).reshape(-1, 2),
        "lead": lead,
        "summary": summary,
        "rc": proc.returncode,
        "out": out,
    }


def expected_texts(trials):
    out = []
    for flashes_of_trial in trials:
        out.append("TrialStart")
        for _, code, target in flashes_of_trial:
            out += [f"Stim/{code}", "Target" if target else "NonTarget"]
        out.append("TrialEnd")
    return out


def check_stamps_on_eeg(r):
    """Each Stim marker's stamp is the stamp of the EEG sample that is its onset sample of the
    file (to 1 µs); Target/NonTarget share it; TrialStart is 1 ms before a trial's first flash."""
    stamps, idx = r["stamps"], r["values"][:, 0]
    onsets = {o for o, _, _ in flashes()}
    assert len(stamps) > 0
    d = np.diff(stamps)
    assert np.all(np.abs(d - 1.0 / SFREQ) < 1e-6), "EEG stamps are t0 + k / sfreq, without gaps"
    m = r["markers"]
    for i, (text, ts) in enumerate(m):
        if not text.startswith("Stim/"):
            continue
        k = int(np.argmin(np.abs(stamps - ts)))
        assert abs(stamps[k] - ts) < 1e-6, f"{text} at {ts} is on no EEG stamp"
        assert int(idx[k]) in onsets, f"{text} falls on file sample {idx[k]}, not an onset"
        code = dict((o, c) for o, c, _ in flashes())[int(idx[k])]
        assert text == f"Stim/{code}"
        assert m[i + 1][0] in ("Target", "NonTarget") and m[i + 1][1] == ts
        if m[i - 1][0] == "TrialStart":
            assert abs(m[i - 1][1] - (ts - 0.001)) < 1e-9


def test_plays_markers_on_eeg_stamps():
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "tiny.dat"
        write_bci2000(path)
        r = play(path)
    assert r["rc"] == 0, r["out"]
    trials = [flashes()[i:i + 8] for i in range(0, 24, 8)]
    assert [t for t, _ in r["markers"]] == expected_texts(trials)
    check_stamps_on_eeg(r)
    # TrialEnd 1 ms after the trial's last flash.
    m = r["markers"]
    for i, (text, ts) in enumerate(m):
        if text == "TrialEnd":
            assert abs(ts - (m[i - 2][1] + 0.001)) < 1e-9
    # The whole file up to the last flash + 1.5 s, in order.
    n = TRIAL_STARTS[-1] + 7 * SOA + int(1.5 * SFREQ) + 1
    assert np.array_equal(r["values"][:, 0], np.arange(n))
    assert abs(r["lead"]) < 0.2, f"stamps on the local clock (lead {r['lead']:.3f} s)"
    s = r["summary"]
    assert s["total_flashes"] == 24 and [t["flashes"] for t in s["trials"]] == [8, 8, 8]
    assert s["decisions"] == 0 and not s["interrupted"]


def test_clock_offset_moves_both_outlets():
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "tiny.dat"
        write_bci2000(path)
        r = play(path, ["--clock-offset-ms", "30"])
    assert r["rc"] == 0, r["out"]
    trials = [flashes()[i:i + 8] for i in range(0, 24, 8)]
    assert [t for t, _ in r["markers"]] == expected_texts(trials)
    check_stamps_on_eeg(r)
    # The stamps run 30 ms ahead of this process's local clock (the same machine's).
    assert 0.03 - 0.2 < r["lead"] < 0.03 + 0.01, f"lead {r['lead']:.3f} s"
    assert r["lead"] > 0.0


def test_stop_shortens_the_trial():
    name = f"test-play-decisions-{os.getpid()}"
    info = pylsl.StreamInfo(name, "oddball-decisions", 1, pylsl.IRREGULAR_RATE, "string", f"{name}-src")
    outlet = pylsl.StreamOutlet(info)
    sent = {"stop": False}

    def on_marker(text, ts, markers):
        trial = sum(1 for t, _ in markers if t == "TrialStart")
        stims = 0
        for t, _ in reversed(markers):
            if t == "TrialStart":
                break
            stims += t.startswith("Stim/")
        if trial == 2 and stims == 2 and not sent["stop"]:
            sent["stop"] = True
            outlet.push_sample([json.dumps({"type": "stop", "trial": 2})])
            outlet.push_sample([json.dumps({"type": "decision", "trial": 2, "choice": "2",
                                            "posterior": {"1": 0.0, "2": 1.0}, "flashes": 2, "time": ts})])
        if text == "TrialEnd" and trial in (1, 3):
            outlet.push_sample([json.dumps({"type": "decision", "trial": trial, "choice": None,
                                            "posterior": {}, "flashes": 8, "time": ts})])

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "tiny.dat"
        write_bci2000(path)
        r = play(path, decisions_name=name, on_marker=on_marker)
    del outlet
    assert r["rc"] == 0, r["out"]
    assert sent["stop"]
    texts = [t for t, _ in r["markers"]]
    per_trial, cur = [], None
    for t in texts:
        if t == "TrialStart":
            cur = 0
        elif t.startswith("Stim/"):
            cur += 1
        elif t == "TrialEnd":
            per_trial.append(cur)
    assert len(per_trial) == 3 and per_trial[0] == 8 and per_trial[2] == 8
    assert 2 <= per_trial[1] < 8, f"trial 2 played {per_trial[1]} flashes"
    check_stamps_on_eeg(r)
    # The EEG jumped from inside trial 2 to 0.5 s before trial 3's first flash, stamps unbroken.
    idx = r["values"][:, 0].astype(int)
    cuts = np.nonzero(np.diff(idx) != 1)[0]
    assert len(cuts) == 1
    assert idx[cuts[0] + 1] == TRIAL_STARTS[2] - int(0.5 * SFREQ)
    assert TRIAL_STARTS[1] < idx[cuts[0]] < TRIAL_STARTS[1] + 7 * SOA
    # The early TrialEnd is stamped at the cut (the next EEG sample's stamp).
    end2 = [ts for t, ts in r["markers"] if t == "TrialEnd"][1]
    assert abs(end2 - r["stamps"][cuts[0] + 1]) < 1e-6
    s = r["summary"]
    assert [t["flashes"] for t in s["trials"]] == per_trial
    assert [t["stopped_early"] for t in s["trials"]] == [False, True, False]
    assert s["total_flashes"] == sum(per_trial) < 24
    assert s["decisions"] == 3 and s["stops"] == 1
    assert "stopped by the decoder" in r["out"]


def test_options_checked_before_streaming():
    for args in (["--speed", "0"], ["--flashes-per-trial", "0"], ["--clock-offset-ms", "nan"],
                 ["--json-summary", "/nonexistent-folder/x.json"]):
        p = subprocess.run([sys.executable, str(HERE / "play_recording.py"), "/dev/null", "--eeg", "a",
                            "--markers", "b", *args], capture_output=True, text=True, timeout=60)
        assert p.returncode == 2, (args, p.stderr)
    p = subprocess.run([sys.executable, str(HERE / "play_recording.py"), "/no/such.dat", "--eeg", "a",
                        "--markers", "b"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "no such file" in p.stderr


if __name__ == "__main__":
    for name, fn in list(globals().items()):
        if name.startswith("test_") and callable(fn):
            t = time.monotonic()
            fn()
            print(f"{name}: ok ({time.monotonic() - t:.1f} s)", flush=True)
