"""CPU and CUDA backends give the same events: on the square and eye scenes, same seed, ideal
sensor and the davis346 sensor model, event counts within 0.5% and F1 >= 0.99 at 100 us (evray
compare); with adaptive sampling and refined sampling (the default) within 2% and F1 >= 0.97,
and adaptive sampling's samples within 2%; on
the deforming test scenes (skins and morph targets, tests/deform_assets.py, where the importer
reads them) likewise, uniformly and adaptively, and with global illumination (F1 >= 0.95); and
on a scene of hits a material rules out (tests/filter_assets.py's "mixed": an alpha-masked card
and a single-sided card seen from behind) likewise; on the scene with every material feature
(tests/all_materials.py: glint, glass, MASK, BLEND, emission, normal map, culling) likewise; with
camera paths and an orthographic camera likewise; the blurred GI estimate (--gi-blur) likewise.
Skipped (exit 77)
where this build has no CUDA backend or no GPU is usable."""
import json
import os
import sys

import evrtest as T

tmp = T.tmpdir()
probe = T.run("demo", "--scene", "square", "-o", os.path.join(tmp, "probe"), "--res", "16x16", "--duration", "0.1",
              "--backend", "cuda", "--quiet", "--no-preview", expect=None)
if probe.returncode != 0:
    T.skip("test_cuda", probe.stderr.strip())

