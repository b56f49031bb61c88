"""Ground truth (README "Ground truth"): labels.h5's optical flow on the square scene equals its
analytic image velocity, depth on a tilted plane equals the analytic depth, the IMU of a camera
turning at a known rate reads that rate, the eye's pupil-centre label is the pupil centre
projected independently here, and labels.h5 reads in h5py (the oracle environment; the test
skips without it)."""
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evrtest as T  # noqa: E402
import gltf_build  # noqa: E402

python = T.oracle_python(["numpy", "h5py"])

# Reads labels.h5 in the oracle environment: every dataset as lists, the attributes and the
# instances table.
READ = r"""
import h5py, json, sys, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    out = {k: np.nan_to_num(f[k][()], nan=-1e30).tolist() for k in
           ("t", "depth", "instance", "flow", "displacement") + (("normal",) if "normal" in f else ())}
    out["attrs"] = {k: (v.decode() if isinstance(v, bytes) else v.item() if hasattr(v, "item") else v)
                    for k, v in f.attrs.items()}
    out["instances"] = [[int(r["id"]), r["node"].decode(), r["mesh"].decode()] for r in f["instances"][()]]
    out["chunks"] = f["depth"].chunks
    out["compression"] = f["depth"].compression
print(json.dumps(out))
"""


def read_labels(path):
    p = subprocess.run([python, "-c", READ, path], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit("reading labels.h5: " + p.stderr)
    return json.loads(p.stdout)


def flow_on_square():
    d = T.tmpdir()
    W = 64
    T.run("demo", "--scene", "square", "--res", f"{W}x{W}", "--duration", "1.5", "--labels-fps",
          "4", "--flow-dt", "0.01", "--label-normals", "-o", d, "-q", "--force")
    L = read_labels(os.path.join(d, "labels.h5"))
    T.check(L["attrs"]["complete"] == 1 and L["attrs"]["width"] == W, "labels.h5 attributes")
    T.check(L["compression"] == "gzip" and L["chunks"] == [1, W, W], "chunked and compressed")
    names = {i: node for i, node, _ in L["instances"]}
    sq = [i for i, n in names.items() if n.endswith("/square")]
    bg = [i for i, n in names.items() if n.endswith("/background")]
    T.check(len(sq) == 1 and len(bg) == 1, f"instances table names the square: {names}")
    T.check(L["t"] == [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5], f"frame times {L['t']}")
    # 1 m/s along +X at 3.99 m: W/2 * 4/3.99 px/s (the view spans x in [-1, 1] at 4 m)
    v = W / 2 * 4 / 3.99
    worst, n_sq, n_bg = 0.0, 0, 0
    for k in range(len(L["t"])):
        for y in range(W):
            for x in range(W):
                i = L["instance"][k][y][x]
                fx, fy = L["flow"][k][y][x]
                dx, dy = L["displacement"][k][y][x]
                z = L["depth"][k][y][x]
                if i == sq[0]:
                    n_sq += 1
                    worst = max(worst, abs(fx - v) / v, abs(fy) / v, abs(dx - 0.01 * v) / (0.01 * v),
                                abs(z - 3.99) / 3.99)
                    nx, ny, nz = L["normal"][k][y][x]
                    worst = max(worst, abs(nz + 1.0))  # facing the camera: optical -z
                elif i == bg[0]:
                    n_bg += 1
                    worst = max(worst, abs(fx) / v, abs(fy) / v, abs(z - 4.0) / 4.0)
                else:
                    T.check(i == 0 and z == -1e30 and fx == -1e30, "background: id 0 and NaN")
    T.check(n_sq > 100 and n_bg > 1000, f"pixels on the square {n_sq}, background {n_bg}")
    T.check(worst < 0.005, f"flow and depth within 0.5% of the analytic ones (worst {worst:.2e})")
    print(f"square: {n_sq} pixels on the square, worst relative error {worst:.2e}")


def flow_orthographic():
    """Through an orthographic camera (xmag = ymag = 2: the view spans 4 m): a square sliding at
    1 m/s along +X flows at W / 4 px/s whatever its depth; depth is the distance to the
    camera's plane."""
    d = T.tmpdir()
    path = os.path.join(d, "ortho.gltf")
    g = gltf_build.Gltf()
    g.cameras.append({"type": "orthographic",
                      "orthographic": {"xmag": 2.0, "ymag": 2.0, "znear": 0.01, "zfar": 100.0}})
    g.node("cam", camera=len(g.cameras) - 1, translation=[0, 0, 3])
    g.light("lamp", "directional", 2.0)
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.4, 0.4, 0.4, 1]}})
    white = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1]}})
    g.mesh_node("background", *gltf_build.rect(-4, 4, -4, 4, 0), grey)
    sq = g.mesh_node("square", *gltf_build.rect(-0.5, 0.5, -0.5, 0.5, 0), white,
                     translation=[-1, 0, 1])
    g.animation([(sq, "translation", [0.0, 2.0], [[-1, 0, 1], [1, 0, 1]])])
    g.write(path)
    W = 32
    out = os.path.join(d, "run")
    T.run("render", path, "--res", f"{W}x{W}", "--duration", "1", "--labels-fps", "4", "-o", out,
          "-q")
    L = read_labels(os.path.join(out, "labels.h5"))
    names = {i: node for i, node, _ in L["instances"]}
    sq_id = [i for i, n in names.items() if n.endswith("square")][0]
    v = W / 4.0
    worst, n_sq = 0.0, 0
    for k in range(len(L["t"])):
        for y in range(W):
            for x in range(W):
                fx, fy = L["flow"][k][y][x]
                z = L["depth"][k][y][x]
                if L["instance"][k][y][x] == sq_id:
                    n_sq += 1
                    worst = max(worst, abs(fx - v) / v, abs(fy) / v, abs(z - 2.0) / 2.0)
                else:
                    worst = max(worst, abs(fx) / v, abs(fy) / v, abs(z - 3.0) / 3.0)
    T.check(n_sq > 100, f"orthographic: pixels on the square {n_sq}")
    T.check(worst < 0.005, f"orthographic flow and depth within 0.5% (worst {worst:.2e})")
    print(f"orthographic: {n_sq} pixels on the square, worst relative error {worst:.2e}")


