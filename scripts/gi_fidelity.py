#!/usr/bin/env python3
"""The GI fidelity table of docs/benchmarks.md: a scene with `--gi photon` at its defaults (the
blurred estimate), with a gather at every sample at several photon budgets, each scored with
`evray compare` against a reference: the same scene with many times the photons and a gather at
every sample (every photon kept: the buffer's layers raised with the budget). The reference
is rendered with two seeds; their agreement says how far it is converged. Direct light alone is
scored too, for scale. Each run is scored twice: within --tol-us, and within the larger of that
and --tol-level times the gap since the reference's previous event of the same pixel and polarity
(`evray compare --tol-level`): an event of a slowly changing pixel is placed by the level of its
log intensity, so a small error of the estimate moves it by a share of that gap.

    scripts/gi_fidelity.py EVRAY [--scene cornell] [--res 173x130] [--duration 1]
                           [--ref-ppp 1024] [--budgets 16,64] [--tol-us 1000] [--tol-level 0.1] [--ref-cache DIR]
                           [--extra "LABEL=OPTS;LABEL=OPTS"]
                           [--write docs/benchmarks.md]

Photon budgets are photons per pixel of the image (`--photons` = ppp x width x height); the
default run (no `--photons`) is one per pixel. --write replaces the text between the lines
'<!-- gi-fidelity:SCENE -->' and '<!-- /gi-fidelity -->' in that file (appending both when
missing). The reference at 1024 photons per pixel takes about 9 GB of memory at 173x130."""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile

from doc_section import write_section

p = argparse.ArgumentParser()
p.add_argument("evray")
p.add_argument("--scene", default="cornell")
p.add_argument("--res", default="173x130")
p.add_argument("--duration", default="1")
p.add_argument("--backend", default="cpu")
p.add_argument("--ref-ppp", type=int, default=1024, help="the reference's photons per pixel")
p.add_argument("--budgets", default="16,64", help="photons per pixel of the rows besides the default")
p.add_argument("--tol-us", type=int, default=1000)
p.add_argument("--tol-level", type=float, default=0.1)
p.add_argument("--extra", default="", help="more GI rows: 'LABEL=OPTIONS' separated by ';' (options split on spaces)")
p.add_argument("--write", default=None)
p.add_argument("--ref-cache", default=None,
               help="a folder that keeps the references: one already there for the same scene, size, duration, "
                    "budget and seed is taken instead of rendered again")
a = p.parse_args()
w, h = (int(v) for v in a.res.split("x"))
tmp = tempfile.mkdtemp(prefix="evray-gi-fidelity-")
common = ["demo", "--scene", a.scene, "--res", a.res, "--duration", a.duration, "--backend", a.backend,
          "--no-preview", "--quiet"]


def budget(ppp):
    """--photons and --photon-layers for ppp photons a pixel with every photon kept: four layers
    for each photon per pixel holds the brightest cells of the Cornell box (at least 64)."""
    return ["--photons", str(ppp * w * h), "--photon-layers", str(min(4096, max(64, 4 * ppp)))]


def render(name, seed, opts):
    out = os.path.join(tmp, name)
    r = subprocess.run([a.evray, *common, "-o", out, "--seed", str(seed), *opts], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"gi_fidelity: {name} failed: {r.stderr.strip()}")
    if "photon buffer" in r.stderr:
        sys.exit(f"gi_fidelity: {name} dropped photons, so it is not the estimate of its budget: {r.stderr.strip()}")
    with open(os.path.join(out, "run.json")) as f:
        st = json.load(f)["stats"]
    print(f"{name}: {st['events']:,} events, {st['wall_seconds']:.1f} s", file=sys.stderr)
    return out, st


def f1(ref, test, level=0.0):
    r = subprocess.run([a.evray, "compare", os.path.join(ref, "events.h5"), os.path.join(test, "events.h5"),
                        "--tol-us", str(a.tol_us), "--tol-level", str(level), "--json"], check=True,
                       capture_output=True, text=True)
    return json.loads(r.stdout)["f1"]


def scores(ref, test):
    """F1 at the fixed tolerance, and with the level tolerance"""
    return f"{f1(ref, test):.3f} ({f1(ref, test, a.tol_level):.3f})"


