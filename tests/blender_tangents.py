"""Blender's MikkTSpace tangents of material_assets.warped_sphere(), for
tests/test_tangents_blender.c.

Run: blender -b --factory-startup --python-exit-code 1 -P tests/blender_tangents.py -- OUT.json
(Debian 12's Blender 3.4). Blender gets the sphere's positions, triangles and uvs with v flipped
(Blender's v grows up the image, glTF's down), smooth shading (its own vertex normals: custom
normals would differ between a vertex's corners in the last bits, and MikkTSpace would not weld
them), and computes the tangents (Mesh.calc_tangents: MikkTSpace); again with u negated
("ball_mirrored": every triangle mirrored, bitangent sign -1). OUT.json: per mesh name,
"vertices", per vertex position (3), normal (3) and uv (2, glTF's v); "loops", per face corner
(three per triangle, in order) its vertex, tangent (3) and bitangent sign."""
import json
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import material_assets  # noqa: E402  (standard library only)

out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
pos, _, uv0, idx = material_assets.warped_sphere()
meshes = {}
for name, uv in (("ball", uv0), ("ball_mirrored", [(-u, v) for u, v in uv0])):
    me = bpy.data.meshes.new(name)
    me.from_pydata(pos, [], [tuple(idx[i:i + 3]) for i in range(0, len(idx), 3)])
    me.update()
    me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
    me.uv_layers.new(name="uv")
    for lp in me.loops:
        u, v = uv[lp.vertex_index]
        me.uv_layers["uv"].data[lp.index].uv = (u, 1.0 - v)
    me.calc_tangents(uvmap="uv")
    meshes[name] = {
        "vertices": [list(v.co) + list(v.normal) + list(uv[v.index]) for v in me.vertices],
        "loops": [[lp.vertex_index] + list(lp.tangent) + [lp.bitangent_sign] for lp in me.loops]}
with open(out, "w") as f:
    json.dump(meshes, f)
