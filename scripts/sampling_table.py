#!/usr/bin/env python3
"""The sampling accuracy table of docs/benchmarks.md: the eye (or another built-in scene) rendered
by the default (refined) sampling, uniform sampling at 10, 100 and 300 samples per frame and
adaptive sampling, each scored with `evray compare` against uniform sampling at 1000 samples per
frame (F1 at 100 us and 1 ms), with wall time, events and samples traced; then the event rate of
the reference, the default and uniform 10 per frame in 0.1 ms bins over the busiest 2 ms of the
first saccade.

    scripts/sampling_table.py EVRAY [--res 346x260] [--start 0] [--duration 3] [--backend cpu]
                              [--scene eye] [--skip adaptive,u300] [--write docs/benchmarks.md]

--write replaces the text between the lines '<!-- sampling-table:SCENE:BACKEND -->' and
'<!-- /sampling-table -->' in that file (appending both when missing). Needs numpy."""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile

import numpy as np

from doc_section import write_section

p = argparse.ArgumentParser()
p.add_argument("evray")
p.add_argument("--scene", default="eye")
p.add_argument("--res", default="346x260")
p.add_argument("--start", default="0")
p.add_argument("--duration", default="3")
p.add_argument("--backend", default="cpu")
p.add_argument("--skip", default="", help="comma-separated rows to leave out: u10, u100, u300, adaptive")
p.add_argument("--zoom", type=float, default=None, help="start of the 2 ms zoom, seconds (default: the "
               "reference's busiest 2 ms in the 0.1 s from its first event: the eye's first saccade)")
p.add_argument("--write", default=None)
a = p.parse_args()
tmp = tempfile.mkdtemp(prefix="evray-sampling-")
common = ["demo", "--scene", a.scene, "--res", a.res, "--start", a.start, "--duration", a.duration,
          "--backend", a.backend, "--format", "npy", "--no-preview", "--quiet"]


def render(name, *opts):
    out = os.path.join(tmp, name)
    subprocess.run([a.evray, *common, "-o", out, *opts], check=True)
    with open(os.path.join(out, "run.json")) as f:
        return out, json.load(f)


def score(ref, test, tol):
    r = subprocess.run([a.evray, "compare", os.path.join(ref, "events.npy"), os.path.join(test, "events.npy"),
                        "--tol-us", str(tol), "--json"], check=True, capture_output=True, text=True)
    return json.loads(r.stdout)["f1"]


rows = [("reference, 1000 samples/frame", "ref", ["--samples-per-frame", "1000"]),
        ("**default (refine)**", "default", []),
        ("10 samples/frame", "u10", ["--samples-per-frame", "10"]),
        ("100 samples/frame", "u100", ["--samples-per-frame", "100"]),
        ("300 samples/frame", "u300", ["--samples-per-frame", "300"]),
        ("`--sampling adaptive` (default settings)", "adaptive", ["--sampling", "adaptive"])]
skip = set(s for s in a.skip.split(",") if s)
done = {}
for label, key, opts in rows:
    if key in skip:
        continue
    out, js = render(key, *opts)
    done[key] = (label, out, js)
    print(f"{label}: {js['stats']['wall_seconds']:.1f} s", file=sys.stderr)
ref = done["ref"][1]
lines = [f"{a.scene}, {a.start} s + {a.duration} s, {a.res}, ideal sensor, thresholds 0.2, backend {a.backend} "
         f"({done['ref'][2].get('device', '')}), {datetime.date.today().isoformat()}, "
         f"`scripts/sampling_table.py EVRAY --scene {a.scene} --res {a.res} --start {a.start} "
         f"--duration {a.duration} --backend {a.backend}`", "",
         "| method | wall s | events | samples traced | F1 @100 µs | F1 @1 ms |", "|---|---|---|---|---|---|"]
for key, (label, out, js) in done.items():
    s = js["stats"]
    f100 = 1.0 if key == "ref" else score(ref, out, 100)
    f1ms = 1.0 if key == "ref" else score(ref, out, 1000)
    lines.append(f"| {label} | {s['wall_seconds']:.1f} | {s['events']:,} | {s['samples_traced']:,} | "
                 f"{f100:.3f} | {f1ms:.3f} |")


def times(key):
    return np.load(os.path.join(done[key][1], "events.npy"))["t"].astype(np.int64)


t_ref = times("ref")
start_us = int(round(float(a.start) * 1e6))
if a.zoom is not None:
    z0 = int(round(a.zoom * 1e6))
else:  # the busiest 2 ms of the reference in the 0.1 s after its first event
    first = int(t_ref.min()) if len(t_ref) else start_us
    early = t_ref[t_ref < first + 100_000]
    h, edges = np.histogram(early, bins=np.arange(first, first + 100_001, 2000))
    z0 = int(edges[int(np.argmax(h))]) if len(early) else first
bins = np.arange(z0, z0 + 2001, 100)
zoom_keys = [k for k in ("ref", "default", "u10") if k in done]
counts = {k: np.histogram(times(k), bins=bins)[0] for k in zoom_keys}
lines += ["", f"Event rate in 0.1 ms bins from {z0 / 1e6:.4f} s (events per bin):", "",
          "| bin start, ms | " + " | ".join(done[k][0].strip("*") for k in zoom_keys) + " |",
          "|---|" + "---|" * len(zoom_keys)]
for i in range(len(bins) - 1):
    lines.append(f"| {bins[i] / 1e3:.1f} | " + " | ".join(str(int(counts[k][i])) for k in zoom_keys) + " |")
text = "\n".join(lines) + "\n"
print(text)
if a.write:
    write_section(a.write, f"<!-- sampling-table:{a.scene}:{a.backend} -->", "<!-- /sampling-table -->", text)
print(f"machine: {platform.node()}, outputs in {tmp}", file=sys.stderr)
