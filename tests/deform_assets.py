"""glTF test assets for skins and morph targets, with exact numbers that tests check analytically.

Standard library only, written through tests/gltf_build.py. Each asset is a function returning
its document under construction (a gltf_build.Gltf; one buffer, embedded as a base64 data: URI;
.write(PATH) writes it); `python3 tests/deform_assets.py OUTDIR` writes every asset as OUTDIR/NAME.gltf.

Common to all: a camera node at the origin looking along -Z (no rotation; bend_cylinder's at
(1, 0.5, 4)), perspective with yfov = 2 atan(0.5) (so the plane z = -1 spans [-0.5, 0.5] in x and
y), aspect 1, znear 0.01; one emissive material "glow" (black base colour, emission 1); no
lights; one scene listing every root node.

  morph_slide      quad at z = -1, x from -2 to -0.5; one morph target moves its right edge by
                   +1 in x; the node's weight goes 0 -> 1 over t in [0, 1] (LINEAR): the right
                   edge is at x = -0.5 + t.
  skin_slide       the same quad skinned to joints [root, mover]; mover's translation goes
                   (0,0,0) -> (1,0,0) over [0, 1]; the right edge's vertices follow mover; the
                   mesh node's translation (5,5,5) must be ignored: the edge is at x = -0.5 + t.
  skin_slide8      skin_slide with 8 influences (JOINTS_1/WEIGHTS_1, UNSIGNED_SHORT joints): the
                   edge's vertices are half on mover, half on mover2 (which moves as mover).
  bend_cylinder    cylinder along +X (x in [0, 2], radius 0.1, 17 rings x 12 segments, capped)
                   on joints j0 (static) and j1 (child, at (1,0,0), rotating about +Z by 0, 45,
                   90 degrees at t = 0, 0.5, 1); at t = 1 the tip centre (2,0,0) is at (1,1,0).
  bad_joint_index  skin_slide with a JOINTS_0 value equal to the number of joints.
  bad_ibm_count    skin_slide with one inverse bind matrix for two joints.
  bad_morph_count  morph_slide whose target POSITION accessor has 3 elements for 4 vertices.
  bad_weights_zero skin_slide with a vertex whose weights are all 0.

Extra assets (not in the lead's list), each pinning one of Assimp 5.2's quirks (import.c):
  morph_node_weights  morph_slide, no animation, mesh weights [0] but node weights [0.5]: the
                      node's weights win, the edge stays at x = 0.
  morph_cubic         morph_slide with a CUBICSPLINE weights sampler (tangents 2, 3 and 4, 5):
                      the values are 0 and 1 at t = 0 and 1, evray interpolates them linearly and
                      warns.
  morph_step          morph_slide with a STEP sampler: the edge stays at x = -0.5 until t = 1.
  morph_two_prims     a mesh of two primitives (two quads), two targets (the first with NORMAL
                      deltas (0, 0.5, 0)), mesh weights [0.25, 0.5], node weights
                      [0.75, 0.125], weights keyed (0, 0.1), (0.2, 0.3), (1, 0.9) at t = 0, 0.5, 1.
  skin_no_ibm         skin_slide without inverseBindMatrices (glTF: identity; Assimp 5.2
                      crashes on it); also written as skin_no_ibm.glb.
  skin_unnormalized   the quad on [root, mover], static, weights (root, mover) per vertex
                      (0.5, 1.5), (0.25, 0.25), (1, 1), (0, 3): normalized (0.25, 0.75),
                      (0.5, 0.5), (0.5, 0.5), (0, 1).
  skin_shared         skin_slide's mesh placed again by node quad2 with the skin "swapped"
                      (joints [mover, root]): quad's right edge slides as in skin_slide, quad2's
                      left edge (vertices 0, 3) is at x = -2 + t and its right edge still.
  seam                the quad with a fifth vertex at vertex 1's position and normal but on joint
                      root (vertex 1: mover) and with a zero morph target delta (vertex 1:
                      (1, 0, 0)); mesh weights [1], static. JoinIdenticalVertices would merge
                      the two.
"""
import math
import os
import sys

import gltf_build as B
from gltf_build import FLOAT, UBYTE, UINT, USHORT

