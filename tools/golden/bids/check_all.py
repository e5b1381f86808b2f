"""Every shared recording exported by `oddball export --bids` as EDF and as BrainVision, and
checked three ways:

* the BIDS validator (errors and warnings per export; `--validator EXE`, e.g.
  tools/bids/node_modules/.bin/bids-validator; left out without it);
* `mne_bids.read_raw_bids` (MNE 1.13.2, mne-bids 0.20.0) against oddball's own reading of the
  original (the `to_npy` example of oddball-io: float64 µV and the events, labelled as the
  export labels them): the rate, the channels, the largest |difference| in µV (EDF: also as a
  fraction of the channel's 16-bit step, range / 65535; the samples of the EDF's padded last
  record are left out), and the events mne-bids makes from `*_events.tsv` (onset sample, code,
  target) equal to the original's;
* `oddball benchmark` (within-session, `--pipeline lda`, one thread) on the BIDS root against
  the same on the original files (their manifest in `datasets/`, or a manifest of the one file
  for the GDF): the AUCs side by side, with the epochs and targets.

    python check_all.py ODDBALL DATA OUT [--validator EXE] [--to-npy EXE]

ODDBALL is the oddball binary (release), DATA the shared data folder, OUT a scratch folder
(replaced). `--to-npy` defaults to `examples/to_npy` beside ODDBALL (`cargo build --release
-p oddball-io --example to_npy`). The recordings: BCI2000 eeg2 and eeg3, the Muse sessions
(the manifest's mapping 2 = target, 1 = non-target), BCI Competition II IIb sessions 10-12 (each
shipped manifest is given to the export as `--manifest`, a copy rooted at DATA, so the test session
is labelled by its `test_text` as `benchmark` labels it), the
OpenViBE GDF, and a simulated oddball session (`oddball online --source sim`, XDF; no
benchmark). Prints a Markdown table and writes OUT/results.json; exits 1 on any check failed.
"""

import argparse
import json
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import mne
import mne_bids
import numpy as np

WS = Path(__file__).resolve().parents[3]
FORMATS = {"edf": ".edf", "brainvision": ".vhdr"}


def label(s):
    return "".join(c for c in s if c.isascii() and c.isalnum())


def run(cmd, **kw):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))}\n{p.stdout}\n{p.stderr}")
    return p.stdout


def keys(ks):
    return ",".join(str(k) for k in ks)


class Set:
    """A data set: its runs as (subject, session, [files]) and how to export and benchmark it."""

    def __init__(self, name, manifest, data, out=None):
        """`data`: the folder the manifest's paths are relative to (its `root`, or `--data`);
        `out`: given for a shipped manifest, which is then copied there with `root = data` and
        given to the export (`--manifest`: its speller and test texts label the runs)."""
        self.name = name
        self.manifest = manifest
        text = Path(manifest).read_text()
        m = tomllib.loads(text)
        self.task = label(m["name"])
        ev = m.get("events")
        self.mapping = (keys(ev["target"]), keys(ev["nontarget"])) if ev else None
        self.extra = []
        if self.mapping:
            self.extra = ["--target-events", self.mapping[0], "--nontarget-events", self.mapping[1]]
        if m.get("read", {}).get("sfreq"):
            self.extra += ["--sfreq", str(m["read"]["sfreq"])]
        if out is not None:
            copy = out / f"{name}-manifest.toml"
            copy.write_text("\n".join(f'root = "{data}"' if line.startswith("root =") else line
                                      for line in text.splitlines()) + "\n")
            self.extra += ["--manifest", str(copy)]
        self.groups = []
        for s in m["subject"]:
            if "sessions" in s:
                for ses, files in s["sessions"].items():
                    self.groups.append((label(s["id"]), label(ses), [data / f for f in files]))
            else:
                files = s.get("train", []) + s.get("test", [])
                self.groups.append((label(s["id"]), None, [data / f for f in files]))


def export(oddball, s, fmt, root):
    for sub, ses, files in s.groups:
        cmd = [oddball, "export", "--bids", root, "--subject", sub, "--task", s.task,
               "--format", fmt, *s.extra]
        if ses:
            cmd += ["--session", ses]
        run(cmd + files)


def validate(exe, root):
    out = subprocess.run([exe, "--json", str(root)], capture_output=True, text=True).stdout
    v = json.loads(out[out.index("{"):])
    codes = lambda k: [i.get("key", "?") for i in v["issues"][k]]  # noqa: E731
    return codes("errors"), codes("warnings")


def original(to_npy, path, mapping, tmp):
    prefix = tmp / "orig"
    run([to_npy, path, prefix] + (list(mapping) if mapping else []))
    meta = json.loads(Path(f"{prefix}.json").read_text())
    return np.load(f"{prefix}.npy"), meta


