#!/usr/bin/env python3
"""Plays a recording over LSL as a stimulus program would: the reference peer of `oddball decode`.

    LSLAPICFG=tools/lsl/lsl_api.cfg python tools/lsl/play_recording.py eeg3_2.dat \\
        --eeg play-eeg --markers play-markers --listen oddball-decisions

Reads FILE with oddball's own readers (`oddball.read_raw`, so every format oddball reads plays)
and opens two LSL outlets:

* EEG (`--eeg NAME`, type `EEG`): float32 (or `--channel-format double64`), nominal rate = the file's, channel labels and unit
  `microvolts` in desc/channels. Stream sample k is stamped exactly `t0 + k / sfreq` and pushed
  in chunks of `--chunk-ms` (20 ms) once its time has come (`--speed X` pushes X times faster;
  the stamps stay on the recording's time base, so with X != 1 they run ahead of the clock).
* Markers (`--markers NAME`, type `Markers`, one string channel), its own texts:
    `TrialStart`           before a trial's first flash, stamped 1 ms before that flash;
    `Stim/{code}`          at each flash, stamped with the EEG stamp of the flash's onset sample;
    `Target`/`NonTarget`   right after a labelled flash's `Stim/{code}`, with the SAME stamp;
    `TrialEnd`             after a trial's last flash, stamped 1 ms after it; or, when the
                           decoder stopped the trial early (or Ctrl-C came inside a trial),
                           stamped with the current stream time (the next EEG sample's stamp).
  A marker is pushed as the EEG chunk holding its sample is pushed (just before it).

`--clock-offset-ms MS` stamps both outlets with local_clock() + MS: a stimulus program whose clock
is off the decoder's by MS, which LSL's time correction cannot see. Markers still fall on the
EEG's own stamps, so a decoder that maps markers onto the EEG stamps epochs them right.

Trials come from the recording: `--flashes-per-trial N` consecutive flashes, else runs of flashes
split where two consecutive flashes are further apart than `--trial-gap S` (default: 3 x the
median inter-flash interval). Trials are numbered 1, 2, ... in the order played.

`--listen NAME` reads the decoder's outlet (JSON text per message, `{"type": "stop", "trial": 3}`
or `{"type": "decision", "trial": 3, ...}`). A stop or decision for the trial being played ends
it at once (TrialEnd) and the playback jumps ahead in the recording to `--resume-before` (0.5 s)
before the next trial's first flash; the EEG stamps continue without a gap (the EEG itself has a
cut there). The last flash is followed by `--tail` (1.5 s) of EEG (the last sample held if the
file ends sooner), then, when listening, up to `--final-wait` s for the remaining decisions.

Prints per trial the flashes played and at the end the totals; `--json-summary FILE` writes them:
{"file", "sfreq", "trials": [{"trial", "flashes", "recorded_flashes", "stopped_early"}],
"total_flashes", "total_seconds" (stream time), "wall_seconds", "decisions", "stops",
"interrupted"}. Exit status 0, 2 for a usage error, 1 for an unreadable recording, 130 after
Ctrl-C / SIGTERM (outlets closed, summary written).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import queue
import signal
import sys
import threading
import time

import numpy as np
import pylsl


def parse_args(argv):
    p = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="\n".join(__doc__.splitlines()[1:]),
    )
    p.add_argument("file", metavar="FILE", help="a recording oddball reads (.dat .csv .edf .bdf .easy .xdf .mat)")
    p.add_argument("--eeg", required=True, metavar="NAME", help="name of the EEG outlet")
    p.add_argument("--markers", required=True, metavar="NAME", help="name of the marker outlet")
    p.add_argument("--listen", metavar="NAME", help="name of the decoder's outlet to follow (stop / decision)")
    p.add_argument("--clock-offset-ms", type=float, default=0.0, metavar="MS",
                   help="stamp both outlets with local_clock() + MS (default 0)")
    p.add_argument("--flashes-per-trial", type=int, metavar="N", help="N consecutive flashes make a trial")
    p.add_argument("--trial-gap", type=float, metavar="S",
                   help="a pause longer than S seconds between flashes starts a new trial "
                        "(default 3 x the median inter-flash interval)")
    p.add_argument("--speed", type=float, default=1.0, metavar="X", help="playback speed (default 1: real time)")
    p.add_argument("--channel-format", choices=["float32", "double64"], default="float32",
                   help="EEG sample format (default float32, as amplifiers send; double64 carries the "
                        "recording's values exactly)")
    p.add_argument("--chunk-ms", type=float, default=20.0, metavar="MS", help="EEG chunk length (default 20)")
    p.add_argument("--tail", type=float, default=1.5, metavar="S", help="EEG after the last flash (default 1.5)")
    p.add_argument("--resume-before", type=float, default=0.5, metavar="S",
                   help="after an early stop, resume S seconds before the next trial's first flash (default 0.5)")
    p.add_argument("--wait", type=float, default=60.0, metavar="S",
                   help="wait up to S seconds for a consumer on both outlets (and for the --listen "
                        "stream) before playing; 0 = start at once (default 60)")
    p.add_argument("--final-wait", type=float, default=3.0, metavar="S",
                   help="with --listen, wait up to S seconds after the tail for outstanding decisions (default 3)")
    p.add_argument("--json-summary", metavar="FILE", help="write the summary as JSON")
    a = p.parse_args(argv)

    def bad(msg):
        p.error(msg)

    if not a.eeg.strip() or not a.markers.strip():
        bad("--eeg and --markers need a non-empty stream name")
    if a.eeg == a.markers:
        bad("--eeg and --markers must name different streams")
    if a.listen is not None and not a.listen.strip():
        bad("--listen needs a non-empty stream name")
    if not math.isfinite(a.clock_offset_ms) or abs(a.clock_offset_ms) > 3.6e6:
        bad(f"--clock-offset-ms must be a finite number of ms within an hour, not {a.clock_offset_ms}")
    if a.flashes_per_trial is not None and a.flashes_per_trial < 1:
        bad(f"--flashes-per-trial must be at least 1, not {a.flashes_per_trial}")
    if a.flashes_per_trial is not None and a.trial_gap is not None:
        bad("give --flashes-per-trial or --trial-gap, not both")
    for name in ("trial_gap", "speed", "chunk_ms"):
        v = getattr(a, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            bad(f"--{name.replace('_', '-')} must be a positive number, not {v}")
    for name in ("tail", "resume_before", "wait", "final_wait"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v >= 0):
            bad(f"--{name.replace('_', '-')} must be a number of seconds >= 0, not {v}")
    if not os.path.isfile(a.file):
        bad(f"{a.file}: no such file")
    if a.json_summary:
        folder = os.path.dirname(os.path.abspath(a.json_summary))
        if not os.path.isdir(folder):
            bad(f"--json-summary: the folder {folder} does not exist")
        if not os.access(folder, os.W_OK):
            bad(f"--json-summary: the folder {folder} is not writable")
    return a


def split_trials(onsets, sfreq, flashes_per_trial, trial_gap):
    """Lists of flash indices (into the onset-sorted flashes), one per trial."""
    n = len(onsets)
    if flashes_per_trial:
        return [list(range(i, min(i + flashes_per_trial, n))) for i in range(0, n, flashes_per_trial)]
    if n == 1:
        return [[0]]
    gaps = np.diff(onsets) / sfreq
    if trial_gap is None:
        trial_gap = 3.0 * float(np.median(gaps))
    trials, cur = [], [0]
    for i in range(1, n):
        if gaps[i - 1] > trial_gap:
            trials.append(cur)
            cur = []
        cur.append(i)
    trials.append(cur)
    return trials


class Listener(threading.Thread):
    """Follows the decoder's outlet: resolves it by name (again after a loss) and queues each
    message as a dict."""

    def __init__(self, name):
        super().__init__(daemon=True)
        self.name_ = name
        self.messages = queue.Queue()
        self.connected = threading.Event()
        self.stopping = threading.Event()
        self.bad = 0

    def run(self):
        inlet = None
        while not self.stopping.is_set():
            if inlet is None:
                found = pylsl.resolve_byprop("name", self.name_, 1, 0.5)
                if found:
                    inlet = pylsl.StreamInlet(found[0], max_buflen=60, recover=True)
                    try:
                        inlet.open_stream(timeout=5.0)
                    except Exception:  # noqa: BLE001 - retried on the next round
                        inlet = None
                        continue
                    self.connected.set()
                continue
            try:
                sample, _ = inlet.pull_sample(timeout=0.1)
            except pylsl.LostError:
                inlet = None
                continue
            if sample is None:
                continue
            try:
                msg = json.loads(sample[0])
                if not isinstance(msg, dict):
                    raise ValueError
            except ValueError:
                self.bad += 1
                print(f"play_recording: ignored a message that is not a JSON object: {sample[0]!r}",
                      file=sys.stderr, flush=True)
                continue
            self.messages.put(msg)


class Player:
    def __init__(self, a, rec):
        self.a = a
        self.data = np.asarray(rec.data, dtype=np.float64 if a.channel_format == "double64" else np.float32)
        self.sfreq = float(rec.sfreq)
        self.ch_names = list(rec.ch_names)
        order = np.argsort(rec.events[:, 0], kind="stable")
        self.onsets = rec.events[order, 0].astype(np.int64)
        self.codes = rec.events[order, 2].astype(np.int64)
        self.targets = np.asarray(rec.event_targets)[order]
        self.trials = split_trials(self.onsets, self.sfreq, a.flashes_per_trial, a.trial_gap)
        self.offset = a.clock_offset_ms / 1000.0
        self.stop_flag = False
        self.listener = None
        self.results = []  # per trial: dict
        self.decisions = 0
        self.stops = 0
        self.decided_trials = set()
        self.k = 0  # stream samples pushed
        self.wall0 = None

    # -- outlets --------------------------------------------------------------------------
    def open(self):
        a = self.a
        n_ch = self.data.shape[0]
        info = pylsl.StreamInfo(a.eeg, "EEG", n_ch, self.sfreq, a.channel_format, f"play_recording-{a.eeg}-{os.getpid()}")
        chans = info.desc().append_child("channels")
        for label in self.ch_names:
            ch = chans.append_child("channel")
            ch.append_child_value("label", label)
            ch.append_child_value("unit", "microvolts")
            ch.append_child_value("type", "EEG")
        info.desc().append_child_value("manufacturer", "oddball play_recording.py")
        self.eeg = pylsl.StreamOutlet(info, 0, 360)
        minfo = pylsl.StreamInfo(a.markers, "Markers", 1, pylsl.IRREGULAR_RATE, "string",
                                 f"play_recording-{a.markers}-{os.getpid()}")
        self.mk = pylsl.StreamOutlet(minfo)
        if a.listen:
            self.listener = Listener(a.listen)
            self.listener.start()

    def wait_for_peers(self):
        a = self.a
        if a.wait <= 0:
            return
        deadline = time.monotonic() + a.wait
        print(f"play_recording: waiting up to {a.wait:g} s for consumers of {a.eeg!r} and {a.markers!r}"
              + (f" and for the stream {a.listen!r}" if a.listen else ""), flush=True)
        while not self.stop_flag and time.monotonic() < deadline:
            ok = self.eeg.have_consumers() and self.mk.have_consumers()
            if self.listener is not None:
                ok = ok and self.listener.connected.is_set()
            if ok:
                return
            time.sleep(0.05)
        if not self.stop_flag:
            print("play_recording: not every peer is there; playing anyway", file=sys.stderr, flush=True)

    def close(self):
        if self.listener is not None:
            self.listener.stopping.set()
        time.sleep(0.3)  # let the last pushes reach the consumers before the outlets go
        del self.eeg
        del self.mk

    # -- time ------------------------------------------------------------------------------
    def stamp(self, k):
        return self.t0 + k / self.sfreq

    def wait_until(self, k):
        """Sleeps until stream sample k-1 has been 'captured' (its time has come)."""
        due = self.wall0 + (k / self.sfreq) / self.a.speed
        while not self.stop_flag:
            left = due - pylsl.local_clock()
            if left <= 0:
                return
            time.sleep(min(left, 0.05))

    def marker(self, text, ts):
        self.mk.push_sample([text], ts)

    # -- the decoder's messages -------------------------------------------------------------
    def poll(self, current_trial, in_trial):
        """Handles the decoder's queued messages; True when the current trial is to end now."""
        end_now = False
        if self.listener is None:
            return False
        while True:
            try:
                msg = self.listener.messages.get_nowait()
            except queue.Empty:
                return end_now
            kind, trial = msg.get("type"), msg.get("trial")
            if kind == "decision":
                self.decisions += 1
                self.decided_trials.add(trial)
                choice = msg.get("choice")
                print(f"  decision for trial {trial}: {choice if choice is not None else 'abstained'}", flush=True)
            elif kind == "stop":
                self.stops += 1
            else:
                continue
            if in_trial and trial == current_trial:
                end_now = True

    # -- playing -----------------------------------------------------------------------------
    def end_trial(self, ti, played, stopped, ts, note=""):
        self.marker("TrialEnd", ts)
        n_rec = len(self.trials[ti])
        self.results.append({"trial": ti + 1, "flashes": played, "recorded_flashes": n_rec, "stopped_early": stopped})
        note = " (stopped by the decoder)" if stopped else note
        print(f"trial {ti + 1}: {played} of {n_rec} flashes played{note}", flush=True)

    def play(self):
        a, sfreq = self.a, self.sfreq
        n_ch, n_times = self.data.shape
        step = max(1, int(round(a.chunk_ms / 1000.0 * sfreq)))
        tail = int(round(a.tail * sfreq))
        lead = int(round(a.resume_before * sfreq))
        end_pos = int(self.onsets[-1]) + tail + 1
        self.wall0 = pylsl.local_clock()
        self.t0 = self.wall0 + self.offset
        pos = 0  # recording sample to push next
        ti, fi, in_trial, played = 0, 0, False, 0
        n_trials = len(self.trials)
        while pos < end_pos and not self.stop_flag:
            if self.poll(ti + 1, in_trial):
                self.end_trial(ti, played, True, self.stamp(self.k))
                in_trial, ti, fi, played = False, ti + 1, 0, 0
                if ti < n_trials:
                    resume = int(self.onsets[self.trials[ti][0]]) - lead
                    if resume > pos:
                        pos = resume
            n = min(step, end_pos - pos)
            self.wait_until(self.k + n)
            if self.stop_flag:
                break
            # Markers of the flashes whose onset falls in this chunk, in order.
            while ti < n_trials:
                f = self.trials[ti][fi]
                onset = int(self.onsets[f])
                if onset >= pos + n:
                    break
                ts = self.stamp(self.k + (onset - pos))
                if fi == 0:
                    self.marker("TrialStart", ts - 0.001)
                    in_trial = True
                self.marker(f"Stim/{int(self.codes[f])}", ts)
                if self.targets[f] == 1:
                    self.marker("Target", ts)
                elif self.targets[f] == 0:
                    self.marker("NonTarget", ts)
                fi += 1
                played += 1
                if fi == len(self.trials[ti]):
                    self.end_trial(ti, played, False, ts + 0.001)
                    in_trial, ti, fi, played = False, ti + 1, 0, 0
            # The EEG chunk, the last sample held past the end of the file.
            idx = np.minimum(np.arange(pos, pos + n), n_times - 1)
            chunk = np.ascontiguousarray(self.data[:, idx].T)
            stamps = [self.stamp(self.k + j) for j in range(n)]
            self.eeg.push_chunk(chunk, stamps)
            self.k += n
            pos += n
        if in_trial:  # interrupted inside a trial: close it for the decoder
            self.end_trial(ti, played, False, self.stamp(self.k), note=" (interrupted)")
        if self.listener is not None and not self.stop_flag:
            deadline = time.monotonic() + a.final_wait
            while time.monotonic() < deadline and not self.stop_flag:
                self.poll(0, False)
                if all(r["trial"] in self.decided_trials for r in self.results):
                    break
                time.sleep(0.05)
            self.poll(0, False)

    def summary(self, interrupted):
        played = sum(r["flashes"] for r in self.results)
        return {
            "file": self.a.file,
            "sfreq": self.sfreq,
            "trials": self.results,
            "total_flashes": played,
            "recorded_flashes": int(len(self.onsets)),
            "total_seconds": round(self.k / self.sfreq, 6),
            "wall_seconds": round(pylsl.local_clock() - self.wall0, 3) if self.wall0 is not None else 0.0,
            "decisions": self.decisions,
            "stops": self.stops,
            "interrupted": interrupted,
        }


