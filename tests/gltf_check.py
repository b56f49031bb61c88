"""A structural check of a binary glTF 2.0 file against the rules of the specification that the
built-in scenes use (standard library only): the GLB layout; buffer views and accessors inside
their data; mesh attributes of the right types and counts, POSITION bounds that match the data,
indices in range; skins (distinct joints with a common root, a skeleton at or above it, MAT4
float inverse bind matrices with last row 0 0 0 1); JOINTS_0 / WEIGHTS_0 (unsigned byte or short
joints inside the skin, weights >= 0 summing to 1, no joint twice); morph targets (the same count
everywhere, POSITION bounds, mesh and node weights of that length); animations (increasing key
times with bounds, outputs of keys x components, unit rotations, "weights" only on morph meshes,
keys x targets values, each node and path once per animation); materials (factors in range,
texture slots naming textures, KHR_texture_transform with offset/scale pairs, alphaMode, the
KHR_materials extensions' values), TANGENT (VEC4 floats, w = +-1, with NORMAL), lights (a radius
in extras >= 0, none on directional lights), and every extension used listed in extensionsUsed.
check(path) returns the parsed
document and a list of problems (empty when the file passes)."""
import json
import math
import struct

FLOAT, UBYTE, USHORT, UINT, BYTE, SHORT = 5126, 5121, 5123, 5125, 5120, 5122
_FMT = {FLOAT: "f", UBYTE: "B", USHORT: "H", UINT: "I", BYTE: "b", SHORT: "h"}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class Glb:
    def __init__(self, path):
        data = open(path, "rb").read()
        self.problems = []
        magic, version, length = struct.unpack_from("<4sII", data, 0)
        if magic != b"glTF" or version != 2 or length != len(data):
            raise ValueError(f"{path}: not a GLB 2 file of its stated length")
        jlen, jtype = struct.unpack_from("<I4s", data, 12)
        if jtype != b"JSON" or jlen % 4:
            raise ValueError(f"{path}: the first chunk is not a 4-byte aligned JSON chunk")
        self.doc = json.loads(data[20:20 + jlen].decode("utf-8"))
        self.bin = b""
        if 20 + jlen < len(data):
            blen, btype = struct.unpack_from("<I4s", data, 20 + jlen)
            if btype != b"BIN\x00" or blen % 4 or 28 + jlen + blen != len(data):
                raise ValueError(f"{path}: bad BIN chunk")
            self.bin = data[28 + jlen:28 + jlen + blen]

    def bad(self, msg):
        self.problems.append(msg)

    def accessor(self, i):
        """The accessor's values as a list of tuples (one per element)."""
        a = self.doc["accessors"][i]
        v = self.doc["bufferViews"][a["bufferView"]]
        n, ct = _NCOMP[a["type"]], a["componentType"]
        size = struct.calcsize("<" + _FMT[ct])
        off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        if off % size:
            self.bad(f"accessor {i}: offset {off} not a multiple of its component size")
        if a["count"] * n * size > v["byteLength"] - a.get("byteOffset", 0):
            self.bad(f"accessor {i}: runs past its buffer view")
            return []
        flat = struct.unpack_from("<%d%s" % (a["count"] * n, _FMT[ct]), self.bin, off)
        if ct == FLOAT and not all(math.isfinite(x) for x in flat):
            self.bad(f"accessor {i}: non-finite values")
        return [flat[k * n:(k + 1) * n] for k in range(a["count"])]

    def expect(self, i, types, cts, what):
        a = self.doc["accessors"][i]
        if a["type"] not in types or a["componentType"] not in cts:
            self.bad(f"{what}: accessor {i} is {a['type']}/{a['componentType']}, wants {types}/{cts}")
        return a


def _bounds_match(g, i, vals, what):
    a = g.doc["accessors"][i]
    if "min" not in a or "max" not in a:
        g.bad(f"{what}: accessor {i} needs min and max")
        return
    for c in range(len(a["min"])):
        lo, hi = min(v[c] for v in vals), max(v[c] for v in vals)
        if abs(lo - a["min"][c]) > 1e-6 * max(1.0, abs(lo)) or abs(hi - a["max"][c]) > 1e-6 * max(1.0, abs(hi)):
            g.bad(f"{what}: accessor {i} bounds {a['min']}..{a['max']} are not its data's")


