"""oddball.read_raw on every format oddball reads (and with the command line's reader options), against independent readers where one exists
(the peer stack's BCI2000 reader, MNE's EDF/BDF readers), and Raw.to_mne()."""
from __future__ import annotations

import sys

import numpy as np
import pytest

import oddball
from conftest import DATA, FIXTURES, data_file, need, need_module

FIXTURE_FILES = {
    "Bci2000": None,  # real data below (eeg3_1.dat)
    "BdfPlus": "numpy_small.bdf",
    "EdfPlus": "pyedflib_small.edf",
    "Easy": "nic_small.easy",
    "Xdf": "xdf/python_small.xdf",
    "Mat": "mat/bci_small.mat",
    "Gdf": "gdf/small_v2.gdf",
    "BrainVision": "brainvision/mne_float32.vhdr",
    "Eeglab": "eeglab/mne_export.set",
    "Fif": "fif/float_raw.fif",
}


@pytest.mark.parametrize("fmt,rel", [(k, v) for k, v in FIXTURE_FILES.items() if v], ids=lambda v: str(v))
def test_every_format_reads_into_a_consistent_raw(fmt, rel):
    raw = oddball.read_raw(need(FIXTURES / rel))
    assert raw.format == fmt
    assert raw.data.dtype == np.float64 and raw.data.shape == (len(raw.ch_names), raw.n_times)
    assert np.all(np.isfinite(raw.data)) and raw.sfreq > 0
    assert raw.events.shape == (len(raw.event_targets), 3) and len(raw.event_labels) == len(raw.events)
    assert np.all((raw.events[:, 0] >= 0) & (raw.events[:, 0] < raw.n_times))
    assert set(np.unique(raw.event_targets)) <= {-1, 0, 1}


def test_csv_reads_too():
    path = data_file("muse-visual-p300-eeg-notebooks/subject1/session1/data_2017-02-04-15_45_13.csv")
    raw = oddball.read_raw(path)
    assert raw.format == "Csv" and raw.ch_names == ["TP9", "AF7", "AF8", "TP10"] and raw.sfreq == 256.0
    # Plain marker codes, labelled by a mapping: code 2 = target, 1 = non-target.
    plain = oddball.read_raw(path, events={"target": [2], "nontarget": [1]})
    assert np.array_equal(plain.event_targets, (plain.events[:, 2] == 2).astype(np.int8))
    assert (plain.event_targets == 1).sum() > 0 and (plain.event_targets == 0).sum() > 0
    with pytest.raises(ValueError, match="both"):
        oddball.read_raw(path, events={"target": [2]})
    with pytest.raises(ValueError):
        oddball.read_raw(path, events={"target": [2], "nontarget": [2]})


def test_bci2000_equals_the_peer_reader():
    path = data_file("bci2000-samplefiles-p300/eeg3_1.dat")
    peer_dir = need(DATA.parent / "peer" / "bci2000.py").parent
    sys.path.insert(0, str(peer_dir))
    try:
        import bci2000
    finally:
        sys.path.remove(str(peer_dir))
    ref = bci2000.read_dat(str(path))
    raw = oddball.read_raw(path)
    assert raw.format == "Bci2000" and raw.sfreq == ref.fs and raw.ch_names == list(ref.ch_names)
    np.testing.assert_allclose(raw.data, ref.data.T, rtol=1e-12, atol=0)
    on = bci2000.stimulus_onsets(ref.states)
    assert np.array_equal(raw.events[:, 0], on)
    assert np.array_equal(raw.events[:, 2], ref.states["StimulusCode"][on])
    assert np.array_equal(raw.event_targets, (ref.states["StimulusType"][on] == 1).astype(np.int8))


@pytest.mark.parametrize("rel,reader", [("pyedflib_small.edf", "read_raw_edf"), ("numpy_small.bdf", "read_raw_bdf")])
def test_edf_and_bdf_equal_mne(rel, reader):
    mne = need_module("mne")
    path = need(FIXTURES / rel)
    ref = getattr(mne.io, reader)(path, preload=True, verbose="error")
    raw = oddball.read_raw(path)
    eeg = [i for i, c in enumerate(raw.ch_names) if c != "Status"]  # BDF's status channel: raw codes in MNE
    assert [raw.ch_names[i] for i in eeg] == [ref.ch_names[i] for i in eeg]
    assert raw.sfreq == ref.info["sfreq"]
    volts = ref.get_data()[eeg]
    np.testing.assert_allclose(raw.data[eeg] * 1e-6, volts, rtol=0, atol=1e-12 * np.abs(volts).max())


def test_to_mne_has_the_data_in_volts_and_the_events_as_annotations():
    mne = need_module("mne")
    raw = oddball.read_raw(data_file("bci2000-samplefiles-p300/eeg3_1.dat"))
    m = raw.to_mne()
    assert isinstance(m, mne.io.RawArray)
    assert m.ch_names == raw.ch_names and m.info["sfreq"] == raw.sfreq
    np.testing.assert_allclose(m.get_data(), raw.data * 1e-6, rtol=1e-15)
    events, ids = mne.events_from_annotations(m, verbose="error")
    assert set(ids) == {"Target", "NonTarget"}
    assert np.array_equal(events[:, 0], raw.events[:, 0])
    assert np.array_equal(events[:, 2] == ids["Target"], raw.event_targets == 1)
    # Events without target information keep their text or code.
    m2 = oddball.read_raw(need(FIXTURES / "nic_small.easy")).to_mne()
    assert len(m2.annotations) == 7 and "70000" in set(m2.annotations.description)


def test_bad_files_are_clear_errors(tmp_path):
    with pytest.raises(OSError, match="nope.dat"):
        oddball.read_raw(tmp_path / "nope.dat")
    bad = tmp_path / "cut.edf"
    bad.write_bytes((FIXTURES / "pyedflib_small.edf").read_bytes()[:300])
    with pytest.raises(OSError, match="cut.edf"):
        oddball.read_raw(bad)


def test_the_command_lines_reader_options_reach_the_readers(tmp_path):
    """sfreq, channels, time_column and events_from as `--sfreq`, `--channels`, `--time-column`
    and `--events-from` give them; a bad option is refused before reading."""
    path = tmp_path / "plain.csv"
    rows = ["t,Cz,Pz,trig"] + [f"{i / 100:.2f},{i},{2 * i},{1 if i % 10 == 3 else 0}" for i in range(50)]
    path.write_text("\n".join(rows) + "\n")
    raw = oddball.read_raw(path, sfreq=128.0, channels=["Pz"], time_column="t", events_from="trig")
    assert raw.sfreq == 128.0 and raw.ch_names == ["Pz"]
    np.testing.assert_array_equal(raw.data[0], 2.0 * np.arange(50))
    assert raw.events[:, 0].tolist() == [3, 13, 23, 33, 43]
    # Without a time column the rate must be given: the error says so.
    nots = tmp_path / "nots.csv"
    nots.write_text("Cz,Pz\n1,2\n3,4\n")
    with pytest.raises(OSError, match="sampling rate"):
        oddball.read_raw(nots)
    assert oddball.read_raw(nots, sfreq=250.0).sfreq == 250.0
    with pytest.raises(ValueError, match="sfreq"):
        oddball.read_raw(nots, sfreq=-1.0)
    # Any format: the channels kept, by name.
    fif = oddball.read_raw(need(FIXTURES / "fif/float_raw.fif"))
    one = oddball.read_raw(need(FIXTURES / "fif/float_raw.fif"), channels=[fif.ch_names[1]])
    np.testing.assert_array_equal(one.data[0], fif.data[1])
