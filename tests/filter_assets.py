"""glTF test scenes for the hit filters (src/core/hit_filter.h): alpha MASK cut-outs and
single-sided surfaces, with geometry simple enough that the tests know every pixel.

Standard library only (the PNG written with zlib). `python3 tests/filter_assets.py OUTDIR` writes
every scene as OUTDIR/NAME.gltf.

Common to all: a camera node at the origin looking along -Z, perspective with yfov = 2 atan(0.5)
(the plane z = -d spans [-d/2, d/2] in x and y), aspect 1; a wall at z = -4 (x, y in [-4, 4],
white, base colour 0.8, facing the camera); a directional light travelling along -Z (intensity
pi: a surface facing it reflects radiance = base colour); a card at z = -2 spanning [-0.5, 0.5]
in x and y, black with emission 0.3 (brighter than the wall in shadow, darker than the lit wall),
uv (0, 0) at its top-left corner (u = x + 0.5, v = 0.5 - y).

  mask_checker   the card is alpha MASK (cutoff 0.5) with a 4x4 checkerboard base texture of alpha
                 1 (texel column + row even) and 0: through the holes the camera sees the wall,
                 and the light reaches the wall through them (the shadow has holes)
  cull_front     the card opaque and single-sided, its front (counter-clockwise) towards the
                 camera: seen; its shadow (shadow rays meet its back face) is on the wall
  cull_back      the same card wound the other way: the camera sees its back, so it is invisible,
                 but its shadow is still on the wall
  both_back      cull_back's card made double-sided: seen
  cull_mirrored  cull_back's card under a node of scale (-1, 1, 1): the mirroring flips its
                 winding (glTF: a negative determinant), so its front faces the camera: seen
  mask_moving    the card alpha MASK with an 8x1 texture, alpha 0 on its left half (u < 0.5) and
                 1 on its right half, translating by +0.25 in x over t in [0, 1] (LINEAR): only
                 the opaque half's edges (at x = 0 and x = 0.5 at t = 0) make events
  mixed          mask_checker's card, mask_moving's card's translation, and cull_back's card
                 behind it at z = -3 offset by (0.6, 0.4): the CPU-vs-CUDA scene
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

FLOAT, UINT = 5126, 5125


def png_rgba(width, height, pixels):
    """An 8-bit RGBA PNG of pixels (rows top to bottom, (r, g, b, a) tuples)."""
    raw = b"".join(b"\x00" + bytes(c for p in pixels[y * width:(y + 1) * width] for c in p)
                   for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def checker_alpha(col, row):
    """mask_checker's texture: 1 where texel column + row is even."""
    return 1 if (col + row) % 2 == 0 else 0


def checker_png():
    return png_rgba(4, 4, [(255, 255, 255, 255 * checker_alpha(c, r)) for r in range(4) for c in range(4)])


def half_png():
    return png_rgba(8, 1, [(255, 255, 255, 255 if c >= 4 else 0) for c in range(8)])


