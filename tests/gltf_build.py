"""The tests' one glTF 2.0 writer: the test scenes (tests/material_assets.py,
tests/filter_assets.py, tests/deform_assets.py, tests/all_materials.py, the small scenes of
tests/evrtest.py and tests/test_texture_motion.py) describe what they hold; this module packs it.

Standard library only (the tests run with /usr/bin/python3): PNG images written by hand with zlib;
the buffer (and images, unless a test gives a file name) embedded as base64 data: URIs, or the
whole document as GLB.

Gltf accumulates one buffer with its views and accessors, images, samplers, textures, materials,
meshes, nodes, cameras, KHR_lights_punctual lights, skins and animations, and makes the document:
    g = Gltf()
    g.camera()                                    # node "camera" at the origin, looking along -Z
    g.light("lamp", "point", 1.0)                 # node "lamp", a white 1 cd point light
    m = g.material({"name": "grey"})
    g.mesh_node("quad", *rect(-0.5, 0.5, -0.5, 0.5, -1.0), m)
    g.write("quad.gltf")
Every list is a public attribute (g.nodes, g.meshes, ...) for what the helpers do not cover;
g.roots (the scene's nodes) lists the nodes added with root=True.
"""
import base64
import json
import math
import struct
import zlib

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
CLAMP_TO_EDGE, LINEAR = 33071, 9729
_FMT = {FLOAT: "f", UBYTE: "B", USHORT: "H", UINT: "I"}
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
# an animation channel's values per key, by the property it drives
_PATH_DIM = {"translation": 3, "scale": 3, "rotation": 4, "weights": 1}

# yfov = 2 atan(0.5): the plane z = -d spans [-d/2, d/2] in x and y (aspect 1)
YFOV = 2 * math.atan(0.5)


def png_bytes(width, height, pixels, channels=4):
    """An 8-bit PNG of pixels (rows top first): channels 4 (RGBA), 3 (RGB) or 1 (grey; a texel
    may then be an int)."""
    raw = bytearray()
    for y in range(height):
        raw.append(0)  # filter: none
        for x in range(width):
            p = pixels[y * width + x]
            raw += bytes((p,) if isinstance(p, int) else p)

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data +
                struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    colour_type = {1: 0, 3: 2, 4: 6}[channels]
    ihdr = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
            chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


def data_uri(raw, mime="application/octet-stream"):
    return "data:%s;base64,%s" % (mime, base64.b64encode(bytes(raw)).decode("ascii"))


def glb_bytes(doc, binary=None):
    """The document as a GLB. binary: the BIN chunk; None: the document's one buffer, taken out
    of its data: URI (the document is not changed)."""
    doc = json.loads(json.dumps(doc))
    if binary is None:
        binary = base64.b64decode(doc["buffers"][0].pop("uri").split(",", 1)[1])
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary = bytes(binary) + b"\0" * (-len(binary) % 4)
    return (struct.pack("<4sII", b"glTF", 2, 28 + len(text) + len(binary)) +
            struct.pack("<I4s", len(text), b"JSON") + text +
            struct.pack("<I4s", len(binary), b"BIN\0") + binary)


def quaternion(axis, degrees):
    """glTF's (x, y, z, w) for a turn of degrees about a unit axis."""
    h = math.radians(degrees) / 2
    return tuple(math.sin(h) * a for a in axis) + (math.cos(h),)


# ---- geometry: (positions, normals, uvs, indices) ----

def rect(x0, x1, y0, y1, z, mirrored=False, facing=1):
    """A rectangle in the plane z, uv (0, 0) at its top-left corner (u across x, v down y;
    mirrored: u flips). facing +1: normal +Z, counter-clockwise seen from +Z; -1: normal -Z,
    wound the other way (its front faces -Z)."""
    pos = [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)]
    uv = []
    for x, y, _ in pos:
        u = (x - x0) / (x1 - x0)
        uv.append((1 - u if mirrored else u, (y1 - y) / (y1 - y0)))
    idx = [0, 1, 2, 0, 2, 3] if facing > 0 else [0, 2, 1, 0, 3, 2]
    return pos, [(0, 0, facing)] * 4, uv, idx


