#!/usr/bin/env python
"""oddball's pipelines through MOABB's WithinSessionEvaluation, next to pyRiemann's, on the local
P300 recordings in ../shared/data (MOABB's own downloads are not reachable here).

MOABB is the documented route for benchmarks across many subjects and machines: its evaluations
fan out over joblib (``n_jobs``), and MOABB's pipelines are scikit-learn pipelines, so oddball's
estimators drop in by changing an import. The recordings are read by oddball's readers
(``oddball.read_raw(...).to_mne()``: an ``mne.io.RawArray`` with Target/NonTarget annotations),
which MOABB then filters (0.5–20 Hz), epochs (0–0.8 s) and resamples (64 Hz) as for any of its
data sets.

    python python/examples/moabb_local.py [--datasets Eeg2 Eeg3 Bci2b] [--n-jobs 1]
"""
from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

from moabb.datasets.base import BaseDataset

DATA = Path(os.environ.get("ODDBALL_DATA", Path(__file__).resolve().parents[2].parent / "shared" / "data"))

# data set → session → runs (files under DATA; every run labelled). One subject per data set:
# MOABB stacks a data set's subjects into one array, so a data set keeps one montage.
RECORDINGS = {
    "Eeg2": {"0": ["bci2000-samplefiles-p300/eeg2_1.dat", "bci2000-samplefiles-p300/eeg2_2.dat"]},
    "Eeg3": {"0": ["bci2000-samplefiles-p300/eeg3_1.dat", "bci2000-samplefiles-p300/eeg3_2.dat"]},
    # BCI Competition II IIb: sessions 10 and 11 (12 is the unlabelled test session)
    "Bci2b": {"0": ["bci-competition-ii-iib/AAS010R01.mat", "bci-competition-ii-iib/AAS010R02.mat"],
              "1": ["bci-competition-ii-iib/AAS011R01.mat", "bci-competition-ii-iib/AAS011R02.mat"]},
}
SFREQ = 64.0  # MOABB resamples every recording to this rate


class LocalP300(BaseDataset):
    """One recording set of ../shared/data (a key of RECORDINGS) as a one-subject MOABB data set,
    read by oddball's readers."""

    def __init__(self, name, data=DATA):
        self.name, self.data = name, Path(data)
        super().__init__(
            subjects=[1],
            sessions_per_subject=len(RECORDINGS[name]),
            events={"Target": 2, "NonTarget": 1},
            code=f"LocalP300-{name}",
            interval=[0, 0.8],
            paradigm="p300",
            doi=None,
        )

    def _get_single_subject_data(self, subject):
        import oddball

        return {
            session: {str(run): oddball.read_raw(self.data / rel).to_mne() for run, rel in enumerate(runs)}
            for session, runs in RECORDINGS[self.name].items()
        }

    def data_path(self, subject, path=None, force_update=False, update_path=None, verbose=None):
        return [str(self.data / rel) for runs in RECORDINGS[self.name].values() for rel in runs]


def named(lib, *steps):
    """``make_pipeline`` with the library in the step names. MOABB keys its stored results by the
    repr of ``get_params()``, which names classes but not their modules: pyRiemann's and
    oddball's pipelines with equal parameters would share one key (and one would silently
    replace the other's results)."""
    from sklearn.pipeline import Pipeline

    return Pipeline([(f"{lib}-{type(s).__name__.lower()}", s) for s in steps])


def pipelines():
    """The same pipelines from pyRiemann and from oddball (only the imports differ), and two of
    oddball's presets."""
    import pyriemann.classification
    import pyriemann.estimation
    import pyriemann.tangentspace
    from sklearn.linear_model import LogisticRegression

    import oddball.classification
    import oddball.estimation
    import oddball.pipelines
    import oddball.tangentspace

    out = {}
    for lib, est, ts, clf in (
        ("pyRiemann", pyriemann.estimation, pyriemann.tangentspace, pyriemann.classification),
        ("oddball", oddball.estimation, oddball.tangentspace, oddball.classification),
    ):
        out[f"{lib} XdawnCov+TS+LR"] = named(
            lib, est.XdawnCovariances(nfilter=4, estimator="oas"), ts.TangentSpace(metric="riemann"),
            LogisticRegression(max_iter=1000))
        out[f"{lib} XdawnCov+MDM"] = named(
            lib, est.XdawnCovariances(nfilter=4, estimator="oas"), clf.MDM(metric="riemann"))
    out["oddball preset stack"] = oddball.pipelines.make("stack", sfreq=SFREQ)
    out["oddball preset toeplitz-lda"] = oddball.pipelines.make("toeplitz-lda", sfreq=SFREQ)
    return out


def evaluate(names=tuple(RECORDINGS), n_jobs=1, results_dir=None):
    """Runs MOABB's WithinSessionEvaluation (5-fold ROC AUC per session) on the data sets
    ``names`` and returns its results table (pandas), one row per data set × session × pipeline."""
    from moabb.evaluations import WithinSessionEvaluation
    from moabb.paradigms import P300

    paradigm = P300(fmin=0.5, fmax=20.0, tmin=0.0, tmax=0.8, resample=SFREQ)
    with tempfile.TemporaryDirectory() as tmp:
        evaluation = WithinSessionEvaluation(
            paradigm=paradigm, datasets=[LocalP300(n) for n in names], overwrite=True,
            hdf5_path=results_dir or tmp, n_jobs=n_jobs, random_state=0, save_model=False,
        )
        return evaluation.process(pipelines())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--datasets", nargs="+", default=list(RECORDINGS), choices=list(RECORDINGS))
    ap.add_argument("--n-jobs", type=int, default=1)
    args = ap.parse_args()
    results = evaluate(args.datasets, args.n_jobs)
    table = results.pivot_table(index=["dataset", "session"], columns="pipeline", values="score")
    times = results.groupby("pipeline")["time"].sum()
    import pandas as pd

    with pd.option_context("display.width", 200, "display.max_columns", 20, "display.precision", 4):
        print("ROC AUC (MOABB WithinSessionEvaluation, 5 folds per session):")
        print(table.T)
        print("\nfit + score time over all folds (s):")
        print(times.round(2))


if __name__ == "__main__":
    main()
