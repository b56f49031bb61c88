"""Event ids (--event-ids, README "Ground truth"): every event names the instance its pixel's
primary ray hit at the sample after the crossing.

- Two static quads lit by a moving lamp: every pixel sees one object throughout, so every event
  carries its pixel's object (100%).
- A bright emissive square sliding over a dim emissive plane (no lights, no shadows): an ON event
  is the square arriving (its id), an OFF event the square leaving (the plane's id), 100%.
- events.txt's fifth column, events.npy's id field and events.h5's events/id hold the same ids,
  and events.h5's /instances names them (h5py, in the oracle environment; that part skips
  without it).
On the CPU, and on the CUDA backend where this build has one and a GPU is present."""
import json
import os
import struct
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evrtest as T  # noqa: E402
import gltf_build  # noqa: E402

W = 48


def two_quads(path):
    g = gltf_build.Gltf()
    g.camera("cam", translation=[0, 0, 3])
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1]}})
    g.mesh_node("left", *gltf_build.rect(-1.6, -0.1, -1.6, 1.6, 0), grey)
    g.mesh_node("right", *gltf_build.rect(0.1, 1.6, -1.6, 1.6, 0), grey)
    lamp = g.light("lamp", "point", 3.0, translation=[-2, 0, 1])
    g.animation([(lamp, "translation", [0.0, 1.0], [[-2, 0, 1], [2, 0, 1]])])
    g.write(path)


def sliding_square(path):
    g = gltf_build.Gltf()
    g.camera("cam", translation=[0, 0, 3])
    dim = g.material({"emissiveFactor": [0.1, 0.1, 0.1],
                      "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}})
    bright = g.material({"emissiveFactor": [1, 1, 1],
                         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}})
    g.mesh_node("plane", *gltf_build.rect(-3, 3, -3, 3, 0), dim)
    sq = g.mesh_node("square", *gltf_build.rect(-0.3, 0.3, -0.3, 0.3, 0), bright,
                     translation=[-1, 0, 0.5])
    g.animation([(sq, "translation", [0.0, 1.0], [[-1, 0, 0.5], [1, 0, 0.5]])])
    g.write(path)


def many_instances(path, n):
    """n instances of one small triangle (EXT_mesh_gpu_instancing), in a row in front of the
    camera."""
    tri = struct.pack("<9f", 0, 0, 0, 0.001, 0, 0, 0, 0.001, 0)
    offs = b"".join(struct.pack("<3f", (i % 256) * 0.01 - 1.28, (i // 256) * 0.01 - 1.28, 0)
                    for i in range(n))
    data = tri + offs
    doc = {"asset": {"version": "2.0"}, "scene": 0, "extensionsUsed": ["EXT_mesh_gpu_instancing"],
           "scenes": [{"nodes": [0, 1]}],
           "nodes": [{"name": "cam", "camera": 0, "translation": [0, 0, 3]},
                     {"name": "many", "mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {
                         "attributes": {"TRANSLATION": 1}}}}],
           "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [0.001, 0.001, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(tri)},
                           {"buffer": 0, "byteOffset": len(tri), "byteLength": len(offs)}],
           "buffers": [{"byteLength": len(data), "uri": "many.bin"}]}
    with open(os.path.join(os.path.dirname(path), "many.bin"), "wb") as f:
        f.write(data)
    with open(path, "w") as f:
        json.dump(doc, f)


def too_many_instances():
    """An event carries a 16-bit id: a scene of more instances than that asked for ids is one
    line and no run folder."""
    d = T.tmpdir()
    scene = os.path.join(d, "many.gltf")
    many_instances(scene, 65536)
    out = os.path.join(d, "run-many")
    p = T.run("render", scene, "--event-ids", "--duration", "0.1", "--res", "16x16", "-o", out,
              "--no-preview", expect=None)
    lines = p.stderr.strip().splitlines()
    T.check(p.returncode != 0 and lines and "65535" in lines[-1] and "65536" in lines[-1] and
            not os.path.exists(out), f"65536 instances with ids: {p.returncode} {p.stderr!r}")


def read_txt(path):
    rows = []
    with open(path) as f:
        for line in f:
            t, x, y, p, i = line.split()
            rows.append((round(float(t) * 1e6), int(x), int(y), int(p), int(i)))
    return rows


def read_npy_ids(path):
    with open(path, "rb") as f:
        data = f.read()
    hlen = struct.unpack_from("<H", data, 8)[0]
    header = data[10:10 + hlen].decode()
    T.check("('id', '<u2')" in header, f"events.npy has an id field: {header.strip()}")
    body = data[10 + hlen:]
    return [struct.unpack_from("<H", body, k + 13)[0] for k in range(0, len(body), 15)]


READ_H5 = r"""
import h5py, json, sys
with h5py.File(sys.argv[1], "r") as f:
    print(json.dumps({"id": f["events/id"][()].tolist(),
                      "instances": {int(r["id"]): r["node"].decode() for r in f["instances"][()]}}))
"""


def run(scene_path, backend, d):
    T.run("render", scene_path, "--res", f"{W}x{W}", "--duration", "1", "--event-ids",
          "--format", "h5,txt,npy", "--backend", backend, "-o", d, "-q", "--no-preview")
    ev = read_txt(os.path.join(d, "events.txt"))
    T.check(len(ev) > 50, f"{backend}: events ({len(ev)})")
    T.check(read_npy_ids(os.path.join(d, "events.npy")) == [e[4] for e in ev],
            f"{backend}: events.npy's ids are events.txt's")
    return ev


