"""The online decoder behind your own stimulus loop: ``oddball decode``'s engine, fed from Python.

Your script pushes EEG blocks (with the time of each block's last sample) and the markers your
stimulus program would send (with their times, on the same clock); the decoder cuts an epoch at
each flash's time, decides each trial, and returns ``oddball decode``'s messages as dicts::

    dec = OnlineDecoder("paradigms/four-bulb.toml", sfreq=500.0, ch_names=names,
                        model=open("model.json").read())
    for msg in dec.push_marker("Stim/3", t_flash) + dec.push_eeg(block, t_last):
        if msg["type"] == "decision": ...

The paradigm file is the one ``oddball decode`` reads (``paradigms/``). Markers may arrive in any
order within the epoch window; the GIL is released while the decoder works.
"""
from __future__ import annotations

import json

import numpy as np

from . import _oddball


class OnlineDecoder:
    """``paradigm``: a paradigm file's path (or its TOML text with ``paradigm_text=True``).

    Start with ``model`` (a saved model's JSON text, from ``oddball train``), or ``calibration``:
    the number of first trials whose target flags or cues calibrate it, or ``0`` (the default)
    for none: the unsupervised decoder, one attended choice per trial.
    """

    def __init__(self, paradigm, sfreq, ch_names, model=None, calibration=0,
                 dynamic_stopping=False, threshold=0.95, paradigm_text=False):
        self._dec = _oddball.OnlineDecoder(
            str(paradigm), float(sfreq), [str(c) for c in ch_names], model, int(calibration),
            bool(dynamic_stopping), float(threshold), bool(paradigm_text))
        self._stopped = set()
        self._current = 0

    @property
    def labels(self):
        """The choices, in the order of each decision's posterior."""
        return list(self._dec.labels)

    def _out(self, texts):
        msgs = [json.loads(t) for t in texts]
        for m in msgs:
            m.pop("time", None)
            if m["type"] in ("stop", "decision"):
                self._stopped.add(m["trial"])
        return msgs

    def push_eeg(self, samples, timestamps):
        """A block ``(n_channels, n_times)`` in µV and its samples' times (s; the last is used),
        or the last sample's time alone. Returns the messages it completed."""
        x = np.ascontiguousarray(samples, dtype=np.float64)
        if x.ndim != 2:
            raise ValueError(f"samples: expected (n_channels, n_times), got shape {x.shape}")
        last = float(np.asarray(timestamps, dtype=np.float64).reshape(-1)[-1])
        return self._out(self._dec.push_eeg(x, last))

    def push_marker(self, marker, timestamp):
        """One marker (text, or a numeric code) at ``timestamp`` (s, the EEG's clock)."""
        if isinstance(marker, str) and marker.startswith("TrialStart"):
            self._current += 1
        return self._out(self._dec.push_marker(str(marker), float(timestamp)))

    def stop_wanted(self, trial=None):
        """Whether the decoder has decided ``trial`` (default: the latest started), so the
        stimulus loop may end it now."""
        return (self._current if trial is None else trial) in self._stopped

    def finish(self):
        """The streams ended: the trials still open are decided on what arrived."""
        return self._out(self._dec.finish())

    def counts(self):
        """Markers read, and those the decoder could not use, by reason."""
        return json.loads(self._dec.counts())
