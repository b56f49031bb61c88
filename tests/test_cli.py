"""The command line: help, version, export, info, a static scene, and bad input (one clear line,
non-zero exit, no crash, nothing half-written left behind)."""
import base64
import json
import os
import struct

import evrtest as T

tmp = T.tmpdir()


def quad_gltf(path, with_triangles=True, animated=False):
    """A lit grey quad facing +Z seen by a camera at z = 3; optionally moving."""
    pos = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    idx = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    times = struct.pack("<2f", 0.0, 1.0)
    trans = struct.pack("<6f", 0, 0, 0, 0.5, 0, 0)
    blob = pos + idx + times + trans
    g = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "cam", "camera": 0, "translation": [0, 0, 3]}, {"name": "quad"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.0, "znear": 0.01}}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 12},
                        {"buffer": 0, "byteOffset": 60, "byteLength": 8},
                        {"buffer": 0, "byteOffset": 68, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
                      {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
                      {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}],
        "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    }
    if with_triangles:
        g["nodes"][1]["mesh"] = 0
    else:
        del g["meshes"]
    if animated:
        g["animations"] = [{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
                            "samplers": [{"input": 2, "output": 3, "interpolation": "LINEAR"}]}]
    with open(path, "w") as f:
        json.dump(g, f)


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
quad_gltf(static)
out = static_out = os.path.join(tmp, "static-run")
p = T.run("render", static, "-o", out, "--res", "32x32", "--duration", "0.2", "--format", "npy")
T.check(T.load_run_json(out)["stats"]["events"] == 0, "static scene: zero events")
T.check("no events" in p.stdout, "static scene: says so")
# the same quad moving gives events
moving = os.path.join(tmp, "moving.gltf")
quad_gltf(moving, animated=True)
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

# bench: one row of figures
b = json.loads(T.run("bench", "--scene", "square", "--res", "32x32", "--duration", "0.5", "--json").stdout.splitlines()[0])
T.check(b["events"] > 0 and b["samples_per_second"] > 0 and b["rays_per_second"] >= b["samples_per_second"], f"bench row {b}")
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
quad_gltf(empty, with_triangles=False)
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
T.finish("test_cli")