# GI runs name --gi-blur: 0 (a gather at every sample) where the backends' agreement on every
# feature is checked, 4 (the default, the blurred estimate) on the two Cornell scenes below
cases = [("square", ["--res", "160x160", "--pos-thres", "0.3", "--neg-thres", "0.25"]),
         # two segments: the CUDA backend carries a segment's latest events into the next one's
         # sort; the last segment gives them all up (else about a tenth of a segment's are lost)
         ("square", ["--res", "160x160", "--duration", "0.06"]),
         ("eye", ["--res", "346x260", "--duration", "1.5"]),
         # the sensor model (mismatch, bandwidth, leak, shot noise, hot pixels, refractory): the
         # same noise on both backends (measured on an H100: 44811 vs 44810 events, F1 0.999)
         ("eye", ["--sensor", "davis346", "--res", "160x120", "--duration", "0.5"]),
         # adaptive sampling (core/adaptive.h): a pixel's sample times follow its intensities, so
         # float differences between the traversals can move them: looser bounds (2%, F1 0.97)
         ("eye", ["--res", "160x120", "--start", "0.2", "--duration", "1.0", "--sampling", "adaptive"]),
         ("eye", ["--sensor", "davis346", "--res", "160x120", "--duration", "0.5", "--sampling", "adaptive"]),
         # adaptive sampling with global illumination (the adaptive kernel's GI variant)
         ("cornell", ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5", "--sampling", "adaptive"]),
         # the sensor model with global illumination (the sensor kernel's GI variant)
         ("cornell", ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5", "--sensor", "davis346"]),
         # the blurred estimate (core/photon_blur.h), and with the second Cornell scene. A ray
         # through a wall's edge may meet the other wall on the other backend (a few pixels of
         # either GI run differ so); a lookup reads nine cells and the blur many more, so such a
         # cell moves the indirect light of the pixels around it by a little, and slowly changing
         # pixels place their events by their level: at 96x72 the F1 was 0.94 and 0.90 (counts
         # within 0.1%), at 173x130 0.996, where edges hold fewer of the pixels
         ("cornell", ["--gi", "photon", "--gi-blur", "4", "--res", "173x130", "--duration", "0.5"]),
         ("cornell-bleed", ["--gi", "photon", "--gi-blur", "4", "--res", "173x130", "--duration", "0.5"])]
# the deforming meshes: a scene file (a path) instead of a built-in scene; vertices per ray
# from the segment's keys (the CPU's Embree user geometry, the GPU's own trees per segment)
for asset in T.deform_assets(tmp):
    cases.append((asset, ["--res", "160x120", "--duration", "1.0"]))
    cases.append((asset, ["--sensor", "davis346", "--res", "128x96", "--duration", "0.5", "--sampling", "adaptive"]))
    cases.append((asset, ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5"]))
# hits a material rules out (core/hit_filter.h; on the GPU the general kernels,
# EVR_GPU_TRACE_GENERAL): an alpha-masked checkerboard card sliding in front of a single-sided card
# seen from behind (invisible, its shadow cast) and a lit wall (tests/filter_assets.py's "mixed")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import filter_assets  # noqa: E402
mixed = filter_assets.write_all(os.path.join(tmp, "filter-assets"))["mixed"]
cases.append((mixed, ["--res", "160x120", "--duration", "1.0"]))
cases.append((mixed, ["--sensor", "davis346", "--res", "128x96", "--duration", "0.5", "--sampling", "adaptive"]))
cases.append((mixed, ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5"]))
# every material feature at once (tests/all_materials.py: a gold mirror sphere with the glint of a
# sphere light, a glass slab with volume attenuation over a checker, alpha MASK and BLEND cards,
# an emissive texture, a normal map, a single-sided quad seen from behind; things move, the lamp
# from t = 0.5 on). The adaptive run stops at 0.5 s, before the lamp moves (while a light moves,
# adaptive sampling samples every pixel every --min-dt), and so does the GI run (to be short).
import all_materials  # noqa: E402
every = all_materials.write(os.path.join(tmp, "all-materials"))
cases.append((every, ["--res", "160x120", "--duration", "1.0"]))
cases.append((every, ["--sensor", "davis346", "--res", "128x96", "--duration", "0.5", "--sampling", "adaptive"]))
cases.append((every, ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5"]))
# camera paths (the camera's own motion track, docs/camera.md), with and without GI, and an
# orthographic camera (core/camera.h's parallel rays, photons seen along them) over a moving quad
cases.append(("square", ["--res", "160x160", "--duration", "0.3", "--camera-path", "orbit+shake"]))
cases.append(("cornell", ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.3", "--camera-path", "pan:rate=10"]))
ortho = os.path.join(tmp, "ortho.gltf")
T.quad_gltf(ortho, animated=True)
with open(ortho) as f:
    g = json.load(f)
g["cameras"] = [{"type": "orthographic", "orthographic": {"xmag": 1.5, "ymag": 1.5, "znear": 0.01, "zfar": 100}}]
with open(ortho, "w") as f:
    json.dump(g, f)
cases.append((ortho, ["--res", "128x128", "--duration", "1.0"]))
with open(mixed) as f:  # GI: photons seen along the parallel rays, between the cards and the wall
    g = json.load(f)
g["cameras"] = [{"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 2.0, "znear": 0.01, "zfar": 100}}]
mixed_ortho = os.path.join(os.path.dirname(mixed), "mixed_ortho.gltf")
with open(mixed_ortho, "w") as f:
    json.dump(g, f)
cases.append((mixed_ortho, ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5"]))
for case, (scene, extra) in enumerate(cases):
    outs = {}
    source = ("render", scene) if os.path.sep in scene else ("demo", "--scene", scene)
    for backend in ("cpu", "cuda"):
        d = os.path.join(tmp, f"{os.path.basename(scene)}-{case}-{backend}")
        T.run(*source, "-o", d, "--backend", backend, "--format", "h5", "--no-preview", "--quiet",
              "--seed", "7", *extra)
        meta = T.load_run_json(d)
        T.check(meta["backend"] == backend, f"{scene}: ran on {backend}")
        outs[backend] = (os.path.join(d, "events.h5"), meta["stats"])
    r = json.loads(T.run("compare", outs["cpu"][0], outs["cuda"][0], "--tol-us", "100", "--json").stdout)
    ncpu, ngpu = outs["cpu"][1]["events"], outs["cuda"][1]["events"]
    print(f"{scene}: cpu {ncpu} events, cuda {ngpu}, ratio {r['count_ratio']:.5f}, F1 {r['f1']:.5f}, "
          f"median |dt| {r['median_dt_us']} us; samples/s cpu {outs['cpu'][1]['samples_per_second']:.3g} "
          f"cuda {outs['cuda'][1]['samples_per_second']:.3g}")
    adaptive = "adaptive" in extra
    # refined sampling (the default, core/refine.h) bisects where the pixel fires: as with adaptive
    # sampling, float differences between the traversals can move its sample times
    refine = json.load(open(os.path.join(d, "run.json")))["config"]["sampling"] == "refine"
    T.check(ncpu > 0, f"{scene}: events")
    tol, f1 = (0.02, 0.97) if adaptive or refine else (0.005, 0.99)
    if "--gi" in extra:
        tol, f1 = 0.02, 0.95  # as the Cornell box's GI below
    T.check(abs(ngpu - ncpu) <= tol * ncpu, f"{scene} case {case}: counts within {tol:.1%} ({ncpu} vs {ngpu})")
    T.check(r["f1"] >= f1, f"{scene} case {case}: F1 {r['f1']} >= {f1}")
    if adaptive:
        scpu, sgpu = outs["cpu"][1]["samples"], outs["cuda"][1]["samples"]
        print(f"  adaptive samples: cpu {scpu}, cuda {sgpu}")
        T.check(abs(sgpu - scpu) <= 0.02 * scpu, f"{scene} case {case}: adaptive samples within 2% ({scpu} vs {sgpu})")

# an event buffer far too small: every segment overflows, is rendered again with a larger buffer,
# and the events are exactly those of a run that never overflowed (nothing dropped)
runs = {}
for label, extra in (("auto", []), ("tiny", ["--gpu-event-capacity", "1000"]),
                     ("adaptive-auto", ["--sampling", "adaptive"]),
                     ("adaptive-tiny", ["--sampling", "adaptive", "--gpu-event-capacity", "1000"])):
    d = os.path.join(tmp, f"overflow-{label}")
    T.run("demo", "--scene", "eye", "-o", d, "--backend", "cuda", "--res", "200x150", "--duration", "1.0",
          "--format", "npy", "--no-preview", "--quiet", *extra)
    runs[label] = open(os.path.join(d, "events.npy"), "rb").read()
T.check(len(runs["auto"]) > 100000 and runs["auto"] == runs["tiny"],
        "overflowing event buffers are re-rendered: identical events with a 1000-event initial buffer")
T.check(len(runs["adaptive-auto"]) > 100000 and runs["adaptive-auto"] == runs["adaptive-tiny"],
        "adaptive sampling: overflowing event buffers are re-rendered, identical events")

# a segment's events come to the host in pieces (cuda_state.cuh's EVENT_PIECE, 1,048,576 keys):
# pieces of 997 (the hidden EVR_EVENT_PIECE), hundreds a segment, ending inside runs of equal
# timestamps, give byte-identical files, event ids included
pieces = {}
for label, value in (("default", None), ("small", "997")):
    d = os.path.join(tmp, f"piece-{label}")
    if value:
        os.environ["EVR_EVENT_PIECE"] = value
    try:
        T.run("demo", "--scene", "eye", "-o", d, "--backend", "cuda", "--res", "200x150", "--duration", "1.0",
              "--event-ids", "--format", "npy,h5", "--no-preview", "--quiet")
    finally:
        os.environ.pop("EVR_EVENT_PIECE", None)
    pieces[label] = [open(os.path.join(d, f), "rb").read() for f in ("events.npy", "events.h5")]
T.check(len(pieces["default"][0]) > 100000 and pieces["default"] == pieces["small"],
        "events in pieces of 997: identical events.npy and events.h5 (ids included)")

# temporal coherence (a primary ray first bounded by its pixel's last hit, traced again unbounded
# when that finds nothing) changes no event: EVR_NO_COHERENCE turns it off
for scene, extra in (("eye", ["--res", "200x150", "--duration", "1.0", "--start", "0.9"]),
                     ("city", ["--res", "160x90", "--duration", "0.3"]),
                     ("square", ["--res", "96x96", "--duration", "1.0"])):
    evs = []
    for env in (None, "EVR_NO_COHERENCE"):
        d = os.path.join(tmp, f"coh-{scene}-{env}")
        T.run_env(env, "demo", "--scene", scene, "-o", d, "--backend", "cuda", "--format", "npy", "--no-preview", "--quiet", *extra)
        evs.append(open(os.path.join(d, "events.npy"), "rb").read())
    T.check(len(evs[0]) > 1000 and evs[0] == evs[1], f"{scene}: identical events with and without temporal coherence")

# global illumination on the GPU (cuda/cuda_gi.cu): the same photons as the CPU's up to float
# differences of the traversals; the buffer is filled in photon order (deterministic: two runs give
# the same events); a segment re-rendered after an overflow finds its own photons; a still Cornell
# box makes no events
gi = ["--gi", "photon", "--gi-blur", "0", "--res", "96x72", "--duration", "0.5", "--format", "npy,h5", "--seed", "5"]
gi_runs = {}
for label, extra in (("cpu", ["--backend", "cpu"]), ("cuda", ["--backend", "cuda"]), ("cuda2", ["--backend", "cuda"]),
                     ("cuda-tiny", ["--backend", "cuda", "--gpu-event-capacity", "1000"])):
    d = os.path.join(tmp, f"gi-{label}")
    T.run("demo", "--scene", "cornell", "-o", d, "--no-preview", "--quiet", *gi, *extra)
    gi_runs[label] = (d, open(os.path.join(d, "events.npy"), "rb").read(), T.load_run_json(d)["stats"])
st_cpu, st_gpu = gi_runs["cpu"][2], gi_runs["cuda"][2]
r = json.loads(T.run("compare", os.path.join(gi_runs["cpu"][0], "events.h5"), os.path.join(gi_runs["cuda"][0], "events.h5"),
                     "--tol-us", "100", "--json").stdout)
print(f"cornell GI: cpu {st_cpu['events']} events, cuda {st_gpu['events']}, F1 {r['f1']:.5f}; photons stored cpu "
      f"{st_cpu.get('photons_stored')} cuda {st_gpu.get('photons_stored')}; photon passes cpu {st_cpu.get('photon_passes')} "
      f"cuda {st_gpu.get('photon_passes')}")
T.check(st_gpu["events"] > 0 and abs(st_gpu["events"] - st_cpu["events"]) <= 0.02 * st_cpu["events"],
        "cornell GI: CUDA event count within 2% of the CPU's")
T.check(r["f1"] >= 0.95, f"cornell GI: CPU vs CUDA F1 {r['f1']} >= 0.95")
T.check(st_gpu.get("photon_passes") == st_cpu.get("photon_passes"), "cornell GI: the same photon passes (still segments reuse)")
T.check(gi_runs["cuda"][1] == gi_runs["cuda2"][1], "cornell GI on CUDA: two runs give identical events")
# the indirect light is linear in time between the photon passes at segment boundaries: GI's
# events do not cluster there (tests/test_gi.py on the CPU)
share = T.boundary_share(gi_runs["cuda"][1], st_gpu["segments"], 0.5)
print(f"cornell GI on CUDA: {share:.3f} of the events within a tenth of a segment of a boundary")
T.check(share < 0.3, "cornell GI on CUDA: events do not cluster at segment boundaries")
T.check(gi_runs["cuda"][1] == gi_runs["cuda-tiny"][1], "cornell GI on CUDA: overflowing segments re-rendered, identical events")
# the gathers deferred to a kernel of their own (cuda/cuda_gi_deferred.cu, the default with uniform
# sampling) give the events of the render kernel that gathers inline (EVR_GI_INLINE=1) bit for
# bit: with change-driven sampling, brute force and the full sensor model; and with a limit on the
# photons per estimate (--gather-max 8: the ring search, not the fixed-point sums)
for label, extra in (("skip", []), ("brute", ["--no-skip"]), ("davis346", ["--sensor", "davis346"]),
                     ("720p", ["--res", "1280x720", "--duration", "0.3"]), ("gather-max", ["--gather-max", "8"]),
                     ("blur", ["--gi-blur", "4"]), ("blur-brute", ["--gi-blur", "4", "--no-skip"])):
    evs = []
    for env in (None, "EVR_GI_INLINE"):
        d = os.path.join(tmp, f"gi-deferred-{label}-{env}")
        T.run_env(env, "demo", "--scene", "cornell", "-o", d, "--no-preview", "--quiet", "--backend", "cuda", *gi, *extra)
        evs.append(open(os.path.join(d, "events.npy"), "rb").read())
    T.check(len(evs[0]) > 10000 and evs[0] == evs[1], f"cornell GI ({label}): deferred and inline gathers give identical events")
# photons whose trails meet nothing that moves keep their outcome (core/photon.h): the same events
# as tracing every photon (EVR_NO_PHOTON_REUSE), and about as many photons reused as on the CPU
d = os.path.join(tmp, "gi-no-reuse")
T.run_env("EVR_NO_PHOTON_REUSE", "demo", "--scene", "cornell", "-o", d, "--no-preview", "--quiet", "--backend", "cuda", *gi)
st_nr = T.load_run_json(d)["stats"]
print(f"photon trails: cuda {st_gpu['photons_reused']} reused / {st_gpu['photons_traced']} traced, cpu "
      f"{st_cpu['photons_reused']} / {st_cpu['photons_traced']}; without reuse {st_nr['photons_traced']} traced")
T.check(open(os.path.join(d, "events.npy"), "rb").read() == gi_runs["cuda"][1],
        "cornell GI on CUDA: the same events with and without reusing photon trails")
T.check(st_gpu["photons_reused"] > st_gpu["photons_traced"] and st_nr["photons_reused"] == 0,
        "cornell GI on CUDA: most photons reuse their trails")
T.check(abs(st_gpu["photons_reused"] - st_cpu["photons_reused"]) <= 0.02 * st_cpu["photons_reused"],
        "cornell GI: CUDA reuses as many photon trails as the CPU (within 2%)")
# at 173x130 the gather's disk spans more than three pixels, so the normalization over the
# cells' view (their footprints' strips, core/photon_buffer.h) is on: CPU and CUDA agree, and the
# deferred gathers give the inline ones' events bit for bit
gi_big = ["--gi", "photon", "--gi-blur", "0", "--res", "173x130", "--duration", "0.5", "--format", "npy,h5", "--seed", "5"]
big = {}
# (and brute force: a launch over every pixel in 8x4 tiles has more threads than 173x130 pixels,
# and the deferred kernels' per-pixel entries once overran their arrays there)
for label, extra, env in (("cpu", ["--backend", "cpu"], None), ("cuda", ["--backend", "cuda"], None),
                          ("cuda-inline", ["--backend", "cuda"], "EVR_GI_INLINE"),
                          ("cuda-brute", ["--backend", "cuda", "--no-skip"], None)):
    d = os.path.join(tmp, f"gi-big-{label}")
    T.run_env(env, "demo", "--scene", "cornell", "-o", d, "--no-preview", "--quiet", *gi_big, *extra)
    big[label] = (d, open(os.path.join(d, "events.npy"), "rb").read())
r = json.loads(T.run("compare", os.path.join(big["cpu"][0], "events.h5"), os.path.join(big["cuda"][0], "events.h5"),
                     "--tol-us", "100", "--json").stdout)
print(f"cornell GI 173x130: CPU vs CUDA F1 {r['f1']:.5f}")
T.check(r["f1"] >= 0.95, f"cornell GI at 173x130: CPU vs CUDA F1 {r['f1']} >= 0.95")
T.check(len(big["cuda"][1]) > 10000 and big["cuda"][1] == big["cuda-inline"][1],
        "cornell GI at 173x130: deferred and inline gathers give identical events")
T.check(big["cuda"][1] == big["cuda-brute"][1], "cornell GI at 173x130 on CUDA: identical events with and without skipping")
# the photon buffer's layers follow the budget on the GPU as on the CPU (16 photons a pixel: 64
# layers, as good as none dropped, about the CPU's photons stored); 8 layers drop them, with the
# warning
layers_runs = {}
for label, extra in (("cpu", ["--backend", "cpu"]), ("cuda", ["--backend", "cuda"]),
                     ("cuda-8", ["--backend", "cuda", "--photon-layers", "8"])):
    d = os.path.join(tmp, f"gi-layers-{label}")
    p = T.run("demo", "--scene", "cornell", "-o", d, "--no-preview", "--quiet", *gi, "--photons", str(16 * 96 * 72),
              *extra)
    layers_runs[label] = (p.stderr, T.load_run_json(d)["stats"])
for label, (err, st) in layers_runs.items():
    print(f"GI, 16 photons a pixel, {label}: {st['photon_layers']} layers, {st['photons_stored']} stored, "
          f"{st['photon_collisions']} dropped")
(_, lc), (ec, lg), (e8, l8) = layers_runs["cpu"], layers_runs["cuda"], layers_runs["cuda-8"]
T.check(lg["photon_layers"] == 64 and lg["photon_collisions"] <= 0.01 * lg["photons_stored"] and "photon buffer" not in ec,
        "cornell GI on CUDA, 16 photons a pixel: 64 layers keep them")
T.check(abs(lg["photons_stored"] - lc["photons_stored"]) <= 0.02 * lc["photons_stored"],
        "cornell GI, 16 photons a pixel: CUDA stores as many photons as the CPU (within 2%)")
T.check(l8["photon_collisions"] > 0.01 * (l8["photons_stored"] + l8["photon_collisions"]) and
        sum("photon buffer" in l for l in e8.splitlines()) == 1, "cornell GI on CUDA, 8 layers: photons dropped, one warning")
for blur in ("0", "4"):
    d = os.path.join(tmp, f"gi-still-{blur}")
    T.run("demo", "--scene", "cornell-still", "-o", d, "--no-preview", "--quiet", "--backend", "cuda", "--gi", "photon",
          "--gi-blur", blur, "--res", "96x72", "--duration", "1.0")
    T.check(T.load_run_json(d)["stats"]["events"] == 0, f"cornell-still with GI (--gi-blur {blur}) on CUDA: no events over 1 s")
# Ctrl-C: the CUDA backend keeps each segment's latest events on the device for the next one's
# sort; the last segment the run finishes must give them up. The interrupted file equals, byte for
# byte, a run of the simulated length that was not interrupted (brute force, to be slow enough).
di = os.path.join(tmp, "int-cuda")
rc, err = T.interrupt(os.path.join(di, "events.npy.tmp"), 1.5, "demo", "--scene", "eye", "-o", di, "--backend", "cuda",
                      "--res", "1280x720", "--no-skip", "--format", "npy", "--no-preview")
T.check(rc == 130, f"interrupted CUDA run exits 130 (got {rc}: {err.strip()[-200:]})")
if rc == 130:
    meta = T.load_run_json(di)
    sim = meta["stats"]["simulated_seconds"]
    T.check(meta["stats"]["interrupted"] is True and 0 < sim < 29.9, f"stopped early ({sim} s)")
    dr = os.path.join(tmp, "int-cuda-ref")
    T.run("demo", "--scene", "eye", "-o", dr, "--backend", "cuda", "--res", "1280x720", "--no-skip", "--format",
          "npy", "--no-preview", "--quiet", "--duration", repr(sim))
    a, b = (open(os.path.join(x, "events.npy"), "rb").read() for x in (di, dr))
    print(f"interrupted at {sim} s: {meta['stats']['events']} events; the same length uninterrupted: "
          f"{T.load_run_json(dr)['stats']['events']}")
    T.check(a == b, "the interrupted run's events are those of an uninterrupted run of its length")

# EVR_TIMELINE (a measurement switch): one row per segment, in order, each row's host and GPU
# times in order, and the segments' own event counts adding up to the run's events
tl = os.path.join(tmp, "timeline.txt")
d = os.path.join(tmp, "timeline-run")
os.environ["EVR_TIMELINE"] = tl
try:
    T.run("demo", "--scene", "eye", "-o", d, "--backend", "cuda", "--res", "96x72", "--duration", "0.5", "--start", "0.9",
          "--format", "npy", "--no-preview", "--quiet")
    os.environ["EVR_TIMELINE"] = os.path.join(tmp, "no-such-folder", "timeline.txt")
    bad = T.run("demo", "--scene", "eye", "-o", os.path.join(tmp, "timeline-bad"), "--backend", "cuda", "--res", "32x24",
                "--duration", "0.1", "--no-preview", "--quiet", expect=None)
finally:
    os.environ.pop("EVR_TIMELINE", None)
lines = open(tl).read().split("\n")
head, rows = lines[0].split(), [list(map(float, l.split())) for l in lines[1:] if l.strip()]
col = {name: k for k, name in enumerate(head)}
T.check([int(r[col["seg"]]) for r in rows] == list(range(15)), f"timeline: one row per segment, in order ({len(rows)} rows)")
T.check(all(r[col["sub0"]] <= r[col["sub1"]] <= r[col["col1"]] and
            r[col["col0"]] <= r[col["counted"]] <= r[col["copied"]] <= r[col["col1"]] and
            r[col["g_start"]] <= r[col["g_rendered"]] <= r[col["g_copied"]] for r in rows), "timeline: each row's times in order")
T.check(int(sum(r[col["n"]] for r in rows)) == T.load_run_json(d)["stats"]["events"], "timeline: the segments' events add up")
T.check(bad.returncode != 0 and "cannot write" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1,
        f"timeline: an unwritable path is a one-line error ({bad.stderr.strip()!r})")

T.finish("test_cuda")