def box(x0, x1, y0, y1, z0, z1):
    """An axis-aligned box with flat faces (4 vertices each, outward normals, uv over each)."""
    pos, nrm, uv, idx = [], [], [], []
    c = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    faces = [((0, 2, 3, 1), (0, 0, -1)), ((4, 5, 7, 6), (0, 0, 1)), ((0, 1, 5, 4), (0, -1, 0)),
             ((2, 6, 7, 3), (0, 1, 0)), ((0, 4, 6, 2), (-1, 0, 0)), ((1, 3, 7, 5), (1, 0, 0))]
    for corners, n in faces:
        base = len(pos)
        for k, ci in enumerate(corners):
            pos.append(c[ci])
            nrm.append(n)
            uv.append(((0, 1, 1, 0)[k], (0, 0, 1, 1)[k]))
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv, idx


def uv_sphere(radius=0.4, segments=24, rings=12):
    """A UV sphere about the origin: u = segment / segments, v = ring / rings, the vertex at
    r (sin(th) sin(ph), cos(th), sin(th) cos(ph)) with ph = 2 pi u, th = pi v (u = 0 faces +z,
    v = 0 is the north pole +Y). The seam column is duplicated (u = 0 and 1)."""
    pos, nrm, uv, idx = [], [], [], []
    for j in range(rings + 1):
        th = math.pi * j / rings
        for i in range(segments + 1):
            ph = 2 * math.pi * i / segments
            n = (math.sin(th) * math.sin(ph), math.cos(th), math.sin(th) * math.cos(ph))
            pos.append(tuple(radius * c for c in n))
            nrm.append(n)
            uv.append((i / segments, j / rings))
    w = segments + 1
    for j in range(rings):
        for i in range(segments):
            a, b, c, d = j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i
            if j > 0:
                idx += [a, d, b]
            if j < rings - 1:
                idx += [b, d, c]
    return pos, nrm, uv, idx


def _extensions_in(obj, found):
    """Every extension named under an "extensions" key anywhere in obj (a material and its
    texture references)."""
    if isinstance(obj, dict):
        for key, value in obj.items():
            if key == "extensions" and isinstance(value, dict):
                found.update(value)
            _extensions_in(value, found)
    elif isinstance(obj, list):
        for value in obj:
            _extensions_in(value, found)


