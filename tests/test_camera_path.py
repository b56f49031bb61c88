"""Camera paths, framing and orthographic cameras end to end (docs/camera.md):
- a still scene makes no events, and with --camera-path orbit makes them along the model's edges
  as they sweep, in every row the model spans, on both sides;
- a TUM trajectory of a steady turn makes the same events as the same turn given as the glTF
  camera's animation (F1 >= 0.99 with evray compare), and camera_poses.txt fed back as a
  trajectory makes the same events again;
- a scene without a camera whose animated part leaves its rest-pose bounds stays in the automatic
  frame (events all the way), and a flat model lying on the ground is seen face-on, not edge-on;
- an orthographic glTF camera draws a quad at its true size at any distance;
- bad values (unknown path kind, malformed TUM lines, times that do not increase, a trajectory
  shorter than the run, bad points and angles) are one line on stderr, a non-zero exit and no
  run folder."""
import base64
import json
import math
import os
import struct

import numpy as np

import evrtest as T

tmp = T.tmpdir()
RES = "64x64"


def gltf(path, meshes, camera=None, camera_rot_keys=None, move_keys=None):
    """A glTF file: meshes is a list of (positions, indices, node rotation xyzw or None); camera
    None (none: the automatic camera), ("perspective", yfov, z) or ("orthographic", ymag, z) at
    (0, 0, z) looking along -Z; camera_rot_keys: [(t, quaternion xyzw)] animating the camera's
    rotation; move_keys: [(t, translation)] animating the first mesh's node."""
    blob = b""
    views, accessors = [], []

    def add(data, count, typ, comp=5126, minmax=None):
        nonlocal blob
        while len(blob) % 4:
            blob += b"\0"
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    nodes, gmeshes = [], []
    for i, (pos, idx, rot) in enumerate(meshes):
        p = add(struct.pack(f"<{len(pos)}f", *pos), len(pos) // 3, "VEC3",
                minmax=([min(pos[k::3]) for k in range(3)], [max(pos[k::3]) for k in range(3)]))
        ix = add(struct.pack(f"<{len(idx)}H", *idx), len(idx), "SCALAR", comp=5123)
        gmeshes.append({"name": f"m{i}", "primitives": [{"attributes": {"POSITION": p}, "indices": ix,
                                                         "material": 0}]})
        node = {"name": f"n{i}", "mesh": i}
        if rot:
            node["rotation"] = rot
        nodes.append(node)
    g = {"asset": {"version": "2.0"}, "scene": 0, "nodes": nodes, "meshes": gmeshes,
         "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0},
                        "doubleSided": True}]}
    channels, samplers = [], []
    if camera:
        kind, size, z = camera
        cam = {"type": kind}
        cam[kind] = ({"yfov": size, "aspectRatio": 1.0, "znear": 0.01} if kind == "perspective"
                     else {"xmag": size, "ymag": size, "znear": 0.01, "zfar": 1000})
        g["cameras"] = [cam]
        nodes.append({"name": "cam", "camera": 0, "translation": [0, 0, z]})
        if camera_rot_keys:
            t = add(struct.pack(f"<{len(camera_rot_keys)}f", *[k[0] for k in camera_rot_keys]),
                    len(camera_rot_keys), "SCALAR",
                    minmax=([camera_rot_keys[0][0]], [camera_rot_keys[-1][0]]))
            q = add(struct.pack(f"<{4 * len(camera_rot_keys)}f", *[c for k in camera_rot_keys for c in k[1]]),
                    len(camera_rot_keys), "VEC4")
            samplers.append({"input": t, "output": q, "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": len(nodes) - 1, "path": "rotation"}})
    if move_keys:
        t = add(struct.pack(f"<{len(move_keys)}f", *[k[0] for k in move_keys]), len(move_keys), "SCALAR",
                minmax=([move_keys[0][0]], [move_keys[-1][0]]))
        v = add(struct.pack(f"<{3 * len(move_keys)}f", *[c for k in move_keys for c in k[1]]), len(move_keys), "VEC3")
        samplers.append({"input": t, "output": v, "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": 0, "path": "translation"}})
    if channels:
        g["animations"] = [{"channels": channels, "samplers": samplers}]
    g["scenes"] = [{"nodes": list(range(len(nodes)))}]
    g["buffers"] = [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," +
                     base64.b64encode(blob).decode()}]
    g["bufferViews"], g["accessors"] = views, accessors
    with open(path, "w") as f:
        json.dump(g, f)
    return path