def depth_on_tilted_plane():
    d = T.tmpdir()
    path = os.path.join(d, "tilted.gltf")
    g = gltf_build.Gltf()
    g.camera("cam", yfov=0.8, translation=[0, 0, 3])
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}})
    pos, nrm, uv, idx = gltf_build.rect(-4, 4, -4, 4, 0)
    g.mesh_node("plane", pos, nrm, uv, idx, grey, rotation=gltf_build.quaternion((0, 1, 0), 30))
    g.write(path)
    W, H = 48, 32
    out = os.path.join(d, "run")
    T.run("render", path, "--res", f"{W}x{H}", "--duration", "0.1", "--labels-fps", "10", "-o",
          out, "-q")
    L = read_labels(os.path.join(out, "labels.h5"))
    n = (math.sin(math.radians(30)), 0.0, math.cos(math.radians(30)))
    th = math.tan(0.4)
    worst, count = 0.0, 0
    for y in range(H):
        for x in range(W):
            sx = (2 * (x + 0.5) / W - 1) * th * W / H
            sy = (1 - 2 * (y + 0.5) / H) * th
            s = -(n[2] * 3.0) / (n[0] * sx + n[1] * sy - n[2])  # camera (0, 0, 3), ray (sx, sy, -1)
            z = L["depth"][0][y][x]
            if L["instance"][0][y][x] == 0:
                continue
            count += 1
            worst = max(worst, abs(z - s) / s)
            fx, fy = L["flow"][0][y][x]
            worst = max(worst, abs(fx), abs(fy))  # nothing moves
    T.check(count == W * H, f"the plane fills the view ({count} of {W * H})")
    T.check(worst < 1e-4, f"depth on the tilted plane (worst relative error {worst:.2e})")
    print(f"tilted plane: worst depth error {worst:.2e}")


