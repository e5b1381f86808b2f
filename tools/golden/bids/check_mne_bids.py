"""Reads BIDS-EEG runs written by `oddball export --bids` with mne-bids and compares them with the
original recordings read by independent readers: BCI2000 `.dat` by the peer reader
(`../shared/peer/bci2000.py`, imported by path) and BCI Competition `.mat` by `scipy.io.loadmat`.

    python check_mne_bids.py ROOT SUBJECT TASK RUN ORIGINAL [RUN ORIGINAL ...]

RUN is the run number (`-` for a run exported alone, without a run entity). For each run it checks
what `mne_bids.read_raw_bids` gives: the rate, the channel count, every original sample within
half of its channel's 16-bit EDF step (range / 65535; the EDF's last record is padded, so MNE
reads up to a record more samples, which are reported and not compared), and the events of
`*_events.tsv` as mne-bids makes them MNE annotations (`trial_type/value`, or `value` alone for an
unlabelled event: onset sample, target
or nontarget, code) against the original's stimulus onsets, codes and targets.
Exits 1 on any difference.
"""

import sys
from pathlib import Path

import mne
import mne_bids
import numpy as np
import scipy.io

HERE = Path(__file__).resolve()
sys.path.insert(0, str(HERE.parents[3].parent / "shared" / "peer"))


def original(path):
    """(data (n_channels, n_times) µV, sfreq, onsets, codes, targets) of a .dat or .mat file."""
    if path.suffix == ".dat":
        import bci2000  # the peer reader

        f = bci2000.read_dat(str(path))
        on = bci2000.stimulus_onsets(f.states)
        codes = f.states["StimulusCode"][on]
        targets = f.states["StimulusType"][on] > 0
        return f.data.T, f.fs, on, codes, targets
    m = scipy.io.loadmat(str(path))
    sig = np.asarray(m["signal"], dtype=float)
    flashing = np.asarray(m["Flashing"]).ravel()
    prev = np.concatenate([[0], flashing[:-1]])
    on = np.flatnonzero((flashing != 0) & (prev == 0))
    codes = np.asarray(m["StimulusCode"]).ravel()[on].astype(int)
    if "StimulusType" in m:
        targets = np.asarray(m["StimulusType"]).ravel()[on] > 0
    else:
        targets = None
    return sig.T, 240.0, on, codes, targets


def check(root, subject, task, run, orig_path):
    bp = mne_bids.BIDSPath(
        root=root, subject=subject, task=task, run=None if run == "-" else run,
        datatype="eeg", suffix="eeg", extension=".edf",
    )
    raw = mne_bids.read_raw_bids(bp, verbose="error")
    data, sfreq, on, codes, targets = original(Path(orig_path))
    got = raw.get_data(picks="eeg") * 1e6
    problems = []
    if raw.info["sfreq"] != sfreq:
        problems.append(f"sfreq {raw.info['sfreq']} vs {sfreq}")
    if got.shape[0] != data.shape[0]:
        problems.append(f"{got.shape[0]} EEG channels vs {data.shape[0]}")
    n = data.shape[1]
    extra = got.shape[1] - n
    if extra < 0:
        problems.append(f"{got.shape[1]} samples vs {n}")
    step = np.maximum((data.max(axis=1) - data.min(axis=1)) / 65535.0, 1e-12)
    diff = np.abs(got[:, :n] - data) if extra >= 0 else np.zeros((1, 1))
    frac = float((diff / step[:, None]).max())
    if frac > 0.55:
        problems.append(f"samples differ by {frac:.3f} of a 16-bit step")
    # Events: MNE's annotations, which mne-bids makes from *_events.tsv as "trial_type/value".
    ann = raw.annotations
    # (a trial_type n/a gives the value alone; a value n/a, the trial_type alone)
    def split(d):
        if "/" in d:
            return d.rsplit("/", 1)
        return ("n/a", d) if d.isdigit() else (d, "n/a")

    kinds, values = zip(*(split(d) for d in ann.description))
    stim = np.array([v != "n/a" for v in values])
    ann_samples = np.round(ann.onset * sfreq).astype(int)[stim]
    ann_codes = np.array([int(v) for v in values if v != "n/a"])
    if not np.array_equal(ann_samples, on):
        problems.append(f"{stim.sum()} annotation onsets vs {on.size} stimulus onsets, or at other samples")
    if not np.array_equal(ann_codes, codes):
        problems.append("event codes differ")
    if targets is not None:
        t = np.array([k == "target" for k, v in zip(kinds, values) if v != "n/a"])
        if not np.array_equal(t, targets):
            problems.append("targets differ")
    n_t = "unlabelled" if targets is None else f"{int(targets.sum())} targets"
    print(
        f"{bp.basename}: {got.shape[0]} EEG x {n} samples at {sfreq:g} Hz (+{extra} EDF padding), "
        f"max |diff| {diff.max():.3e} uV = {frac:.3f} step; {on.size} events ({n_t}) as the original"
        + ("" if not problems else "  PROBLEMS: " + "; ".join(problems))
    )
    return not problems


def main(argv):
    if len(argv) < 5 or (len(argv) - 3) % 2:
        print(__doc__)
        return 2
    root, subject, task = argv[:3]
    pairs = list(zip(argv[3::2], argv[4::2]))
    print(f"mne {mne.__version__}, mne-bids {mne_bids.__version__}")
    ok = all([check(root, subject, task, run, orig) for run, orig in pairs])
    print("OK" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