QUAD = ([-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0], [0, 1, 2, 0, 2, 3])
CUBE = ([-0.5, -0.5, -0.5, 0.5, -0.5, -0.5, 0.5, 0.5, -0.5, -0.5, 0.5, -0.5,
         -0.5, -0.5, 0.5, 0.5, -0.5, 0.5, 0.5, 0.5, 0.5, -0.5, 0.5, 0.5],
        [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3,
         1, 2, 6, 1, 6, 5])
# a small cross beside the quad: more edges, in more directions, for the trajectory comparison
CROSS = ([1.3, -0.1, 0.5, 1.9, -0.1, 0.5, 1.9, 0.1, 0.5, 1.3, 0.1, 0.5,
          1.5, -0.4, 0.5, 1.7, -0.4, 0.5, 1.7, 0.4, 0.5, 1.5, 0.4, 0.5], [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7])


def render(scene, name, *extra):
    d = os.path.join(tmp, name)
    T.run("render", scene, "-o", d, "--res", RES, "--format", "npy", "--no-preview", "--quiet", *extra)
    return d, np.load(os.path.join(d, "events.npy"))


def still(scene, name, *extra):
    out = os.path.join(tmp, name + ".pfm")
    T.run("still", scene, "-o", out, "--res", RES, *extra)
    w, h, px = T.read_pfm(out)
    return np.array(px, dtype=np.float64).reshape(h, w, 3)[::-1].mean(axis=2)  # rows top first


def poses(d):
    rows = [list(map(float, line.split())) for line in open(os.path.join(d, "camera_poses.txt"))
            if not line.startswith("#")]
    return np.array(rows)


# ---- a still scene: nothing, then the orbit sweeps its edges ----
quad = gltf(os.path.join(tmp, "quad.gltf"), [(*QUAD, None)], camera=("perspective", 0.8, 3.0))
_, ev = render(quad, "still", "--duration", "0.25")
T.check(len(ev) == 0, f"a still scene makes no events ({len(ev)})")
d, ev = render(quad, "orbit", "--duration", "0.25", "--camera-path", "orbit:period=4")
print(f"orbit: {len(ev)} events")
T.check(len(ev) > 300, f"the orbit makes events ({len(ev)})")
# the quad spans rows and columns 32 +- 32 / (3 tan 0.4) at the start: 6 .. 57
lo, hi = int(32 - 32 / (3 * math.tan(0.4))), int(32 + 32 / (3 * math.tan(0.4)))
rows = range(lo + 3, hi - 3)
left = sum(1 for y in rows if np.any((ev["y"] == y) & (ev["x"] < 32)))
right = sum(1 for y in rows if np.any((ev["y"] == y) & (ev["x"] >= 32)))
T.check(left == len(rows) and right == len(rows),
        f"events along both vertical edges in every row the quad spans ({left}, {right} of {len(rows)})")
inside = np.sum((ev["x"] > lo + 8) & (ev["x"] < hi - 8) & (ev["y"] > lo + 8) & (ev["y"] < hi - 8))
T.check(inside < 0.02 * len(ev), f"few events inside the uniform quad ({inside} of {len(ev)})")
p = poses(d)
T.check(len(p) == 251 and abs(p[0, 0]) < 1e-9 and abs(p[-1, 0] - 0.25) < 1e-9,
        f"camera_poses.txt: 1 kHz over the run, both ends ({len(p)} lines)")