class _Doc:
    def __init__(self):
        self.data = bytearray()
        self.g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}], "nodes": [],
                  "meshes": [], "materials": [], "accessors": [], "bufferViews": [], "images": [],
                  "textures": [], "samplers": [{"magFilter": 9729, "minFilter": 9729}],
                  "cameras": [{"type": "perspective", "perspective": {
                      "yfov": 2 * math.atan(0.5), "aspectRatio": 1.0, "znear": 0.01}}],
                  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular"],
                  "extensions": {"KHR_lights_punctual": {"lights": [
                      {"type": "directional", "intensity": math.pi, "color": [1, 1, 1]}]}}}
        self.node("camera", camera=0)
        self.node("sun", extensions={"KHR_lights_punctual": {"light": 0}})

    def accessor(self, ctype, rows, minmax=False):
        dim = len(rows[0])
        fmt = "f" if ctype == FLOAT else "I"
        while len(self.data) % 4:
            self.data.append(0)
        off = len(self.data)
        for r in rows:
            self.data += struct.pack("<" + fmt * dim, *r)
        self.g["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(self.data) - off})
        a = {"bufferView": len(self.g["bufferViews"]) - 1, "componentType": ctype, "count": len(rows),
             "type": {1: "SCALAR", 2: "VEC2", 3: "VEC3"}[dim]}
        if minmax:
            a["min"] = [min(r[i] for r in rows) for i in range(dim)]
            a["max"] = [max(r[i] for r in rows) for i in range(dim)]
        self.g["accessors"].append(a)
        return len(self.g["accessors"]) - 1

    def node(self, name, **kw):
        self.g["nodes"].append(dict(name=name, **kw))
        self.g["scenes"][0]["nodes"].append(len(self.g["nodes"]) - 1)
        return len(self.g["nodes"]) - 1

    def texture(self, png):
        self.g["images"].append({"uri": "data:image/png;base64," + base64.b64encode(png).decode()})
        self.g["textures"].append({"source": len(self.g["images"]) - 1, "sampler": 0})
        return len(self.g["textures"]) - 1

    def material(self, name, base=(0, 0, 0, 1), emissive=(0, 0, 0), texture=None, mask=False,
                 double_sided=False):
        pbr = {"baseColorFactor": list(base), "metallicFactor": 0.0, "roughnessFactor": 1.0}
        if texture is not None:
            pbr["baseColorTexture"] = {"index": texture}
        # Lambert (no specular layer: KHR_materials_specular factor 0), so that the expected
        # intensities are albedo / pi times the irradiance
        m = {"name": name, "pbrMetallicRoughness": pbr, "emissiveFactor": list(emissive),
             "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
        if mask:
            m["alphaMode"] = "MASK"
            m["alphaCutoff"] = 0.5
        if double_sided:
            m["doubleSided"] = True
        self.g["materials"].append(m)
        return len(self.g["materials"]) - 1

    def quad(self, name, x0, x1, y0, y1, z, material, towards_camera=True, **node):
        """A quad in the plane z, uv (0, 0) at its top-left corner; its front (counter-clockwise)
        faces +Z (the camera) or, with towards_camera False, -Z."""
        pos = [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)]
        uv = [(0, 1), (1, 1), (1, 0), (0, 0)]
        idx = [(0, 1, 2), (0, 2, 3)] if towards_camera else [(0, 2, 1), (0, 3, 2)]
        nz = 1.0 if towards_camera else -1.0
        prim = {"attributes": {"POSITION": self.accessor(FLOAT, pos, minmax=True),
                               "NORMAL": self.accessor(FLOAT, [(0, 0, nz)] * 4),
                               "TEXCOORD_0": self.accessor(FLOAT, uv)},
                "indices": self.accessor(UINT, [(i,) for t in idx for i in t]), "material": material}
        self.g["meshes"].append({"name": name, "primitives": [prim]})
        return self.node(name, mesh=len(self.g["meshes"]) - 1, **node)

    def translate_x(self, node, dx):
        """Animates node's translation from its own to +dx in x over t in [0, 1], LINEAR."""
        t0 = self.g["nodes"][node].get("translation", [0, 0, 0])
        times = self.accessor(FLOAT, [(0.0,), (1.0,)], minmax=True)
        vals = self.accessor(FLOAT, [tuple(t0), (t0[0] + dx, t0[1], t0[2])])
        self.g["nodes"][node]["translation"] = list(t0)
        self.g.setdefault("animations", []).append({
            "name": "slide", "samplers": [{"input": times, "output": vals, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": node, "path": "translation"}}]})

    def finish(self):
        self.g["buffers"] = [{"byteLength": len(self.data), "uri": "data:application/octet-stream;base64," +
                              base64.b64encode(bytes(self.data)).decode()}]
        for k in ("images", "textures"):
            if not self.g[k]:
                del self.g[k]
        return self.g


def _base():
    d = _Doc()
    d.quad("wall", -4, 4, -4, 4, -4, d.material("white", base=(0.8, 0.8, 0.8, 1)))
    return d


def mask_checker():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
           d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(checker_png()), mask=True))
    return d.finish()


def cull_front():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)))
    return d.finish()


def cull_back():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False)
    return d.finish()


def both_back():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
           d.material("two_sided", emissive=(0.3, 0.3, 0.3), double_sided=True), towards_camera=False)
    return d.finish()


def cull_mirrored():
    d = _base()
    d.quad("card", -0.5, 0.5, -0.5, 0.5, -2, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False, scale=[-1, 1, 1])
    return d.finish()


def mask_moving():
    d = _base()
    card = d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
                  d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(half_png()), mask=True))
    d.translate_x(card, 0.25)
    return d.finish()


def mixed():
    d = _base()
    card = d.quad("card", -0.5, 0.5, -0.5, 0.5, -2,
                  d.material("cutout", emissive=(0.3, 0.3, 0.3), texture=d.texture(checker_png()), mask=True))
    d.translate_x(card, 0.25)
    d.quad("back", -0.5, 0.5, -0.5, 0.5, 0, d.material("one_sided", emissive=(0.3, 0.3, 0.3)),
           towards_camera=False, translation=[0.6, 0.4, -3])
    return d.finish()


ASSETS = {f.__name__: f for f in (mask_checker, cull_front, cull_back, both_back, cull_mirrored, mask_moving,
                                   mixed)}


def write_all(outdir):
    """Writes every scene as outdir/NAME.gltf; returns {name: path}."""
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for name, f in ASSETS.items():
        paths[name] = os.path.join(outdir, name + ".gltf")
        with open(paths[name], "w") as fh:
            json.dump(f(), fh)
    return paths


if __name__ == "__main__":
    write_all(sys.argv[1] if len(sys.argv) > 1 else ".")
