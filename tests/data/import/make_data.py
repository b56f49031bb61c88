#!/usr/bin/env python3
"""Writes the small scene files that tests/test_import.c, tests/test_anim.c and tests/test_clips.c load.

Run from anywhere: python3 tests/data/import/make_data.py (it writes next to itself). The files
are committed; this script documents what they hold and regenerates them. Standard library only.
glTF conventions: quaternions x, y, z, w; times in seconds; uv (0,0) at the image's top-left."""
import base64, json, math, os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def png(w, h, rgba):
    """An 8-bit RGBA PNG."""
    raw = b''.join(b'\0' + bytes(rgba[y * w * 4:(y + 1) * w * 4]) for y in range(h))
    def chunk(t, d):
        return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 6, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))


# 2x2 sRGB image: red, (0,128,255), black, white with alpha 128
CHECKER = png(2, 2, [255, 0, 0, 255, 0, 128, 255, 255, 0, 0, 0, 255, 255, 255, 255, 128])


class Gltf:
    def __init__(self):
        self.bin = b''
        self.views = []
        self.acc = []
        self.d = {"asset": {"version": "2.0", "generator": "evray tests/data/import/make_data.py"}}

    def _view(self, data):
        while len(self.bin) % 4:
            self.bin += b'\0'
        off = len(self.bin)
        self.bin += data
        self.views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data)})
        return len(self.views) - 1

    def floats(self, vals, typ):
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[typ]
        v = self._view(struct.pack('<%df' % len(vals), *vals))
        a = {"bufferView": v, "componentType": 5126, "count": len(vals) // n, "type": typ}
        if typ in ("SCALAR", "VEC3"):
            a["min"] = [min(vals[i::n]) for i in range(n)]
            a["max"] = [max(vals[i::n]) for i in range(n)]
        self.acc.append(a)
        return len(self.acc) - 1

    def indices(self, idx):
        v = self._view(struct.pack('<%dH' % len(idx), *idx))
        self.acc.append({"bufferView": v, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
        return len(self.acc) - 1

    def image_view(self, data):
        return self._view(data)

    def finish(self, glb=False):
        d = dict(self.d)
        d["bufferViews"] = self.views
        d["accessors"] = self.acc
        if glb:
            binary = self.bin
            while len(binary) % 4:
                binary += b'\0'
            d["buffers"] = [{"byteLength": len(binary)}]
            j = json.dumps(d, separators=(',', ':')).encode()
            while len(j) % 4:
                j += b' '
            total = 12 + 8 + len(j) + 8 + len(binary)
            return (b'glTF' + struct.pack('<II', 2, total) + struct.pack('<I', len(j)) + b'JSON' + j +
                    struct.pack('<I', len(binary)) + b'BIN\0' + binary)
        d["buffers"] = [{"byteLength": len(self.bin),
                         "uri": "data:application/octet-stream;base64," + base64.b64encode(self.bin).decode()}]
        return json.dumps(d, indent=1).encode()


def cube(g):
    """A unit cube centred on the origin: positions accessor, indices accessor."""
    p = []
    for i in range(8):
        p += [0.5 if i & 1 else -0.5, 0.5 if i & 2 else -0.5, 0.5 if i & 4 else -0.5]
    idx = [0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5]
    return g.floats(p, "VEC3"), g.indices(idx)


def qaxis(axis, deg):
    """glTF quaternion (x, y, z, w) for a rotation of deg degrees about a unit axis."""
    h = math.radians(deg) / 2
    return [axis[0] * math.sin(h), axis[1] * math.sin(h), axis[2] * math.sin(h), math.cos(h)]


def write(name, data):
    with open(os.path.join(HERE, name), 'wb') as f:
        f.write(data)


# ---- anim.gltf: interpolation modes, Assimp quirks, spinning and a hierarchy ----------------
def anim():
    g = Gltf()
    pos, idx = cube(g)
    nodes, samplers, channels = [], [], []

    def node(n):
        nodes.append(n)
        return len(nodes) - 1

    def channel(nd, path, times, values, interp="LINEAR"):
        typ = "VEC4" if path == "rotation" else "VEC3"
        samplers.append({"input": g.floats(times, "SCALAR"), "output": g.floats(values, typ), "interpolation": interp})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": nd, "path": path}})

    # LINEAR translation with a bend at t = 1 s, LINEAR scale
    n = node({"name": "lin_t", "mesh": 0})
    channel(n, "translation", [0, 1, 2], [0, 0, 0, 2, 4, 0, 2, 4, 6])
    n = node({"name": "lin_s", "mesh": 0})
    channel(n, "scale", [0, 2], [1, 1, 1, 3, 1, 2])
    # STEP translation and scale: Assimp 5.2 passes them as plain keys
    n = node({"name": "step_t", "mesh": 0})
    channel(n, "translation", [0, 1, 2], [0, 0, 0, 5, 0, 0, 7, 0, 0], "STEP")
    n = node({"name": "step_s", "mesh": 0})
    channel(n, "scale", [0, 1], [1, 1, 1, 2, 2, 2], "STEP")
    # slerp between q and -q' : the second key is the negated 90-degree turn about +Y, so the
    # shortest arc turns +90 degrees (45 at t = 0.5), not -270
    n = node({"name": "slerp", "mesh": 0})
    channel(n, "rotation", [0, 1], [0, 0, 0, 1] + [-c for c in qaxis([0, 1, 0], 90)])
    # spinning 270 degrees about Z in 0.3 s through 4 keys, moving at constant velocity
    n = node({"name": "spin", "mesh": 0})
    channel(n, "rotation", [0, 0.1, 0.2, 0.3], sum((qaxis([0, 0, 1], a) for a in (0, 90, 180, 270)), []))
    channel(n, "translation", [0, 0.3], [0, 0, 0, 3, 0, 0])
    # a parent turning 270 degrees about Y, a child offset along X with its own scale animation
    child = len(nodes) + 1
    n = node({"name": "parent", "children": [child], "translation": [0, 1, 0]})
    channel(n, "rotation", [0, 0.1, 0.2, 0.3], sum((qaxis([0, 1, 0], a) for a in (0, 90, 180, 270)), []))
    c = node({"name": "child", "mesh": 0, "translation": [2, 0, 0]})
    assert c == child
    channel(c, "scale", [0, 0.3], [1, 1, 1, 1, 2, 1])
    # CUBICSPLINE: per key in-tangent (9s), value, out-tangent (8s)
    n = node({"name": "cubic", "mesh": 0})
    channel(n, "translation", [0, 1, 2], [9, 9, 9, 0, 0, 0, 8, 8, 8,
                                          9, 9, 9, 1, 2, 3, 8, 8, 8,
                                          9, 9, 9, 4, 5, 6, 8, 8, 8], "CUBICSPLINE")
    # a node given by a matrix with skew and non-uniform scale (column-major), not animated
    node({"name": "mat_skew", "mesh": 0, "matrix": [1, 0, 0, 0, 0.5, 2, 0, 0, 0, 0, 3, 0, 4, 5, 6, 1]})
    # a matrix node (90 degrees about X, scale 1 2 3, translation 1 1 1) with a translation
    # channel: Assimp synthesizes identity rotation and unit scale keys for it
    n = node({"name": "mat_anim", "mesh": 0,
              "matrix": [1, 0, 0, 0, 0, 0, 2, 0, 0, -3, 0, 0, 1, 1, 1, 1]})
    channel(n, "translation", [0, 2], [1, 1, 1, 1, 1, 5])
    # TRS node whose only channel is rotation: translation and scale stay at rest
    n = node({"name": "trs_rot", "mesh": 0, "translation": [1, 2, 3], "scale": [2, 2, 2]})
    channel(n, "rotation", [0, 2], qaxis([1, 0, 0], 0) + qaxis([1, 0, 0], 90))
    # cameras: yfov 0.5 with aspect 2 at (0, 1, 10); yfov 0.7 without aspect, turned 90 about Y
    node({"name": "cam_main", "camera": 0, "translation": [0, 1, 10]})
    node({"name": "cam_side", "camera": 1, "translation": [10, 0, 0], "rotation": qaxis([0, 1, 0], 90)})
    # a static node
    node({"name": "static", "mesh": 0, "translation": [0, -3, 0]})

    roots = [i for i in range(len(nodes)) if i != child]
    g.d.update({"scene": 0, "scenes": [{"nodes": roots}], "nodes": nodes,
                "meshes": [{"name": "cube", "primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
                "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 2.0, "znear": 0.1}},
                            {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.05}}],
                "animations": [{"name": "main", "samplers": samplers, "channels": channels}]})
    write("anim.gltf", g.finish())


# ---- lights.gltf / lights.glb: KHR_lights_punctual, textures, materials -------------------
def lights(glb):
    g = Gltf()
    pos, idx = cube(g)
    uv = g.floats([0.25, 0.75, 0.5, 0.125, 1, 1], "VEC2")
    tri = g.floats([0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3")
    tri_idx = g.indices([0, 1, 2])
    pts = g.floats([0, 0, 0, 5, 5, 5], "VEC3")
    if glb:
        img0 = {"bufferView": g.image_view(CHECKER), "mimeType": "image/png"}
    else:
        img0 = {"uri": "data:image/png;base64," + base64.b64encode(CHECKER).decode()}
    g.d.update({
        "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6]}],
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "bulb", "type": "point", "color": [1, 0.5, 0.25], "intensity": 10},
            {"name": "torch", "type": "spot", "intensity": 5, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
            {"name": "sun", "type": "directional", "color": [0, 1, 0], "intensity": 3}]}},
        "nodes": [
            {"name": "box_emb", "mesh": 0},
            {"name": "tri_ext", "mesh": 1, "translation": [2, 0, 0]},
            {"name": "bulb_node", "translation": [1, 2, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "torch_node", "translation": [0, 4, 0], "rotation": qaxis([1, 0, 0], -90),
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "sun_node", "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"name": "tri_ext2", "mesh": 2, "translation": [-2, 0, 0]},
            {"name": "points", "mesh": 3}],
        "images": [img0, {"uri": "checker.png"}],
        "textures": [{"source": 0}, {"source": 1}],
        "materials": [
            {"name": "embedded", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 1],
             "baseColorTexture": {"index": 0}, "metallicFactor": 0.25, "roughnessFactor": 0.75},
             "emissiveFactor": [1, 0.5, 0],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}},
            {"name": "external", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
            {"name": "external_again", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1},
             "metallicFactor": 0}}],
        "meshes": [
            {"name": "box", "primitives": [{"attributes": {"POSITION": pos}, "indices": idx, "material": 0}]},
            {"name": "tri", "primitives": [{"attributes": {"POSITION": tri, "TEXCOORD_0": uv}, "indices": tri_idx, "material": 1}]},
            {"name": "tri2", "primitives": [{"attributes": {"POSITION": tri, "TEXCOORD_0": uv}, "indices": tri_idx, "material": 2}]},
            {"name": "dots", "primitives": [{"attributes": {"POSITION": pts}, "mode": 0}]}]})
    write("lights.glb" if glb else "lights.gltf", g.finish(glb))


