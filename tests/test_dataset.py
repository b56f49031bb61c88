"""evray dataset (python/evray/dataset.py, run by the evray program): a 6-clip specification over
built-in scenes runs to a complete manifest on this machine's cores; each clip's parameters follow
from the master seed and its index alone; a run killed halfway and run again finishes only the
missing clips; a clip remade alone is byte-identical to its run inside the dataset (events.h5,
labels.h5 and its scene); the loader reads every clip back; a bad specification gets one line.
The same on a local Dask cluster: tests/test_dataset_dask.py."""
import importlib.util
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import struct

import evrtest as T
import gltf_build

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
RUNNER = os.path.join(ROOT, "python", "evray", "dataset.py")

SPEC = {
    "clips": 6, "seed": 11,
    "scenes": [{"demo": "eye"}, {"demo": "square"}, {"demo": "disk", "weight": 0.5}],
    "format": "h5,npy", "labels_fps": 20,
    "options": {"duration": 0.2, "res": "48x36", "samples-per-frame": 10},
    "vary": {"thres": [0.15, 0.3], "sensor": {"choice": ["ideal", "davis346"]},
             "camera_path": {"kinds": ["orbit", "pan", "still"], "shake": 0.5},
             "light_intensity": [0.5, 2.0], "light_offset": 0.002, "base_color": 0.2,
             "scene_seed": True},
}


def slow_evray(tmp, evray):
    """A program that runs evray, except that clip 3's render hangs (a run to kill halfway)."""
    wrapper = os.path.join(tmp, "slow-evray")
    with open(wrapper, "w") as f:
        f.write("#!/bin/sh\ncase \"$*\" in *clips/00003*) sleep 600;; esac\n"
                f"exec {os.path.abspath(evray)} \"$@\"\n")
    os.chmod(wrapper, 0o755)
    return wrapper


def manifest(d):
    """The manifest's rows; a last line still being written (read while a run appends it, so
    without its newline yet) is left out, as evray.dataset.read_manifest leaves it out."""
    path = os.path.join(d, "manifest.jsonl")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [json.loads(l) for l in f if l.endswith("\n")]


def latest(d):
    rows = {}
    for r in manifest(d):
        rows[r["clip"]] = r
    return rows


def dataset(*args, expect=0, env=None):
    p = subprocess.run([T.EVRAY, "dataset", *args], capture_output=True, text=True, env=env)
    T.check(p.returncode == expect, f"evray dataset {' '.join(args)}: exit {p.returncode} "
            f"(expected {expect}); stderr: {p.stderr.strip()[-400:]}")
    return p


def same_files(a, b, names):
    for n in names:
        with open(os.path.join(a, n), "rb") as fa, open(os.path.join(b, n), "rb") as fb:
            if fa.read() != fb.read():
                return n
    return None


def load_runner():
    """The runner as a module from its file (the package's compiled part is not needed)."""
    spec_mod = importlib.util.spec_from_file_location("evray_dataset", RUNNER)
    mod = importlib.util.module_from_spec(spec_mod)
    spec_mod.loader.exec_module(mod)
    return mod