def imu_of_turning_camera():
    d = T.tmpdir()
    path = os.path.join(d, "turn.gltf")
    g = gltf_build.Gltf()
    cam = g.camera("cam", yfov=0.8, translation=[0, 0, 3])
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}})
    pos, nrm, uv, idx = gltf_build.rect(-4, 4, -4, 4, 0)
    g.mesh_node("plane", pos, nrm, uv, idx, grey)
    # about the camera's own up axis (+Y), 60 degrees in 1 s: slerp, a constant rate
    g.animation([(cam, "rotation", [0.0, 1.0],
                  [gltf_build.quaternion((0, 1, 0), 0), gltf_build.quaternion((0, 1, 0), 60)])])
    g.write(path)
    out = os.path.join(d, "run")
    T.run("render", path, "--res", "32x32", "--duration", "1", "--trajectories", "-o", out, "-q")
    rate = math.radians(60)
    worst, rows = 0.0, 0
    with open(os.path.join(out, "imu.txt")) as f:
        for line in f:
            if line.startswith("#"):
                continue
            t, gx, gy, gz, ax, ay, az = map(float, line.split())
            if t < 0.01 or t > 0.99:
                continue
            rows += 1
            # optical frame, y down: a turn about glTF's +Y is about optical -Y; at rest on the
            # ground the accelerometer reads g upwards: optical -Y
            worst = max(worst, abs(gx) / rate, abs(gy + rate) / rate, abs(gz) / rate,
                        abs(ax) / 9.80665, abs(ay + 9.80665) / 9.80665, abs(az) / 9.80665)
    T.check(rows == 981, f"1 kHz samples ({rows})")
    T.check(worst < 1e-3, f"IMU angular rate and specific force (worst relative error {worst:.2e})")
    print(f"imu: worst relative error {worst:.2e}")


def pupil_centre():
    d = T.tmpdir()
    W, H = 160, 120
    T.run("demo", "--scene", "eye", "--res", f"{W}x{H}", "--duration", "0.02", "--eye-labels",
          "--trajectories", "--preview", "none", "-o", d, "-q")
    poses, names = {}, {}
    with open(os.path.join(d, "node_poses.txt")) as f:
        for line in f:
            if line.startswith("# node "):
                _, _, i, p = line.split(maxsplit=3)
                names[p.strip().rsplit("/", 1)[-1]] = int(i)
            elif not line.startswith("#"):
                v = line.split()
                poses[(round(float(v[0]) * 1000), int(v[1]))] = list(map(float, v[2:]))
    eyeball = names["eyeball"]
    # the camera: at (0, -10, 40) mm looking at the eye centre, +Y up, yfov 45 degrees
    c = (0.0, -0.010, 0.040)
    fwd = [-a / math.sqrt(sum(b * b for b in c)) for a in c]
    right = [fwd[1] * 0 - fwd[2] * 1, fwd[2] * 0 - fwd[0] * 0, fwd[0] * 1 - fwd[1] * 0]
    rl = math.sqrt(sum(a * a for a in right))
    right = [a / rl for a in right]
    up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
          right[0] * fwd[1] - right[1] * fwd[0]]
    th = math.tan(math.radians(22.5))
    worst, rows = 0.0, 0
    with open(os.path.join(d, "eye.txt")) as f:
        for line in f:
            if line.startswith("#"):
                continue
            v = list(map(float, line.split()))
            t, px, py, phase = v[0], v[7], v[8], int(v[11])
            tx, ty, tz, qx, qy, qz, qw = poses[(round(t * 1000), eyeball)]
            # the pupil disc's centre: 11.55 mm along the eyeball's +Z (demo_eye.c)
            zx = 2 * (qx * qz + qw * qy)
            zy = 2 * (qy * qz - qw * qx)
            zz = 1 - 2 * (qx * qx + qy * qy)
            p = [tx + 0.01155 * zx - c[0], ty + 0.01155 * zy - c[1], tz + 0.01155 * zz - c[2]]
            depth = sum(a * b for a, b in zip(p, fwd))
            sx = sum(a * b for a, b in zip(p, right)) / depth
            sy = sum(a * b for a, b in zip(p, up)) / depth
            ex = (sx / (th * W / H) + 1) * 0.5 * W
            ey = (1 - sy / th) * 0.5 * H
            worst = max(worst, abs(ex - px), abs(ey - py))
            rows += 1
            T.check(phase in (0, 1, 2), "a phase")
    T.check(rows == 21, f"1 kHz eye samples ({rows})")
    T.check(worst < 0.01, f"pupil centre label vs its projection (worst {worst:.4f} px)")
    print(f"eye: pupil centre within {worst:.4f} px")


flow_on_square()
flow_orthographic()
depth_on_tilted_plane()
imu_of_turning_camera()
pupil_centre()
T.finish("test_labels")
