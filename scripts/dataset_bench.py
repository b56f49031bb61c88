#!/usr/bin/env python3
"""Clips per hour of `evray dataset` on this machine (docs/benchmarks.md, "Datasets"): the standard
specification, eye clips at 346x260 for 3 s (each its own gaze plan and iris: --scene-seed), the
default sampling, events.h5; run with every GPU count given, each into a fresh folder.

    scripts/dataset_bench.py EVRAY --clips 8 [--gpus 1,2,4] [--jobs N] [--out DIR]

Without --gpus it runs on the cores (--jobs CPU jobs at once; default: the runner's). Prints one
line per run: clips, wall seconds, clips per hour, and the speedup over the first run."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("evray")
    ap.add_argument("--clips", type=int, default=4)
    ap.add_argument("--gpus", help="GPU counts to run with, e.g. 1,2,4")
    ap.add_argument("--jobs", type=int)
    ap.add_argument("--per-gpu", default="1", help="clips at once per GPU: one run each, e.g. 1,2")
    ap.add_argument("--res", default="346x260")
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--out", help="keep the datasets here (default: a temporary folder)")
    a = ap.parse_args()
    spec = {"clips": a.clips, "seed": 1, "scenes": [{"demo": "eye"}], "format": "h5",
            "options": {"res": a.res, "duration": a.duration},
            "vary": {"scene_seed": True}}
    root = a.out or tempfile.mkdtemp(prefix="evray-dataset-bench-")
    os.makedirs(root, exist_ok=True)
    path = os.path.join(root, "spec.json")
    json.dump(spec, open(path, "w"))
    runs = [("gpus", int(g), int(m)) for m in a.per_gpu.split(",") for g in a.gpus.split(",")] \
        if a.gpus else [("cpu", a.jobs, 1)]
    first = None
    for kind, n, per in runs:
        out = os.path.join(root, f"{kind}{n or ''}x{per}")
        shutil.rmtree(out, ignore_errors=True)
        cmd = [a.evray, "dataset", path, "-o", out]
        cmd += ["--gpus", str(n), "--per-gpu", str(per)] if kind == "gpus" else ["--backend", "cpu"] + \
            (["--jobs", str(n)] if n else [])
        t0 = time.time()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.time() - t0
        if p.returncode != 0:
            print(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr.strip()[-500:]}", file=sys.stderr)
            return 1
        rows = [json.loads(l) for l in open(os.path.join(out, "manifest.jsonl"))]
        events = sum(r["events"] for r in rows)
        first = first or wall
        label = f"{n} GPU{'s' if n != 1 else ''}, {per} clip{'s' if per != 1 else ''} each" \
            if kind == "gpus" else \
            f"CPU ({n or 'default'} jobs, {os.cpu_count()} cores)"
        print(f"{label}: {a.clips} clips ({a.res}, {a.duration:g} s each, {events:,} events) in "
              f"{wall:.1f} s: {3600 * a.clips / wall:.1f} clips/hour, speedup {first / wall:.2f}x; "
              f"clip wall s {min(r['wall_s'] for r in rows):.1f}-{max(r['wall_s'] for r in rows):.1f}",
              flush=True)
    if not a.out:
        shutil.rmtree(root, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
