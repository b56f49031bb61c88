"""Prophesee EVT 2.0, EVT 3.0 and DAT files read back by independent readers, installed by
scripts/test-venv.sh into build/venv (never the system Python): expelliarmus (EVT 2.0, DAT), evlib
(EVT 2.0, EVT 3.0), evt3 and faery (EVT 3.0). Every event must come back identical (t, x, y, p) to
events.npy, on a run of more than one EVT 3.0 wrap (2^24 us) and the same events shifted by 40 s
(several wraps), with rows dense enough for vector words. And `evray convert`: h5 -> each format
-> h5 gives identical events. Skips (77) when the environment is missing or unusable."""
import json
import os
import subprocess
import sys

import numpy as np

import evrtest as T

venv_python = T.oracle_python(["numpy", "h5py", "expelliarmus", "evlib", "evt3", "faery"])

# The readers, run in the virtual environment: one JSON line per (reader, file).
ORACLES = r'''
import json, sys, warnings
import numpy as np
warnings.simplefilter("ignore")
jobs = json.loads(sys.argv[1])

def same(ref, t, x, y, p):
    t, x, y, p = (np.asarray(a).astype(np.int64) for a in (t, x, y, p))
    if len(t) != len(ref):
        return f"{len(t)} events, expected {len(ref)}"
    bad = (t != ref["t"]) | (x != ref["x"]) | (y != ref["y"]) | ((p > 0) != (ref["p"] > 0))
    if bad.any():
        i = int(np.nonzero(bad)[0][0])
        return (f"{int(bad.sum())} events differ, first #{i}: {(t[i], x[i], y[i], p[i])} "
                f"expected {tuple(int(ref[k][i]) for k in 'txyp')}")
    return ""

def read(reader, path):
    if reader == "expelliarmus":
        from expelliarmus import Wizard
        enc = "dat" if path.endswith(".dat") else "evt2"
        a = Wizard(encoding=enc).read(path)
        return a["t"], a["x"], a["y"], a["p"]
    if reader == "evlib":
        import evlib
        df = evlib.load_events(path)
        df = df.collect() if hasattr(df, "collect") else df
        t, x, y, p = (df["t"].dt.total_microseconds().to_numpy(), df["x"].to_numpy(), df["y"].to_numpy(),
                      df["polarity"].to_numpy())
        # evlib decodes in chunks of 202,107 events and may swap events that share a timestamp
        # across a chunk's end: the file's (t, y, x) order is restored before comparing
        o = np.lexsort((x, y, t))
        return t[o], x[o], y[o], p[o]
    if reader == "evt3":
        import evt3
        e = evt3.decode_file(path)
        return e.timestamp, e.x, e.y, e.polarity
    if reader == "faery":
        import faery
        a = np.concatenate(list(faery.events_stream_from_file(path)))
        return a["t"], a["x"], a["y"], a["on"]
    if reader == "h5py":
        import h5py
        with h5py.File(path, "r") as f:
            return tuple(f["events"][k][:] for k in "txyp")
    raise ValueError(reader)

for reader, path, ref_path in jobs:
    ref = np.load(ref_path)
    try:
        why = same(ref, *read(reader, path))
    except Exception as e:
        why = f"{type(e).__name__}: {e}"[:300]
    print(json.dumps([reader, path, why]), flush=True)
'''

d = T.tmpdir()
run = os.path.join(d, "run")
W, H = 64, 48
T.run("demo", "--scene", "eye", "-o", run, "--res", f"{W}x{H}", "--duration", "20",
      "--format", "npy,h5,evt2,evt3,dat", "--no-preview", "--quiet")
npy = os.path.join(run, "events.npy")
ref = np.load(npy)
T.check(len(ref) > 100000 and int(ref["t"][-1]) > (1 << 24), "a run of many events past one EVT 3.0 wrap")


def evt3_vector_words(path):
    data = open(path, "rb").read()
    at = data.index(b"% end\n") + 6
    words = np.frombuffer(data[at:], dtype="<u2")
    return int(np.count_nonzero((words >> 12 == 4) | (words >> 12 == 5)))


nvec = evt3_vector_words(os.path.join(run, "events_evt3.raw"))
T.check(nvec > 1000, f"dense rows written as vector words ({nvec})")

# the same events 40 s later: several wraps, and a long stretch before the first event
shifted = ref.copy()
shifted["t"] += 40_000_000
snpy = os.path.join(d, "shifted.npy")
np.save(snpy, shifted)
for name in ("shifted_evt2.raw", "shifted_evt3.raw", "shifted.dat"):
    T.run("convert", snpy, os.path.join(d, name), "--quiet")

jobs = []
for base, ref_path in ((run, npy), (d, snpy)):
    pre = "events_" if base == run else "shifted_"
    evt2 = os.path.join(base, pre + "evt2.raw")
    evt3 = os.path.join(base, pre + "evt3.raw")
    dat = os.path.join(base, "events_td.dat" if base == run else "shifted.dat")
    jobs += [("expelliarmus", evt2, ref_path), ("evlib", evt2, ref_path), ("expelliarmus", dat, ref_path),
             ("evlib", evt3, ref_path), ("evt3", evt3, ref_path), ("faery", evt3, ref_path)]

# evray convert: h5 -> each format -> h5, read back by h5py
h5 = os.path.join(run, "events.h5")
for ext in ("npy", "txt", "evt2.raw", "evt3.raw", "dat"):
    mid = os.path.join(d, "conv." + ext)
    back = os.path.join(d, f"back_{ext.replace('.', '_')}.h5")
    T.run("convert", h5, mid, "--quiet")
    T.run("convert", mid, back, "--quiet")
    jobs.append(("h5py", back, npy))

p = subprocess.run([venv_python, "-c", ORACLES, json.dumps(jobs)], capture_output=True, text=True)
if p.returncode != 0:
    print(p.stderr, file=sys.stderr)
T.check(p.returncode == 0, "the oracle script ran")
seen = 0
for line in p.stdout.splitlines():
    reader, path, why = json.loads(line)
    seen += 1
    T.check(why == "", f"{reader} reads {os.path.basename(path)} back identical to events.npy {why}")
    if not why:
        print(f"{reader}: {os.path.basename(path)}: every event identical")
T.check(seen == len(jobs), f"every oracle answered ({seen} of {len(jobs)})")

# bad input through the program: one line, exit 1, no crash
bad = os.path.join(d, "bad.raw")
with open(os.path.join(run, "events_evt3.raw"), "rb") as f:
    data = f.read()
with open(bad, "wb") as f:
    f.write(data[:-1])
r = T.run("compare", bad, npy, expect=1)
T.check("truncated" in r.stderr and len(r.stderr.strip().splitlines()) == 1, "a truncated file: one line")
r = T.run("plot", os.path.join(run, "events_td.dat"), "-o",
          os.path.join(d, "plot.png"))
T.check(os.path.exists(os.path.join(d, "plot.png")), "evray plot reads DAT")
T.finish("test_prophesee")