# direct light sampled as `--gi` samples (uniform, 10 a frame, each pixel's phase from the seed)
rows = [("direct light only (`--samples-per-frame 10`)", "direct", ["--samples-per-frame", "10"])]
rows.append(("GI, the defaults (one photon a pixel, blurred: `--gi-blur 4`)", "default", ["--gi", "photon"]))
rows.append(("GI, a gather at every sample (`--gi-blur 0`)", "gather", ["--gi", "photon", "--gi-blur", "0"]))
for ppp in (int(v) for v in a.budgets.split(",") if v):
    rows.append((f"GI, {ppp} photons a pixel, a gather at every sample", f"p{ppp}",
                 ["--gi", "photon", "--gi-blur", "0", *budget(ppp)]))
for item in (v for v in a.extra.split(";") if v.strip()):
    label, opts = item.split("=", 1)
    rows.append((f"GI, {label.strip()} (`{opts.strip()}`)", "x-" + "".join(c for c in label if c.isalnum()),
                 ["--gi", "photon", *opts.split()]))
ref_opts = ["--gi", "photon", "--gi-blur", "0", *budget(a.ref_ppp)]


def reference(seed):
    if not a.ref_cache:
        return render(f"ref-seed{seed}", seed, ref_opts)
    out = os.path.join(a.ref_cache, f"{a.scene}-{a.res}-{a.duration}s-{a.ref_ppp}ppp-{a.backend}-seed{seed}")
    if not os.path.exists(os.path.join(out, "run.json")):
        r = subprocess.run([a.evray, *common, "-o", out, "--seed", str(seed), *ref_opts, "--force"],
                           capture_output=True, text=True)
        if r.returncode != 0 or "photon buffer" in r.stderr:
            sys.exit(f"gi_fidelity: the reference of seed {seed} failed: {r.stderr.strip()}")
    with open(os.path.join(out, "run.json")) as f:
        st = json.load(f)["stats"]
    print(f"reference of seed {seed}: {st['events']:,} events, {st['wall_seconds']:.1f} s ({out})", file=sys.stderr)
    return out, st


ref1, ref1_st = reference(1)
ref2, ref2_st = reference(2)
tol = f"{a.tol_us / 1000:g} ms" if a.tol_us >= 1000 else f"{a.tol_us} µs"
lines = [f"{a.scene}, {a.duration} s, {a.res}, ideal sensor, thresholds 0.2, backend {a.backend}, "
         f"{datetime.date.today().isoformat()}, `scripts/gi_fidelity.py EVRAY --scene {a.scene} --res {a.res} "
         f"--duration {a.duration} --ref-ppp {a.ref_ppp} --budgets {a.budgets} --tol-us {a.tol_us} "
         f"--tol-level {a.tol_level:g}" + (f" --extra '{a.extra}'`; " if a.extra else "`; ") +
         f"the reference: {a.ref_ppp} photons a pixel (`{' '.join(ref_opts)}`); a run of seed k is scored against "
         f"the reference of seed k (the same sample phases), its events counted against seed 1's. F1 at {tol}, and in "
         f"brackets within {a.tol_level:g} of the reference's gap (`--tol-level {a.tol_level:g}`).", "",
         f"| run | events, seed 1 / seed 2 | against the reference's events | F1 against the reference "
         f"of its seed (seed 1 / seed 2) | F1 between the seeds | wall s (seed 1) |",
         "|---|---|---|---|---|---|"]
ref_events = ref1_st["events"]
ref_pair = scores(ref1, ref2)
lines.append(f"| reference, {a.ref_ppp} photons a pixel | {ref_events:,} / {ref2_st['events']:,} | "
             f"{(ref2_st['events'] - ref_events) / ref_events:+.1%} (seed 2) | 1 / 1 | "
             f"{ref_pair} | {ref1_st['wall_seconds']:.1f} |")
for label, key, opts in rows:
    o1, s1 = render(key + "-seed1", 1, opts)
    o2, s2 = render(key + "-seed2", 2, opts)
    lines.append(f"| {label} | {s1['events']:,} / {s2['events']:,} | "
                 f"{(s1['events'] - ref_events) / ref_events:+.1%} / {(s2['events'] - ref_events) / ref_events:+.1%} | "
                 f"{scores(ref1, o1)} / {scores(ref2, o2)} | {scores(o1, o2)} | {s1['wall_seconds']:.1f} |")
text = "\n".join(lines) + "\n"
print(text)
if a.write:
    write_section(a.write, f"<!-- gi-fidelity:{a.scene} -->", "<!-- /gi-fidelity -->", text)
print(f"machine: {platform.node()}, outputs in {tmp}", file=sys.stderr)