IDENTITY = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)  # column-major, as glTF stores it
# j1's inverse bind matrix: j1 sits at (1, 0, 0)
SHIFTED = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1)

QUAD_POSITIONS = [(-2, -2, -1), (-0.5, -2, -1), (-0.5, 2, -1), (-2, 2, -1)]
QUAD_INDICES = [0, 1, 2, 0, 2, 3]
QUAD_NORMALS = [(0, 0, 1)] * 4

GLOW = {"name": "glow", "emissiveFactor": [1, 1, 1],
        "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0,
                                 "roughnessFactor": 1}}


def _gltf(camera_at=None, material=GLOW):
    """A document with the camera (node 0, at camera_at) and one material (index 0)."""
    g = B.Gltf("evray tests/deform_assets.py")
    g.camera(**({"translation": camera_at} if camera_at else {}))
    g.material(material)
    return g


def _quad_primitive(g, **extra):
    prim = g.primitive(QUAD_POSITIONS, QUAD_INDICES, 0, QUAD_NORMALS)
    prim.update(extra)
    return prim


def _turning(degrees=(0, 45, 90)):
    """Rotation keys about +Z at t = 0, 0.5, 1."""
    return [0.0, 0.5, 1.0], [B.quaternion((0, 0, 1), d) for d in degrees]


# ---- morph targets ----

def _morph_quad(target_deltas=None, node_weights=None, animate="LINEAR"):
    g = _gltf()
    deltas = target_deltas or [(0, 0, 0), (1, 0, 0), (1, 0, 0), (0, 0, 0)]
    target = {"POSITION": g.accessor(FLOAT, deltas, minmax=True)}
    mesh = g.mesh("quad", [_quad_primitive(g, targets=[target])], weights=[0])
    quad = g.node("quad", mesh=mesh, **({"weights": node_weights} if node_weights else {}))
    if animate == "LINEAR":
        g.animation([(quad, "weights", [0.0, 1.0], [0.0, 1.0])], name="weights_1")
    elif animate == "CUBICSPLINE":
        # per key: in-tangent, value, out-tangent (one target each)
        g.animation([(quad, "weights", [0.0, 1.0], [2.0, 0.0, 3.0, 4.0, 1.0, 5.0], "CUBICSPLINE")],
                    name="weights_1")
    elif animate == "STEP":
        g.animation([(quad, "weights", [0.0, 1.0], [0.0, 1.0], "STEP")], name="weights_1")
    return g


def morph_slide():
    return _morph_quad()


def morph_node_weights():
    return _morph_quad(node_weights=[0.5], animate=None)


def morph_cubic():
    return _morph_quad(animate="CUBICSPLINE")


def morph_step():
    return _morph_quad(animate="STEP")


def morph_two_prims():
    g = _gltf()
    prims = []
    for shift in (0.0, 3.0):  # the second quad 3 units higher, its own accessors
        t1 = {"POSITION": g.accessor(FLOAT, [(0, 0, 0), (1, 0, 0), (1, 0, 0), (0, 0, 0)],
                                     minmax=True),
              "NORMAL": g.accessor(FLOAT, [(0, 0.5, 0)] * 4)}
        t2 = {"POSITION": g.accessor(FLOAT, [(0, 0, 0), (0, 1, 0), (0, 1, 0), (0, 0, 0)],
                                     minmax=True)}
        prim = g.primitive([(x, y + shift, z) for x, y, z in QUAD_POSITIONS], QUAD_INDICES, 0,
                           QUAD_NORMALS)
        prim["targets"] = [t1, t2]
        prims.append(prim)
    pair = g.node("pair", mesh=g.mesh("pair", prims, weights=[0.25, 0.5]), weights=[0.75, 0.125])
    g.animation([(pair, "weights", [0.0, 0.5, 1.0], [0.0, 0.1, 0.2, 0.3, 1.0, 0.9])],
                name="weights_1")
    return g


def bad_morph_count():
    return _morph_quad(target_deltas=[(0, 0, 0), (1, 0, 0), (1, 0, 0)])


# ---- skins ----

