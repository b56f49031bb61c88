"""glTF test assets for skins and morph targets, with exact numbers that tests check analytically.

Standard library only. Each asset is a function returning the glTF dict (one buffer, embedded as
a base64 data: URI); `python3 tests/deform_assets.py OUTDIR` writes every asset as OUTDIR/NAME.gltf.

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
import base64
import json
import math
import os
import struct
import sys

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
_FMT = {FLOAT: "f", UBYTE: "B", USHORT: "H", UINT: "I"}
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}

IDENTITY = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)  # column-major, as glTF stores it

QUAD_POSITIONS = [(-2, -2, -1), (-0.5, -2, -1), (-0.5, 2, -1), (-2, 2, -1)]
QUAD_INDICES = [0, 1, 2, 0, 2, 3]
QUAD_NORMALS = [(0, 0, 1)] * 4


class _Gltf:
    """Accumulates one buffer's bytes, its views and accessors, then makes the document."""

    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def accessor(self, ctype, values, minmax=False):
        """Appends values (a list of scalars or of equal-length tuples) as one accessor."""
        rows = [v if isinstance(v, (tuple, list)) else (v,) for v in values]
        dim = len(rows[0])
        flat = [x for r in rows for x in r]
        raw = struct.pack("<%d%s" % (len(flat), _FMT[ctype]), *flat)
        while len(self.data) % 4:
            self.data.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)})
        self.data += raw
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype, "count": len(rows),
               "type": _TYPES[dim]}
        if minmax:
            acc["min"] = [min(r[i] for r in rows) for i in range(dim)]
            acc["max"] = [max(r[i] for r in rows) for i in range(dim)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def document(self, nodes, meshes, roots, skins=None, animations=None, yfov=2 * math.atan(0.5)):
        while len(self.data) % 4:
            self.data.append(0)
        doc = {
            "asset": {"version": "2.0", "generator": "evray tests/deform_assets.py"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": nodes,
            "meshes": meshes,
            "materials": [{"name": "glow", "emissiveFactor": [1, 1, 1],
                           "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                                    "metallicFactor": 0, "roughnessFactor": 1}}],
            "cameras": [{"type": "perspective",
                         "perspective": {"yfov": yfov, "aspectRatio": 1.0, "znear": 0.01}}],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": len(self.data),
                         "uri": "data:application/octet-stream;base64," +
                                base64.b64encode(bytes(self.data)).decode("ascii")}],
        }
        if skins:
            doc["skins"] = skins
        if animations:
            doc["animations"] = animations
        return doc


def _camera_node(translation=None):
    n = {"name": "camera", "camera": 0}
    if translation:
        n["translation"] = list(translation)
    return n


def _quad_attributes(g):
    return {"POSITION": g.accessor(FLOAT, QUAD_POSITIONS, minmax=True),
            "NORMAL": g.accessor(FLOAT, QUAD_NORMALS)}


def _linear_channel(g, node, path, times, values, interpolation="LINEAR"):
    """One animation with one sampler and channel."""
    return {"name": "%s_%s" % (path, node),
            "samplers": [{"input": g.accessor(FLOAT, times, minmax=True),
                          "output": g.accessor(FLOAT, values), "interpolation": interpolation}],
            "channels": [{"sampler": 0, "target": {"node": node, "path": path}}]}


# ---- morph targets ----

def _morph_quad(target_deltas=None, node_weights=None, animate="LINEAR"):
    g = _Gltf()
    attrs = _quad_attributes(g)
    idx = g.accessor(USHORT, QUAD_INDICES)
    deltas = target_deltas or [(0, 0, 0), (1, 0, 0), (1, 0, 0), (0, 0, 0)]
    target = {"POSITION": g.accessor(FLOAT, deltas, minmax=True)}
    mesh = {"name": "quad", "primitives": [{"attributes": attrs, "indices": idx, "material": 0,
                                            "targets": [target]}], "weights": [0]}
    quad = {"name": "quad", "mesh": 0}
    if node_weights is not None:
        quad["weights"] = node_weights
    nodes = [_camera_node(), quad]
    anims = None
    if animate == "LINEAR":
        anims = [_linear_channel(g, 1, "weights", [0.0, 1.0], [0.0, 1.0])]
    elif animate == "CUBICSPLINE":
        # per key: in-tangent, value, out-tangent (one target each)
        anims = [_linear_channel(g, 1, "weights", [0.0, 1.0], [2.0, 0.0, 3.0, 4.0, 1.0, 5.0],
                                 "CUBICSPLINE")]
    elif animate == "STEP":
        anims = [_linear_channel(g, 1, "weights", [0.0, 1.0], [0.0, 1.0], "STEP")]
    return g.document(nodes, [mesh], [0, 1], animations=anims)


def morph_slide():
    return _morph_quad()


def morph_node_weights():
    return _morph_quad(node_weights=[0.5], animate=None)


def morph_cubic():
    return _morph_quad(animate="CUBICSPLINE")


def morph_step():
    return _morph_quad(animate="STEP")


def morph_two_prims():
    g = _Gltf()
    prims = []
    for shift in (0.0, 3.0):  # the second quad 3 units higher, its own accessors
        attrs = {"POSITION": g.accessor(FLOAT, [(x, y + shift, z) for x, y, z in QUAD_POSITIONS],
                                        minmax=True),
                 "NORMAL": g.accessor(FLOAT, QUAD_NORMALS)}
        t1 = {"POSITION": g.accessor(FLOAT, [(0, 0, 0), (1, 0, 0), (1, 0, 0), (0, 0, 0)],
                                     minmax=True),
              "NORMAL": g.accessor(FLOAT, [(0, 0.5, 0)] * 4)}
        t2 = {"POSITION": g.accessor(FLOAT, [(0, 0, 0), (0, 1, 0), (0, 1, 0), (0, 0, 0)],
                                     minmax=True)}
        prims.append({"attributes": attrs, "indices": g.accessor(USHORT, QUAD_INDICES),
                      "material": 0, "targets": [t1, t2]})
    mesh = {"name": "pair", "primitives": prims, "weights": [0.25, 0.5]}
    nodes = [_camera_node(), {"name": "pair", "mesh": 0, "weights": [0.75, 0.125]}]
    anims = [_linear_channel(g, 1, "weights", [0.0, 0.5, 1.0], [0.0, 0.1, 0.2, 0.3, 1.0, 0.9])]
    return g.document(nodes, [mesh], [0, 1], animations=anims)


def bad_morph_count():
    return _morph_quad(target_deltas=[(0, 0, 0), (1, 0, 0), (1, 0, 0)])


# ---- skins ----

def _skin_quad(eight=False, bad_joint=False, ibm_count=None, zero_weights=False, no_ibm=False):
    g = _Gltf()
    attrs = _quad_attributes(g)
    idx = g.accessor(USHORT, QUAD_INDICES)
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
    attrs["JOINTS_0"] = g.accessor(jtype, joints0)
    attrs["WEIGHTS_0"] = g.accessor(FLOAT, weights0)
    if eight:
        attrs["JOINTS_1"] = g.accessor(jtype, joints1)
        attrs["WEIGHTS_1"] = g.accessor(FLOAT, weights1)
    mesh = {"name": "quad", "primitives": [{"attributes": attrs, "indices": idx, "material": 0}]}
    # nodes: 0 camera, 1 quad (skinned; its own transform is ignored), 2 root, 3 mover, [4 mover2]
    nodes = [_camera_node(), {"name": "quad", "mesh": 0, "skin": 0, "translation": [5, 5, 5]},
             {"name": "root"}, {"name": "mover"}]
    joints = [2, 3]
    if eight:
        nodes.append({"name": "mover2"})
        joints.append(4)
    ibm = [IDENTITY] * (num_joints if ibm_count is None else ibm_count)
    skins = [{"name": "quad_skin", "joints": joints, "inverseBindMatrices": g.accessor(FLOAT, ibm)}]
    if no_ibm:
        del skins[0]["inverseBindMatrices"]
    # one clip: every mover's translation (0,0,0) -> (1,0,0) over [0, 1]
    anim = _linear_channel(g, 3, "translation", [0.0, 1.0], [(0, 0, 0), (1, 0, 0)])
    anim["name"] = "slide"
    for j in joints[2:]:
        anim["samplers"].append(dict(anim["samplers"][0]))
        anim["channels"].append({"sampler": len(anim["samplers"]) - 1,
                                 "target": {"node": j, "path": "translation"}})
    anims = [anim]
    return g.document(nodes, [mesh], list(range(len(nodes))), skins=skins, animations=anims)


def skin_slide():
    return _skin_quad()


def skin_slide8():
    return _skin_quad(eight=True)


def skin_no_ibm():
    return _skin_quad(no_ibm=True)


def skin_shared():
    doc = _skin_quad()
    doc["nodes"].append({"name": "quad2", "mesh": 0, "skin": 1})
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    doc["skins"].append({"name": "swapped", "joints": [3, 2],
                         "inverseBindMatrices": doc["skins"][0]["inverseBindMatrices"]})
    return doc


def _static_skin(positions, indices, joints, weights, targets=None, mesh_weights=None):
    """A static mesh on joints [root, mover] (nodes 2, 3), identity inverse bind matrices."""
    g = _Gltf()
    attrs = {"POSITION": g.accessor(FLOAT, positions, minmax=True),
             "NORMAL": g.accessor(FLOAT, [(0, 0, 1)] * len(positions)),
             "JOINTS_0": g.accessor(UBYTE, joints), "WEIGHTS_0": g.accessor(FLOAT, weights)}
    prim = {"attributes": attrs, "indices": g.accessor(USHORT, indices), "material": 0}
    mesh = {"name": "quad", "primitives": [prim]}
    if targets:
        prim["targets"] = [{"POSITION": g.accessor(FLOAT, t, minmax=True)} for t in targets]
        mesh["weights"] = mesh_weights
    nodes = [_camera_node(), {"name": "quad", "mesh": 0, "skin": 0}, {"name": "root"},
             {"name": "mover"}]
    skins = [{"joints": [2, 3], "inverseBindMatrices": g.accessor(FLOAT, [IDENTITY] * 2)}]
    return g.document(nodes, [mesh], [0, 1, 2, 3], skins=skins)


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


# ---- a bending cylinder ----

CYL_RINGS, CYL_SEGMENTS, CYL_RADIUS, CYL_LENGTH = 17, 12, 0.1, 2.0


def _cyl_weight_j1(x):
    """j1's weight: 0 up to x = 0.8, 1 from x = 1.2, linear between."""
    return min(1.0, max(0.0, (x - 0.8) / 0.4))


def bend_cylinder():
    g = _Gltf()
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
    attrs = {"POSITION": g.accessor(FLOAT, pos, minmax=True), "NORMAL": g.accessor(FLOAT, nrm),
             "JOINTS_0": g.accessor(UBYTE, joints), "WEIGHTS_0": g.accessor(FLOAT, weights)}
    mesh = {"name": "cylinder",
            "primitives": [{"attributes": attrs, "indices": g.accessor(USHORT, idx),
                            "material": 0}]}
    ibm = [IDENTITY, (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1)]
    # nodes: 0 camera, 1 cylinder, 2 j0, 3 j1 (child of j0)
    nodes = [_camera_node((1, 0.5, 4)), {"name": "cylinder", "mesh": 0, "skin": 0},
             {"name": "j0", "children": [3]}, {"name": "j1", "translation": [1, 0, 0]}]
    skins = [{"name": "cylinder_skin", "joints": [2, 3], "skeleton": 2,
              "inverseBindMatrices": g.accessor(FLOAT, ibm)}]
    rot = []
    for deg in (0, 45, 90):
        h = math.radians(deg) / 2
        rot.append((0.0, 0.0, math.sin(h), math.cos(h)))  # glTF quaternions are x, y, z, w
    anims = [_linear_channel(g, 3, "rotation", [0.0, 0.5, 1.0], rot)]
    return g.document(nodes, [mesh], [0, 1, 2], skins=skins, animations=anims)


ASSETS = {f.__name__: f for f in (morph_slide, skin_slide, skin_slide8, bend_cylinder,
                                  bad_joint_index, bad_ibm_count, bad_morph_count,
                                  bad_weights_zero, morph_node_weights, morph_cubic, morph_step,
                                  morph_two_prims, skin_no_ibm, skin_unnormalized, skin_shared,
                                  seam)}
BAD = ("bad_joint_index", "bad_ibm_count", "bad_morph_count", "bad_weights_zero")
GLB_TOO = ("skin_no_ibm",)  # also written as NAME.glb


def glb_bytes(doc):
    """The document as a GLB: its one buffer becomes the BIN chunk."""
    doc = json.loads(json.dumps(doc))
    data = base64.b64decode(doc["buffers"][0].pop("uri").split(",", 1)[1])
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    data += b"\0" * (-len(data) % 4)
    return (struct.pack("<4sII", b"glTF", 2, 28 + len(text) + len(data)) +
            struct.pack("<I4s", len(text), b"JSON") + text +
            struct.pack("<I4s", len(data), b"BIN\0") + data)


def write_all(outdir):
    """Writes every asset as outdir/NAME.gltf (and NAME.glb for GLB_TOO); returns {name: path}
    of the .gltf files."""
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for name, make in ASSETS.items():
        paths[name] = os.path.join(outdir, name + ".gltf")
        with open(paths[name], "w") as f:
            json.dump(make(), f, indent=1)
        if name in GLB_TOO:
            with open(os.path.join(outdir, name + ".glb"), "wb") as f:
                f.write(glb_bytes(make()))
    return paths


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: deform_assets.py OUTDIR")
    for path in write_all(sys.argv[1]).values():
        print(path)
