"""Change-driven sampling gives exactly the events of brute force (--no-skip): every built-in scene
and the moving square, ideal sensor and the davis346 noise model, the deforming test scenes
(skins and morph targets, tests/deform_assets.py, where the importer reads them), a scene of
hits a material rules out (tests/filter_assets.py's "mixed"), the scene with every material
feature (tests/all_materials.py), camera paths (a moving camera, and a trajectory that holds still
between moves), on the CPU and
(where a GPU is usable) on CUDA, with uniform sampling (10 per frame) and with refined sampling
(the default, where global illumination does not rule it out); and it really skips: run.json
accounts for the samples traced and the pixels skipped per segment (uniform sampling)."""
import os
import sys

import evrtest as T

tmp = T.tmpdir()
names = T.run("demo", "--list").stdout.split()
probe = T.run("demo", "--scene", "square", "-o", os.path.join(tmp, "probe"), "--res", "16x16", "--duration", "0.1",
              "--backend", "cuda", "--quiet", "--no-preview", expect=None)
backends = ["cpu"] + (["cuda"] if probe.returncode == 0 else [])
print("backends:", backends)

cases = [(n, ["--res", "64x48", "--duration", "0.4"]) for n in names]
cases.append(("square", ["--res", "96x96", "--duration", "1.0", "--pos-thres", "0.3", "--neg-thres", "0.25"]))
cases.append(("square", ["--sensor", "davis346", "--res", "64x48", "--duration", "0.5"]))
cases.append(("cornell", ["--sensor", "davis346", "--res", "64x48", "--duration", "0.5"]))
# global illumination (the blurred estimate): a pixel whose nine cells' lookups did not change keeps
# its intensity
cases.append(("cornell", ["--gi", "photon", "--res", "64x48", "--duration", "0.4"]))
cases.append(("cornell-bleed", ["--gi", "photon", "--res", "64x48", "--duration", "0.4"]))
# a gather at every sample: wider windows (a still pixel's sums updated from the cells that
# changed), and the ring search with a limit on the photons per estimate
cases.append(("cornell", ["--gi", "photon", "--res", "160x120", "--duration", "0.2", "--gi-blur", "0"]))
cases.append(("cornell", ["--gi", "photon", "--res", "64x48", "--duration", "0.4", "--gather-max", "8", "--gi-blur", "0"]))
# a gather at every sample (--gi-blur 0; the cases above take the blurred estimate, the default,
# where a pixel keeps its light while its cell and the eight around it give the same lookups): the
# pixel keeps it while its gather window saw no photon change
cases.append(("cornell", ["--gi", "photon", "--res", "64x48", "--duration", "0.4", "--gi-blur", "0"]))
cases.append(("cornell-bleed", ["--gi", "photon", "--res", "96x72", "--duration", "0.4", "--gi-blur", "0"]))
cases.append(("cornell", ["--gi", "photon", "--res", "64x48", "--duration", "0.2", "--gi-blur", "0",
                          "--camera-path", "pan:rate=5"]))
# the deforming meshes (a path: a scene file): a still stretch keeps its vertices and (on CUDA) its
# tree bit for bit, so pixels that see it skip exactly
for asset in T.deform_assets(tmp):
    cases.append((asset, ["--res", "64x48", "--duration", "1.0"]))
    cases.append((asset, ["--sensor", "davis346", "--res", "64x48", "--duration", "0.5"]))
    cases.append((asset, ["--gi", "photon", "--res", "64x48", "--duration", "0.4"]))
# hits a material rules out (alpha MASK, single-sided; on CUDA the general kernels)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import filter_assets  # noqa: E402
mixed = filter_assets.write_all(os.path.join(tmp, "filter-assets"))["mixed"]
cases.append((mixed, ["--res", "64x48", "--duration", "1.0"]))
# every material feature at once (tests/all_materials.py): a pixel depends on every ray of its
# path (reflected, refracted, BLEND layers, each vertex's shadow rays); the lamp holds still until
# t = 0.5, so pixels that see nothing moving skip until then
import all_materials  # noqa: E402
every = all_materials.write(os.path.join(tmp, "all-materials"))
cases.append((every, ["--res", "64x48", "--duration", "1.0"]))
# camera paths (docs/camera.md): a moving camera is "everything changes", and a trajectory that
# holds still, then moves, then holds again skips exactly where it holds
still_move = os.path.join(tmp, "still-move.txt")
with open(still_move, "w") as f:
    f.write("0 0 0 4 1 0 0 0\n0.2 0 0 4 1 0 0 0\n0.3 0.05 0 4 0.9999 0 -0.01 0\n0.5 0.05 0 4 0.9999 0 -0.01 0\n")