def _skin_quad(eight=False, bad_joint=False, ibm_count=None, zero_weights=False, no_ibm=False):
    g = _gltf()
    on_edge = (1, 2)  # the right edge's vertices
    joints0, weights0, joints1, weights1 = [], [], [], []
    for v in range(4):
        if v in on_edge:
            joints0.append((1, 0, 0, 0))
            weights0.append((0.5, 0, 0, 0) if eight else (1, 0, 0, 0))
            joints1.append((2, 0, 0, 0))
            weights1.append((0.5, 0, 0, 0))
        else:
            joints0.append((0, 0, 0, 0))
            weights0.append((1, 0, 0, 0))
            joints1.append((0, 0, 0, 0))
            weights1.append((0, 0, 0, 0))
    num_joints = 3 if eight else 2
    if bad_joint:
        joints0[1] = (num_joints, 0, 0, 0)
    if zero_weights:
        weights0[0] = (0, 0, 0, 0)
    jtype = USHORT if eight else UBYTE
    prim = _quad_primitive(g)
    prim["attributes"]["JOINTS_0"] = g.accessor(jtype, joints0)
    prim["attributes"]["WEIGHTS_0"] = g.accessor(FLOAT, weights0)
    if eight:
        prim["attributes"]["JOINTS_1"] = g.accessor(jtype, joints1)
        prim["attributes"]["WEIGHTS_1"] = g.accessor(FLOAT, weights1)
    # nodes: 0 camera, 1 quad (skinned; its own transform is ignored), 2 root, 3 mover, [4 mover2]
    g.node("quad", mesh=g.mesh("quad", [prim]), skin=0, translation=[5, 5, 5])
    joints = [g.node("root"), g.node("mover")]
    if eight:
        joints.append(g.node("mover2"))
    ibm = [IDENTITY] * (num_joints if ibm_count is None else ibm_count)
    skin = {"name": "quad_skin", "joints": joints}
    if not no_ibm:
        skin["inverseBindMatrices"] = g.accessor(FLOAT, ibm)
    g.skins.append(skin)
    # one clip: every mover's translation (0,0,0) -> (1,0,0) over [0, 1]
    g.animation([(j, "translation", [0.0, 1.0], [(0, 0, 0), (1, 0, 0)]) for j in joints[1:]],
                name="slide")
    return g


def skin_slide():
    return _skin_quad()


def skin_slide8():
    return _skin_quad(eight=True)


def skin_no_ibm():
    return _skin_quad(no_ibm=True)


def skin_shared():
    g = _skin_quad()
    g.node("quad2", mesh=0, skin=1)
    g.skins.append({"name": "swapped", "joints": [3, 2],
                    "inverseBindMatrices": g.skins[0]["inverseBindMatrices"]})
    return g


def _static_skin(positions, indices, joints, weights, targets=None, mesh_weights=None):
    """A static mesh on joints [root, mover] (nodes 2, 3), identity inverse bind matrices."""
    g = _gltf()
    prim = g.primitive(positions, indices, 0, [(0, 0, 1)] * len(positions))
    prim["attributes"]["JOINTS_0"] = g.accessor(UBYTE, joints)
    prim["attributes"]["WEIGHTS_0"] = g.accessor(FLOAT, weights)
    if targets:
        prim["targets"] = [{"POSITION": g.accessor(FLOAT, t, minmax=True)} for t in targets]
    g.node("quad", mesh=g.mesh("quad", [prim], weights=mesh_weights if targets else None), skin=0)
    g.skins.append({"joints": [g.node("root"), g.node("mover")],
                    "inverseBindMatrices": g.accessor(FLOAT, [IDENTITY] * 2)})
    return g


def skin_unnormalized():
    return _static_skin(QUAD_POSITIONS, QUAD_INDICES, [(0, 1, 0, 0)] * 4,
                        [(0.5, 1.5, 0, 0), (0.25, 0.25, 0, 0), (1, 1, 0, 0), (0, 3, 0, 0)])