def _parents(g):
    parent = {}
    for i, n in enumerate(g.doc.get("nodes", [])):
        for c in n.get("children", []):
            if c in parent:
                g.bad(f"node {c} has two parents")
            parent[c] = i
    return parent


def _chain(parent, n):
    out = [n]
    while out[-1] in parent:
        out.append(parent[out[-1]])
        if len(out) > 100000:
            break
    return out


def check(path):
    g = Glb(path)
    d = g.doc
    nodes, meshes = d.get("nodes", []), d.get("meshes", [])
    if d.get("asset", {}).get("version") != "2.0":
        g.bad("asset.version is not 2.0")
    for i, v in enumerate(d.get("bufferViews", [])):
        if v.get("byteOffset", 0) + v["byteLength"] > len(g.bin):
            g.bad(f"bufferView {i} runs past the buffer")
    parent = _parents(g)
    targets_of = []
    for mi, m in enumerate(meshes):
        nt = None
        for p in m["primitives"]:
            at = p["attributes"]
            pos = g.accessor(at["POSITION"])
            g.expect(at["POSITION"], ["VEC3"], [FLOAT], f"mesh {mi} POSITION")
            _bounds_match(g, at["POSITION"], pos, f"mesh {mi} POSITION")
            count = len(pos)
            if "TANGENT" in at:
                if "NORMAL" not in at:
                    g.bad(f"mesh {mi}: TANGENT without NORMAL")
                if d["accessors"][at["TANGENT"]]["type"] == "VEC4" and \
                        any(t[3] not in (1.0, -1.0) for t in g.accessor(at["TANGENT"])):
                    g.bad(f"mesh {mi}: a TANGENT whose w is not +-1")
            if "material" in p and not 0 <= p["material"] < len(d.get("materials", [])):
                g.bad(f"mesh {mi}: no material {p['material']}")
            for name, types, cts in (("NORMAL", ["VEC3"], [FLOAT]), ("TEXCOORD_0", ["VEC2"], [FLOAT]),
                                     ("TANGENT", ["VEC4"], [FLOAT]),
                                     ("JOINTS_0", ["VEC4"], [UBYTE, USHORT]), ("WEIGHTS_0", ["VEC4"], [FLOAT])):
                if name in at:
                    g.expect(at[name], types, cts, f"mesh {mi} {name}")
                    if d["accessors"][at[name]]["count"] != count:
                        g.bad(f"mesh {mi}: {name} count differs from POSITION's")
            if ("JOINTS_0" in at) != ("WEIGHTS_0" in at):
                g.bad(f"mesh {mi}: JOINTS_0 without WEIGHTS_0 or the reverse")
            if "indices" in p and any(x[0] >= count for x in g.accessor(p["indices"])):
                g.bad(f"mesh {mi}: an index out of range")
            ts = p.get("targets", [])
            if nt is not None and len(ts) != nt:
                g.bad(f"mesh {mi}: primitives with different numbers of targets")
            nt = len(ts)
            for ti, t in enumerate(ts):
                for name, acc in t.items():
                    if name not in at:
                        g.bad(f"mesh {mi} target {ti}: {name} has no base attribute")
                    g.expect(acc, ["VEC3"], [FLOAT], f"mesh {mi} target {ti} {name}")
                    vals = g.accessor(acc)
                    if len(vals) != count:
                        g.bad(f"mesh {mi} target {ti}: {name} count differs from POSITION's")
                    if name == "POSITION":
                        _bounds_match(g, acc, vals, f"mesh {mi} target {ti} POSITION")
        nt = nt or 0
        targets_of.append(nt)
        if "weights" in m and len(m["weights"]) != nt:
            g.bad(f"mesh {mi}: {len(m['weights'])} weights for {nt} targets")
        names = m.get("extras", {}).get("targetNames")
        if names is not None and len(names) != nt:
            g.bad(f"mesh {mi}: {len(names)} target names for {nt} targets")
    for si, s in enumerate(d.get("skins", [])):
        js = s["joints"]
        if not js or len(set(js)) != len(js) or any(not 0 <= j < len(nodes) for j in js):
            g.bad(f"skin {si}: joints must be distinct nodes")
            continue
        common = set(_chain(parent, js[0]))
        for j in js[1:]:
            common &= set(_chain(parent, j))
        if not common:
            g.bad(f"skin {si}: the joints have no common root")
        elif "skeleton" in s and s["skeleton"] not in common:
            g.bad(f"skin {si}: skeleton is not the joints' common root or above it")
        if "inverseBindMatrices" in s:
            g.expect(s["inverseBindMatrices"], ["MAT4"], [FLOAT], f"skin {si} inverseBindMatrices")
            ibm = g.accessor(s["inverseBindMatrices"])
            if len(ibm) < len(js):
                g.bad(f"skin {si}: fewer inverse bind matrices than joints")
            if any((m[3], m[7], m[11], m[15]) != (0.0, 0.0, 0.0, 1.0) for m in ibm):
                g.bad(f"skin {si}: an inverse bind matrix whose last row is not 0 0 0 1")
    for ni, n in enumerate(nodes):
        m = meshes[n["mesh"]] if "mesh" in n else None
        if "skin" in n:
            if m is None:
                g.bad(f"node {ni}: a skin without a mesh")
                continue
            nj = len(d["skins"][n["skin"]]["joints"])
            for p in m["primitives"]:
                at = p["attributes"]
                if "JOINTS_0" not in at:
                    g.bad(f"node {ni}: skinned, but its mesh has no JOINTS_0")
                    continue
                for jv, wv in zip(g.accessor(at["JOINTS_0"]), g.accessor(at["WEIGHTS_0"])):
                    if any(j >= nj for j in jv):
                        g.bad(f"node {ni}: a joint index past its skin's {nj} joints")
                        break
                    nz = [j for j, w in zip(jv, wv) if w != 0]
                    if min(wv) < 0 or abs(sum(wv) - 1.0) > 1e-5 or len(set(nz)) != len(nz):
                        g.bad(f"node {ni}: weights {wv} on joints {jv}")
                        break
        if "weights" in n and (m is None or len(n["weights"]) != targets_of[n["mesh"]]):
            g.bad(f"node {ni}: weights do not match its mesh's targets")
    for ai, a in enumerate(d.get("animations", [])):
        seen = set()
        for c in a["channels"]:
            t, smp = c["target"], a["samplers"][c["sampler"]]
            key = (t["node"], t["path"])
            if key in seen:
                g.bad(f"animation {ai}: node {t['node']} {t['path']} twice")
            seen.add(key)
            g.expect(smp["input"], ["SCALAR"], [FLOAT], f"animation {ai} input")
            times = [x[0] for x in g.accessor(smp["input"])]
            _bounds_match(g, smp["input"], [(x,) for x in times], f"animation {ai} input")
            if any(b <= a_ for a_, b in zip(times, times[1:])) or times[0] < 0:
                g.bad(f"animation {ai}: key times not increasing from >= 0")
            per_key = 3 if smp.get("interpolation") == "CUBICSPLINE" else 1
            out = g.accessor(smp["output"])
            if t["path"] == "weights":
                n = nodes[t["node"]]
                nt = targets_of[n["mesh"]] if "mesh" in n else 0
                g.expect(smp["output"], ["SCALAR"], [FLOAT], f"animation {ai} weights output")
                if nt == 0:
                    g.bad(f"animation {ai}: weights on node {t['node']} without morph targets")
                elif len(out) != len(times) * nt * per_key:
                    g.bad(f"animation {ai}: {len(out)} weight values for {len(times)} keys x {nt} targets")
            else:
                want = "VEC4" if t["path"] == "rotation" else "VEC3"
                g.expect(smp["output"], [want], [FLOAT], f"animation {ai} {t['path']} output")
                if len(out) != len(times) * per_key:
                    g.bad(f"animation {ai}: {len(out)} outputs for {len(times)} keys")
                if t["path"] == "rotation" and any(abs(math.sqrt(sum(x * x for x in q)) - 1) > 1e-3 for q in out):
                    g.bad(f"animation {ai}: a rotation that is not a unit quaternion")
    _check_materials(g)
    return d, g.problems


