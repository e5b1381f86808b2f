"""Reading recordings with oddball's readers (``oddball_io::read``)."""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from . import _oddball

__all__ = ["Epochs", "Raw", "read_epochs", "read_raw"]


@dataclass
class Raw:
    """A recording: ``data`` ``(n_channels, n_times)`` in µV, ``sfreq`` Hz, ``ch_names``, and its
    stimulus events (``events`` in MNE's layout ``(n_events, 3)``: onset sample, 0, code;
    ``event_targets``: 1 target, 0 non-target, -1 unknown; ``event_labels``: text or None)."""

    data: np.ndarray
    sfreq: float
    ch_names: list
    events: np.ndarray
    event_targets: np.ndarray
    event_labels: list
    format: str
    path: str
    extras: dict = field(default_factory=dict)

    @property
    def n_channels(self) -> int:
        return self.data.shape[0]

    @property
    def n_times(self) -> int:
        return self.data.shape[1]

    def event_descriptions(self) -> list:
        """Per event: ``"Target"``/``"NonTarget"`` when known, else its text label, else its code."""
        out = []
        for (_, _, code), t, label in zip(self.events, self.event_targets, self.event_labels):
            if t == 1:
                out.append("Target")
            elif t == 0:
                out.append("NonTarget")
            elif label:
                out.append(label.strip())
            else:
                out.append(str(int(code)))
        return out

    def to_mne(self, ch_types="eeg", verbose="error"):
        """An ``mne.io.RawArray`` (volts, as MNE's unit) with one zero-length annotation per event
        (:meth:`event_descriptions`). Needs MNE (``pip install mne``)."""
        try:
            import mne
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Raw.to_mne() needs MNE: pip install mne") from e
        info = mne.create_info(list(self.ch_names), self.sfreq, ch_types=ch_types)
        raw = mne.io.RawArray(self.data * 1e-6, info, verbose=verbose)
        onsets = self.events[:, 0] / self.sfreq
        raw.set_annotations(
            mne.Annotations(onset=onsets, duration=np.zeros(len(onsets)),
                            description=self.event_descriptions())
        )
        return raw


def _keys(keys) -> str:
    if isinstance(keys, (str, int, np.integer)):
        keys = [keys]
    return ",".join(str(k) for k in keys)


def read_raw(path, events=None, text=None, *, sfreq=None, channels=None, montage=None, time_column=None,
             events_from=None, data_from=None) -> Raw:
    """Reads a recording in any format oddball reads (BCI2000 ``.dat``, CSV, EDF/EDF+/BDF, NIC
    ``.easy``, XDF, MATLAB ``.mat``, GDF, BrainVision ``.vhdr``, EEGLAB ``.set``, FIF; chosen by
    extension).

    What a file does not say, as the command line's options give it: ``sfreq`` (Hz: a CSV without a
    time column, a MAT file), ``channels`` (CSV: the EEG columns; MAT: the signal's column names;
    other formats: the channels kept, by name), ``montage`` (an EEGLAB ``.loc`` naming the file's
    channels, e.g. BCI2000's ``eeg64.loc``), ``time_column`` (CSV), ``events_from`` (the CSV marker
    column or MAT code variable), ``data_from`` (the MAT variable of samples).

    ``events`` labels plain markers as targets and non-targets: a dict
    ``{"target": [2], "nontarget": [1]}`` or a pair ``(target_keys, nontarget_keys)``, keys being
    codes or marker texts (``"Target"``); events matching neither are dropped. ``text``: for a
    speller recording without labels, the text it spelled.
    """
    target = nontarget = None
    if events is not None:
        if isinstance(events, dict):
            unknown = set(events) - {"target", "nontarget"}
            if unknown:
                raise ValueError(f"events: unknown keys {sorted(unknown)}; use 'target' and 'nontarget'")
            target, nontarget = events.get("target"), events.get("nontarget")
        else:
            target, nontarget = events
        if target is None or nontarget is None:
            raise ValueError("events: give both target and non-target keys")
        target, nontarget = _keys(target), _keys(nontarget)
    if isinstance(channels, str):
        channels = [channels]
    d = _oddball.read_raw(
        os.fspath(path), target, nontarget, text, None if sfreq is None else float(sfreq),
        None if channels is None else [str(c) for c in channels],
        None if montage is None else os.fspath(montage), time_column, events_from, data_from)
    onsets = np.asarray(d["onsets"], dtype=np.int64)
    ev = np.column_stack([onsets, np.zeros_like(onsets), np.asarray(d["codes"], dtype=np.int64)])
    return Raw(
        data=d["data"], sfreq=d["sfreq"], ch_names=list(d["ch_names"]), events=ev.reshape(-1, 3),
        event_targets=np.asarray(d["targets"], dtype=np.int8), event_labels=list(d["labels"]),
        format=d["format"], path=os.fspath(path),
    )


@dataclass
class Epochs:
    """A recording's flashes as ``oddball evaluate`` epochs them: ``data``
    ``(n_epochs, n_channels, n_times)`` µV (band-passed), ``sfreq`` Hz, ``tmin`` s, ``ch_names``,
    each epoch's stimulus ``codes`` and ``targets`` (1, 0, -1 unknown); for a speller recording
    also ``trials`` (each flash's character, from 0), ``sets`` (the rows' and the columns' codes:
    what competes in a trial) and ``matrix`` (its symbols by row), else None."""

    data: np.ndarray
    sfreq: float
    tmin: float
    ch_names: list
    codes: np.ndarray
    targets: np.ndarray
    trials: np.ndarray | None
    sets: list | None
    matrix: list | None

    def symbol(self, choice) -> str:
        """The speller symbol of ``(row code, column code)``."""
        r, c = (int(v) for v in choice)
        return self.matrix[self.sets[0].index(r)][self.sets[1].index(c)]


def read_epochs(path, preprocess="peer", text=None) -> Epochs:
    """Reads a recording and cuts an epoch at each flash the way ``oddball evaluate`` does (the
    peer stack's 0.5–20 Hz band-pass, zero-phase, or ``preprocess="peer-causal"`` as a live
    session filters; 0.8 s from each onset). ``text``: for a speller run recorded without labels,
    the text it spelled."""
    d = _oddball.read_epochs(os.fspath(path), preprocess, text)
    trials = None if d["trials"] is None else np.asarray(d["trials"], dtype=np.int64)
    return Epochs(
        data=d["data"], sfreq=d["sfreq"], tmin=d["tmin"], ch_names=list(d["ch_names"]),
        codes=np.asarray(d["codes"], dtype=np.int64), targets=np.asarray(d["targets"], dtype=np.int8),
        trials=trials, sets=d["sets"], matrix=d["matrix"],
    )
