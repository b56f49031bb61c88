"""Builds two deforming test scenes from scratch inside Blender and exports them with Blender's
own glTF exporter, for tests/test_blender.py:

  arm.glb    a skinned arm: a body block and three cylinder segments with ball joints and a
             hand, one mesh, weighted explicitly to a chain of three bones (root, upper, fore);
             the root never moves, "upper" bends the rest up from 0.25 s to 1.0 s, "fore" bends
             the forearm from 1.0 s to 1.75 s.
  face.glb   a morph model: a sphere with three shape keys animated one after another: "bulge"
             (the right side swells, 0.2-0.8 s), "mouth" (a dent opens in the front, lower middle,
             0.8-1.3 s) and "stretch" (the top rises, 1.3-1.8 s).

Each file holds its camera (160x120, looking along Blender's +Y) and a sun, and gets a sidecar
NAME.json with what the test checks, from Blender's own evaluation of the deformed mesh at every
frame projected by that camera: per phase of motion its time span, the pixel box that the faces
moving in it cover (a face moves when one of its vertices moves or turns its normal) and the pixel
box of the vertices that stay; the box the object covers over the whole animation (outside it:
background); the animation's time span as exported.

Run: blender -b --factory-startup --python-exit-code 1 -P tests/blender_assets.py -- OUTDIR
 (Debian 12's Blender 3.4), or with the bpy module: python3.11 tests/blender_assets.py OUTDIR
 (PyPI's bpy 4.2 gives the same sidecars).
"""
import json
import math
import os
import struct
import sys

import bpy  # first: in the bpy module, bpy's import makes bmesh and mathutils importable
import bmesh
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Matrix, Quaternion, Vector

FPS = 24
FRAMES = 48          # 2 s
RES = (160, 120)
MOVE_EPS = 1e-4      # metres: a vertex moved
TURN_EPS = 1e-3      # normal change (unit vectors): a vertex turned


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = FPS
    scene.render.fps_base = 1.0
    # frame 0 is time 0 in the exported file whatever the exporter does with the start
    scene.frame_start = 0
    scene.frame_end = FRAMES
    scene.render.resolution_x, scene.render.resolution_y = RES
    scene.render.resolution_percentage = 100
    return scene


def grey_material():
    mat = bpy.data.materials.new("grey")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.6, 0.6, 0.6, 1.0)
    bsdf.inputs["Roughness"].default_value = 1.0
    # no highlight: the sensor should see the shape; named "Specular IOR Level" from Blender 4.0
    for name in ("Specular", "Specular IOR Level"):
        if name in bsdf.inputs:
            bsdf.inputs[name].default_value = 0.0
    return mat


def mesh_object(name, bm):
    me = bpy.data.meshes.new(name)
    bm.to_mesh(me)
    bm.free()
    for p in me.polygons:
        p.use_smooth = True
    me.materials.append(grey_material())
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def linear_keys(action):
    # straight ramps: the motion starts and stops exactly at the phase times
    for fc in action.fcurves:
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"


# ---------------------------------------------------------------- the skinned arm
ARM_JOINTS = (-2.0, -0.6, 0.4, 1.6)      # x of root head, elbow 1, elbow 2, fore tail
ARM_BLEND = 0.15                         # half-width of the weight blend at a joint
ARM_PHASES = (("upper bends", 6, 24), ("fore bends", 24, 42))


