"""MOABB's WithinSessionEvaluation runs oddball's pipelines next to pyRiemann's on local data
sets over ../shared/data (examples/moabb_local.py), and the twins score the same."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from conftest import DATA, data_file, need_module

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "moabb_local.py"


def load_example():
    spec = importlib.util.spec_from_file_location("moabb_local", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_moabb_within_session_evaluation(tmp_path, capsys):
    need_module("moabb")
    need_module("pyriemann")
    ex = load_example()
    names = ("Eeg2", "Eeg3")  # the BCI2000 sample files; Bci2b (64 channels, 2 sessions) in the example
    for name in names:
        for runs in ex.RECORDINGS[name].values():
            for rel in runs:
                data_file(rel)
    assert ex.DATA == DATA
    results = ex.evaluate(names, n_jobs=1, results_dir=str(tmp_path))
    table = results.pivot_table(index="pipeline", columns=["dataset", "session"], values="score")
    with capsys.disabled():
        print("\n" + table.round(4).to_string())
    expected = set(ex.pipelines())
    assert set(table.index) == expected
    assert table.shape[1] == len(names)  # one session each
    for pipe in ("XdawnCov+TS+LR", "XdawnCov+MDM"):
        ours, ref = table.loc[f"oddball {pipe}"].to_numpy(), table.loc[f"pyRiemann {pipe}"].to_numpy()
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-6)
    assert np.all(table.to_numpy() > 0.8)  # every pipeline decodes the P300
