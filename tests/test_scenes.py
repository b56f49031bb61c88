"""Every built-in scene renders on the CPU at a small size, makes events, and exports as a glTF
file that follows the glTF 2.0 rules gltf_check.py knows (skins and morph targets included) and
renders the same events as the built-in scene."""
import os

import evrtest as T
import gltf_check

tmp = T.tmpdir()
names = T.run("demo", "--list").stdout.split()
T.check({"eye", "square", "disk", "cornell"} <= set(names), f"built-in scenes listed ({names})")
for name in names:
    d = os.path.join(tmp, name)
    T.run("demo", "--scene", name, "-o", d, "--res", "48x36", "--duration", "0.3", "--format", "npy",
          "--no-preview", "--quiet", "--backend", "cpu")
    n = T.load_run_json(d)["stats"]["events"]
    if name.endswith("-still"):   # nothing moves: no events
        T.check(n == 0, f"{name}: no events ({n})")
    else:
        T.check(n > 0, f"{name}: events in the first 0.3 s ({n})")
    glb = os.path.join(tmp, name + ".glb")
    T.run("demo", "--scene", name, "--export", glb)
    doc, problems = gltf_check.check(glb)
    T.check(not problems, f"{name}: the GLB follows the glTF rules ({problems[:3]})")
    d2 = os.path.join(tmp, name + "-file")
    T.run("render", glb, "-o", d2, "--res", "48x36", "--duration", "0.3", "--format", "npy", "--no-preview",
          "--quiet", "--backend", "cpu")
    a = open(os.path.join(d, "events.npy"), "rb").read()
    b = open(os.path.join(d2, "events.npy"), "rb").read()
    T.check(a == b, f"{name}: the exported file renders the same events")
T.finish("test_scenes")