class Gltf:
    """One glTF document under construction (see the module's comment)."""

    def __init__(self, generator=None):
        self.generator = generator
        self.data = bytearray()
        self.views, self.accessors = [], []
        self.images, self.samplers, self.textures = [], [], []
        self.materials, self.meshes, self.nodes = [], [], []
        self.roots = []
        self.cameras, self.lights, self.skins, self.animations = [], [], [], []
        self.used = set()

    # ---- the buffer ----

    def accessor(self, ctype, values, minmax=False):
        """Appends values (scalars, or equal-length tuples) as one view and accessor, 4-byte
        aligned; minmax: with their bounds (POSITION and animation inputs need them)."""
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

    # ---- images and materials ----

    def image(self, png=None, name=None, uri=None):
        """An image: png bytes embedded, or uri (a file beside the document). Its index."""
        img = {"uri": uri if uri is not None else data_uri(png, "image/png")}
        if name is not None:
            img = {"name": name, **img}
        self.images.append(img)
        return len(self.images) - 1

    def sampler(self, **fields):
        self.samplers.append(fields)
        return len(self.samplers) - 1

    def texture(self, image, sampler=None):
        """A texture of image (an index of image()), with a sampler index or the default."""
        tex = {"source": image}
        if sampler is not None:
            tex["sampler"] = sampler
        self.textures.append(tex)
        return len(self.textures) - 1

    def material(self, mat):
        """Adds a material (a glTF material dict); the extensions it names are listed used."""
        _extensions_in(mat, self.used)
        self.materials.append(mat)
        return len(self.materials) - 1

    # ---- meshes and nodes ----

    def primitive(self, positions, indices, material=None, normals=None, uvs=None, uvs1=None,
                  tangents=None, index_type=USHORT):
        """A triangle-list primitive (a dict for mesh()); positions with their bounds."""
        attrs = {"POSITION": self.accessor(FLOAT, positions, minmax=True)}
        for key, values in (("NORMAL", normals), ("TEXCOORD_0", uvs), ("TEXCOORD_1", uvs1),
                            ("TANGENT", tangents)):
            if values is not None:
                attrs[key] = self.accessor(FLOAT, values)
        prim = {"attributes": attrs, "indices": self.accessor(index_type, indices)}
        if material is not None:
            prim["material"] = material
        return prim

    def mesh(self, name, primitives, weights=None):
        self.meshes.append({"name": name, "primitives": primitives})
        if weights is not None:
            self.meshes[-1]["weights"] = weights
        return len(self.meshes) - 1

    def node(self, name=None, root=True, **fields):
        """A node (fields: translation, rotation, scale, mesh, children, ...); root: one of the
        scene's nodes. Its index."""
        node = {} if name is None else {"name": name}
        node.update({k: list(v) if isinstance(v, tuple) else v for k, v in fields.items()})
        self.nodes.append(node)
        if root:
            self.roots.append(len(self.nodes) - 1)
        return len(self.nodes) - 1

    def mesh_node(self, name, positions, normals, uvs, indices, material, tangents=None, uvs1=None,
                  index_type=USHORT, **fields):
        """One primitive's mesh under a node of the same name. The node's index."""
        prim = self.primitive(positions, indices, material, normals, uvs, uvs1, tangents,
                              index_type)
        return self.node(name, mesh=self.mesh(name, [prim]), **fields)

    def camera(self, name="camera", yfov=YFOV, aspect=1.0, znear=0.01, **fields):
        """A perspective camera under a node (no rotation: looking along -Z). The node's index."""
        self.cameras.append({"type": "perspective", "perspective": {
            "yfov": yfov, "aspectRatio": aspect, "znear": znear}})
        return self.node(name, camera=len(self.cameras) - 1, **fields)

    def light(self, name, kind, intensity, color=(1, 1, 1), radius=None, spot=None, **fields):
        """A KHR_lights_punctual light (kind point, spot or directional; radius: evray's
        extras.radius, a sphere light) under a node. The node's index."""
        light = {"name": name, "type": kind, "color": list(color), "intensity": intensity}
        if spot is not None:
            light["spot"] = spot
        if radius is not None:
            light["extras"] = {"radius": radius}
        self.lights.append(light)
        self.used.add("KHR_lights_punctual")
        return self.node(name, extensions={"KHR_lights_punctual": {"light": len(self.lights) - 1}},
                         **fields)

    def animation(self, channels, name=None):
        """An animation of channels (node, path, times, values[, interpolation]), one sampler
        each (LINEAR unless given); values flat or as tuples. Its index."""
        anim = {"samplers": [], "channels": []}
        if name is not None:
            anim = {"name": name, **anim}
        for node, path, times, values, *interp in channels:
            dim = _PATH_DIM[path]
            if dim > 1 and not isinstance(values[0], (tuple, list)):
                values = [tuple(values[i:i + dim]) for i in range(0, len(values), dim)]
            anim["samplers"].append({"input": self.accessor(FLOAT, times, minmax=True),
                                     "output": self.accessor(FLOAT, values),
                                     "interpolation": interp[0] if interp else "LINEAR"})
            anim["channels"].append({"sampler": len(anim["samplers"]) - 1,
                                     "target": {"node": node, "path": path}})
        self.animations.append(anim)
        return len(self.animations) - 1

    # ---- the document ----

    def document(self):
        """The glTF document (a dict), the buffer embedded; empty lists are left out."""
        while len(self.data) % 4:
            self.data.append(0)
        doc = {"asset": {"version": "2.0"}}
        if self.generator:
            doc["asset"]["generator"] = self.generator
        if self.used:
            doc["extensionsUsed"] = sorted(self.used)
        if self.lights:
            doc["extensions"] = {"KHR_lights_punctual": {"lights": self.lights}}
        doc.update({"scene": 0, "scenes": [{"nodes": self.roots}]})
        for key, value in (("nodes", self.nodes), ("meshes", self.meshes),
                           ("materials", self.materials), ("cameras", self.cameras),
                           ("skins", self.skins), ("animations", self.animations),
                           ("images", self.images), ("samplers", self.samplers),
                           ("textures", self.textures), ("accessors", self.accessors),
                           ("bufferViews", self.views)):
            if value:
                doc[key] = value
        if self.data:
            doc["buffers"] = [{"byteLength": len(self.data), "uri": data_uri(self.data)}]
        return doc

    def write(self, path, indent=None):
        """Writes the document as glTF JSON (a .gltf path) or GLB (.glb). Returns path."""
        doc = self.document()
        if path.endswith(".glb"):
            with open(path, "wb") as f:
                f.write(glb_bytes(doc))
        else:
            with open(path, "w") as f:
                json.dump(doc, f, indent=indent)
        return path
