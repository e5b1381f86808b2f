#!/usr/bin/env python3
"""Fails when a locked dependency (normal, dev or build, for this host) declares a rust-version
above the workspace's `rust-version`: the declared MSRV would then not build with Cargo.lock.

Run from the workspace root: `python3 tools/msrv/check_locked_msrv.py`. No toolchain other than
the installed one is needed: Cargo's metadata gives every package's declared rust-version.
Language features and std APIs of our own code are checked by clippy's `incompatible_msrv` lint,
which reads the same `rust-version` (`cargo clippy --workspace --all-targets -- -D warnings`).
"""
import json
import subprocess
import sys


def version(v):
    return tuple(int(x) for x in v.split("."))[:3] + (0,) * (3 - len(v.split(".")))


host = subprocess.run(["rustc", "-vV"], capture_output=True, text=True, check=True).stdout
target = next(l.split(": ", 1)[1] for l in host.splitlines() if l.startswith("host: "))
meta = json.loads(
    subprocess.run(
        ["cargo", "metadata", "--locked", "--format-version", "1", "--filter-platform", target],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
)
members = set(meta["workspace_members"])
ours = {p["rust_version"] for p in meta["packages"] if p["id"] in members}
if len(ours) != 1 or None in ours:
    sys.exit(f"workspace members declare rust-versions {sorted(map(str, ours))}; expected one")
msrv = ours.pop()
resolved = {n["id"] for n in meta["resolve"]["nodes"]}
too_new = sorted(
    (p["rust_version"], p["name"], p["version"])
    for p in meta["packages"]
    if p["id"] in resolved
    and p["id"] not in members
    and p.get("rust_version")
    and version(p["rust_version"]) > version(msrv)
)
for rv, name, ver in too_new:
    print(f"{name} {ver} needs Rust {rv} > the workspace's rust-version {msrv}")
if too_new:
    sys.exit(1)
print(f"every locked dependency builds with the declared rust-version {msrv}")