ang = 2 * math.degrees(math.atan2(math.hypot(p[-1, 4], p[-1, 6]), math.hypot(p[-1, 5], p[-1, 7])))
# the optical frame's quaternion at the start is (1, 0, 0, 0) (x y z w): half a turn about x
T.check(abs(np.hypot(p[-1, 1], p[-1, 3]) - 3.0) < 1e-4 and abs(p[-1, 2]) < 1e-6,
        "the orbit keeps the camera 3 m from the centre, at its height")
T.check(abs(math.degrees(math.atan2(p[-1, 1], p[-1, 3])) - 22.5) < 0.01,
        f"a quarter period turns a sixteenth: 22.5 degrees ({math.degrees(math.atan2(p[-1, 1], p[-1, 3])):.3f})")
_, brute = render(quad, "orbit-brute", "--duration", "0.25", "--camera-path", "orbit:period=4", "--no-skip")
T.check(np.array_equal(ev, brute), "skipping stays exact with a moving camera")

# ---- a trajectory of a steady turn = the same turn as the camera's glTF animation ----
rate = math.radians(20.0)  # per second, about +Y
keys = [(0.1 * k, (0.0, math.sin(rate * 0.1 * k / 2), 0.0, math.cos(rate * 0.1 * k / 2))) for k in range(6)]
anim = gltf(os.path.join(tmp, "turn.gltf"), [(*QUAD, None), (*CROSS, None)], camera=("perspective", 0.8, 3.0),
            camera_rot_keys=keys)
tum = os.path.join(tmp, "turn.txt")
with open(tum, "w") as f:
    f.write("# t tx ty tz qx qy qz qw: the glTF turn in the optical frame (q * (1, 0, 0, 0))\n")
    for t, (x, y, z, w) in keys:  # (0, s, 0, c) times half a turn about x: (c, 0, -s, 0)
        f.write(f"{1000.0 + t:.6f} 0 0 3 {w:.17g} 0 {-y:.17g} 0\n")  # epoch-like times
d_anim, ev_anim = render(anim, "turn-anim", "--duration", "0.5")
d_tum, ev_tum = render(anim, "turn-tum", "--duration", "0.5", "--camera-path", "tum:" + tum)
T.check(len(ev_anim) > 500, f"the turn makes events ({len(ev_anim)})")
cmp = T.run("compare", os.path.join(d_anim, "events.npy"), os.path.join(d_tum, "events.npy")).stdout
f1 = float(cmp.split("F1 ")[1].split()[0].rstrip(","))
print(f"trajectory vs animation: F1 {f1}, {len(ev_tum)} vs {len(ev_anim)} events")
T.check(f1 >= 0.99, f"TUM trajectory vs glTF animation: F1 {f1} >= 0.99 ({len(ev_tum)} vs {len(ev_anim)} events)")
T.check(np.abs(poses(d_anim)[:, 1:] - poses(d_tum)[:, 1:]).max() < 1e-5, "the same poses written")
# camera_poses.txt read back: the same camera again
d_back, ev_back = render(anim, "turn-back", "--camera-path", os.path.join(d_anim, "camera_poses.txt"))
cmp = T.run("compare", os.path.join(d_anim, "events.npy"), os.path.join(d_back, "events.npy")).stdout
f1 = float(cmp.split("F1 ")[1].split()[0].rstrip(","))
T.check(f1 >= 0.99 and abs(len(ev_back) - len(ev_anim)) <= 0.01 * len(ev_anim),
        f"camera_poses.txt fed back: F1 {f1}, lasting as long as the trajectory")