def check_h5(d, ev, backend, names):
    """events.h5's events/id are events.txt's, and its /instances names id i by a node path
    ending in names[i] (skipped without the oracle environment)."""
    if ORACLE is None:
        return
    p = subprocess.run([ORACLE, "-c", READ_H5, os.path.join(d, "events.h5")], capture_output=True,
                       text=True)
    if p.returncode != 0:
        raise SystemExit(p.stderr)
    h = json.loads(p.stdout)
    T.check(h["id"] == [e[4] for e in ev], f"{backend}: events.h5's events/id are events.txt's")
    got = {int(k): v for k, v in h["instances"].items()}
    T.check(all(got.get(i, "").endswith(n) for i, n in names.items()),
            f"{backend}: /instances {got}, expected nodes ending in {names}")


def check_backend(backend):
    tmp = T.tmpdir()
    quads, square = os.path.join(tmp, "quads.gltf"), os.path.join(tmp, "square.gltf")
    two_quads(quads)
    sliding_square(square)

    d = os.path.join(tmp, f"quads-{backend}")
    ev = run(quads, backend, d)
    # instance order is the scene's: left then right (ids 1, 2)
    left, right = 1, 2
    check_h5(d, ev, backend, {left: "left", right: "right"})
    # the quads' gap, x in (-0.1, 0.1) at 3 m: columns W/2 -+ 0.8 (and one either side)
    bad = [e for e in ev if (e[1] < W // 2 - 2 and e[4] != left) or
           (e[1] >= W // 2 + 2 and e[4] != right) or e[4] not in (left, right)]
    T.check(not bad, f"{backend}: {len(bad)} of {len(ev)} events of the static quads with another "
                     f"id, e.g. {bad[:3]}")
    print(f"{backend}: {len(ev)} events of the static quads, each with its pixel's quad")

    d = os.path.join(tmp, f"square-{backend}")
    ev = run(square, backend, d)
    plane, sq = 1, 2
    check_h5(d, ev, backend, {plane: "plane", sq: "square"})
    on = [e for e in ev if e[3] == 1]
    off = [e for e in ev if e[3] == 0]
    T.check(len(on) > 20 and len(off) > 20, f"{backend}: ON {len(on)}, OFF {len(off)}")
    T.check(all(e[4] == sq for e in on),
            f"{backend}: ON events (the square arriving) with another id: "
            f"{sum(e[4] != sq for e in on)} of {len(on)}")
    T.check(all(e[4] == plane for e in off),
            f"{backend}: OFF events (the square leaving) with another id: "
            f"{sum(e[4] != plane for e in off)} of {len(off)}")
    print(f"{backend}: {len(on)} ON events all on the square, {len(off)} OFF all on the plane")
    if backend == "cpu":
        convert_keeps_ids(d, ev)


def convert_keeps_ids(d, ev):
    """evray convert reads the ids back (events/id, the npy field, the fifth column) and writes
    them where the format holds them; a format without a place for them says so."""
    ids = [e[4] for e in ev]
    chain = [("events.h5", "c1.npy"), ("c1.npy", "c2.txt"), ("c2.txt", "c3.h5"), ("c3.h5", "c4.txt")]
    for src, dst in chain:
        p = T.run("convert", os.path.join(d, src), os.path.join(d, dst))
        T.check("note" not in p.stderr, f"convert {src} -> {dst}: no note ({p.stderr.strip()})")
    T.check([e[4] for e in read_txt(os.path.join(d, "c4.txt"))] == ids,
            "ids through h5 -> npy -> txt -> h5 -> txt")
    p = T.run("convert", os.path.join(d, "c3.h5"), os.path.join(d, "c5.raw"))
    T.check("no place for event ids" in p.stderr, f"EVT 3.0 says it leaves the ids out: {p.stderr!r}")
    # an id out of range in a text file: one line naming the line, nothing written
    for bad in ("0.000001 1 2 1 -3\n", "0.000001 1 2 1 65536\n", "0.000001 1 2 1 7 9\n"):
        src, dst = os.path.join(d, "bad.txt"), os.path.join(d, "bad.h5")
        with open(src, "w") as f:
            f.write(bad)
        p = T.run("convert", src, dst, expect=None)
        lines = p.stderr.strip().splitlines()
        T.check(p.returncode == 1 and len(lines) == 1 and "bad.txt:1" in lines[0] and
                not os.path.exists(dst), f"convert of {bad!r}: {p.returncode} {p.stderr!r}")
    # a run asked for ids that writes a format without a place for them says so
    p = T.run("demo", "--scene", "square", "--res", "16x16", "--duration", "0.2", "--event-ids",
              "--format", "h5,evt3", "-o", os.path.join(d, "run-evt3"), "--no-preview")
    T.check("events_evt3.raw has no place for event ids" in p.stderr and "events.h5" not in p.stderr,
            f"the run's note names the EVT 3.0 file only: {p.stderr!r}")


# the h5 part needs the oracle environment (its Python, probed once); the rest runs without it
try:
    ORACLE = T.oracle_python(["h5py"])
except SystemExit:
    ORACLE = None
    print("events.h5 part skipped: no oracle environment with h5py")

check_backend("cpu")
too_many_instances()
probe = T.run("demo", "--scene", "square", "-o", os.path.join(T.tmpdir(), "probe"), "--res",
              "16x16", "--duration", "0.1", "--backend", "cuda", "--quiet", "--no-preview",
              expect=None)
if probe.returncode == 0:
    check_backend("cuda")
else:
    print("CUDA part skipped:", probe.stderr.strip())
T.finish("test_event_ids")
