"""Bad inputs (issues 29 and 31): each one a clear one-line error and a non-zero exit within
seconds, never a crash, a hang or exit 0 in silence. Malformed glTF (a GLB whose lengths lie,
indices past the vertices, a node translation of two numbers or a string, a channel naming no
node, NaN or infinite vertices and keys, zero quaternions, cameras with no field of view,
negative lights), files outside the scene's folder (a buffer at ../../etc/passwd, a texture at
an absolute path, a link out, /dev/zero) unless --allow-external-files, FIFOs as scene and event
files, corrupt event files, and options out of bounds (--start 1e308, --duration 1e9,
--duration 1e6 --fps 1e6, --thres 1e-9, --leak-jitter 1e30, --preview-window 1e300 and 1e-9,
a file or an empty path as --bvh-cache, animations of 1e30 s)."""
import base64
import copy
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import time

import evrtest as T

tmp = T.tmpdir()
SECONDS = 20  # what "within seconds" allows on a loaded 2-core machine under ASan


def run(*args, timeout=60):
    """evray with args: (returncode, stderr lines, seconds); a hang is a failed check."""
    t0 = time.time()
    try:
        p = subprocess.run([T.EVRAY, *map(str, args)], capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, ["(hung: killed after %d s)" % timeout], time.time() - t0
    return p.returncode, [l for l in p.stderr.splitlines() if l.strip()], time.time() - t0


def refused(name, want, *args):
    """evray args fails with one error line containing want, quickly."""
    rc, lines, secs = run(*args)
    T.check(rc not in (None, 0) and rc > 0, f"{name}: a non-zero exit, no crash (got {rc}: {lines})")
    T.check(len(lines) == 1 and lines[0].startswith("evray: error:") and want in lines[0],
            f"{name}: one error line saying '{want}' (got {lines})")
    T.check(secs < SECONDS, f"{name}: refused within {SECONDS} s (took {secs:.1f} s)")
    return lines


# ---- a valid scene to break: a quad with a camera, a light and a moving node ----

QUAD = [(-0.5, -0.5, -1.0), (0.5, -0.5, -1.0), (0.5, 0.5, -1.0), (-0.5, 0.5, -1.0)]


def scene(positions=QUAD, indices=(0, 1, 2, 0, 2, 3), times=(0.0, 1.0),
          moves=((0, 0, 0), (0.1, 0, 0)), rotations=None):
    """The document and its binary data (positions, indices, key times, key values)."""
    parts = [struct.pack("<%df" % (3 * len(positions)), *[x for p in positions for x in p]),
             struct.pack("<%dH" % len(indices), *indices),
             struct.pack("<%df" % len(times), *times),
             struct.pack("<%df" % (3 * len(moves)), *[x for m in moves for x in m])]
    if rotations is not None:
        parts.append(struct.pack("<%df" % (4 * len(rotations)), *[x for q in rotations for x in q]))
    data, views = b"", []
    for p in parts:
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(p)})
        data += p + b"\0" * (-len(p) % 4)
    acc = [{"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3"},
           {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"},
           {"bufferView": 2, "componentType": 5126, "count": len(times), "type": "SCALAR"},
           {"bufferView": 3, "componentType": 5126, "count": len(moves), "type": "VEC3"}]
    channels = [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]
    samplers = [{"input": 2, "output": 3}]
    if rotations is not None:
        acc.append({"bufferView": 4, "componentType": 5126, "count": len(rotations), "type": "VEC4"})
        channels.append({"sampler": 1, "target": {"node": 0, "path": "rotation"}})
        samplers.append({"input": 2, "output": 4})
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
           "nodes": [{"name": "quad", "mesh": 0},
                     {"name": "camera", "camera": 0, "translation": [0, 0, 1]},
                     {"name": "lamp", "translation": [0, 0, 1],
                      "extensions": {"KHR_lights_punctual": {"light": 0}}}],
           "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "cameras": [{"type": "perspective",
                        "perspective": {"yfov": 0.9, "aspectRatio": 1.0, "znear": 0.01}}],
           "extensionsUsed": ["KHR_lights_punctual"],
           "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5.0}]}},
           "animations": [{"channels": channels, "samplers": samplers}],
           "buffers": [{"byteLength": len(data)}], "bufferViews": views, "accessors": acc}
    return doc, data


