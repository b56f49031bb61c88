"""The command line: help, version, export, info, a static scene, and bad input (one clear line,
non-zero exit, no crash, nothing half-written left behind)."""
import json
import os
import struct

import evrtest as T

tmp = T.tmpdir()


def expect_error(args, what, out_dir=None):
    p = T.run(*args, expect=None)
    lines = [l for l in p.stderr.splitlines() if l.strip()]
    T.check(p.returncode not in (0,) and p.returncode > 0, f"{what}: non-zero exit without a crash (got {p.returncode})")
    T.check(len(lines) == 1 and lines[0].startswith("evray: error: "), f"{what}: one error line (got {lines!r})")
    if out_dir:
        T.check(not os.path.exists(out_dir), f"{what}: no run folder left behind")


# help and version for every command
for args in (["--help"], ["render", "--help"], ["info", "--help"], ["demo", "--help"]):
    p = T.run(*args)
    T.check("usage: evray" in p.stdout, f"{' '.join(args)} prints usage")
T.check(T.run("--version").stdout.startswith("evray "), "--version")

# demo export is a valid glTF that the importer reads back
glb = os.path.join(tmp, "eye.glb")
T.run("demo", "--export", glb)
with open(glb, "rb") as f:
    head = f.read(12)
T.check(head[:4] == b"glTF" and struct.unpack("<I", head[4:8])[0] == 2, "exported file is GLB version 2")
info = T.run("info", glb).stdout
T.check("eye_camera" in info and "ir_led" in info, "info lists the demo's camera and light")

# a static scene gives no events, and says so
static = os.path.join(tmp, "static.gltf")
T.quad_gltf(static)
out = static_out = os.path.join(tmp, "static-run")
p = T.run("render", static, "-o", out, "--res", "32x32", "--duration", "0.2", "--format", "npy")
T.check(T.load_run_json(out)["stats"]["events"] == 0, "static scene: zero events")
T.check("no events" in p.stdout, "static scene: says so")
# the same quad moving gives events
moving = os.path.join(tmp, "moving.gltf")
T.quad_gltf(moving, animated=True)
out = os.path.join(tmp, "moving-run")
T.run("render", moving, "-o", out, "--res", "32x32", "--format", "npy", "--quiet")
T.check(T.load_run_json(out)["stats"]["events"] > 0, "moving quad: events")

# compare: a run against itself, and against the same run in another format
out2 = os.path.join(tmp, "moving-run2")
T.run("render", moving, "-o", out2, "--res", "32x32", "--format", "txt,h5", "--quiet")
r = json.loads(T.run("compare", os.path.join(out, "events.npy"), os.path.join(out2, "events.txt"), "--json").stdout)
T.check(r["f1"] == 1.0 and r["count_ratio"] == 1.0, f"compare: identical runs match fully ({r})")
r = json.loads(T.run("compare", os.path.join(out, "events.npy"), os.path.join(static_out, "events.npy"), "--json").stdout)
T.check(r["recall"] == 0.0, "compare: nothing matches an empty stream")
expect_error(["compare", os.path.join(out, "events.npy")], "compare with one file")
r = json.loads(T.run("compare", os.path.join(out, "events.npy"), os.path.join(out2, "events.txt"), "--tol-level", "0.1",
                     "--json").stdout)
T.check(r["f1"] == 1.0 and r["tol_level"] == 0.1, f"compare --tol-level: identical runs match fully ({r})")
expect_error(["compare", os.path.join(out, "events.npy"), os.path.join(out2, "events.txt"), "--tol-level", "0.6"],
             "compare --tol-level above 0.5")

# bench: one row of figures
b = json.loads(T.run("bench", "--scene", "square", "--res", "32x32", "--duration", "0.5", "--json").stdout.splitlines()[0])
T.check(b["events"] > 0 and b["samples_per_second"] > 0 and b["rays"] >= b["samples_traced"] > 0, f"bench row {b}")
T.check(b["skip"] and b["samples_traced"] < b["samples_per_second"] * b["wall_seconds"] and b["pixels_skipped"] > 0,
        f"bench: the square's still background is skipped ({b})")