def _in(v, lo, hi):
    return isinstance(v, (int, float)) and lo <= v <= hi


def _ext(obj, used, g, what):
    """The object's extensions, each checked to be listed in extensionsUsed."""
    ext = obj.get("extensions", {})
    for name in ext:
        if name not in used:
            g.bad(f"{what}: extension {name} is not in extensionsUsed")
    return ext


def _slot(g, used, info, what):
    if info is None:
        return
    if not 0 <= info.get("index", -1) < len(g.doc.get("textures", [])):
        g.bad(f"{what}: no texture {info.get('index')}")
    tt = _ext(info, used, g, what).get("KHR_texture_transform")
    if tt is not None:
        if len(tt.get("offset", [0, 0])) != 2 or len(tt.get("scale", [1, 1])) != 2 or \
                not math.isfinite(tt.get("rotation", 0.0)):
            g.bad(f"{what}: a bad KHR_texture_transform {tt}")


def _check_materials(g):
    d = g.doc
    used = set(d.get("extensionsUsed", []))
    lights = _ext(d, used, g, "document").get("KHR_lights_punctual", {}).get("lights", [])
    for li, l in enumerate(lights):
        r = l.get("extras", {}).get("radius")
        if r is not None and (not _in(r, 0.0, math.inf) or l.get("type") == "directional"):
            g.bad(f"light {li}: radius {r}")
    for ti, t in enumerate(d.get("textures", [])):
        if not 0 <= t.get("source", -1) < len(d.get("images", [])):
            g.bad(f"texture {ti}: no image")
    for mi, m in enumerate(d.get("materials", [])):
        w = f"material {mi}"
        pbr = m.get("pbrMetallicRoughness", {})
        if not all(_in(c, 0, 1) for c in pbr.get("baseColorFactor", [1, 1, 1, 1])) or \
                not _in(pbr.get("metallicFactor", 1), 0, 1) or not _in(pbr.get("roughnessFactor", 1), 0, 1) or \
                not all(_in(c, 0, 1) for c in m.get("emissiveFactor", [0, 0, 0])):
            g.bad(f"{w}: a factor outside [0,1]")
        for slot in ("baseColorTexture", "metallicRoughnessTexture"):
            _slot(g, used, pbr.get(slot), f"{w} {slot}")
        for slot in ("normalTexture", "occlusionTexture", "emissiveTexture"):
            _slot(g, used, m.get(slot), f"{w} {slot}")
        if not _in(m.get("occlusionTexture", {}).get("strength", 1), 0, 1):
            g.bad(f"{w}: occlusion strength outside [0,1]")
        if m.get("alphaMode", "OPAQUE") not in ("OPAQUE", "MASK", "BLEND") or not _in(m.get("alphaCutoff", 0.5), 0, math.inf):
            g.bad(f"{w}: bad alphaMode or alphaCutoff")
        if not isinstance(m.get("doubleSided", False), bool):
            g.bad(f"{w}: doubleSided is not a boolean")
        ext = _ext(m, used, g, w)
        tr = ext.get("KHR_materials_transmission")
        if tr is not None:
            if not _in(tr.get("transmissionFactor", 0), 0, 1):
                g.bad(f"{w}: transmissionFactor outside [0,1]")
            _slot(g, used, tr.get("transmissionTexture"), f"{w} transmissionTexture")
        ior = ext.get("KHR_materials_ior", {}).get("ior", 1.5)
        if not (ior == 0 or _in(ior, 1, math.inf)):
            g.bad(f"{w}: ior {ior}")
        vol = ext.get("KHR_materials_volume")
        if vol is not None and (not _in(vol.get("thicknessFactor", 0), 0, math.inf) or
                                not _in(vol.get("attenuationDistance", 1), 1e-30, math.inf) or
                                not all(_in(c, 0, 1) for c in vol.get("attenuationColor", [1, 1, 1]))):
            g.bad(f"{w}: bad KHR_materials_volume {vol}")
        sp = ext.get("KHR_materials_specular")
        if sp is not None and (not _in(sp.get("specularFactor", 1), 0, 1) or
                               not all(_in(c, 0, math.inf) for c in sp.get("specularColorFactor", [1, 1, 1]))):
            g.bad(f"{w}: bad KHR_materials_specular {sp}")
        if not _in(ext.get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1), 0, math.inf):
            g.bad(f"{w}: emissiveStrength < 0")
