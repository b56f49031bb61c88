"""A glossy Cornell box (issue 21): the built-in "cornell" room as `evray demo --scene cornell
--export` writes it, with two materials changed: the tall box a rough metal ("metal": base
colour (0.95, 0.64, 0.54), copper's reflectance at normal incidence, metallic 1, roughness 0.3)
and the floor a glossy dielectric ("glossy": the white walls' base colour (0.725, 0.71, 0.68),
metallic 0, roughness 0.3, IOR 1.5; the camera sees the floor at a grazing angle, where the
dielectric's lobe reflects most). Both rough enough (at least EVR_MIRROR_ROUGHNESS, 0.2) that
direct light does not trace them as mirrors: their reflections are indirect light, the path
tracer's and the photon pass's to make. The rest (walls, short box, the ceiling's panel and point
light, the camera, the short box's animation) is the built-in scene's.

Standard library only:  python3 tests/cornell_glossy.py EVRAY OUT.glb
"""
import json
import os
import struct
import subprocess
import sys
import tempfile


def read_glb(path):
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or length != len(data):
        raise ValueError(f"{path}: not a glTF 2.0 binary")
    chunks, at = [], 12
    while at < length:
        n, kind = struct.unpack_from("<I4s", data, at)
        chunks.append((kind, data[at + 8:at + 8 + n]))
        at += 8 + n
    if not chunks or chunks[0][0] != b"JSON":
        raise ValueError(f"{path}: no JSON chunk first")
    return json.loads(chunks[0][1].decode("utf-8")), chunks[1:]


def write_glb(path, doc, rest):
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text
    for kind, payload in rest:
        body += struct.pack("<I4s", len(payload), kind) + payload
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)


def material(doc, name, base, metallic, roughness):
    doc["materials"].append({
        "name": name,
        "doubleSided": True,
        "pbrMetallicRoughness": {"baseColorFactor": list(base) + [1.0], "metallicFactor": metallic,
                                 "roughnessFactor": roughness},
    })
    return len(doc["materials"]) - 1


def set_material(doc, node_name, index):
    node = next(n for n in doc["nodes"] if n.get("name") == node_name)
    for prim in doc["meshes"][node["mesh"]]["primitives"]:
        prim["material"] = index


def make(evray, out):
    with tempfile.TemporaryDirectory() as tmp:
        plain = os.path.join(tmp, "cornell.glb")
        subprocess.run([evray, "demo", "--scene", "cornell", "--export", plain], check=True,
                       stdout=subprocess.DEVNULL)
        doc, rest = read_glb(plain)
    set_material(doc, "tall_box", material(doc, "metal", (0.95, 0.64, 0.54), 1.0, 0.3))
    set_material(doc, "floor", material(doc, "glossy", (0.725, 0.71, 0.68), 0.0, 0.3))
    write_glb(out, doc, rest)
    return out


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: cornell_glossy.py EVRAY OUT.glb")
    make(sys.argv[1], sys.argv[2])