T.check(abs(b["equivalent_samples_per_second"] - b["samples_per_second"]) <= 1e-6 * b["samples_per_second"],
        "bench: samples/s is the equivalent (brute-force) rate")
vs = T.run("bench", "--scene", "square", "--res", "32x32", "--duration", "0.5", "--vs-brute", "--json").stdout.splitlines()
rows = [json.loads(l) for l in vs]
T.check(len(rows) == 3 and rows[0]["skip"] and not rows[1]["skip"] and rows[2]["identical"]
        and rows[2]["events"] == rows[0]["events"], f"bench --vs-brute: two rows and an identity check ({vs})")
expect_error(["bench", "--vs-brute", "--no-skip"], "bench --vs-brute with --no-skip")
expect_error(["bench", "--vs-brute", "--suite", "seed"], "bench --vs-brute with --suite")
T.check(abs(b["temporal_resolution_us"] - 1e6 / 300) < 0.1, "bench: 30 fps x 10 samples = 3333 us between a pixel's samples")

# bad input
noout = os.path.join(tmp, "never")
expect_error(["render", os.path.join(tmp, "missing.glb"), "-o", noout], "missing file", noout)
garbage = os.path.join(tmp, "garbage.glb")
with open(garbage, "wb") as f:
    f.write(os.urandom(3000))
expect_error(["render", garbage, "-o", noout], "garbage file", noout)
trunc = os.path.join(tmp, "trunc.glb")
with open(glb, "rb") as f:
    data = f.read()
with open(trunc, "wb") as f:
    f.write(data[: len(data) // 3])
expect_error(["render", trunc, "-o", noout], "truncated glb", noout)
empty = os.path.join(tmp, "empty.gltf")
T.quad_gltf(empty, with_triangles=False)
expect_error(["render", empty, "-o", noout], "no triangles", noout)
expect_error(["render", glb, "-o", noout, "--camera", "nope"], "unknown camera", noout)
expect_error(["render", glb, "-o", noout, "--pos-thres", "-0.2"], "negative threshold", noout)
expect_error(["render", glb, "-o", noout, "--res", "0x480"], "zero resolution", noout)
expect_error(["render", glb, "-o", noout, "--res", "banana"], "resolution not WxH", noout)
expect_error(["render", glb, "-o", noout, "--duration", "1000"], "duration beyond the animation", noout)
expect_error(["render", glb, "-o", noout, "--samples-per-frame", "0"], "zero samples", noout)
expect_error(["render", glb, "-o", noout, "--fps", "abc"], "fps not a number", noout)
expect_error(["render", glb, "-o", noout, "--format", "avi"], "unknown format", noout)
expect_error(["render", glb, "--bogus"], "unknown option")
expect_error(["info", os.path.join(tmp, "missing.gltf")], "info on a missing file")
expect_error(["demo", "--scene", "nope", "--export", os.path.join(tmp, "x.glb")], "unknown demo")
# evray convert picks the format by the registry's file name endings (the longest that fits):
# npy -> each -> npy gives the same bytes, and the .raw files say which EVT version they hold
run = os.path.join(tmp, "conv-run")
T.run("demo", "--scene", "square", "--res", "32x32", "--duration", "0.2", "-o", run, "--format", "npy",
      "--no-preview", "--quiet")
npy = os.path.join(run, "events.npy")
for name, header in (("c.h5", None), ("c.hdf5", None), ("c.txt", None), ("c.dat", b"% Height"),
                     ("c_evt2.raw", b"% evt 2.0"), ("c.raw", b"% evt 3.0")):
    mid, back = os.path.join(tmp, name), os.path.join(tmp, name + ".npy")
    T.run("convert", npy, mid, "--quiet")
    T.run("convert", mid, back, "--quiet")
    T.check(open(back, "rb").read() == open(npy, "rb").read(), f"convert npy -> {name} -> npy: identical")
    if header:
        T.check(header in open(mid, "rb").read(200), f"convert to {name}: its header says {header!r}")
expect_error(["convert", npy, os.path.join(tmp, "x.bin")], "convert to an unknown file type")
T.finish("test_cli")
