"""Skins and morph targets on the command line: `evray info` lists each skin and morphing mesh
with its weight channel, a warning reaches stderr (render) and the listing (info), each bad
asset of tests/deform_assets.py is one error line and a non-zero exit from info and render, and
a skinned and a morphing asset render events. The imported data and the deformation itself are
checked in tests/test_deform_import.c."""
import os

import deform_assets
import evrtest as T

tmp = T.tmpdir()
paths = deform_assets.write_all(tmp)


def info(name):
    p = T.run("info", paths[name])
    T.check(p.stderr == "", f"info {name}: nothing on stderr (got {p.stderr!r})")
    return p.stdout


# item 3 of the listing: skins (mesh, joints, influences) and morphing meshes (targets, normal
# deltas, the node's weight channel with its key count and time range)
out = info("skin_slide")
T.check('skins: 1\n  [0] "quad": 2 joints ("root", "mover"), 1 influence per vertex' in out,
        f"info skin_slide lists the skin:\n{out}")
out = info("skin_slide8")
T.check('"quad": 3 joints ("root", "mover", "mover2"), 2 influences per vertex' in out,
        f"info skin_slide8: JOINTS_1 read (mover2, 2 influences):\n{out}")
out = info("bend_cylinder")
T.check('"cylinder": 2 joints ("j0", "j1"), 2 influences per vertex' in out,
        f"info bend_cylinder lists the skin:\n{out}")
out = info("morph_slide")
T.check('morph targets: 1 mesh\n  [0] "quad": 1 target, no normal deltas' in out,
        f"info morph_slide lists the morphing mesh:\n{out}")
T.check('node "quad": weights (0), channel 2 keys linear, 0 s to 1 s' in out,
        f"info morph_slide lists the weight channel:\n{out}")
T.check("animation: 0 s to 1 s" in out and '"quad": morph weights 2 keys linear' in out,
        f"info morph_slide: the weight curve makes the animation:\n{out}")
out = info("morph_two_prims")
T.check('2 targets, normal deltas' in out and 'node "pair": weights (0.75 0.125), channel 3 keys'
        in out, f"info morph_two_prims: normal deltas, node weights:\n{out}")
out = info("morph_step")
T.check("channel 2 keys step" in out, f"info morph_step: a STEP channel:\n{out}")
out = info("morph_node_weights")
T.check('node "quad": weights (0.5), no channel' in out, f"info morph_node_weights:\n{out}")

# what evray does not render: a warning, listed by info and printed by render
out = info("morph_cubic")
T.check("warnings: 1\n  node 'quad': CUBICSPLINE morph weights" in out,
        f"info morph_cubic lists the warning:\n{out}")
run_dir = os.path.join(tmp, "cubic-run")
p = T.run("render", paths["morph_cubic"], "-o", run_dir, "--res", "16x16", "--duration", "0.2",
          "--format", "npy", "--backend", "cpu", "--quiet")
warn = [l for l in p.stderr.splitlines() if l.startswith("evray: warning:")]
T.check(len(warn) == 1 and "CUBICSPLINE" in warn[0], f"render morph_cubic warns once ({p.stderr!r})")

# the slides render events (the edge sweeps the view)
for name in ("morph_slide", "skin_slide", "skin_no_ibm"):
    out_dir = os.path.join(tmp, name + "-run")
    T.run("render", paths[name], "-o", out_dir, "--res", "16x16", "--duration", "0.5",
          "--format", "npy", "--backend", "cpu", "--quiet")
    T.check(T.load_run_json(out_dir)["stats"]["events"] > 0, f"render {name}: events")

# each bad asset: one error line naming the mesh, a non-zero exit, no run folder
for name in deform_assets.BAD:
    for args in (["info", paths[name]],
                 ["render", paths[name], "-o", os.path.join(tmp, name + "-run"), "--res", "16x16",
                  "--backend", "cpu", "--quiet"]):
        p = T.run(*args, expect=None)
        lines = [l for l in p.stderr.splitlines() if l.strip()]
        T.check(p.returncode > 0, f"{args[0]} {name}: non-zero exit without a crash "
                f"(got {p.returncode})")
        T.check(len(lines) == 1 and lines[0].startswith("evray: error: ") and "mesh 'quad'" in
                lines[0], f"{args[0]} {name}: one error line naming the mesh (got {lines!r})")
        T.check(p.stdout == "", f"{args[0]} {name}: nothing on stdout")
    T.check(not os.path.exists(os.path.join(tmp, name + "-run")), f"{name}: no run folder")

T.finish("test_deform_cli")