def smoothstep(a, b, x):
    t = min(max((x - a) / (b - a), 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def build_arm():
    bm = bmesh.new()
    along_x = Matrix.Rotation(math.radians(90.0), 4, "Y")   # cylinders along X
    bmesh.ops.create_cube(bm, size=0.8, matrix=Matrix.Translation((-2.2, 0.0, 0.0)))
    for x0, x1, r in ((-2.0, -0.6, 0.22), (-0.6, 0.4, 0.2), (0.4, 1.4, 0.17)):
        bmesh.ops.create_cone(bm, cap_ends=True, segments=16, radius1=r, radius2=r, depth=x1 - x0,
                              matrix=Matrix.Translation((0.5 * (x0 + x1), 0.0, 0.0)) @ along_x)
    for x, r in ((-0.6, 0.26), (0.4, 0.23)):
        bmesh.ops.create_uvsphere(bm, u_segments=16, v_segments=8, radius=r,
                                  matrix=Matrix.Translation((x, 0.0, 0.0)))
    bmesh.ops.create_cube(bm, size=0.4, matrix=Matrix.Translation((1.55, 0.0, 0.0)))
    # rings every 0.1 along the arm, so that a bend stays near its joint
    for i in range(-19, 14):
        bmesh.ops.bisect_plane(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:], dist=1e-4,
                               plane_co=(0.1 * i + 0.05, 0.0, 0.0), plane_no=(1.0, 0.0, 0.0))
    obj = mesh_object("arm", bm)

    arm_data = bpy.data.armatures.new("rig")
    rig = bpy.data.objects.new("rig", arm_data)
    bpy.context.scene.collection.objects.link(rig)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    parent = None
    for name, x0, x1 in zip(("root", "upper", "fore"), ARM_JOINTS[:-1], ARM_JOINTS[1:]):
        b = arm_data.edit_bones.new(name)
        b.head, b.tail, b.roll = (x0, 0.0, 0.0), (x1, 0.0, 0.0), 0.0
        if parent:
            b.parent, b.use_connect = parent, True
        parent = b
    bpy.ops.object.mode_set(mode="OBJECT")

    # explicit weights: by position along the arm, blended smoothly across each elbow
    groups = {n: obj.vertex_groups.new(name=n) for n in ("root", "upper", "fore")}
    for v in obj.data.vertices:
        x = v.co.x
        s1 = smoothstep(ARM_JOINTS[1] - ARM_BLEND, ARM_JOINTS[1] + ARM_BLEND, x)
        s2 = smoothstep(ARM_JOINTS[2] - ARM_BLEND, ARM_JOINTS[2] + ARM_BLEND, x)
        for name, w in (("root", 1.0 - s1), ("upper", s1 * (1.0 - s2)), ("fore", s1 * s2)):
            if w > 0.0:
                groups[name].add([v.index], w, "REPLACE")
    obj.parent = rig
    mod = obj.modifiers.new("skin", "ARMATURE")
    mod.object = rig

    # bend up in the camera's view plane (world XZ): about world -Y, in each bone's rest space
    rig.animation_data_create()
    rig.animation_data.action = bpy.data.actions.new("bend")
    for pb in rig.pose.bones:
        pb.rotation_mode = "QUATERNION"
    for name, (_, f0, f1), angle in (("upper", ARM_PHASES[0], 50.0), ("fore", ARM_PHASES[1], 60.0)):
        pb = rig.pose.bones[name]
        axis = pb.bone.matrix_local.to_3x3().inverted() @ Vector((0.0, -1.0, 0.0))
        for frame, a in ((0, 0.0), (f0, 0.0), (f1, angle), (FRAMES, angle)):
            pb.rotation_quaternion = Quaternion(axis, math.radians(a))
            pb.keyframe_insert("rotation_quaternion", frame=frame)
    linear_keys(rig.animation_data.action)
    return obj, ARM_PHASES


# ---------------------------------------------------------------- the morph face
FACE_PHASES = (("bulge", 5, 19), ("mouth", 19, 31), ("stretch", 31, 43))


def build_face():
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=1.0)
    obj = mesh_object("face", bm)
    obj.shape_key_add(name="Basis")
    for name in ("bulge", "mouth", "stretch"):
        key = obj.shape_key_add(name=name, from_mix=False)
        for v, kv in zip(obj.data.vertices, key.data):
            x, y, z = v.co
            if name == "bulge" and x > 0.2:          # the right side swells outwards
                kv.co = v.co + Vector((0.6 * (x - 0.2), 0.0, 0.0))
            elif name == "mouth" and y < -0.5 and abs(x) < 0.45 and -0.65 < z < -0.1:
                kv.co = v.co + Vector((0.0, 0.3, 0.0))   # the front (camera side) caves in
            elif name == "stretch" and z > 0.3:      # the top rises
                kv.co = v.co + Vector((0.0, 0.0, 0.7 * (z - 0.3)))
    keys = obj.data.shape_keys
    for name, f0, f1 in FACE_PHASES:
        kb = keys.key_blocks[name]
        for frame, value in ((0, 0.0), (f0, 0.0), (f1, 1.0), (FRAMES, 1.0)):
            kb.value = value
            kb.keyframe_insert("value", frame=frame)
    linear_keys(keys.animation_data.action)
    return obj, FACE_PHASES


# ---------------------------------------------------------------- evaluation and framing
def evaluate(obj, scene):
    """Per frame: world positions and normals of the deformed mesh's vertices."""
    frames = []
    for f in range(FRAMES + 1):
        scene.frame_set(f)
        ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        me = ev.to_mesh()
        m = ev.matrix_world.copy()
        n3 = m.to_3x3().inverted().transposed()
        frames.append(([m @ v.co for v in me.vertices], [(n3 @ v.normal).normalized() for v in me.vertices]))
        ev.to_mesh_clear()
    scene.frame_set(0)
    return frames


def add_camera_and_sun(scene, frames):
    """A camera on -Y looking along +Y (up +Z) that frames every vertex at every frame with a
    margin, and a sun shining from the camera's upper left (shadows fall behind the object)."""
    pts = [p for pos, _ in frames for p in pos]
    lo = Vector([min(p[i] for p in pts) for i in range(3)])
    hi = Vector([max(p[i] for p in pts) for i in range(3)])
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.angle = math.radians(50.0)
    cam_data.clip_start = 0.1
    tan_x = math.tan(0.5 * cam_data.angle)
    tan_y = tan_x * RES[1] / RES[0]
    dist = 1.25 * max(half.x / tan_x, half.z / tan_y) + half.y
    cam = bpy.data.objects.new("camera", cam_data)
    cam.location = centre + Vector((0.0, -dist, 0.0))
    cam.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    sun_data = bpy.data.lights.new("sun", "SUN")
    sun_data.energy = math.pi        # evray's headlight has pi lux: white shows as radiance 1
    sun = bpy.data.objects.new("sun", sun_data)
    sun.rotation_euler = Vector((0.35, 1.0, -0.35)).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun)
    bpy.context.view_layer.update()
    return cam