def main(argv=None):
    a = parse_args(argv)
    try:
        import oddball
    except ImportError as e:
        print(f"play_recording: needs oddball's Python package (pip install ./python): {e}", file=sys.stderr)
        return 1
    try:
        rec = oddball.read_raw(a.file)
    except (OSError, ValueError) as e:
        print(f"play_recording: {e}", file=sys.stderr)
        return 1
    if len(rec.events) == 0:
        print(f"play_recording: {a.file} has no stimulus events to play", file=sys.stderr)
        return 1
    player = Player(a, rec)
    n_labelled = int(np.sum(player.targets >= 0))
    sizes = sorted({len(t) for t in player.trials})
    print(f"{a.file}: {len(player.ch_names)} channels at {player.sfreq:g} Hz, {rec.n_times / player.sfreq:.1f} s, "
          f"{len(player.onsets)} flashes ({n_labelled} labelled target/non-target) in {len(player.trials)} trials "
          f"of {', '.join(map(str, sizes))} flashes", flush=True)
    if a.flashes_per_trial and len(player.onsets) % a.flashes_per_trial:
        print(f"play_recording: {len(player.onsets)} flashes are not a whole number of trials of "
              f"{a.flashes_per_trial}; the last trial is shorter", file=sys.stderr, flush=True)

    interrupted = False

    def on_signal(signum, frame):
        nonlocal interrupted
        if interrupted:
            raise SystemExit(130)
        interrupted = True
        player.stop_flag = True

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)

    player.open()
    try:
        player.wait_for_peers()
        if not player.stop_flag:
            player.play()
    finally:
        player.close()
    s = player.summary(interrupted)
    print(f"total: {s['total_flashes']} of {s['recorded_flashes']} flashes in {len(s['trials'])} trials, "
          f"{s['total_seconds']:.1f} s of EEG ({s['wall_seconds']:.1f} s wall), "
          f"{s['decisions']} decisions and {s['stops']} stops received"
          + (" (interrupted)" if interrupted else ""), flush=True)
    if a.json_summary:
        tmp = a.json_summary + ".tmp"
        with open(tmp, "w") as f:
            json.dump(s, f, indent=1)
            f.write("\n")
        os.replace(tmp, a.json_summary)
    return 130 if interrupted else 0


if __name__ == "__main__":
    sys.exit(main())