def target_of(description):
    """True, False or None: the annotation of a target, a non-target, or neither (mne-bids names
    an annotation `trial_type`, or `trial_type/value` when one trial_type has several values)."""
    kind = description.split("/", 1)[0]
    return {"target": True, "nontarget": False}.get(kind)


def read_back(root, sub, ses, task, run_no, fmt, data, meta):
    """The checks of one run; returns (max |diff| µV, max fraction of a 16-bit step, problems,
    events labelled on export that the original leaves unlabelled)."""
    bp = mne_bids.BIDSPath(root=root, subject=sub, session=ses, task=task, run=run_no,
                           datatype="eeg", suffix="eeg", extension=FORMATS[fmt])
    raw = mne_bids.read_raw_bids(bp, verbose="error")
    problems = []
    sfreq = meta["sfreq"]
    if abs(raw.info["sfreq"] - sfreq) > 1e-9 * sfreq:
        problems.append(f"sfreq {raw.info['sfreq']!r} vs {sfreq!r}")
    if raw.ch_names != meta["ch_names"]:
        problems.append(f"channels {raw.ch_names} vs {meta['ch_names']}")
    got = raw.get_data() * 1e6
    n = data.shape[1]
    if got.shape[1] < n or (fmt == "brainvision" and got.shape[1] != n):
        problems.append(f"{got.shape[1]} samples vs {n}")
        return float("nan"), float("nan"), problems, 0
    diff = np.abs(got[:, :n] - data)
    step = np.maximum((data.max(axis=1) - data.min(axis=1)) / 65535.0, 1e-12)
    frac = float((diff / step[:, None]).max())
    if fmt == "edf" and frac > 0.55:
        problems.append(f"samples differ by {frac:.3f} of a 16-bit step")
    if fmt == "brainvision":
        f32 = data.astype(np.float32).astype(np.float64)
        rel = float((np.abs(got - f32) / np.maximum(np.abs(f32), 1e-6)).max())
        if rel > 1e-9:
            problems.append(f"not the original rounded to f32 (relative {rel:.2e})")
    # The codes: mne-bids's own event_id of the events file (annotation description -> value);
    # rows whose value is n/a (an oddball session's cues and decisions) are no stimuli.
    with mne.utils.use_log_level("error"):
        tsv = bp.copy().update(suffix="events", extension=".tsv").fpath
        event_id = mne_bids.events_file_to_annotation_kwargs(tsv)["event_id"]
    onsets, codes, targets = [], [], []
    for onset, d in zip(raw.annotations.onset, raw.annotations.description):
        code = event_id.get(d)
        if code is None or not np.isfinite(code) or code < 0:
            continue
        onsets.append(int(round(onset * raw.info["sfreq"])))
        codes.append(int(code))
        targets.append(target_of(d))
    ev = meta["events"]
    if list(onsets) != [e[0] for e in ev]:
        problems.append(f"{len(onsets)} event onsets vs {len(ev)}, or at other samples")
    elif codes != [e[1] for e in ev]:
        problems.append("event codes differ")
    elif any(t != e[2] for t, e in zip(targets, ev) if e[2] is not None):
        problems.append("targets differ")
    # Targets the original does not say, labelled on export (a test run's text in the manifest).
    labelled = sum(1 for t, e in zip(targets, ev) if e[2] is None and t is not None)
    return float(diff.max()), frac, problems, labelled


def benchmark(oddball, source, out_json, data=None):
    cmd = [oddball, "benchmark", source, "--pipeline", "lda", "--protocol", "within-session",
           "--threads", "1", "--json", out_json]
    if data:
        cmd += ["--data", data]
    run(cmd)
    rows = json.loads(Path(out_json).read_text())["results"]
    return [(r["subject"], r.get("session"), r["auc"], r["n_epochs"], r["n_targets"]) for r in rows]


def session_set(oddball, out):
    """A simulated oddball session (XDF) as a one-file set."""
    sdir = out / "session-rec"
    run([oddball, "online", "--calibrate", "--calibration-per-bulb", "2", "--fast", "--commands",
         "up,left", "--source", "sim", "--out", sdir])
    return sdir / "session.xdf"