# ---- plain.gltf: one cube, no camera, no light ----------------------------------------------
def plain():
    g = Gltf()
    pos, idx = cube(g)
    g.d.update({"scene": 0, "scenes": [{"nodes": [0, 1]}],
                "nodes": [{"name": "a", "mesh": 0, "translation": [1, 0, 0]}, {"name": "b", "mesh": 0, "translation": [-1, 0, 0]}],
                "meshes": [{"name": "cube", "primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}]})
    write("plain.gltf", g.finish())


# ---- lines.gltf: points and lines only ------------------------------------------------------
def lines():
    g = Gltf()
    p = g.floats([0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0], "VEC3")
    g.d.update({"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "wire", "mesh": 0}],
                "meshes": [{"name": "wire", "primitives": [{"attributes": {"POSITION": p}, "mode": 1},
                                                          {"attributes": {"POSITION": p}, "mode": 0}]}]})
    write("lines.gltf", g.finish())


# ---- clips.gltf: clips that share nodes and clips that do not (src/scene/import_clips.c) -------
def clips():
    g = Gltf()
    pos, idx = cube(g)
    up = g.floats([0, 1, 0] * 8, "VEC3")  # a morph target lifting the whole cube by 1
    anims = []

    def clip(name, channels):
        samplers, chans = [], []
        for nd, path, times, values in channels:
            typ = {"rotation": "VEC4", "weights": "SCALAR"}.get(path, "VEC3")
            samplers.append({"input": g.floats(times, "SCALAR"), "output": g.floats(values, typ)})
            chans.append({"sampler": len(samplers) - 1, "target": {"node": nd, "path": path}})
        a = {"samplers": samplers, "channels": chans}
        if name is not None:
            a["name"] = name
        anims.append(a)

    clip("walk", [(0, "translation", [0, 1], [0, 0, 0, 2, 0, 0])])     # a: +X, 1 s
    clip("run", [(0, "translation", [0, 0.5], [0, 0, 0, 0, 3, 0]),      # a: +Y and taller, 0.5 s
                 (0, "scale", [0, 0.5], [1, 1, 1, 1, 2, 1])])
    clip("wave", [(1, "rotation", [0, 1.3], qaxis([0, 0, 1], 0) + qaxis([0, 0, 1], 90))])  # b alone
    clip("blink", [(0, "weights", [0, 0.8], [0, 1])])                   # a's morph weight
    clip(None, [(2, "translation", [0.25, 0.75], [0, 0, 5, 0, 0, 6])])  # c alone, unnamed
    g.d.update({"scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
                "nodes": [{"name": "a", "mesh": 0}, {"name": "b", "mesh": 1, "translation": [3, 0, 0]},
                          {"name": "c", "mesh": 1, "translation": [0, 0, 5]}],
                "meshes": [{"name": "morph_cube", "weights": [0],
                            "primitives": [{"attributes": {"POSITION": pos}, "indices": idx,
                                            "targets": [{"POSITION": up}]}]},
                           {"name": "cube", "primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}],
                "animations": anims})
    write("clips.gltf", g.finish())


# ---- camera.3ds: a 3DS camera (Z-up) with a keyframer section ------------------------------------
def camera_3ds():
    """An L of 4 triangles in the 3DS XZ plane (y = 0, facing -Y): a bar x 0..2, z 0..0.5 and a bar
    x 0..0.5, z 0..2. Camera01 at (1, -10, 1) looks at (1, 0, 1) (along +Y), bank 0, lens
    43.456 mm (45 degrees across 3ds Max's 36 mm film). The keyframer section gives the camera's
    node one position key, (1, -10, 1), which Assimp also keeps in mPosition."""
    def chunk(cid, data):
        return struct.pack('<HI', cid, 6 + len(data)) + data

    def cstr(text):
        return text.encode() + b'\0'

    verts = [(0, 0, 0), (2, 0, 0), (2, 0, 0.5), (0.5, 0, 0.5), (0.5, 0, 2), (0, 0, 2)]
    faces = [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]
    vdata = struct.pack('<H', len(verts)) + b''.join(struct.pack('<3f', *v) for v in verts)
    fdata = struct.pack('<H', len(faces)) + b''.join(struct.pack('<4H', a, b, c, 0) for a, b, c in faces)
    mesh = chunk(0x4000, cstr('shape') + chunk(0x4100, chunk(0x4110, vdata) + chunk(0x4120, fdata)))
    cam = chunk(0x4000, cstr('Camera01') + chunk(0x4700, struct.pack('<8f', 1, -10, 1, 1, 0, 1, 0, 43.456)))
    edit = chunk(0x3D3D, chunk(0x3D3E, struct.pack('<I', 3)) + mesh + cam)

    def node(name):
        return chunk(0xB010, cstr(name) + struct.pack('<HHH', 0, 0, 0xFFFF))

    def position(p):  # one key at frame 0, no TCB data
        return chunk(0xB020, struct.pack('<5H', 0, 0, 0, 0, 0) + struct.pack('<IIH', 1, 0, 0) + struct.pack('<3f', *p))
    kf = chunk(0xB000, chunk(0xB00A, struct.pack('<H', 5) + cstr('MAXSCENE') + struct.pack('<I', 100)) +
               chunk(0xB002, node('shape')) + chunk(0xB003, node('Camera01') + position((1, -10, 1))) +
               chunk(0xB004, node('Camera01') + position((1, 0, 1))))
    write("camera.3ds", chunk(0x4D4D, chunk(0x0002, struct.pack('<I', 3)) + edit + kf))


anim()
clips()
lights(False)
lights(True)
plain()
lines()
camera_3ds()
write("checker.png", CHECKER)
