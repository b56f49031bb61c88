"""A big static glTF for set-up timing (issue 27: set-up of a 1 M-triangle model): one bumpy
torus of U x V quads (2 U V triangles; the default 1024 x 512 gives 1,048,576), with normals,
uvs, a base colour texture and a normal map (so the import generates tangents and mip-maps two
textures), a camera and a light; nothing moves. Made when a bench or test needs it, never kept in
the repository.

    python3 tests/big_asset.py OUT.glb [--grid U V] [--texture N]

Standard library only (tests/gltf_build.py writes it).
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_build  # noqa: E402


def torus_point(u, v, major=1.0, minor=0.35):
    """The surface at parameters u, v in [0, 1): a torus with small bumps along its normal."""
    a, b = 2 * math.pi * u, 2 * math.pi * v
    r = minor * (1.0 + 0.04 * math.sin(37 * a) * math.sin(11 * b))
    return ((major + r * math.cos(b)) * math.cos(a), r * math.sin(b),
            (major + r * math.cos(b)) * math.sin(a))


def torus(nu, nv):
    """Positions, normals (from the surface's derivatives), uvs and triangle indices; the seams
    share vertices, so the mesh is closed."""
    pos, nrm, uvs = [], [], []
    du, dv = 1e-4, 1e-4
    for j in range(nv):
        v = j / nv
        for i in range(nu):
            u = i / nu
            p = torus_point(u, v)
            pu, pv = torus_point(u + du, v), torus_point(u, v + dv)
            eu = (pu[0] - p[0], pu[1] - p[1], pu[2] - p[2])
            ev = (pv[0] - p[0], pv[1] - p[1], pv[2] - p[2])
            n = (ev[1] * eu[2] - ev[2] * eu[1], ev[2] * eu[0] - ev[0] * eu[2],
                 ev[0] * eu[1] - ev[1] * eu[0])
            ln = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) or 1.0
            pos.append(p)
            nrm.append((n[0] / ln, n[1] / ln, n[2] / ln))
            uvs.append((4.0 * u, 2.0 * v))
    idx = []
    for j in range(nv):
        j1 = (j + 1) % nv
        for i in range(nu):
            i1 = (i + 1) % nu
            a, b, c, d = j * nu + i, j * nu + i1, j1 * nu + i1, j1 * nu + i
            idx += (a, c, b, a, d, c)
    return pos, nrm, uvs, idx


def textures(n):
    """A checker base colour and a normal map of gentle ripples, n x n each (PNG bytes)."""
    colour, normal = [], []
    for y in range(n):
        for x in range(n):
            on = ((x * 16 // n) + (y * 16 // n)) & 1
            colour.append((200, 180, 150, 255) if on else (90, 110, 140, 255))
            s = math.sin(2 * math.pi * 8 * x / n)
            normal.append((int(128 + 60 * s), 128, int(128 + 110 * math.sqrt(1 - 0.3 * s * s)),
                           255))
    return gltf_build.png_bytes(n, n, colour), gltf_build.png_bytes(n, n, normal)


def build(path, nu=1024, nv=512, tex=1024):
    g = gltf_build.Gltf("tests/big_asset.py")
    pos, nrm, uvs, idx = torus(nu, nv)
    colour, normal = textures(tex)
    mat = g.material({
        "name": "surface",
        "pbrMetallicRoughness": {"baseColorTexture": {"index": g.texture(g.image(colour))},
                                 "metallicFactor": 0.0, "roughnessFactor": 0.8},
        "normalTexture": {"index": g.texture(g.image(normal))}})
    g.mesh_node("torus", pos, nrm, uvs, idx, mat, index_type=gltf_build.UINT)
    # looking down at the torus from 3.2 units, along the view's -Z
    g.camera("camera", yfov=0.9, aspect=4.0 / 3.0, translation=(0.0, 2.2, 2.4),
             rotation=gltf_build.quaternion((1, 0, 0), -42.0))
    g.light("lamp", "point", 40.0, translation=(1.5, 3.0, 2.0))
    g.write(path)
    return len(idx) // 3


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--grid", nargs=2, type=int, default=(1024, 512), metavar=("U", "V"))
    ap.add_argument("--texture", type=int, default=1024)
    a = ap.parse_args()
    tris = build(a.out, a.grid[0], a.grid[1], a.texture)
    print("%s: %d triangles" % (a.out, tris))


if __name__ == "__main__":
    main()