cases.append(("square", ["--res", "64x48", "--duration", "0.4", "--camera-path", "orbit+shake"]))
cases.append(("square", ["--res", "64x48", "--duration", "0.5", "--camera-path", "tum:" + still_move]))
cases.append(("cornell", ["--gi", "photon", "--res", "64x48", "--duration", "0.2", "--camera-path", "pan:rate=5"]))
for backend in backends:
    for case, (scene, extra) in enumerate(cases):
        source = ("render", scene) if os.path.sep in scene else ("demo", "--scene", scene)
        if "--gi" not in extra:  # refined sampling: the same events with and without skipping
            runs = {}
            for mode in ("skip", "brute"):
                d = os.path.join(tmp, f"{backend}-{os.path.basename(scene)}-{case}-refine-{mode}")
                T.run(*source, "-o", d, "--backend", backend, "--format", "npy", "--no-preview", "--quiet",
                      "--seed", "3", *extra, *(["--no-skip"] if mode == "brute" else []))
                runs[mode] = (open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d))
            (ev_s, js), (ev_b, jb) = runs["skip"], runs["brute"]
            print(f"{backend} {scene} {' '.join(extra)}, refine: {js['stats']['events']} events; traced "
                  f"{js['stats']['samples_traced']} vs {jb['stats']['samples_traced']} by brute force")
            T.check(js["config"]["sampling"] == "refine", f"{backend} {scene}: refined sampling by default")
            T.check(ev_s == ev_b, f"{backend} {scene} case {case}: refine: identical events with and without skipping")
        runs = {}
        for mode in ("skip", "brute"):
            d = os.path.join(tmp, f"{backend}-{os.path.basename(scene)}-{case}-{mode}")
            T.run(*source, "-o", d, "--backend", backend, "--format", "npy", "--no-preview", "--quiet",
                  "--seed", "3", "--samples-per-frame", "10", *extra, *(["--no-skip"] if mode == "brute" else []))
            runs[mode] = (open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d))
        (ev_s, js), (ev_b, jb) = runs["skip"], runs["brute"]
        ss, sb = js["stats"], jb["stats"]
        print(f"{backend} {scene} {' '.join(extra)}: {ss['events']} events; traced {ss['samples_traced']} of "
              f"{ss['samples']} samples, {ss['pixels_skipped']} pixel-segments skipped; rays {ss['rays']} vs {sb['rays']}")
        T.check(ss["events"] > 0 or scene.endswith("-still"), f"{backend} {scene} case {case}: events")
        T.check(ev_s == ev_b, f"{backend} {scene} case {case}: identical events with and without skipping")
        T.check(js["config"]["skip"] == "exact" and jb["config"]["skip"] == "off", f"{backend} {scene}: skip in config")
        T.check(sb["samples_traced"] == sb["samples"] and sb["pixels_skipped"] == 0,
                f"{backend} {scene}: brute force traces every sample")
        T.check(ss["samples"] == sb["samples"], f"{backend} {scene}: the same samples counted")
        per = ss["pixels_skipped_per_segment"]
        T.check(len(per) == ss["segments"] and sum(per) == ss["pixels_skipped"],
                f"{backend} {scene}: pixels skipped per segment add up")
        # a pixel either skips the segment (no sample traced), settles after its first sample, or
        # traces them all
        untouched = ss["samples"] - ss["pixels_skipped"] * 10
        T.check(ss["samples_traced"] <= untouched, f"{backend} {scene}: traced + skipped samples <= all samples")
        path = extra[extra.index("--camera-path") + 1] if "--camera-path" in extra else None
        if scene in ("square", "cornell") and not path:
            T.check(ss["samples_traced"] < untouched, f"{backend} {scene}: pixels settle after their first sample")
        if scene == every:
            T.check(ss["pixels_skipped"] > 0, f"{backend} all materials: pixels skip while the lamp holds still")
        if scene in ("square", "cornell") and not path:   # a small mover on a still background
            T.check(ss["samples_traced"] < 0.5 * ss["samples"], f"{backend} {scene}: most samples skipped")
            T.check(ss["rays"] < sb["rays"], f"{backend} {scene}: fewer rays")
        if path and path.startswith("tum:"):  # still over segments 0-5 and 9-14, moving over 6-8
            T.check(sum(per[1:6]) > 0 and per[6:9] == [0, 0, 0] and sum(per[10:]) > 0,
                    f"{backend} {scene} {path}: skips while the camera holds still only ({per})")
        elif path:
            T.check(ss["pixels_skipped"] == 0, f"{backend} {scene} {path}: a moving camera skips nothing")
# inside one of the eye's fixations (3.5-3.8 s) nothing moves: after the first segment, whose pixels
# settle after one sample each, every pixel skips every segment (still nodes must be bitwise still:
# one key per segment, held curve values exact, the same key from segment to segment)
for backend in backends:
    d = os.path.join(tmp, f"{backend}-fixation")
    T.run("demo", "--scene", "eye", "-o", d, "--backend", backend, "--format", "npy", "--no-preview", "--quiet",
          "--res", "64x48", "--start", "3.5", "--duration", "0.3")
    st = T.load_run_json(d)["stats"]
    npix = 64 * 48
    T.check(st["events"] == 0 and st["pixels_skipped"] == (st["segments"] - 1) * npix and st["samples_traced"] == npix,
            f"{backend} eye fixation: one sample per pixel, then nothing traced ({st['samples_traced']} traced, "
            f"{st['pixels_skipped']} skipped, {st['segments']} segments)")
T.finish("test_skip")