def write_gltf(name, doc, data, folder=None):
    doc = copy.deepcopy(doc)
    if "uri" not in doc["buffers"][0]:
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + \
            base64.b64encode(data).decode()
    folder = folder or tmp
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name + ".gltf")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def glb_bytes(doc, data):
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    data += b"\0" * (-len(data) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(data), b"BIN\0") + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def write_glb(name, raw):
    path = os.path.join(tmp, name + ".glb")
    with open(path, "wb") as f:
        f.write(raw)
    return path


DOC, DATA = scene()
good = write_gltf("good", DOC, DATA)
rc, lines, _ = run("info", good)
T.check(rc == 0, f"the unbroken scene loads ({lines})")
good_glb = write_glb("good", glb_bytes(DOC, DATA))
rc, lines, _ = run("info", good_glb)
T.check(rc == 0, f"the unbroken GLB loads ({lines})")


def mutated(name, change, want, data=DATA):
    doc = copy.deepcopy(DOC)
    change(doc)
    refused(name, want, "info", write_gltf(name, doc, data))


# ---- GLB containers that lie about their lengths ----
raw = bytearray(glb_bytes(DOC, DATA))
huge_total = raw[:8] + struct.pack("<I", 0xFFFFFFF0) + raw[12:]
refused("GLB total length 4 GB", "GLB header gives a length", "info", write_glb("huge_total", bytes(huge_total)))
jlen = struct.unpack("<I", raw[12:16])[0]
at = 20 + jlen
huge_bin = raw[:at] + struct.pack("<I", 0xFFFFFF00) + raw[at + 4:]
refused("GLB BIN chunk of 4 GB (issue 31: 4.2 GB allocated)", "reaches past the end", "info",
        write_glb("huge_bin", bytes(huge_bin)))
huge_json = raw[:12] + struct.pack("<I", 0x7FFFFFFF) + raw[16:]
refused("GLB JSON chunk of 2 GB", "JSON chunk", "info", write_glb("huge_json", bytes(huge_json)))
refused("GLB version 1", "GLB version 1", "info",
        write_glb("v1", bytes(raw[:4] + struct.pack("<I", 1) + raw[8:])))
