"""Output files read back with independent readers (h5py, numpy): sorted, in bounds, of the
documented types, matching each other and the counts in run.json."""
import os
import shutil

import numpy as np

import evrtest as T

d = os.path.join(T.tmpdir(), "run")
W, H = 96, 72
T.run("demo", "--scene", "eye", "-o", d, "--res", f"{W}x{H}", "--duration", "0.6", "--format", "all",
      "--samples-per-frame", "4", "--preview", "png", "--quiet")
meta = T.load_run_json(d)
stats = meta["stats"]
ev, ms, attrs = T.load_h5(os.path.join(d, "events.h5"))
n = len(ev["t"])
T.check(n > 0, "the eye demo makes events in its first 0.6 s")
T.check(n == stats["events"], f"h5 count {n} == run.json events {stats['events']}")
T.check(ev["x"].dtype == np.uint16 and ev["y"].dtype == np.uint16, "x, y are uint16")
T.check(ev["t"].dtype == np.uint32 and ev["p"].dtype == np.int8, "t is uint32 (as DSEC's, t_offset 0), p is int8")
T.check(bool(np.all(np.diff(ev["t"]) >= 0)), "events sorted by time")
T.check(bool(np.all(ev["x"] < W) and np.all(ev["y"] < H)), "coordinates inside the image")
T.check(set(np.unique(ev["p"]).tolist()) <= {0, 1}, "polarity is 0 or 1")
T.check(int(np.sum(ev["p"] == 1)) == stats["events_on"], "ON count matches run.json")
T.check(int(np.sum(ev["p"] == 0)) == stats["events_off"], "OFF count matches run.json")
T.check(len(np.unique(ev["t"])) == stats["unique_timestamps"], "unique timestamps match run.json")
T.check(ev["t"][0] >= 0 and ev["t"][-1] <= 600000, "timestamps inside the simulated time")
T.check(int(attrs["width"]) == W and int(attrs["height"]) == H, "width/height attributes")
T.check("samples_per_frame" in str(attrs.get("config", "")), "configuration stored as an attribute")
# ms_to_idx as in DSEC: first event index with t >= i ms
expect = np.searchsorted(ev["t"], np.arange(len(ms)) * 1000, side="left")
T.check(bool(np.array_equal(ms, expect)), "ms_to_idx indexes the first event of every millisecond")
T.check(len(ms) >= 600, "ms_to_idx covers the simulated time")

# a segment of more than 131,072 events is counted on several threads: the counts still match
d2 = os.path.join(T.tmpdir(), "big")
T.run("demo", "--scene", "eye", "-o", d2, "--res", "640x360", "--start", "0.9", "--duration", "0.034",
      "--samples-per-frame", "10", "--quiet", "--no-preview")
s2 = T.load_run_json(d2)["stats"]
ev2, _, _ = T.load_h5(os.path.join(d2, "events.h5"))
T.check(len(ev2["t"]) > 131072, f"one segment of {len(ev2['t'])} events, enough for several counting threads")
T.check(int(np.sum(ev2["p"] == 1)) == s2["events_on"] and int(np.sum(ev2["p"] == 0)) == s2["events_off"],
        "ON/OFF counts of a large segment match run.json")
T.check(len(np.unique(ev2["t"])) == s2["unique_timestamps"], "unique timestamps of a large segment match run.json")

npy = np.load(os.path.join(d, "events.npy"))
T.check(len(npy) == n, "npy count matches")
for k in ("x", "y", "t", "p"):
    T.check(bool(np.array_equal(npy[k], ev[k])), f"npy field {k} equals h5")
txt = np.loadtxt(os.path.join(d, "events.txt"), ndmin=2)
T.check(txt.shape == (n, 4), "txt has one line per event, 4 columns")
if txt.shape == (n, 4):
    T.check(bool(np.array_equal(np.round(txt[:, 0] * 1e6).astype(np.int64), ev["t"])), "txt t in seconds")
    T.check(bool(np.array_equal(txt[:, 1].astype(int), ev["x"])) and bool(np.array_equal(txt[:, 3].astype(int), ev["p"])), "txt x, p")

# statistics are consistent with the configuration
T.check(stats["samples"] == W * H * 4 * 18, f"samples = pixels x samples x segments ({stats['samples']})")
T.check(stats["rays"] >= stats["samples_traced"] > 0, "at least one ray per traced sample")
T.check(stats["samples_traced"] <= stats["samples"], "no more samples traced than taken")
T.check(stats["time_motion_seconds"] >= 0 and stats["time_render_seconds"] >= 0 and stats["time_plan_wait_seconds"] >= 0,
        "run.json: host time in motion keys (planner thread), waiting for the planner, and rendering")
T.check(stats["samples_per_second"] > 0 and stats["wall_seconds"] > 0, "speed reported")
T.check(meta["config"]["width"] == W and meta["config"]["pos_thres"] == 0.2, "config in run.json")
prev = sorted(os.listdir(os.path.join(d, "preview")))
T.check(sum(p.startswith("events_") for p in prev) == 12, "one event frame per 50 ms window")
T.check(sum(p.startswith("intensity_") for p in prev) == 12, "one intensity frame per 50 ms window")
T.check(not os.path.exists(os.path.join(d, "preview.apng")), "--preview png: no video")
T.check(not any(f.endswith(".tmp") for f in os.listdir(d)), "no temporary files left")

# an existing run folder is not overwritten without --force
p = T.run("demo", "--scene", "eye", "-o", d, "--res", "16x12", "--duration", "0.1", "--quiet", expect=None)
T.check(p.returncode != 0 and "--force" in p.stderr, "refuses to overwrite a run folder")
T.check(T.load_run_json(d)["config"]["width"] == W, "old run left intact")
T.run("demo", "--scene", "eye", "-o", d, "--res", "16x12", "--duration", "0.1", "--quiet", "--force")
T.check(T.load_run_json(d)["config"]["width"] == 16, "--force overwrites")

# same seed, different thread counts: byte-identical events
d1, d2 = os.path.join(T.tmpdir(), "a"), os.path.join(T.tmpdir(), "b")
for dd, th in ((d1, 1), (d2, 2)):
    T.run("demo", "--scene", "eye", "-o", dd, "--res", "64x48", "--duration", "0.3", "--threads", th,
          "--format", "npy", "--no-preview", "--quiet")
a, b = (open(os.path.join(x, "events.npy"), "rb").read() for x in (d1, d2))
T.check(a == b, "identical events for 1 and 2 threads")

# Ctrl-C: stops after the current segment, leaves complete files holding every event so far
d3 = os.path.join(T.tmpdir(), "int")
rc, err = T.interrupt(os.path.join(d3, "events.h5.tmp"), 1.0, "demo", "--scene", "eye", "-o", d3, "--res", "200x150",
                      "--samples-per-frame", "20", "--format", "h5,npy", "--no-preview", "--threads", "1")
T.check(rc == 130, f"interrupted run exits 130 (got {rc}: {err.strip()})")
if rc == 130:
    meta = T.load_run_json(d3)
    T.check(meta["stats"]["interrupted"] is True, "run.json says interrupted")
    ev3, ms3, _ = T.load_h5(os.path.join(d3, "events.h5"))
    T.check(len(ev3["t"]) == meta["stats"]["events"], "interrupted h5 holds every counted event")
    T.check(len(np.load(os.path.join(d3, "events.npy"))) == meta["stats"]["events"], "interrupted npy too")
    T.check(meta["stats"]["simulated_seconds"] < 2.9, "stopped early")
shutil.rmtree(os.path.dirname(d), ignore_errors=True)
T.finish("test_outputs")
