"""AEDAT 4.0 files read back by iniVation's dv-processing and by aedat (neuromorphic-paris),
installed by scripts/test-venv.sh into build/venv (never the system Python). Every event must come
back identical (t, x, y, p) to events.npy, on a run of the eye and on made-up events (a millisecond
of 40000 events, Unix-time microseconds, the largest int16 addresses); each packet holds one
millisecond's events, at most 8192; dv-processing's time-range reads (through the data table)
give the same events as slicing; the stream is "events" at the run's size. Files dv-processing
writes (every compression: NONE, LZ4, LZ4_HIGH, ZSTD, ZSTD_HIGH) read back identical through
`evray convert`, and h5 -> aedat4 -> h5 gives identical events. The same for ZSTD packets
(--format aedat4-zstd, files named *zstd.aedat4), which are smaller. Skips (77) when the
environment is missing or unusable."""
import json
import os
import subprocess
import sys

import numpy as np

import evrtest as T

venv_python = T.oracle_python(["numpy", "h5py", "dv_processing", "aedat"])

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

def packets_ok(ts):
    """each packet one millisecond's events, at most 8192"""
    for k, t in enumerate(ts):
        if len(t) == 0 or len(t) > 8192 or t[0] // 1000 != t[-1] // 1000:
            return f"packet {k}: {len(t)} events from {t[0] if len(t) else '-'} to {t[-1] if len(t) else '-'} us"
    return ""