# ---- the automatic camera: the whole animation in frame, flat models face-on ----
away = gltf(os.path.join(tmp, "away.gltf"), [(*CUBE, None)], move_keys=[(0.0, (0, 0, 0)), (1.0, (10, 0, 0))])
_, ev = render(away, "away")
bins = np.histogram(ev["t"], bins=5, range=(0, 1e6))[0]
T.check(bool(np.all(bins > 20)), f"the cube moving 10 m away makes events all the way: {list(bins)}")
T.check(np.sum(ev["t"] > 0.9e6) > 20, "... in the last tenth of the run too")
flat = gltf(os.path.join(tmp, "flat.gltf"), [(*QUAD, [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)])])  # faces +Y
img = still(flat, "flat")
T.check(np.mean(img > 0.05) > 0.3, f"a quad lying flat is seen from above ({np.mean(img > 0.05):.2f} of the image lit)")

# ---- orthographic cameras: true size at any distance ----
lit = []
for z in (3.0, 30.0):
    ortho = gltf(os.path.join(tmp, f"ortho{z:g}.gltf"), [(*QUAD, None)], camera=("orthographic", 2.0, z))
    img = still(ortho, f"ortho{z:g}")
    lit.append(img > 0.05)
    T.check(int(np.sum(lit[-1])) == 32 * 32 and bool(np.all(lit[-1][16:48, 16:48])),
            f"orthographic camera at z = {z}: the quad (2 of the view's 4) covers 32x32 pixels ({np.sum(lit[-1])})")
T.check(np.array_equal(lit[0], lit[1]), "... the same at both distances")
T.check("orthographic, 4 high" in T.run("info", ortho).stdout, "evray info names the orthographic camera")

# ---- bad values: one line, non-zero exit, nothing left behind ----
def write(name, text):
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        f.write(text)
    return path


bad_line = write("bad-line.txt", "0 0 0 3 1 0 0 0\n0.1 0 0 3 1 0 0\n")
backwards = write("backwards.txt", "0 0 0 3 1 0 0 0\n0.2 0 0 3 1 0 0 0\n0.1 0 0 3 1 0 0 0\n")
short = write("short.txt", "0 0 0 3 1 0 0 0\n0.5 0 0 3 1 0 0 0\n")
ortho = os.path.join(tmp, "ortho3.gltf")
cases = [
    (quad, ["--camera-path", "spiral"], "unknown kind 'spiral'"),
    (quad, ["--camera-path", "orbit:speed=2"], "unknown parameter 'speed'"),
    (quad, ["--camera-path", "orbit:period=0"], "period must not be 0"),
    (quad, ["--camera-path", "tum:" + os.path.join(tmp, "missing.txt")], "cannot open camera path file"),
    (quad, ["--camera-path", "tum:" + bad_line], "line 2: expected 8 numbers"),
    (quad, ["--camera-path", backwards], "line 3: time 0.1 is not after the line before's (0.2)"),
    (quad, ["--camera-path", "tum:" + short, "--duration", "1"], "covers 0 to 0.5 s"),
    (quad, ["--look-from", "1,2"], "--look-from expects X,Y,Z"),
    (quad, ["--look-at", "0,0,x"], "--look-at expects X,Y,Z"),
    (quad, ["--fov", "200"], "between 0 and 180 degrees"),
    (quad, ["--look-from", "0,0,1", "--look-at", "0,0,1"], "the same point"),
    (ortho, ["--fov", "30"], "is orthographic"),
]
for i, (scene, args, needle) in enumerate(cases):
    d = os.path.join(tmp, f"bad{i}")
    r = T.run("render", scene, "-o", d, "--res", RES, "--quiet", *args, expect=None)
    lines = r.stderr.strip().splitlines()
    T.check(r.returncode != 0 and len(lines) == 1 and needle in lines[0],
            f"{' '.join(args)}: exit {r.returncode}, stderr {r.stderr.strip()!r} (wanted '{needle}')")
    T.check(not os.path.exists(d), f"{' '.join(args)}: no run folder left behind")

# ---- the options are documented ----
helptext = T.run("render", "--help").stdout
readme = open(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "README.md")).read()
for opt in ("--camera-path", "--look-from", "--look-at", "--fov"):
    T.check(opt in helptext and opt in readme, f"{opt} in --help and the README")
T.finish("test_camera_path")
