#!/usr/bin/env python3
"""Compares two output folders of tools/relayer/run.sh: every file equal byte for byte, except
what varies from run to run of the same binary (found by running it twice): the output folder's
own path (read as OUT), JSON keys matched by TIMING_KEYS are left out, the numbers of timing tokens
in text (stdout, CSV) matched by TIMING_TOKENS are masked, and an XDF recording's wall-clock stamps (its
streams' samples, marker texts and headers are compared through pyxdf when it is importable,
e.g. `python -m venv v && v/bin/pip install -r tools/golden/xdf/requirements.txt`).
Prints each difference; exits 1 if there is any."""
import difflib
import json
import re
import sys
from pathlib import Path

TIMING_KEYS = re.compile(
    r"(wall|elapsed|seconds_wall|fit_s$|score_s$|decode_ms|latency|per_s$|_per_second|"
    r"epochs_per_s|time_ms|duration_wall|processing|decoding_ms|fit_seconds|score_seconds|"
    r"decode_s$|wall_s$|realtime_factor)"
)
TIMING_TOKENS = re.compile(
    r"(fit +[0-9.]+ s|[0-9.]+ epochs/s|in [0-9.]+ s|[0-9.]+ ± [0-9.]+ ms \[[0-9., ]+\]|"
    r"[0-9.]+ ms|took [0-9.]+ s|wall time [0-9.]+ s|[0-9.]+x real time)"
)


ROW_KEYS = ("dataset", "subject", "protocol", "preset", "pipeline")


def row_name(v, i):
    """A list item's name in a path: its identifying fields when it is a result row (so a row
    added in between, e.g. a new preset, shows as added rather than shifting the others)."""
    if isinstance(v, dict) and any(k in v for k in ROW_KEYS):
        return "{" + ",".join(str(v[k]) for k in ROW_KEYS if k in v) + "}"
    return str(i)


def flat(x, path=""):
    if isinstance(x, dict):
        for k, v in x.items():
            yield from flat(v, f"{path}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from flat(v, f"{path}[{row_name(v, i)}]")
    else:
        yield path, x


def json_diffs(a, b):
    fa = {p: v for p, v in flat(json.loads(a)) if not TIMING_KEYS.search(p)}
    fb = {p: v for p, v in flat(json.loads(b)) if not TIMING_KEYS.search(p)}
    for p in sorted(set(fa) | set(fb)):
        if fa.get(p, "<absent>") != fb.get(p, "<absent>"):
            yield f"{p}: {fa.get(p, '<absent>')!r} != {fb.get(p, '<absent>')!r}"


def mask(line):
    return TIMING_TOKENS.sub(lambda m: re.sub(r"[0-9]+(\.[0-9]+)?", "#", m.group(0)), line)


def text_diffs(a, b):
    la = [mask(x) for x in a.decode(errors="replace").splitlines()]
    lb = [mask(x) for x in b.decode(errors="replace").splitlines()]
    for line in difflib.unified_diff(la, lb, "before", "after", n=0, lineterm=""):
        if not line.startswith(("---", "+++")):
            yield line


def xdf_diffs(a, b):
    try:
        import pyxdf
    except ImportError:
        yield "XDF bytes differ and pyxdf is not importable to compare the streams"
        return
    sa, _ = pyxdf.load_xdf(str(a), synchronize_clocks=False, dejitter_timestamps=False)
    sb, _ = pyxdf.load_xdf(str(b), synchronize_clocks=False, dejitter_timestamps=False)
    if len(sa) != len(sb):
        yield f"{len(sa)} streams != {len(sb)}"
        return
    key = lambda s: s["info"]["name"][0]
    for x, y in zip(sorted(sa, key=key), sorted(sb, key=key)):
        name = key(x)
        tx, ty = x["time_series"], y["time_series"]
        if isinstance(tx, list):
            if tx != ty:
                yield f"stream {name}: marker texts differ"
        elif tx.shape != ty.shape or not (tx == ty).all():
            yield f"stream {name}: samples differ"
        if len(x["time_stamps"]) != len(y["time_stamps"]):
            yield f"stream {name}: {len(x['time_stamps'])} stamps != {len(y['time_stamps'])}"


def main(before, after):
    before, after = Path(before), Path(after)
    out_a = str(before.resolve()).encode() + b"/"
    out_b = str(after.resolve()).encode() + b"/"
    names = sorted(
        {p.relative_to(before) for p in before.rglob("*") if p.is_file()}
        | {p.relative_to(after) for p in after.rglob("*") if p.is_file()}
    )
    bad = 0
    for n in names:
        a, b = before / n, after / n
        if not a.exists() or not b.exists():
            print(f"{n}: only in {'after' if b.exists() else 'before'}")
            bad += 1
            continue
        x = a.read_bytes().replace(out_a, b"OUT/")
        y = b.read_bytes().replace(out_b, b"OUT/")
        if x == y:
            continue
        if n.suffix == ".xdf":
            d = list(xdf_diffs(a, b))
        elif n.suffix == ".json":
            d = list(json_diffs(x, y))
        elif n.suffix in (".stdout", ".stderr", ".csv", ".rc", ".txt"):
            d = list(text_diffs(x, y))
        else:
            d = [f"{len(x)} bytes != {len(y)} bytes (binary)"]
        if d:
            bad += 1
            print(f"{n}:")
            for line in d[:20]:
                print(f"  {line}")
            if len(d) > 20:
                print(f"  … {len(d) - 20} more")
    print(f"{len(names)} files compared, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