def seam():
    pos = QUAD_POSITIONS + [QUAD_POSITIONS[1]]
    return _static_skin(pos, [0, 1, 2, 0, 2, 3, 4, 2, 3],
                        [(0, 0, 0, 0), (1, 0, 0, 0), (1, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0)],
                        [(1, 0, 0, 0)] * 5,
                        targets=[[(0, 0, 0), (1, 0, 0), (1, 0, 0), (0, 0, 0), (0, 0, 0)]],
                        mesh_weights=[1])


def bad_joint_index():
    return _skin_quad(bad_joint=True)


def bad_ibm_count():
    return _skin_quad(ibm_count=1)


def bad_weights_zero():
    return _skin_quad(zero_weights=True)


def _bent_skeleton(g, mesh):
    """Nodes: 1 the skinned mesh, 2 j0 (static), 3 j1 (its child at (1, 0, 0), turning about +Z
    by 0, 45, 90 degrees at t = 0, 0.5, 1); the skin; the turn's animation."""
    g.node(g.meshes[mesh]["name"], mesh=mesh, skin=0)
    j0 = g.node("j0", children=[3])
    j1 = g.node("j1", root=False, translation=[1, 0, 0])
    g.skins.append({"joints": [j0, j1], "inverseBindMatrices": g.accessor(FLOAT, [IDENTITY, SHIFTED])})
    g.animation([(j1, "rotation", *_turning())], name="rotation_3")


# ---- a bending cylinder ----

CYL_RINGS, CYL_SEGMENTS, CYL_RADIUS, CYL_LENGTH = 17, 12, 0.1, 2.0


def _cyl_weight_j1(x):
    """j1's weight: 0 up to x = 0.8, 1 from x = 1.2, linear between."""
    return min(1.0, max(0.0, (x - 0.8) / 0.4))


def bend_cylinder():
    g = _gltf(camera_at=(1, 0.5, 4))
    pos, nrm, idx = [], [], []
    for i in range(CYL_RINGS):
        x = CYL_LENGTH * i / (CYL_RINGS - 1)
        for j in range(CYL_SEGMENTS):
            a = 2 * math.pi * j / CYL_SEGMENTS
            pos.append((x, CYL_RADIUS * math.cos(a), CYL_RADIUS * math.sin(a)))
            nrm.append((0.0, math.cos(a), math.sin(a)))
    for i in range(CYL_RINGS - 1):
        for j in range(CYL_SEGMENTS):
            a, b = i * CYL_SEGMENTS + j, i * CYL_SEGMENTS + (j + 1) % CYL_SEGMENTS
            c, d = a + CYL_SEGMENTS, b + CYL_SEGMENTS
            idx += [a, b, d, a, d, c]  # outward facing (counter-clockwise seen from outside)
    for x, sign in ((0.0, -1.0), (CYL_LENGTH, 1.0)):  # caps: a centre and their own ring
        centre = len(pos)
        pos.append((x, 0.0, 0.0))
        nrm.append((sign, 0.0, 0.0))
        for j in range(CYL_SEGMENTS):
            a = 2 * math.pi * j / CYL_SEGMENTS
            pos.append((x, CYL_RADIUS * math.cos(a), CYL_RADIUS * math.sin(a)))
            nrm.append((sign, 0.0, 0.0))
        for j in range(CYL_SEGMENTS):
            a, b = centre + 1 + j, centre + 1 + (j + 1) % CYL_SEGMENTS
            idx += [centre, b, a] if sign < 0 else [centre, a, b]
    joints, weights = [], []
    for p in pos:
        w1 = _cyl_weight_j1(p[0])
        joints.append((0, 1, 0, 0))
        weights.append((1.0 - w1, w1, 0.0, 0.0))
    prim = g.primitive(pos, idx, 0, nrm)
    prim["attributes"]["JOINTS_0"] = g.accessor(UBYTE, joints)
    prim["attributes"]["WEIGHTS_0"] = g.accessor(FLOAT, weights)
    # nodes: 0 camera, 1 cylinder, 2 j0, 3 j1 (child of j0)
    _bent_skeleton(g, g.mesh("cylinder", [prim]))
    g.skins[0].update(name="cylinder_skin", skeleton=2)
    return g