def dv_read(path, ref, size):
    import dv_processing as dv
    r = dv.io.MonoCameraRecording(path)
    if r.getEventResolution() != tuple(size) or not r.isEventStreamAvailable("events"):
        return f"resolution {r.getEventResolution()}, streams {r.getStreamNames()}"
    parts = []
    while True:
        b = r.getNextEventBatch()
        if b is None:
            break
        parts.append(b.numpy())
    a = np.concatenate(parts)
    why = same(ref, a["timestamp"], a["x"], a["y"], a["polarity"]) or packets_ok([p["timestamp"] for p in parts])
    # time ranges, found through the data table: [a, b) as slicing gives it
    t = ref["t"]
    for lo, hi in ((t[0], t[0] + 1), (t[len(t) // 3], t[2 * len(t) // 3]), (t[-1] - 1500, t[-1] + 1)):
        lo, hi = int(lo), int(hi)
        got = r.getEventsTimeRange(lo, hi)
        g = got.numpy() if got is not None else np.zeros(0, dtype=a.dtype)
        m = (t >= lo) & (t < hi)
        w = same(ref[m], g["timestamp"], g["x"], g["y"], g["polarity"])
        if w:
            return f"time range [{lo}, {hi}): {w}"
    return why

def aedat_read(path, ref, size):
    import aedat
    d = aedat.Decoder(path)
    s = d.id_to_stream()
    if s != {0: {"type": "events", "width": size[0], "height": size[1]}}:
        return f"streams {s}"
    parts = [p["events"] for p in d if "events" in p]
    a = np.concatenate(parts)
    return same(ref, a["t"], a["x"], a["y"], a["on"]) or packets_ok([p["t"] for p in parts])

def h5_read(path, ref, size):
    import h5py
    with h5py.File(path, "r") as f:
        return same(ref, *(f["events"][k][:] for k in "txyp"))

def dv_write(path, ref, size):
    """ref's events written by dv-processing, one file per compression (path % name)"""
    import dv_processing as dv
    stores = []  # one store a packet (writing slices of one store repeats events)
    for k in range(0, len(ref), 5000):
        stores.append(dv.EventStore())
        for e in ref[k:k + 5000]:
            stores[-1].push_back(int(e["t"]), int(e["x"]), int(e["y"]), bool(e["p"]))
    for name in ("NONE", "LZ4", "LZ4_HIGH", "ZSTD", "ZSTD_HIGH"):
        cfg = dv.io.MonoCameraWriter.EventOnlyConfig("DVXplorer_evray", tuple(size),
                                                     getattr(dv.CompressionType, name))
        w = dv.io.MonoCameraWriter(path % name, cfg)
        for store in stores:
            w.writeEvents(store)
        del w
    return ""

READ = {"dv_processing": dv_read, "aedat": aedat_read, "h5py": h5_read, "dv_write": dv_write}
for reader, path, ref_path, size in jobs:
    ref = np.load(ref_path)
    try:
        why = READ[reader](path, ref, size)
    except Exception as e:
        why = f"{type(e).__name__}: {e}"[:300]
    print(json.dumps([reader, path, why]), flush=True)
'''

d = T.tmpdir()
run = os.path.join(d, "run")
W, H = 64, 48
T.run("demo", "--scene", "eye", "-o", run, "--res", f"{W}x{H}", "--duration", "2",
      "--format", "npy,h5,aedat4,aedat4-zstd", "--no-preview", "--quiet")
npy = os.path.join(run, "events.npy")
ref = np.load(npy)
T.check(len(ref) > 100000, f"a run of many events ({len(ref)})")
aedat4 = os.path.join(run, "events.aedat4")
zaedat4 = os.path.join(run, "events_zstd.aedat4")
# the IOHeader's compression (after the version line, at 28 in its FlatBuffer): LZ4 1, ZSTD 3
T.check(open(aedat4, "rb").read()[42] == 1 and open(zaedat4, "rb").read()[42] == 3,
        "the IOHeaders say LZ4 and ZSTD")
T.check(os.path.getsize(zaedat4) < os.path.getsize(aedat4),
        f"ZSTD packets are smaller than LZ4's ({os.path.getsize(zaedat4)} against {os.path.getsize(aedat4)} bytes)")

# made up: a millisecond of 40000 events (two packets), Unix-time microseconds as a camera
# stamps them, the largest addresses int16 holds
rng = np.random.default_rng(7)
n = 100000
syn = np.zeros(n, dtype=ref.dtype)
t = 1_700_000_000_000_000 + np.cumsum(rng.integers(0, 40, n))
t[30000:70000] = t[30000] // 1000 * 1000 + 1000 + np.arange(40000) // 50
t[70000:] = t[69999] + 1 + np.cumsum(rng.integers(0, 3, n - 70000))
syn["t"] = t
syn["x"] = rng.integers(0, 32768, n)
syn["y"] = rng.integers(0, 300, n)
syn["p"] = rng.integers(0, 2, n)
syn["x"][5] = 32767
T.check(bool(np.all(np.diff(syn["t"]) >= 0)), "made-up events in time order")
snpy = os.path.join(d, "syn.npy")
np.save(snpy, syn)
saedat4 = os.path.join(d, "syn.aedat4")
T.run("convert", snpy, saedat4, "--quiet")
szaedat4 = os.path.join(d, "syn.zstd.aedat4")
T.run("convert", snpy, szaedat4, "--quiet")
ssize = [32768, int(syn["y"].max()) + 1]

# the run's h5 converted: the same bytes as the run wrote (packets depend only on the events)
conv = os.path.join(d, "conv.aedat4")
T.run("convert", os.path.join(run, "events.h5"), conv, "--quiet")
T.check(open(conv, "rb").read() == open(aedat4, "rb").read(),
        "h5 -> aedat4 by evray convert is byte-identical to the run's events.aedat4")
back = os.path.join(d, "back.h5")
T.run("convert", conv, back, "--quiet")
zconv = os.path.join(d, "conv.zstd.aedat4")
T.run("convert", os.path.join(run, "events.h5"), zconv, "--quiet")
T.check(open(zconv, "rb").read() == open(zaedat4, "rb").read(),
        "h5 -> zstd.aedat4 by evray convert is byte-identical to the run's events_zstd.aedat4")
zback = os.path.join(d, "zback.h5")
T.run("convert", zconv, zback, "--quiet")

dvsmall = os.path.join(d, "small.npy")
np.save(dvsmall, ref[:20000])
dvfiles = os.path.join(d, "dv_%s.aedat4")
jobs = [("dv_processing", aedat4, npy, [W, H]), ("aedat", aedat4, npy, [W, H]),
        ("dv_processing", saedat4, snpy, ssize), ("aedat", saedat4, snpy, ssize),
        ("dv_processing", zaedat4, npy, [W, H]), ("aedat", zaedat4, npy, [W, H]),
        ("dv_processing", szaedat4, snpy, ssize), ("aedat", szaedat4, snpy, ssize),
        ("h5py", back, npy, [W, H]), ("h5py", zback, npy, [W, H]),
        ("dv_write", dvfiles, dvsmall, [W, H])]
p = subprocess.run([venv_python, "-c", ORACLES, json.dumps(jobs)], capture_output=True, text=True)
if p.returncode != 0:
    print(p.stderr, file=sys.stderr)
T.check(p.returncode == 0, "the oracle script ran")
seen = 0
for line in p.stdout.splitlines():
    reader, path, why = json.loads(line)
    seen += 1
    T.check(why == "", f"{reader} {os.path.basename(path)}: {why or 'ok'}")
    if not why:
        print(f"dv_processing wrote {os.path.basename(path)} with every compression" if reader == "dv_write"
              else f"{reader}: {os.path.basename(path)}: every event identical")
T.check(seen == len(jobs), f"every oracle answered ({seen} of {len(jobs)})")

# dv-processing's own files, every compression, read by evray
small = np.load(dvsmall)
for name in ("NONE", "LZ4", "LZ4_HIGH", "ZSTD", "ZSTD_HIGH"):
    out = os.path.join(d, f"dv_{name}.npy")
    if not os.path.exists(dvfiles % name):
        T.check(False, f"dv-processing wrote {dvfiles % name}")
        continue
    T.run("convert", dvfiles % name, out, "--quiet")
    b = np.load(out)
    ok = len(b) == len(small) and all(np.array_equal(b[k], small[k]) for k in "txyp")
    T.check(ok, f"evray reads dv-processing's {name} file: every event identical")
    if ok:
        print(f"evray: dv-processing's {name} file: every event identical")

# bad input through the program: one line, exit 1, no crash
data = open(aedat4, "rb").read()
bad = os.path.join(d, "bad.aedat4")
for cut, what in ((len(data) - 1, "truncated"), (len(data) // 2, "truncated"), (9, "truncated"),
                  (0, "not an AEDAT")):
    with open(bad, "wb") as f:
        f.write(data[:cut])
    r = T.run("compare", bad, npy, expect=1)
    T.check(what in r.stderr and len(r.stderr.strip().splitlines()) == 1,
            f"a file cut at {cut} bytes: one line saying '{what}' ({r.stderr.strip()})")
T.run("plot", aedat4, "-o", os.path.join(d, "plot.png"))
T.check(os.path.exists(os.path.join(d, "plot.png")), "evray plot reads AEDAT 4.0")
T.finish("test_aedat4")
