"""glTF test assets for robust import (issue 22): missing and unreadable textures, quantized
meshes (KHR_mesh_quantization), GPU instancing (EXT_mesh_gpu_instancing) and KTX2 textures.

Standard library only (runs with /usr/bin/python3). Each asset is a function NAME(outdir) that
writes OUTDIR/NAME.gltf (and any file beside it) and returns its path;
`python3 tests/import_assets.py OUTDIR` writes them all (with GLB copies of the quantized and
instanced ones: to_glb).

Common to all: a camera node "camera" at (0, 0, 2) looking along -Z, perspective with
yfov = 2 atan(0.5) and aspect 1, so the plane z = 0 spans [-1, 1] in x and y and fills the view.
No light: evray adds its headlight. A "unit quad" is two triangles in the plane z = 0 spanning
x, y in [-0.5, 0.5] (its true size) with normal +Z: it covers the middle half of the view in x
and y, a quarter of the image. Materials are unlit white unless an asset says
otherwise, so that a rendered pixel is 1 on the quad and 0 beside it (KHR_materials_unlit with
base colour 1).

  missing_texture      unit quad, material "painted": baseColorFactor (0.8, 0.2, 0.1, 1),
                       metallic 0, roughness 0.5, baseColorTexture -> image uri
                       "no_such_texture.png", which does not exist. evray warns naming the image
                       and the material and keeps the factors (no texture).
  unreadable_texture   the same with image uri "broken.png", a file that is not a PNG.
  missing_texture_obj  (.obj + .mtl) a unit quad whose material "painted" has Kd 0.8 0.2 0.1 and
                       map_Kd /nonexistent/machine/textures/wood.png (an absolute path from
                       another machine).
  ktx2_texture         unit quad, material "basis": baseColorFactor (0.3, 0.6, 0.9, 1), its
                       texture's source only in KHR_texture_basisu, image "wood.ktx2" (a KTX2
                       header, no payload). evray warns naming the texture; the factors stay.
  quantized_short      unit quad under node "quad" with scale (0.5, 0.5, 0.5), KHR_mesh_quantization
                       required: POSITION normalized SHORT (+-32767: +-1 before the scale: +-0.5
                       after it), NORMAL normalized BYTE (0, 0, 127), TEXCOORD_0 normalized
                       UNSIGNED_SHORT (0 or 65535). World bounds (-0.5, -0.5, 0) to (0.5, 0.5, 0).
  quantized_byte       unit quad under node "quad" with translation (-0.5, -0.5, 0) and scale
                       (0.25, 0.25, 1), POSITION UNSIGNED_BYTE not normalized (0 or 4): world
                       bounds as above. Its NORMAL is normalized SHORT (0, 0, 32767).
  instanced            a cube "box" (0.1 a side, centred on its origin) on node "grid" with
                       EXT_mesh_gpu_instancing: 125 instances, TRANSLATION (float) on a 5 x 5 x 5
                       grid of pitch 0.3 centred on the origin (-0.6 .. 0.6), ROTATION normalized
                       SHORT (identity), SCALE float (1, 1, 1). The node itself has translation
                       (0, 0, -1): the instances' centres span x, y in [-0.6, 0.6], z in
                       [-1.6, -0.4]; world bounds (-0.65, -0.65, -1.65) to (0.65, 0.65, -0.35).
                       No instance sits at the node's own origin alone: the grid is the scene.
  odd_clip             unit quad "quad" (grey, lit) whose translation moves from (0, 0, 0) at
                       t = 0 to (0.2, 0, 0) at t = 41/12 s (3.41666...: the float32 nearest),
                       one LINEAR channel: a clip length that a rounded print would not give back.

For previews (tests/test_preview.py, docs/img):
  dark_stage           on a black background (nothing behind): a 3 x 3 x 3 grid "grid" of grey
                       boxes (0.2 a side, pitch 0.3, EXT_mesh_gpu_instancing) at (0, 0.15, -0.5)
                       turning about +Y by 90 degrees over 1 s (keys at 0, 0.5, 1 s); a static
                       grey strip "strip" (x in [-0.9, 0.9], y in [-0.95, -0.75], z = 0); a
                       bright emissive quad "flare" (0.3 x 0.3, emissive 1 times
                       KHR_materials_emissive_strength 20) entering from the right: x = 2.0 at
                       t <= 0.5 s, x = 0.7 at t = 1 s (y = -0.4, z = 0). Lit by evray's
                       headlight. The strip's pixels never change; the flare brightens the
                       frames after 0.5 s.
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
_FMT = {BYTE: "b", UBYTE: "B", SHORT: "h", USHORT: "H", UINT: "I", FLOAT: "f"}
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
YFOV = 2 * math.atan(0.5)
WHITE = {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]},
         "extensions": {"KHR_materials_unlit": {}}}


def png_bytes(width, height, rgb):
    """An 8-bit RGB PNG of one colour."""
    raw = (b"\0" + bytes(rgb) * width) * height

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data +
                struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


class Doc:
    """One buffer (a data: URI), its views and accessors of any component type, and the rest of
    the document as plain JSON lists."""

    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []
        self.meshes, self.materials = [], []
        self.images, self.textures = [], []
        self.nodes = [{"name": "camera", "camera": 0, "translation": [0, 0, 2]}]
        self.used, self.required = set(), set()

    def accessor(self, ctype, rows, normalized=False, attribute=True, minmax=False):
        """rows: tuples of one to four components. Vertex attributes keep each element 4-byte
        aligned (a byteStride when the element is shorter), as glTF requires."""
        n = len(rows[0])
        elem = struct.calcsize("<%d%s" % (n, _FMT[ctype]))
        stride = (elem + 3) // 4 * 4 if attribute else elem
        raw = b"".join(struct.pack("<%d%s" % (n, _FMT[ctype]), *r) + b"\0" * (stride - elem)
                       for r in rows)
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)}
        if stride != elem:
            view["byteStride"] = stride
        self.views.append(view)
        self.data += raw
        acc = {"bufferView": len(self.views) - 1, "componentType": ctype, "count": len(rows),
               "type": _TYPES[n]}
        if normalized:
            acc["normalized"] = True
        if minmax:
            acc["min"] = [min(r[i] for r in rows) for i in range(n)]
            acc["max"] = [max(r[i] for r in rows) for i in range(n)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def material(self, mat):
        for ext in mat.get("extensions", {}):
            self.used.add(ext)
        self.materials.append(mat)
        return len(self.materials) - 1

    def mesh(self, name, attributes, indices, material):
        self.meshes.append({"name": name, "primitives": [{
            "attributes": attributes, "material": material,
            "indices": self.accessor(USHORT, [(i,) for i in indices], attribute=False)}]})
        return len(self.meshes) - 1

    def write(self, outdir, name):
        while len(self.data) % 4:
            self.data.append(0)
        doc = {
            "asset": {"version": "2.0", "generator": "evray tests/import_assets.py"},
            "scene": 0,
            "scenes": [{"nodes": list(range(len(self.nodes)))}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "cameras": [{"type": "perspective",
                         "perspective": {"yfov": YFOV, "aspectRatio": 1.0, "znear": 0.01}}],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{"byteLength": len(self.data),
                         "uri": "data:application/octet-stream;base64," +
                                base64.b64encode(bytes(self.data)).decode("ascii")}],
        }
        if self.used:
            doc["extensionsUsed"] = sorted(self.used)
        if self.required:
            doc["extensionsRequired"] = sorted(self.required)
        if self.images:
            doc["images"] = self.images
            doc["textures"] = self.textures
        path = os.path.join(outdir, name + ".gltf")
        with open(path, "w") as f:
            json.dump(doc, f, indent=1)
        return path


QUAD = [(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)]
QUAD_UV = [(0, 1), (1, 1), (1, 0), (0, 0)]
QUAD_TRIS = [0, 1, 2, 0, 2, 3]


def _textured_quad(outdir, name, uri, factor=(0.8, 0.2, 0.1, 1)):
    g = Doc()
    g.images.append({"uri": uri})
    g.textures.append({"source": 0})
    mat = g.material({"name": "painted", "pbrMetallicRoughness": {
        "baseColorFactor": list(factor), "metallicFactor": 0, "roughnessFactor": 0.5,
        "baseColorTexture": {"index": 0}}})
    m = g.mesh("quad", {"POSITION": g.accessor(FLOAT, QUAD, minmax=True),
                        "NORMAL": g.accessor(FLOAT, [(0, 0, 1)] * 4),
                        "TEXCOORD_0": g.accessor(FLOAT, QUAD_UV)}, QUAD_TRIS, mat)
    g.nodes.append({"name": "quad", "mesh": m})
    return g.write(outdir, name)


def missing_texture(outdir):
    return _textured_quad(outdir, "missing_texture", "no_such_texture.png")


def unreadable_texture(outdir):
    with open(os.path.join(outdir, "broken.png"), "wb") as f:
        f.write(b"this is not an image\n" * 4)
    return _textured_quad(outdir, "unreadable_texture", "broken.png")


def missing_texture_obj(outdir):
    with open(os.path.join(outdir, "missing_texture_obj.mtl"), "w") as f:
        f.write("newmtl painted\nKd 0.8 0.2 0.1\nmap_Kd /nonexistent/machine/textures/wood.png\n")
    path = os.path.join(outdir, "missing_texture_obj.obj")
    with open(path, "w") as f:
        f.write("mtllib missing_texture_obj.mtl\n")
        for p in QUAD:
            f.write("v %g %g %g\n" % p)
        for u, v in QUAD_UV:
            f.write("vt %g %g\n" % (u, 1 - v))
        f.write("vn 0 0 1\nusemtl painted\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")
    return path


def ktx2_texture(outdir):
    # the KTX2 identifier and a header of zeros: enough to be recognised, nothing to decode
    with open(os.path.join(outdir, "wood.ktx2"), "wb") as f:
        f.write(b"\xabKTX 20\xbb\r\n\x1a\n" + bytes(68))
    g = Doc()
    g.images.append({"uri": "wood.ktx2", "mimeType": "image/ktx2"})
    g.textures.append({"extensions": {"KHR_texture_basisu": {"source": 0}}})
    g.used.add("KHR_texture_basisu")
    g.required.add("KHR_texture_basisu")
    mat = g.material({"name": "basis", "pbrMetallicRoughness": {
        "baseColorFactor": [0.3, 0.6, 0.9, 1], "baseColorTexture": {"index": 0}}})
    m = g.mesh("quad", {"POSITION": g.accessor(FLOAT, QUAD, minmax=True),
                        "TEXCOORD_0": g.accessor(FLOAT, QUAD_UV)}, QUAD_TRIS, mat)
    g.nodes.append({"name": "quad", "mesh": m})
    return g.write(outdir, "ktx2_texture")


def quantized_short(outdir):
    g = Doc()
    g.used.add("KHR_mesh_quantization")
    g.required.add("KHR_mesh_quantization")
    pos = [(-32767, -32767, 0), (32767, -32767, 0), (32767, 32767, 0), (-32767, 32767, 0)]
    uv = [(0, 65535), (65535, 65535), (65535, 0), (0, 0)]
    m = g.mesh("quad", {"POSITION": g.accessor(SHORT, pos, normalized=True, minmax=True),
                        "NORMAL": g.accessor(BYTE, [(0, 0, 127)] * 4, normalized=True),
                        "TEXCOORD_0": g.accessor(USHORT, uv, normalized=True)},
               QUAD_TRIS, g.material(WHITE))
    g.nodes.append({"name": "quad", "mesh": m, "scale": [0.5, 0.5, 0.5]})
    return g.write(outdir, "quantized_short")


def quantized_byte(outdir):
    g = Doc()
    g.used.add("KHR_mesh_quantization")
    g.required.add("KHR_mesh_quantization")
    pos = [(0, 0, 0), (4, 0, 0), (4, 4, 0), (0, 4, 0)]
    m = g.mesh("quad", {"POSITION": g.accessor(UBYTE, pos, minmax=True),
                        "NORMAL": g.accessor(SHORT, [(0, 0, 32767)] * 4, normalized=True)},
               QUAD_TRIS, g.material(WHITE))
    g.nodes.append({"name": "quad", "mesh": m, "translation": [-0.5, -0.5, 0],
                    "scale": [0.25, 0.25, 1]})
    return g.write(outdir, "quantized_byte")


def cube(half):
    """A cube's 24 vertices (4 per face, flat normals) and 36 indices."""
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            u, v = [(axis + 1) % 3, (axis + 2) % 3][::sign]
            base = len(pos)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0, 0, 0]
                p[axis], p[u], p[v] = sign * half, a * half, b * half
                pos.append(tuple(p))
                nrm.append(tuple(n))
            idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, idx