def _arm_part(g, x0, x1, rings, segments, shift, skin_weights):
    """A tube from x0 to x1 (rings x segments, no caps) moved by -shift in x; skin_weights(x) gives
    j1's weight, or None for no skin attributes. Returns the primitive."""
    pos, nrm, idx, joints, weights = [], [], [], [], []
    for i in range(rings):
        x = x0 + (x1 - x0) * i / (rings - 1)
        for j in range(segments):
            a = 2 * math.pi * j / segments
            pos.append((x - shift, 0.3 * math.cos(a), 0.3 * math.sin(a)))
            nrm.append((0.0, math.cos(a), math.sin(a)))
            if skin_weights:
                w1 = skin_weights(x)
                joints.append((0, 1, 0, 0))
                weights.append((1.0 - w1, w1, 0.0, 0.0))
    for i in range(rings - 1):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            idx += [a, b, b + segments, a, b + segments, a + segments]
    prim = g.primitive(pos, idx, 0, nrm, index_type=UINT)
    if skin_weights:
        prim["attributes"]["JOINTS_0"] = g.accessor(UBYTE, joints)
        prim["attributes"]["WEIGHTS_0"] = g.accessor(FLOAT, weights)
    return prim


def bench_arm(skinned=True, rings=401, segments=64):
    """For measuring what deformation costs: a grey tube (radius 0.3, x in [0, 2]) lit by a point
    light, its half beyond x = 1 turning 90 degrees about +Z over 1 s around (1, 0, 0). skinned:
    one mesh on joints j0, j1 (the bend over x in [0.95, 1.05]); else its rigid twin, the same
    triangles as two meshes, the outer one on the turning node. 2 (rings - 1) segments
    triangles either way."""
    g = _gltf(camera_at=(1, 0.8, 6), material={"name": "grey", "pbrMetallicRoughness": {
        "baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0, "roughnessFactor": 1}})
    half = rings // 2 + 1
    if skinned:
        prim = _arm_part(g, 0.0, 2.0, rings, segments, 0.0,
                         lambda x: min(1.0, max(0.0, (x - 0.95) / 0.1)))
        _bent_skeleton(g, g.mesh("arm", [prim]))
    else:
        inner = _arm_part(g, 0.0, 1.0, half, segments, 0.0, None)
        outer = _arm_part(g, 1.0, 2.0, rings - half + 1, segments, 1.0, None)
        g.node("upper", mesh=g.mesh("upper", [inner]))
        g.node("j0", children=[3])
        j1 = g.node("j1", root=False, translation=[1, 0, 0], mesh=g.mesh("fore", [outer]))
        g.animation([(j1, "rotation", *_turning())], name="rotation_3")
    g.light("light", "point", 60, translation=[1, 3, 4])
    return g


ASSETS = {f.__name__: f for f in (morph_slide, skin_slide, skin_slide8, bend_cylinder,
                                  bad_joint_index, bad_ibm_count, bad_morph_count,
                                  bad_weights_zero, morph_node_weights, morph_cubic, morph_step,
                                  morph_two_prims, skin_no_ibm, skin_unnormalized, skin_shared,
                                  seam)}
BAD = ("bad_joint_index", "bad_ibm_count", "bad_morph_count", "bad_weights_zero")
GLB_TOO = ("skin_no_ibm",)  # also written as NAME.glb


def write_all(outdir):
    """Writes every asset as outdir/NAME.gltf (and NAME.glb for GLB_TOO); returns {name: path}
    of the .gltf files."""
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for name, make in ASSETS.items():
        g = make()
        paths[name] = g.write(os.path.join(outdir, name + ".gltf"), indent=1)
        if name in GLB_TOO:
            g.write(os.path.join(outdir, name + ".glb"))
    return paths


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--bench":  # the benchmark pair (docs/benchmarks.md)
        os.makedirs(sys.argv[2], exist_ok=True)
        for name, skinned in (("bench_arm_skinned", True), ("bench_arm_rigid", False)):
            print(bench_arm(skinned).write(os.path.join(sys.argv[2], name + ".gltf")))
    elif len(sys.argv) == 2:
        for path in write_all(sys.argv[1]).values():
            print(path)
    else:
        sys.exit("usage: deform_assets.py OUTDIR | --bench OUTDIR")
