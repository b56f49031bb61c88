"""Shared helpers for the Python tests: run the evray binary, load its outputs."""
import json
import os
import subprocess
import sys
import tempfile

EVRAY = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("EVRAY", "build/evray")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("CHECK failed:", what, file=sys.stderr)


def run(*args, expect=0):
    p = subprocess.run([EVRAY, *map(str, args)], capture_output=True, text=True)
    if expect is not None and p.returncode != expect:
        print(p.stdout, p.stderr, file=sys.stderr)
        raise SystemExit(f"evray {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}")
    return p


def tmpdir():
    return tempfile.mkdtemp(prefix="evray-test-")


def load_run_json(d):
    with open(os.path.join(d, "run.json")) as f:
        return json.load(f)


def load_h5(path):
    import h5py
    with h5py.File(path, "r") as f:
        ev = {k: f["events"][k][()] for k in ("x", "y", "t", "p")}
        ms = f["ms_to_idx"][()]
        attrs = dict(f.attrs)
    return ev, ms, attrs


def finish(name):
    if failures:
        print(f"{name}: {len(failures)} check(s) failed")
        raise SystemExit(1)
    print(f"{name}: all checks passed")