refused("GLB cut short", "GLB header gives a length", "info", write_glb("short", bytes(raw[:len(raw) // 2])))

# ---- indices, references, types ----
refused("indices past the vertex count (60000 of 4)", "past its 4 vertices", "info",
        write_gltf("far_index", *scene(indices=(0, 1, 60000, 0, 2, 3))))


def line_loop(d):
    d["meshes"][0]["primitives"][0]["mode"] = 2


refused("LINE_LOOP with indices out of range", "past its 4 vertices", "info",
        write_gltf("loop", *[(lambda d: (line_loop(d), d)[1])(scene(indices=(0, 1, 9, 3, 7, 2))[0]),
                             scene(indices=(0, 1, 9, 3, 7, 2))[1]]))
mutated("translation as a string", lambda d: d["nodes"][0].update(translation="1 2 3"),
        "'translation' must be an array of 3 numbers")
mutated("translation of two numbers", lambda d: d["nodes"][0].update(translation=[1, 2]),
        "'translation' must be an array of 3 numbers")
mutated("a channel naming no node", lambda d: d["animations"][0]["channels"][0]["target"].update(node=7),
        "names node 7, which the file does not have")
mutated("a channel without a node",
        lambda d: d["animations"][0]["channels"][0]["target"].pop("node"), "has no 'node'")
mutated("a node that is its own child", lambda d: d["nodes"][0].update(children=[0]), "its own child")
mutated("nodes in a loop", lambda d: (d["nodes"][1].update(children=[2]), d["nodes"][2].update(children=[1])),
        "loop")
mutated("an accessor past its view", lambda d: d["accessors"][0].update(count=400), "reaches past the end")
mutated("a view past its buffer", lambda d: d["bufferViews"][0].update(byteLength=100000),
        "reaches past the end of buffer 0")
mutated("a mesh index out of range", lambda d: d["nodes"][0].update(mesh=5), "names mesh 5")
mutated("keys and values of different counts", lambda d: d["accessors"][3].update(count=1),
        "2 keys but 1 values")
mutated("glTF 1.0", lambda d: d["asset"].update(version="1.0"), "evray reads glTF 2.0")

# ---- numbers: NaN and infinite vertices and keys, zero quaternions, cameras, lights ----
nan, inf = float("nan"), float("inf")
refused("a NaN vertex", "not finite", "info",
        write_gltf("nan_vertex", *scene(positions=[(nan, 0, -1)] + QUAD[1:])))
refused("an infinite vertex", "not finite", "info",
        write_gltf("inf_vertex", *scene(positions=[(inf, 0, -1)] + QUAD[1:])))
refused("a key time of Inf", "key time 1 is inf", "info",
        write_gltf("inf_key", *scene(times=(0.0, inf))))
refused("a NaN key time", "key time 1 is nan", "info", write_gltf("nan_key", *scene(times=(0.0, nan))))
refused("a negative key time", "key time 0 is -1", "info", write_gltf("neg_key", *scene(times=(-1.0, 1.0))))
refused("a NaN key value", "not finite", "info",
        write_gltf("nan_value", *scene(moves=((0, 0, 0), (nan, 0, 0)))))
refused("a zero rotation key", "zero quaternion", "info",
        write_gltf("zero_quat_key", *scene(rotations=((0, 0, 0, 1), (0, 0, 0, 0)))))
refused("a NaN rotation key", "not finite", "info",
        write_gltf("nan_quat_key", *scene(rotations=((0, 0, 0, 1), (nan, 0, 0, 1)))))
mutated("a zero node rotation", lambda d: d["nodes"][0].update(rotation=[0, 0, 0, 0]), "zero quaternion")
mutated("yfov 0", lambda d: d["cameras"][0]["perspective"].update(yfov=0), "yfov 0 must be between 0 and pi")
mutated("yfov 4 (more than pi)", lambda d: d["cameras"][0]["perspective"].update(yfov=4), "yfov 4")
mutated("znear 0", lambda d: d["cameras"][0]["perspective"].update(znear=0), "znear 0 must be > 0")
mutated("a negative light intensity",
        lambda d: d["extensions"]["KHR_lights_punctual"]["lights"][0].update(intensity=-3),
        "intensity -3 is negative")

# ---- the same numbers from the other formats (through Assimp), checked after the import (a
# camera's 0 field of view or near plane there means "not given": evray's defaults) ----
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "import", "camera.dae")) as f:
    dae = f.read()
for name, text, want in (
        ("an OBJ NaN vertex", "v nan 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n", "vertex 0 is not finite"),
        ("an OBJ infinite vertex", "v 1e39 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 3\n", "vertex 0 is not finite"),
        ("a Collada camera at NaN", dae.replace("<translate>0 0 5</translate>", "<translate>nan 0 5</translate>"),
         "not finite")):
    ext = ".obj" if name.startswith("an OBJ") else ".dae"
    path = os.path.join(tmp, name.replace(" ", "_") + ext)
    with open(path, "w") as f:
        f.write(text)
    refused(name, want, "info", path)

# ---- files that crash or hang Assimp's other importers (found by tests/fuzz/fuzz_scene_assimp.c;
# the first byte of a corpus file is the target's choice of format): read in a child process
# first, a crash or a hang there is one line here ----
regress = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fuzz", "regress", "scene_assimp")
for name, want in (("ply-assert-abort", "Assimp crashed reading it"),
                   ("ply-hang", "took longer than 3 s")):
    with open(os.path.join(regress, name), "rb") as f:
        body = f.read()[1:]
    path = os.path.join(tmp, name + ".ply")
    with open(path, "wb") as f:
        f.write(body)
    os.environ["EVR_IMPORT_SECONDS"] = "3"
    refused(name, want, "info", path)
    os.environ.pop("EVR_IMPORT_SECONDS")

# ---- animations too long to run: refused before the run, info still describes them ----
far = write_gltf("far_keys", *scene(times=(0.0, 1e30)))
rc, lines, _ = run("info", far)
T.check(rc == 0, f"keys up to 1e30 s: info describes the scene ({lines})")
refused("keys up to 1e30 s, rendered", "cannot be simulated", "render", far, "-o", os.path.join(tmp, "o1"))
long_anim = write_gltf("long_anim", *scene(times=(0.0, 1e6)))
refused("a 1e6 s animation at the default duration", "more than", "render", long_anim,
        "-o", os.path.join(tmp, "o2"))

# ---- options out of bounds, on a static scene ----
static_doc, static_data = scene()
del static_doc["animations"]
static = write_gltf("static", static_doc, static_data)
out = os.path.join(tmp, "o3")
for args, want in ((("--start", "1e308"), "start time must be between 0 and 1e6"),
                   (("--duration", "1e9"), "at most 1e6"),
                   (("--duration", "1e308"), "at most 1e6"),
                   (("--duration", "1e6", "--fps", "1e6"), "segments, more than"),
                   (("--duration", "1e5"), "more than --max-samples"),
                   (("--thres", "1e-9"), "threshold must be between 0.001 and 100"),
                   (("--leak-jitter", "1e30"), "leak jitter must be between 0 and 10"),
                   (("--preview-window", "1e300"), "preview window must be between 0"),
                   (("--preview-window", "1e-9"), "at least 0.001 seconds"),
                   (("--leak-rate-hz", "1000", "--duration", "100"), "more than --max-noise-events"),
                   (("--bvh-cache", static), "is not a folder"),
                   (("--bvh-cache", ""), "empty path")):
    refused("render " + " ".join(args), want, "render", static, "-o", out, *args)
T.check(not os.path.exists(out), "a refused run leaves no run folder")
for args, want in ((("--time", "1e308"), "--time must be between 0 and 1e6"),
                   (("--time", "-1"), "--time must be between 0 and 1e6"),
                   (("--gi", "path", "--spp", "1000000", "--res", "16384x16384"), "more than 1e12 paths"),
                   (("--gi", "path", "--spp", "1000000000"), "--spp must be between 1 and 1000000")):
    refused("still " + " ".join(args), want, "still", static, "-o", os.path.join(tmp, "s.png"), *args)
# the limits can be raised: the same run starts (a short one, to see it accepted)
rc, lines, _ = run("render", static, "-o", os.path.join(tmp, "o4"), "--res", "8x6", "--duration", "0.1",
                   "--max-samples", "0", "--no-preview", "--format", "npy", "--quiet")
T.check(rc == 0, f"--max-samples 0 (no limit) is accepted ({lines})")

# ---- files outside the scene's folder ----
scene_dir = os.path.join(tmp, "scene_dir")
os.makedirs(scene_dir)
outside = os.path.join(tmp, "outside")
os.makedirs(outside)
with open(os.path.join(outside, "quad.bin"), "wb") as f:
    f.write(DATA)
with open(os.path.join(scene_dir, "quad.bin"), "wb") as f:
    f.write(DATA)


def with_buffer(name, uri):
    doc = copy.deepcopy(DOC)
    doc["buffers"][0]["uri"] = uri
    return write_gltf(name, doc, DATA, scene_dir)


rc, lines, _ = run("info", with_buffer("inside", "quad.bin"))
T.check(rc == 0, f"a buffer beside the scene loads ({lines})")
refused("a buffer at ../../etc/passwd", "outside the scene's folder", "info",
        with_buffer("passwd", "../../../../../../../../etc/passwd"))
refused("a buffer by an absolute path", "outside the scene's folder", "info",
        with_buffer("absolute", os.path.join(outside, "quad.bin")))
refused("a buffer through ..", "outside the scene's folder", "info", with_buffer("dotdot", "../outside/quad.bin"))
os.symlink(os.path.join(outside, "quad.bin"), os.path.join(scene_dir, "link.bin"))
refused("a buffer through a link out of the folder", "outside the scene's folder", "info",
        with_buffer("link", "link.bin"))
refused("a buffer at /dev/zero", "character device", "info", with_buffer("zero", "/dev/zero"))
refused("a buffer at /dev/zero, external files allowed", "character device", "info",
        with_buffer("zero2", "/dev/zero"), "--allow-external-files")
rc, lines, _ = run("info", with_buffer("absolute2", os.path.join(outside, "quad.bin")), "--allow-external-files")
T.check(rc == 0, f"--allow-external-files reads a buffer outside the folder ({lines})")

# a texture outside: a warning (the material keeps its factors), nothing read
png = os.path.join(outside, "wood.png")
import gltf_build  # noqa: E402
with open(png, "wb") as f:
    f.write(gltf_build.png_bytes(2, 2, [(200, 100, 50, 255)] * 4))


def with_texture(name, uri):
    doc = copy.deepcopy(DOC)
    doc["images"] = [{"uri": uri}]
    doc["textures"] = [{"source": 0}]
    doc["materials"] = [{"name": "wood", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    return write_gltf(name, doc, DATA, scene_dir)


for name, uri, want in (("tex_abs", png, "outside the scene's folder"),
                        ("tex_dotdot", "../outside/wood.png", "outside the scene's folder"),
                        ("tex_zero", "/dev/zero", "character device")):
    rc, out_lines, _ = run("info", with_texture(name, uri))
    p = subprocess.run([T.EVRAY, "info", with_texture(name, uri)], capture_output=True, text=True, timeout=60)
    T.check(p.returncode == 0 and want in p.stdout and "keeps its factors" in p.stdout and "textures: 0" in p.stdout,
            f"{name}: a warning saying '{want}', the texture not read")
    refused(name + " --strict", want, "info", with_texture(name, uri), "--strict")
p = subprocess.run([T.EVRAY, "info", with_texture("tex_allowed", png), "--allow-external-files"],
                   capture_output=True, text=True, timeout=60)
T.check(p.returncode == 0 and "textures: 1" in p.stdout, "--allow-external-files reads the texture")

# ---- FIFOs and devices ----
fifo = os.path.join(tmp, "scene.glb")
os.mkfifo(fifo)
refused("a FIFO as the scene file", "FIFO", "info", fifo)
refused("a FIFO as the scene file, render", "FIFO", "render", fifo, "-o", os.path.join(tmp, "o5"))
refused("a device as the scene file", "character device", "info", "/dev/zero")
for ext in ("h5", "txt", "npy", "raw", "dat", "bag"):
    f = os.path.join(tmp, "events_fifo." + ext)
    os.mkfifo(f)
    refused(f"a FIFO as an {ext} event file", "FIFO", "plot", f, "-o", os.path.join(tmp, "p.png"))

# ---- corrupt event files: one line, non-zero, no HDF5 error stack ----
run_dir = os.path.join(tmp, "events")
T.run("render", good, "-o", run_dir, "--res", "16x12", "--duration", "0.5", "--format", "h5,npy,evt3,rosbag",
      "--no-preview", "--quiet")
h5 = os.path.join(run_dir, "events.h5")
with open(h5, "rb") as f:
    blob = bytearray(f.read())
cuts = {"truncated": blob[:len(blob) // 3], "no_superblock": b"\0" * 8 + blob[8:],
        "garbage": bytes((b * 7 + 13) & 0xFF for b in blob[:4096])}
flipped = bytearray(blob)
for k in range(64, len(flipped), 97):
    flipped[k] ^= 0x5A
cuts["bit_flips"] = flipped
for name, b in cuts.items():
    p = os.path.join(tmp, "corrupt_%s.h5" % name)
    with open(p, "wb") as f:
        f.write(b)
    for cmd in (("plot", p, "-o", os.path.join(tmp, "p.png")), ("compare", h5, p)):
        rc, lines, secs = run(*cmd)
        T.check(rc not in (None, 0), f"corrupt h5 ({name}), {cmd[0]}: a non-zero exit (got {rc})")
        T.check(len(lines) == 1 and lines[0].startswith("evray: error:") and "HDF5-DIAG" not in " ".join(lines),
                f"corrupt h5 ({name}), {cmd[0]}: one error line, no HDF5 error stack (got {lines[:3]})")
# HDF5 itself divides by zero on this one (found by tests/fuzz/fuzz_events_h5.c): read in a child
# process first, one line here
rc, lines, _ = run("plot", os.path.join(os.path.dirname(os.path.abspath(__file__)), "fuzz", "regress",
                                        "events_h5", "hdf5-crash-2.h5"), "-o", os.path.join(tmp, "p.png"))
T.check(rc == 1 and len(lines) == 1 and "HDF5 crashed reading it" in lines[0],
        f"an h5 file that crashes HDF5: one error line, exit 1 ({rc}: {lines})")
for ext in ("npy", "raw", "bag"):
    src = [os.path.join(run_dir, n) for n in os.listdir(run_dir) if n.endswith("." + ext)][0]
    with open(src, "rb") as f:
        b = f.read()
    p = os.path.join(tmp, "cut." + ext)
    with open(p, "wb") as f:
        f.write(b[:len(b) * 2 // 3 + 1])
    rc, lines, _ = run("plot", p, "-o", os.path.join(tmp, "p.png"))
    T.check(rc not in (None, 0) and len(lines) == 1 and lines[0].startswith("evray: error:"),
            f"a truncated .{ext}: one error line, non-zero ({rc}: {lines})")

T.finish("test_bad_inputs")