def main():
    tmp = tempfile.mkdtemp(prefix="evray-dataset-")
    try:
        spec = os.path.join(tmp, "spec.json")
        json.dump(SPEC, open(spec, "w"))

        # parameters: from the master seed and the index alone (more clips leave the first alone)
        a = dataset(spec, "-o", os.path.join(tmp, "x"), "--list").stdout.splitlines()
        more = dict(SPEC, clips=9)
        json.dump(more, open(os.path.join(tmp, "more.json"), "w"))
        b = dataset(os.path.join(tmp, "more.json"), "-o", os.path.join(tmp, "x"),
                    "--list").stdout.splitlines()
        T.check(len(a) == 6 and len(b) == 9 and b[:6] == a, "clip k's parameters depend on k alone")
        params = [json.loads(l) for l in a]
        T.check(len({p["seed"] for p in params}) == 6, "each clip has its own seed")
        eyes = [p for p in params if p["scene"].get("demo") == "eye"]
        T.check(all(p["scene"].get("seed") for p in eyes),
                f"the eye's clips draw their own gaze plan and iris (scene seeds: {eyes})")

        # the whole dataset on this machine's cores
        full = os.path.join(tmp, "full")
        t0 = time.time()
        e = dataset(spec, "-o", full).stderr.strip().splitlines()
        rows = latest(full)
        T.check(sorted(rows) == list(range(6)) and all(r["status"] == "done" for r in rows.values()),
                f"a complete manifest: {[(k, r['status'], r.get('error')) for k, r in rows.items()]}")
        for k, r in rows.items():
            folder = os.path.join(full, "clips", f"{k:05d}")
            T.check(r["events"] > 0 and {"events.h5", "events.npy", "labels.h5", "run.json"}
                    <= set(r["files"]) and all(os.path.exists(os.path.join(folder, f))
                                               for f in r["files"]),
                    f"clip {k}: its files and events ({r.get('files')}, {r.get('events')})")
            T.check(r["wall_s"] > 0 and r["params"] == params[k],
                    f"clip {k}: its row holds its parameters and wall time")
        print(f"test_dataset: 6 clips in {time.time() - t0:.1f} s, "
              f"{sum(r['events'] for r in rows.values()):,} events")
        total = sum(r["events"] for r in rows.values())
        T.check(e[-1] == f"evray dataset: 6 of 6 clips done (6 in this run), {total:,} events, "
                f"in {full}", f"the closing line: {e[-1]!r}")
        n_rows = len(manifest(full))
        e = dataset(spec, "-o", full).stderr.strip().splitlines()
        T.check(e[-1].startswith("evray dataset: 6 of 6 clips done (0 in this run)"),
                f"the closing line of a run with nothing left: {e[-1]!r}")
        T.check(len(manifest(full)) == n_rows, "a second run of a finished dataset runs nothing")
        # the scenes differ as drawn: two eye clips with different gaze plans
        glbs = [open(os.path.join(full, "scenes", f"{p['clip']:05d}.glb"), "rb").read()
                for p in eyes]
        T.check(len(set(glbs)) == len(glbs), "each eye clip has its own scene")

        # the edits are in each clip's scene: lights and base colours against the scene exported
        # as it is, the iris swapped for a file's (a spec of its own)
        mod = load_runner()
        for p in params:
            scene = p["scene"]
            base = os.path.join(tmp, "base.glb")
            subprocess.run([T.EVRAY, "demo", "--scene", scene["demo"], "--export", base],
                           capture_output=True, check=True)
            d0, _, _ = mod.read_gltf(base)
            d1, _, _ = mod.read_gltf(os.path.join(full, "scenes", f"{p['clip']:05d}.glb"))
            f = p["edits"]["light_intensity"]
            l0 = d0["extensions"]["KHR_lights_punctual"]["lights"]
            l1 = d1["extensions"]["KHR_lights_punctual"]["lights"]
            T.check(all(abs(b["intensity"] - a.get("intensity", 1.0) * f) <= 1e-6 * b["intensity"]
                        for a, b in zip(l0, l1)), f"clip {p['clip']}: light intensity times {f}")
            c0 = [m.get("pbrMetallicRoughness", {}).get("baseColorFactor", [1, 1, 1, 1])
                  for m in d0["materials"]]
            c1 = [m["pbrMetallicRoughness"]["baseColorFactor"] for m in d1["materials"]]
            T.check(all(min(1.0, a[i] * 0.8) - 1e-6 <= b[i] <= min(1.0, a[i] * 1.2) + 1e-6
                        and a[3] == b[3] for a, b in zip(c0, c1) for i in range(3)) and c0 != c1,
                    f"clip {p['clip']}: base colours within 1 +- 0.2 of the scene's")
            moved = [n for n0, n in zip(d0["nodes"], d1["nodes"])
                     if "KHR_lights_punctual" in n.get("extensions", {})
                     and n.get("translation") != n0.get("translation")]
            T.check(bool(moved) and all(abs(a - b) <= 0.002 + 1e-9 for n0, n in zip(d0["nodes"], d1["nodes"])
                                        if n in moved for a, b in zip(n0.get("translation", [0] * 3),
                                                                      n["translation"])),
                    f"clip {p['clip']}: lights moved by at most 0.002")
        with open(os.path.join(tmp, "blue.png"), "wb") as f:
            f.write(gltf_build.png_bytes(4, 4, [(40, 60, 200)] * 16, channels=3))
        swap = dict(SPEC, clips=1, scenes=[{"demo": "eye"}], vary={"textures": {"iris_texture":
                                                                              ["blue.png"]}})
        json.dump(swap, open(os.path.join(tmp, "swap.json"), "w"))
        dataset(os.path.join(tmp, "swap.json"), "-o", os.path.join(tmp, "swap"))
        d1, _, _ = mod.read_gltf(os.path.join(tmp, "swap", "scenes", "00000.glb"))
        iris = [im for im in d1["images"] if im.get("name") == "iris_texture"]
        T.check(len(iris) == 1 and iris[0].get("uri", "").startswith("data:image/png;base64,")
                and latest(os.path.join(tmp, "swap"))[0]["status"] == "done",
                "the iris texture swapped for a file's, and the clip rendered")
        # scene files with edits: a GLB and the same scene as .gltf with its buffer beside it (the
        # edited copy points at that buffer and may read it) give the same events
        os.makedirs(os.path.join(tmp, "ext"))
        sq = os.path.join(tmp, "ext", "sq.glb")
        subprocess.run([T.EVRAY, "demo", "--scene", "square", "--export", sq], capture_output=True,
                       check=True)
        doc, binary, _ = mod.read_gltf(sq)
        open(os.path.join(tmp, "ext", "sq.bin"), "wb").write(binary)
        doc["buffers"][0]["uri"] = "sq.bin"
        json.dump(doc, open(os.path.join(tmp, "ext", "sq.gltf"), "w"))
        events = {}
        for name in ("sq.glb", "sq.gltf"):
            d = os.path.join(tmp, "file-" + name)
            json.dump(dict(SPEC, clips=1, scenes=[{"file": "ext/" + name}],
                           vary={"base_color": 0.2, "light_intensity": [0.5, 2.0]}),
                      open(d + ".json", "w"))
            dataset(d + ".json", "-o", d)
            r = latest(d)[0]
            T.check(r["status"] == "done" and r["events"] > 0, f"{name} with edits renders: {r}")
            events[name] = mod.EventDataset(d, event_file="events.npy")[0]["events"]
            if name == "sq.gltf":
                copy = json.load(open(os.path.join(d, "scenes", "00000.gltf")))
                T.check(os.path.normpath(os.path.join(d, "scenes", copy["buffers"][0]["uri"])) ==
                        os.path.join(tmp, "ext", "sq.bin") and
                        "--allow-external-files" in r["command"],
                        "the edited .gltf points at its buffer where it lies and may read it")
        T.check(len(events["sq.glb"]) > 0 and
                (events["sq.glb"].tobytes() == events["sq.gltf"].tobytes()),
                "the same scene as GLB and as .gltf, edited alike, gives the same events")
        json.dump(dict(swap, vary={"textures": {"no_such_image": ["blue.png"]}}),
                  open(os.path.join(tmp, "swap2.json"), "w"))
        dataset(os.path.join(tmp, "swap2.json"), "-o", os.path.join(tmp, "swap2"), expect=1)
        r = latest(os.path.join(tmp, "swap2"))[0]
        T.check(r["status"] == "failed" and "no image named 'no_such_image'" in r["error"],
                f"a swap of an image the scene lacks fails the clip with a reason: {r.get('error')}")

        # killed halfway: clip 3 hangs (a wrapper around evray), the runner is killed; the rerun
        # runs clips 3, 4 and 5 only
        killed = os.path.join(tmp, "killed")
        wrapper = slow_evray(tmp, T.EVRAY)
        p = subprocess.Popen([sys.executable, RUNNER, spec, "-o", killed, "--jobs", "1",
                              "--evray", wrapper], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True)
        deadline = time.time() + 300
        while time.time() < deadline and len(latest(killed)) < 3:
            time.sleep(0.05)
        time.sleep(0.5)  # clip 3 has started and hangs
        e = dataset(spec, "-o", killed, expect=1).stderr.strip()
        T.check("another evray dataset is running" in e, f"a second run into a busy folder: {e!r}")
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        before = latest(killed)
        T.check(sorted(before) == [0, 1, 2] and all(r["status"] == "done" for r in before.values()),
                f"the killed run finished clips 0-2 ({[(k, r['status']) for k, r in before.items()]})")
        n_before = len(manifest(killed))
        dataset(spec, "-o", killed, "--jobs", "1")
        new = manifest(killed)[n_before:]
        T.check(sorted(r["clip"] for r in new) == [3, 4, 5] and all(r["status"] == "done"
                                                                     for r in new),
                f"the rerun ran only the missing clips: {[(r['clip'], r['status']) for r in new]}")
        for k in range(6):
            d = same_files(os.path.join(full, "clips", f"{k:05d}"),
                           os.path.join(killed, "clips", f"{k:05d}"),
                           ["events.h5", "events.npy", "labels.h5"])
            T.check(d is None, f"clip {k} of the resumed dataset: {d} differs from the full run's")

        # a clip remade alone, in a folder of its own
        alone = os.path.join(tmp, "alone")
        dataset(spec, "-o", alone, "--only", "4")
        T.check(sorted(latest(alone)) == [4], "--only 4 runs clip 4 alone")
        d = same_files(os.path.join(full, "clips", "00004"), os.path.join(alone, "clips", "00004"),
                       ["events.h5", "events.npy", "labels.h5"])
        T.check(d is None, f"clip 4 remade alone: {d} differs from its run in the dataset")
        T.check(same_files(os.path.join(full, "scenes"), os.path.join(alone, "scenes"),
                           ["00004.glb"]) is None, "clip 4's scene remade alone is the same")

        # the loader
        ds = mod.EventDataset(full, event_file="events.h5")
        T.check(len(ds) == 6, f"the loader sees 6 clips ({len(ds)})")
        for i, item in enumerate(ds):
            T.check(len(item["events"]) == rows[i]["events"] and item["clip"] == i and
                    item["labels"] and os.path.exists(item["labels"]),
                    f"clip {i} read back: {len(item['events'])} events, manifest {rows[i]['events']}")
            t = item["events"]["t"]
            T.check(bool((t[1:] >= t[:-1]).all()), f"clip {i}: events in time order")

        # bad specifications and arguments: one line each, exit 1
        for bad, what in [({"clips": 0, "scenes": [{"demo": "eye"}]}, "clips must be"),
                          (dict(SPEC, colour=1), "unknown key 'colour'"),
                          (dict(SPEC, vary={"thres": [0.3, 0.1]}), "runs backwards"),
                          (dict(SPEC, scenes=[{"demo": "eye", "file": "x.glb"}]), "each scene is")]:
            path = os.path.join(tmp, "bad.json")
            json.dump(bad, open(path, "w"))
            e = dataset(path, "-o", os.path.join(tmp, "bad"), expect=1).stderr.strip()
            T.check(len(e.splitlines()) == 1 and what in e, f"a bad specification: {e!r}")
        with open(os.path.join(tmp, "bad.glb"), "wb") as f:  # a GLB whose JSON is cut short
            f.write(b"glTF" + struct.pack("<III", 2, 32, 4) + b"JSON" + b'{"a')
        json.dump(dict(SPEC, clips=2, scenes=[{"file": "bad.glb"}]),
                  open(os.path.join(tmp, "badscene.json"), "w"))
        dataset(os.path.join(tmp, "badscene.json"), "-o", os.path.join(tmp, "badscene"), expect=1)
        rows = latest(os.path.join(tmp, "badscene"))
        T.check(sorted(rows) == [0, 1] and all(r["status"] == "failed" and "not a glTF file" in
                                               r["error"] for r in rows.values()),
                f"an unreadable scene fails each clip with its reason: {rows}")
        for args, rc, what in [(["--scene", "eye", "--scene-seed", "-3"], 2, "non-negative integer"),
                               (["--scene", "eye", "--scene-seed", "1" + "0" * 20], 2,
                                "non-negative integer"),
                               (["--scene", "square", "--scene-seed", "3"], 1,
                                "no variants; the scenes with variants are: eye eye-drift")]:
            p = subprocess.run([T.EVRAY, "demo", *args, "--export", os.path.join(tmp, "v.glb")],
                               capture_output=True, text=True)
            T.check(p.returncode == rc and what in p.stderr and len(p.stderr.splitlines()) == 1
                    and not os.path.exists(os.path.join(tmp, "v.glb")),
                    f"evray demo {' '.join(args)}: exit {p.returncode}, {p.stderr.strip()!r}")
        p = subprocess.run([T.EVRAY, "demo", "--list-variants"], capture_output=True, text=True)
        T.check(p.returncode == 0 and p.stdout.split() == ["eye", "eye-drift"],
                f"evray demo --list-variants: {p.stdout!r}")
        mixed = os.path.join(tmp, "mixed.json")  # a scene seed reaches only the scenes that vary
        json.dump({"clips": 12, "seed": 5, "scenes": [{"demo": "eye"}, {"demo": "square"}],
                   "vary": {"scene_seed": True}}, open(mixed, "w"))
        p = dataset(mixed, "-o", os.path.join(tmp, "mixed"), "--list")
        clips = [json.loads(line) for line in p.stdout.splitlines()]
        kinds = {(c["scene"]["demo"], "seed" in c["scene"]) for c in clips}
        T.check(len(clips) == 12 and kinds == {("eye", True), ("square", False)},
                f"scene_seed on eye and square clips: {sorted(kinds)}")
        other = os.path.join(tmp, "other.json")
        json.dump(dict(SPEC, seed=12), open(other, "w"))
        e = dataset(other, "-o", full, expect=1).stderr.strip()
        T.check("another specification" in e, f"a folder of another specification is refused: {e!r}")
        e = dataset(spec, "-o", os.path.join(tmp, "y"), "--only", "6", expect=1).stderr.strip()
        T.check("not in the dataset" in e, f"--only past the last clip: {e!r}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    T.finish("test_dataset")


if __name__ == "__main__":
    main()
