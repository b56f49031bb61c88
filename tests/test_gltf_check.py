"""gltf_check.py's rules for materials, tangents and lights, on small GLB files built here: a file
with every material field the writer can give (texture slots with KHR_texture_transform, alpha,
the KHR_materials extensions), a TANGENT attribute and a light with a radius passes; each of a
list of single mistakes is reported."""
import copy
import os
import struct

import evrtest as T
import gltf_build
import gltf_check


pos = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
nrm = [(0, 0, 1)] * 3
tan = [(1, 0, 0, 1), (1, 0, 0, 1), (1, 0, 0, -1)]
binary = b"".join(struct.pack("<3f", *p) for p in pos) + b"".join(struct.pack("<3f", *n) for n in nrm) + \
    b"".join(struct.pack("<4f", *t) for t in tan) + struct.pack("<3I", 0, 1, 2)
xf = {"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.25, "scale": [2, 2]}}
good = {
    "asset": {"version": "2.0"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength",
                       "KHR_materials_unlit", "KHR_materials_transmission", "KHR_materials_ior",
                       "KHR_materials_volume", "KHR_materials_specular"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 1, "extras": {"radius": 0.0015}},
        {"type": "directional", "intensity": 1}]}},
    "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TANGENT": 2}, "indices": 3,
                                "material": 0}]}],
    "materials": [{
        "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "baseColorTexture": {"index": 0, "extensions": xf},
                                 "metallicRoughnessTexture": {"index": 0}, "metallicFactor": 0,
                                 "roughnessFactor": 0.03},
        "normalTexture": {"index": 0, "scale": 0.5}, "occlusionTexture": {"index": 0, "strength": 0.5},
        "emissiveTexture": {"index": 0}, "emissiveFactor": [1, 1, 1], "alphaMode": "MASK", "alphaCutoff": 0.4,
        "doubleSided": True,
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4},
                       "KHR_materials_unlit": {},
                       "KHR_materials_transmission": {"transmissionFactor": 1, "transmissionTexture": {"index": 0}},
                       "KHR_materials_ior": {"ior": 1.376},
                       "KHR_materials_volume": {"thicknessFactor": 0.005, "attenuationDistance": 2,
                                                "attenuationColor": [1, 0.5, 1]},
                       "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1, 1, 2]}}}],
    "textures": [{"source": 0}],
    "images": [{"bufferView": 4, "mimeType": "image/png"}],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"},
        {"bufferView": 3, "componentType": 5125, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 72, "byteLength": 48}, {"buffer": 0, "byteOffset": 120, "byteLength": 12},
                    {"buffer": 0, "byteOffset": 0, "byteLength": 4}],
    "buffers": [{"byteLength": 132}],
}


tmp = T.tmpdir()


def problems(doc, bin_=binary):
    path = os.path.join(tmp, "check.glb")
    with open(path, "wb") as f:
        f.write(gltf_build.glb_bytes(doc, bin_))
    return gltf_check.check(path)[1]


p = problems(good)
T.check(not p, f"a file with every material field, TANGENT and a light radius passes ({p[:3]})")


def mat(d):
    return d["materials"][0]


def ext(d):
    return mat(d)["extensions"]


# (what is broken, how, a word the report must contain)
cases = [
    ("an extension not in extensionsUsed", lambda d: d["extensionsUsed"].remove("KHR_materials_ior"), "extensionsUsed"),
    ("a texture transform not listed", lambda d: d["extensionsUsed"].remove("KHR_texture_transform"),
     "KHR_texture_transform"),
    ("a texture slot naming no texture", lambda d: mat(d)["normalTexture"].update(index=3), "no texture"),
    ("a bad texture transform", lambda d: xf_bad(d), "KHR_texture_transform"),
    ("an alpha mode", lambda d: mat(d).update(alphaMode="CUTOUT"), "alphaMode"),
    ("doubleSided not a boolean", lambda d: mat(d).update(doubleSided=1), "doubleSided"),
    ("a roughness above 1", lambda d: mat(d)["pbrMetallicRoughness"].update(roughnessFactor=1.5), "[0,1]"),
    ("an occlusion strength above 1", lambda d: mat(d)["occlusionTexture"].update(strength=2), "occlusion"),
    ("a transmission above 1", lambda d: ext(d)["KHR_materials_transmission"].update(transmissionFactor=2),
     "transmission"),
    ("an IOR below 1", lambda d: ext(d)["KHR_materials_ior"].update(ior=0.5), "ior"),
    ("a zero attenuation distance", lambda d: ext(d)["KHR_materials_volume"].update(attenuationDistance=0),
     "volume"),
    ("a negative specular colour", lambda d: ext(d)["KHR_materials_specular"].update(specularColorFactor=[1, -1, 1]),
     "specular"),
    ("a negative emissive strength",
     lambda d: ext(d)["KHR_materials_emissive_strength"].update(emissiveStrength=-1), "emissiveStrength"),
    ("a radius on a directional light",
     lambda d: d["extensions"]["KHR_lights_punctual"]["lights"][1].update(extras={"radius": 0.01}), "radius"),
    ("a negative radius",
     lambda d: d["extensions"]["KHR_lights_punctual"]["lights"][0].update(extras={"radius": -1}), "radius"),
    ("TANGENT without NORMAL", lambda d: d["meshes"][0]["primitives"][0]["attributes"].pop("NORMAL"), "NORMAL"),
    ("TANGENT as VEC3", lambda d: d["accessors"][2].update(type="VEC3", count=4), "TANGENT"),
    ("a mesh naming no material", lambda d: d["meshes"][0]["primitives"][0].update(material=5), "material"),
]


def xf_bad(d):
    mat(d)["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"]["scale"] = [2]


for what, breaks, word in cases:
    d = copy.deepcopy(good)
    breaks(d)
    p = problems(d)
    T.check(any(word in x for x in p), f"{what} is reported ({p[:3]})")

# a tangent whose w is not +-1
bad_w = binary[:72 + 44] + struct.pack("<f", 0.5) + binary[72 + 48:]
p = problems(good, bad_w)
T.check(any("TANGENT" in x for x in p), f"a TANGENT with w = 0.5 is reported ({p[:3]})")
T.finish("test_gltf_check")