def to_pixels(scene, cam, p):
    ndc = world_to_camera_view(scene, cam, p)
    if ndc.z <= 0.0:
        raise SystemExit(f"blender_assets: a vertex is behind the camera ({p})")
    return ndc.x * RES[0], (1.0 - ndc.y) * RES[1]   # evray: x right, rows top to bottom


def box(points):
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return [round(min(xs), 2), round(min(ys), 2), round(max(xs), 2), round(max(ys), 2)]


def sidecar(scene, cam, obj, frames, phases, glb):
    polys = [tuple(p.vertices) for p in obj.data.polygons]
    px = [[to_pixels(scene, cam, p) for p in pos] for pos, _ in frames]
    whole = box([q for f in px for q in f])
    if whole[0] < 2 or whole[1] < 2 or whole[2] > RES[0] - 2 or whole[3] > RES[1] - 2:
        raise SystemExit(f"blender_assets: {obj.name} leaves the image ({whole})")
    out_phases = []
    for name, f0, f1 in phases:
        pos0, nrm0 = frames[f0]
        moved = set()
        for f in range(f0, f1 + 1):
            pos, nrm = frames[f]
            moved |= {i for i in range(len(pos))
                      if (pos[i] - pos0[i]).length > MOVE_EPS or (nrm[i] - nrm0[i]).length > TURN_EPS}
        if not moved:
            raise SystemExit(f"blender_assets: nothing moves in phase {name}")
        faces = {i for poly in polys if moved & set(poly) for i in poly}
        still = [i for i in range(len(pos0)) if i not in faces]
        # outside the phase nothing of it moves: frames before f0 and after f1 equal the ends
        out_phases.append({
            "name": name, "t0": f0 / FPS, "t1": f1 / FPS,
            "moving_box": box([px[f][i] for f in range(f0, f1 + 1) for i in faces]),
            "still_box": box([px[f0][i] for i in still]) if still else None,
            "moving_vertices": len(moved), "vertices": len(pos0)})
    # the file's own clock: every animation sampler's time range
    times = gltf_time_span(glb)
    if abs(times[0]) > 1e-6 or abs(times[1] - FRAMES / FPS) > 1e-6:
        raise SystemExit(f"blender_assets: {glb} animates {times} s, not 0 to {FRAMES / FPS} s")
    return {"file": os.path.basename(glb), "resolution": list(RES), "fps": FPS,
            "duration": FRAMES / FPS, "exported_time_span": times, "object_box": whole,
            "phases": out_phases, "blender": bpy.app.version_string}


def gltf_time_span(glb):
    with open(glb, "rb") as f:
        data = f.read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    inputs = {s["input"] for a in gltf.get("animations", []) for s in a["samplers"]}
    if not inputs:
        raise SystemExit(f"blender_assets: {glb} has no animation")
    acc = gltf["accessors"]
    return [min(acc[i]["min"][0] for i in inputs), max(acc[i]["max"][0] for i in inputs)]


def export(path, skins):
    # lights in the file's units as Blender shows them (W/m^2 of a sun as lux), not scaled by
    # 683 lm/W; the option's name changed after Blender 3.4
    props = bpy.ops.export_scene.gltf.get_rna_type().properties.keys()
    light = next(k for k in ("convert_lighting_mode", "export_import_convert_lighting_mode") if k in props)
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", export_yup=True,
                              export_animations=True, export_force_sampling=True,
                              export_frame_range=True, export_skins=skins, export_morph=True,
                              export_morph_normal=True, export_cameras=True, export_lights=True,
                              export_materials="EXPORT", **{light: "COMPAT"})


def main():
    # blender -P: the script's arguments follow "--"; the bpy module (python blender_assets.py
    # OUTDIR) has them as usual
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    if len(argv) != 1:
        raise SystemExit("usage: blender -b --factory-startup --python-exit-code 1 -P blender_assets.py -- OUTDIR")
    out = argv[0]
    os.makedirs(out, exist_ok=True)
    for name, build in (("arm", build_arm), ("face", build_face)):
        scene = reset()
        obj, phases = build()
        frames = evaluate(obj, scene)
        cam = add_camera_and_sun(scene, frames)
        glb = os.path.join(out, name + ".glb")
        export(glb, skins=(name == "arm"))
        info = sidecar(scene, cam, obj, frames, phases, glb)
        with open(os.path.join(out, name + ".json"), "w") as f:
            json.dump(info, f, indent=1)
        print(f"blender_assets: wrote {glb} and {name}.json")


main()
if not bpy.app.binary_path:
    # the bpy module (PyPI's bpy 4.2 at least) crashes in its exit handlers after Python has
    # finalized (SpaceType destructors call back into Python): the files are written, so leave
    # before those handlers run
    sys.stdout.flush()
    os._exit(0)
