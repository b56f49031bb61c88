"""Joining identical vertices (src/scene/import_join.c): the import skips Assimp's
JoinIdenticalVertices only where it would change nothing, so every mesh keeps exactly the
vertices Assimp's step leaves: duplicates and near-duplicates (normals within 1e-5) joined,
positions 1e-6 apart joined (Assimp 5.2.4 does), unused vertices dropped, vertices that differ
kept; a mesh with nothing to join as it is."""
import os
import re
import sys

import evrtest as T

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_build  # noqa: E402

tmp = T.tmpdir()
UP = (0.0, 0.0, 1.0)


def two_triangles(path, normal_b=UP, offset_b=0.0, unused=False, uvs=True):
    """Two triangles of a quad, each with its own three vertices: the shared edge's two
    vertices appear twice, the second copies with normal_b and moved by offset_b in x."""
    pos = [(0, 0, -1), (1, 0, -1), (1, 1, -1),
           (0 + offset_b, 0, -1), (1 + offset_b, 1, -1), (0, 1, -1)]
    nrm = [UP, UP, UP, normal_b, normal_b, UP]
    uv = [(0, 1), (1, 1), (1, 0), (0, 1), (1, 0), (0, 0)]
    if unused:
        pos.append((5, 5, -1))
        nrm.append(UP)
        uv.append((0.5, 0.5))
    g = gltf_build.Gltf()
    g.camera()
    g.light("lamp", "point", 1.0)
    m = g.material({"name": "grey"})
    g.mesh_node("quad", pos, nrm, uv if uvs else None, [0, 1, 2, 3, 4, 5], m)
    return g.write(path)


def vertices(path):
    out = T.run("info", path).stdout
    m = re.search(r'\[0\] "quad": (\d+) vertices, (\d+) triangles', out)
    T.check(m is not None, "evray info lists the quad: " + out)
    return int(m.group(1)), int(m.group(2))


def unit(x, y, z):
    n = (x * x + y * y + z * z) ** 0.5
    return (x / n, y / n, z / n)


cases = [
    ("exact duplicates joined", {}, 4),
    ("without uvs, joined the same", {"uvs": False}, 4),
    ("normals 5e-6 apart joined (Assimp's 1e-5)", {"normal_b": unit(5e-6, 0.0, 1.0)}, 4),
    ("normals 1e-3 apart kept", {"normal_b": unit(1e-3, 0.0, 1.0)}, 6),
    ("positions 1e-6 apart joined", {"offset_b": 1e-6}, 4),
    ("positions 1e-2 apart kept", {"offset_b": 1e-2}, 6),
    ("normals 1e-3 apart kept, an unused vertex dropped",
     {"normal_b": unit(1e-3, 0.0, 1.0), "unused": True}, 6),
]
for name, kw, want in cases:
    path = two_triangles(os.path.join(tmp, re.sub(r"\W+", "_", name) + ".gltf"), **kw)
    got, tris = vertices(path)
    T.check(tris == 2, "%s: 2 triangles (got %d)" % (name, tris))
    T.check(got == want, "%s: %d vertices (got %d)" % (name, want, got))

# a mesh with nothing to join keeps its vertices, in its order: the same events as before
import big_asset  # noqa: E402

big = os.path.join(tmp, "grid.glb")
tris = big_asset.build(big, 48, 24, 16)
out = T.run("info", big).stdout
T.check("%d vertices, %d triangles" % (48 * 24, tris) in out, "the torus keeps its vertices: " + out)

T.finish("test_join")