GRID = [(0.3 * i - 0.6, 0.3 * j - 0.6, 0.3 * k - 0.6)
        for i in range(5) for j in range(5) for k in range(5)]


def instanced(outdir):
    g = Doc()
    g.used.add("EXT_mesh_gpu_instancing")
    pos, nrm, idx = cube(0.05)
    m = g.mesh("box", {"POSITION": g.accessor(FLOAT, pos, minmax=True),
                       "NORMAL": g.accessor(FLOAT, nrm)}, idx,
               g.material({"name": "grey", "pbrMetallicRoughness": {
                   "baseColorFactor": [0.7, 0.7, 0.7, 1]}}))
    n = len(GRID)
    attrs = {"TRANSLATION": g.accessor(FLOAT, GRID, attribute=False),
             "ROTATION": g.accessor(SHORT, [(0, 0, 0, 32767)] * n, normalized=True,
                                    attribute=False),
             "SCALE": g.accessor(FLOAT, [(1, 1, 1)] * n, attribute=False)}
    g.nodes.append({"name": "grid", "mesh": m, "translation": [0, 0, -1],
                    "extensions": {"EXT_mesh_gpu_instancing": {"attributes": attrs}}})
    return g.write(outdir, "instanced")


def _grey(g):
    return g.material({"name": "grey", "pbrMetallicRoughness": {
        "baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0, "roughnessFactor": 0.8}})


def _channel(g, node, path, times, values):
    return ({"input": g.accessor(FLOAT, [(t,) for t in times], attribute=False, minmax=True),
             "output": g.accessor(FLOAT, values, attribute=False), "interpolation": "LINEAR"},
            {"sampler": None, "target": {"node": node, "path": path}})


def _animations(g, channels):
    samplers, chans = [], []
    for sampler, chan in channels:
        chan["sampler"] = len(samplers)
        samplers.append(sampler)
        chans.append(chan)
    return [{"name": "motion", "samplers": samplers, "channels": chans}]


def odd_clip(outdir):
    g = Doc()
    m = g.mesh("quad", {"POSITION": g.accessor(FLOAT, QUAD, minmax=True),
                        "NORMAL": g.accessor(FLOAT, [(0, 0, 1)] * 4)}, QUAD_TRIS, _grey(g))
    g.nodes.append({"name": "quad", "mesh": m})
    anims = _animations(g, [_channel(g, 1, "translation", [0.0, 41 / 12], [(0, 0, 0), (0.2, 0, 0)])])
    path = g.write(outdir, "odd_clip")
    with open(path) as f:
        doc = json.load(f)
    doc["animations"] = anims
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
    return path


def dark_stage(outdir):
    g = Doc()
    g.used.add("EXT_mesh_gpu_instancing")
    grey = _grey(g)
    pos, nrm, idx = cube(0.1)
    box = g.mesh("box", {"POSITION": g.accessor(FLOAT, pos, minmax=True),
                         "NORMAL": g.accessor(FLOAT, nrm)}, idx, grey)
    grid = [(0.3 * i - 0.3, 0.3 * j - 0.3, 0.3 * k - 0.3)
            for i in range(3) for j in range(3) for k in range(3)]
    inst = {"TRANSLATION": g.accessor(FLOAT, grid, attribute=False)}
    g.nodes.append({"name": "grid", "mesh": box, "translation": [0, 0.15, -0.5],
                    "extensions": {"EXT_mesh_gpu_instancing": {"attributes": inst}}})
    strip = [(-0.9, -0.95, 0), (0.9, -0.95, 0), (0.9, -0.75, 0), (-0.9, -0.75, 0)]
    m = g.mesh("strip", {"POSITION": g.accessor(FLOAT, strip, minmax=True),
                         "NORMAL": g.accessor(FLOAT, [(0, 0, 1)] * 4)}, QUAD_TRIS, grey)
    g.nodes.append({"name": "strip", "mesh": m})
    flare = [(-0.15, -0.15, 0), (0.15, -0.15, 0), (0.15, 0.15, 0), (-0.15, 0.15, 0)]
    glow = g.material({"name": "flare", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]},
                       "emissiveFactor": [1, 1, 1],
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20}}})
    m = g.mesh("flare", {"POSITION": g.accessor(FLOAT, flare, minmax=True),
                         "NORMAL": g.accessor(FLOAT, [(0, 0, 1)] * 4)}, QUAD_TRIS, glow)
    g.nodes.append({"name": "flare", "mesh": m, "translation": [2.0, -0.4, 0]})
    h = math.sqrt(0.5)
    anims = _animations(g, [
        _channel(g, 1, "rotation", [0.0, 0.5, 1.0],
                 [(0, 0, 0, 1), (0, math.sin(math.pi / 8), 0, math.cos(math.pi / 8)), (0, h, 0, h)]),
        _channel(g, 3, "translation", [0.0, 0.5, 1.0], [(2.0, -0.4, 0), (2.0, -0.4, 0), (0.7, -0.4, 0)])])
    path = g.write(outdir, "dark_stage")
    with open(path) as f:
        doc = json.load(f)
    doc["animations"] = anims
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
    return path


def to_glb(gltf_path):
    """The same document as a GLB beside it (buffer 0 moved into the BIN chunk): its path."""
    with open(gltf_path) as f:
        doc = json.load(f)
    uri = doc["buffers"][0].pop("uri")
    data = base64.b64decode(uri.split(",", 1)[1])
    data += b"\0" * (-len(data) % 4)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = (struct.pack("<I", len(text)) + b"JSON" + text +
            struct.pack("<I", len(data)) + b"BIN\0" + data)
    path = gltf_path[:-5] + ".glb"
    with open(path, "wb") as f:
        f.write(b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)
    return path


ASSETS = [missing_texture, unreadable_texture, missing_texture_obj, ktx2_texture,
          quantized_short, quantized_byte, instanced, odd_clip, dark_stage]


def write_all(outdir):
    """Every asset, and GLB copies of the quantized and instanced ones (NAME_glb)."""
    os.makedirs(outdir, exist_ok=True)
    paths = {f.__name__: f(outdir) for f in ASSETS}
    for name in ("quantized_short", "instanced"):
        paths[name + "_glb"] = to_glb(paths[name])
    return paths


if __name__ == "__main__":
    for name, path in write_all(sys.argv[1] if len(sys.argv) > 1 else ".").items():
        print(name, path)