def one_file_set(name, task, path, out):
    """A set of one file: a manifest of it in OUT (root: the file's folder)."""
    m = out / f"{name}.toml"
    m.write_text(f'name = "{task}"\nroot = "{path.parent}"\n\n[[subject]]\nid = "1"\n'
                 f'train = ["{path.name}"]\n')
    return Set(name, m, path.parent)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("oddball", type=Path)
    ap.add_argument("data", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--validator")
    ap.add_argument("--to-npy", type=Path)
    a = ap.parse_args()
    oddball, data, out = a.oddball.resolve(), a.data.resolve(), a.out.resolve()
    to_npy = (a.to_npy or oddball.parent / "examples" / "to_npy").resolve()
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    print(f"mne {mne.__version__}, mne-bids {mne_bids.__version__}", flush=True)

    sets = [Set(n, WS / f"datasets/{m}.toml", data, out) for n, m in [
        ("eeg2", "bci2000-eeg2"), ("eeg3", "bci2000-eeg3"), ("muse", "muse-visual-p300"),
        ("iib", "bci-competition-ii-iib")]]
    sets.append(one_file_set("gdf", "p300", data / "openvibe-p300-gdf/data_sample_8ch.gdf", out))
    sets.append(one_file_set("session", "online", session_set(oddball, out), out))

    results, ok = [], True
    for s in sets:
        orig_auc = None
        if s.name != "session":
            shipped = s.name in ("eeg2", "eeg3", "muse", "iib")
            orig_auc = benchmark(oddball, s.manifest, out / f"{s.name}-orig.json",
                                 data if shipped else None)
        for fmt in FORMATS:
            root = out / f"{s.name}-{fmt}"
            export(oddball, s, fmt, root)
            errors, warnings = validate(a.validator, root) if a.validator else (None, None)
            worst_uv, worst_frac, problems, n_runs, n_events, n_labelled = 0.0, 0.0, [], 0, 0, 0
            for sub, ses, files in s.groups:
                for i, f in enumerate(files):
                    run_no = str(i + 1) if len(files) > 1 else None
                    d, meta = original(to_npy, f, s.mapping, out)
                    uv, frac, p, lab = read_back(root, sub, ses, s.task, run_no, fmt, d, meta)
                    n_labelled += lab
                    worst_uv, worst_frac = max(worst_uv, uv), max(worst_frac, frac)
                    problems += [f"{f.name}: {x}" for x in p]
                    n_runs += 1
                    n_events += len(meta["events"])
            bids_auc = None
            if orig_auc is not None:
                bids_auc = benchmark(oddball, root, out / f"{s.name}-{fmt}.json")
                if len(bids_auc) != len(orig_auc):
                    problems.append(f"{len(bids_auc)} benchmark rows vs {len(orig_auc)}")
                else:
                    for x, y in zip(orig_auc, bids_auc):
                        if x[3:] != y[3:]:
                            problems.append(f"epochs/targets {x[3:]} vs {y[3:]}")
                        if fmt == "edf" and abs(x[2] - y[2]) > 1e-3:
                            problems.append(f"AUC {y[2]} vs {x[2]}")
            if errors:
                problems.append(f"validator errors {sorted(set(errors))}")
            ok &= not problems
            r = {
                "set": s.name, "format": fmt, "runs": n_runs, "events": n_events,
                "labelled_on_export": n_labelled,
                "validator_errors": errors, "validator_warnings": warnings,
                "max_abs_diff_uv": worst_uv, "max_step_fraction": worst_frac,
                "auc_original": [x[2] for x in orig_auc] if orig_auc else None,
                "auc_bids": [y[2] for y in bids_auc] if bids_auc else None,
                "auc_rows": [f"{x[0]}/{x[1]}" for x in orig_auc] if orig_auc else None,
                "problems": problems,
            }
            results.append(r)
            print(json.dumps(r), flush=True)

    (out / "results.json").write_text(json.dumps(results, indent=1))
    print()
    print("| recording | format | runs | events | validator errors / warnings | max abs diff (µV) "
          "| max diff / 16-bit step | AUC original | AUC BIDS | max abs AUC diff | problems |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        v = "n/a" if r["validator_errors"] is None else \
            f"{len(r['validator_errors'])} / {len(r['validator_warnings'])} {sorted(set(r['validator_warnings']))}"
        ao, ab = r["auc_original"], r["auc_bids"]
        fmt_auc = lambda xs: " ".join(f"{x:.6f}" for x in xs) if xs else "–"  # noqa: E731
        dauc = f"{max(abs(x - y) for x, y in zip(ao, ab)):.2e}" if ao and ab and len(ao) == len(ab) else "–"
        print(f"| {r['set']} | {r['format']} | {r['runs']} | {r['events']} | {v} | "
              f"{r['max_abs_diff_uv']:.3e} | {r['max_step_fraction']:.3f} | {fmt_auc(ao)} | "
              f"{fmt_auc(ab)} | {dauc} | {'; '.join(r['problems']) or 'none'} |")
    print("OK" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
