"""Datasets at scale: many evray runs ("clips") from one specification, as jobs on every local GPU
and core, or on a Dask cluster.

    evray dataset SPEC -o DIR [--scheduler ADDRESS|local:N] [--gpus N] [--per-gpu N] [--jobs N]
                  [--only K,...]
    python3 -m evray.dataset SPEC -o DIR ...           # the same (the evray program runs this)

    from evray.dataset import run, EventDataset
    run("spec.yaml", "out/")                           # the same from Python
    for clip in EventDataset("out/"): clip["events"]   # x, y, t (us), p: a PyTorch-style dataset

The specification (YAML or JSON; paths in it are relative to its own folder):

    clips: 6                      # how many clips
    seed: 1                       # the master seed: clip k's parameters follow from it and k alone
    scenes:                       # one drawn per clip (optional weight: N)
      - demo: eye                 # a built-in scene (evray demo --list)
      - file: robot.glb           # a glTF/GLB file (any scene evray renders)
    format: h5                    # --format of every clip (default h5)
    labels_fps: 30                # also labels.h5 at this rate (optional)
    options:                      # evray render options for every clip, name: value (true: a flag)
      duration: 3
      res: 346x260
    vary:                         # what each clip draws (from its own seed)
      res: [346x260, 640x480]               # a list: one of them
      thres: [0.15, 0.3]                    # two numbers: uniform between them
      sensor: {choice: [ideal, davis346]}   # explicit: choice, uniform [a, b], int [a, b]
      camera_path: {kinds: [orbit, dolly, pan, tilt, still], period: [4, 12], speed: [0.02, 0.1],
                    rate: [2, 10], shake: 0.5}  # or a list of --camera-path values
      light_intensity: [0.5, 2.0]           # every light's intensity times a factor
      light_offset: 0.01                    # every light moved by up to this along each axis
      base_color: 0.2                       # every base colour times 1 +- 0.2 per channel
      textures: {iris_texture: [iris_a.png, iris_b.png]}  # an image (by name) swapped
      scene_seed: true                      # built-in eye: its own gaze plan and iris per clip
    sensor_seed: true             # --seed of each clip from its seed (default true)

Any other key of vary is an evray render option. Each clip gets its own folder, DIR/clips/NNNNN
(the run folder: events in the chosen formats, labels, run.json); the scene it rendered (a
built-in scene exported, the variations applied) is DIR/scenes/NNNNN.glb. DIR/manifest.jsonl has
one row per finished attempt (clip, status, seed, parameters, command, files, events, wall
seconds, backend, error); the latest row of a clip counts. A second run of the same
specification into DIR skips the clips done and runs the rest (failed, killed or never started).
"""
import argparse
import base64
import concurrent.futures
import fcntl
import hashlib
import json
import os
import random
import shutil
import struct
import subprocess
import sys
import threading
import time

MANIFEST = "manifest.jsonl"
SPEC_COPY = "dataset.json"
LOCK = ".evray-dataset.lock"
SPECIAL = ("camera_path", "light_intensity", "light_offset", "base_color", "textures",
           "scene_seed")


class DatasetError(Exception):
    """A specification or a dataset folder evray cannot use (one line, for the user)."""


# ---- the specification ----

def load_spec(path):
    """The specification at path (YAML or JSON) as a dict, with its folder in "_dir"."""
    try:
        text = open(path, encoding="utf-8").read()
    except OSError as e:
        raise DatasetError(f"cannot read {path}: {e.strerror}")
    if path.endswith((".yaml", ".yml")):
        try:
            import yaml
        except ImportError:
            raise DatasetError(f"{path}: reading YAML needs PyYAML (pip install pyyaml), "
                               "or write the specification as JSON")
        try:
            spec = yaml.safe_load(text)
        except yaml.YAMLError as e:
            raise DatasetError(f"{path}: not valid YAML: {str(e).splitlines()[0]}")
    else:
        try:
            spec = json.loads(text)
        except ValueError as e:
            raise DatasetError(f"{path}: not valid JSON: {e}")
    check_spec(spec, path)
    spec["_dir"] = os.path.dirname(os.path.abspath(path))
    return spec


def check_spec(spec, where):
    if not isinstance(spec, dict):
        raise DatasetError(f"{where}: the specification must be a mapping")
    known = {"clips", "seed", "scenes", "format", "labels_fps", "options", "vary", "sensor_seed",
             "name"}
    for k in spec:
        if k not in known and not k.startswith("_"):
            raise DatasetError(f"{where}: unknown key '{k}' (known: {', '.join(sorted(known))})")
    clips = spec.get("clips")
    if not isinstance(clips, int) or isinstance(clips, bool) or clips < 1 or clips > 10**7:
        raise DatasetError(f"{where}: clips must be a whole number from 1 to 10000000")
    seed = spec.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise DatasetError(f"{where}: seed must be a whole number from 0")
    scenes = spec.get("scenes")
    if not isinstance(scenes, list) or not scenes:
        raise DatasetError(f"{where}: scenes must be a list of {{demo: NAME}} or {{file: PATH}}")
    for s in scenes:
        if not isinstance(s, dict) or len([k for k in ("demo", "file") if k in s]) != 1:
            raise DatasetError(f"{where}: each scene is {{demo: NAME}} or {{file: PATH}} (got {s!r})")
        w = s.get("weight", 1)
        if not isinstance(w, (int, float)) or isinstance(w, bool) or not w > 0:
            raise DatasetError(f"{where}: a scene's weight must be a number above 0 (got {w!r})")
    for key in ("options", "vary"):
        if not isinstance(spec.get(key, {}), dict):
            raise DatasetError(f"{where}: {key} must be a mapping of option names to values")
    for name, v in spec.get("vary", {}).items():
        if name not in SPECIAL:
            draw_value(random.Random(0), v, f"{where}: vary.{name}")  # fails on a bad range
    lf = spec.get("labels_fps")
    if lf is not None and (not isinstance(lf, (int, float)) or isinstance(lf, bool) or lf <= 0):
        raise DatasetError(f"{where}: labels_fps must be a number above 0")


def clip_seed(master, k):
    """Clip k's seed: a hash of the master seed and k alone (the same on any machine)."""
    h = hashlib.sha256(f"evray-dataset:{master}:{k}".encode()).digest()
    return int.from_bytes(h[:8], "little")


def draw_value(rng, v, where):
    """A value drawn from a vary entry: a list of two numbers is a uniform range, any other list a
    choice; {choice: [...]}, {uniform: [a, b]}, {int: [a, b]} say it outright; a scalar is
    itself."""
    if isinstance(v, dict):
        if len(v) != 1:
            raise DatasetError(f"{where}: one of choice, uniform or int (got {sorted(v)})")
        (kind, arg), = v.items()
        if kind == "choice" and isinstance(arg, list) and arg:
            return arg[rng.randrange(len(arg))]
        if kind in ("uniform", "int") and isinstance(arg, list) and len(arg) == 2 and \
                all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in arg) and \
                arg[0] <= arg[1]:
            return rng.uniform(arg[0], arg[1]) if kind == "uniform" else rng.randint(int(arg[0]),
                                                                                     int(arg[1]))
        raise DatasetError(f"{where}: {kind} needs a list (choice) or [low, high] (uniform, int)")
    if isinstance(v, list):
        if not v:
            raise DatasetError(f"{where}: an empty list")
        if len(v) == 2 and all(isinstance(a, (int, float)) and not isinstance(a, bool) for a in v):
            if v[0] > v[1]:
                raise DatasetError(f"{where}: the range [{v[0]}, {v[1]}] runs backwards")
            return rng.uniform(v[0], v[1])
        return v[rng.randrange(len(v))]
    return v


def camera_path(rng, v, seed, where):
    """A --camera-path value (None: the camera's own motion) from vary.camera_path."""
    if isinstance(v, list) or not isinstance(v, dict) or "kinds" not in v:
        p = draw_value(rng, v, where)
        return None if p in (None, "", "still", "none") else str(p)
    kinds = v["kinds"]
    if not isinstance(kinds, list) or not kinds:
        raise DatasetError(f"{where}: kinds must be a list of orbit, dolly, pan, tilt, still")
    kind = kinds[rng.randrange(len(kinds))]
    def rnd(name, lo, hi):
        r = v.get(name, [lo, hi])
        return draw_value(rng, r, f"{where}.{name}")
    if kind == "orbit":
        path = f"orbit:period={rnd('period', 4.0, 12.0):.4g}"
    elif kind == "dolly":
        path = f"dolly:speed={rnd('speed', 0.02, 0.1):.4g}"
    elif kind in ("pan", "tilt"):
        path = f"{kind}:rate={rng.choice((-1, 1)) * rnd('rate', 2.0, 10.0):.4g}"
    elif kind in ("still", "none"):
        path = None
    else:
        raise DatasetError(f"{where}: unknown camera path kind '{kind}' "
                           "(orbit, dolly, pan, tilt, still)")
    shake = v.get("shake", 0.0)
    if not isinstance(shake, (int, float)) or not 0.0 <= shake <= 1.0:
        raise DatasetError(f"{where}.shake: the odds of a hand-held shake, 0 to 1")
    if rng.random() < shake:
        s = f"shake:seed={seed % 2**31}"
        path = s if path is None else path + "+" + s
    return path


def find_evray(evray=None):
    evray = evray or os.environ.get("EVRAY") or shutil.which("evray")
    if not evray:
        raise DatasetError("no evray program found: pass evray=PATH (or --evray), or put it on PATH")
    return evray


def variant_demos(spec, evray):
    """The spec's built-in scenes that take a scene seed, as the program says (none are asked
    for when nothing varies scene_seed)."""
    if not spec.get("vary", {}).get("scene_seed") or \
            not any("demo" in s for s in spec["scenes"]):
        return frozenset()
    try:
        p = subprocess.run([evray, "demo", "--list-variants"], capture_output=True, text=True)
    except OSError as e:
        raise DatasetError(f"cannot run {evray}: {e.strerror}")
    if p.returncode != 0:
        raise DatasetError(f"{evray} demo --list-variants: exit {p.returncode}: "
                           f"{p.stderr.strip()[-300:]}")
    return frozenset(p.stdout.split())


def clip_params(spec, k, variants=frozenset()):
    """Everything clip k draws, from the master seed and k alone: a JSON-able dict. variants: the
    built-in scenes that take a scene seed (variant_demos)."""
    seed = clip_seed(spec.get("seed", 0), k)
    rng = random.Random(seed)
    scenes = spec["scenes"]
    weights = [s.get("weight", 1) for s in scenes]
    r, acc, pick = rng.random() * sum(weights), 0.0, len(scenes) - 1
    for i, w in enumerate(weights):
        acc += w
        if r < acc:
            pick = i
            break
    scene = {key: val for key, val in scenes[pick].items() if key != "weight"}
    vary = spec.get("vary", {})
    options, edits = {}, {}
    for name in sorted(vary):  # sorted: the draws do not depend on the file's key order
        v, where = vary[name], f"vary.{name}"
        if name == "camera_path":
            p = camera_path(rng, v, seed, where)
            if p:
                options["camera-path"] = p
        elif name == "light_intensity":
            edits["light_intensity"] = float(draw_value(rng, v, where))
        elif name == "light_offset":
            a = float(draw_value(rng, v, where))
            edits["light_offset_rng"] = rng.randrange(2**31)
            edits["light_offset"] = a
        elif name == "base_color":
            edits["base_color"] = float(draw_value(rng, v, where))
            edits["base_color_rng"] = rng.randrange(2**31)
        elif name == "textures":
            if not isinstance(v, dict):
                raise DatasetError(f"{where}: a mapping of image names to lists of files")
            edits["textures"] = {img: draw_value(rng, files, f"{where}.{img}")
                                 for img, files in sorted(v.items())}
        elif name == "scene_seed":
            if v and scene.get("demo") in variants:
                scene["seed"] = 1 + seed % (2**63 - 1)
        else:
            options[name.replace("_", "-")] = draw_value(rng, v, where)
    if spec.get("sensor_seed", True) and "seed" not in options:
        options["seed"] = seed % 2**31
    return {"clip": k, "seed": seed, "scene": scene, "options": options, "edits": edits}


# ---- scene edits (glTF 2.0: KHR_lights_punctual lights, materials, images) ----

def read_gltf(path):
    """(json dict, bin bytes or None, is_glb)."""
    try:
        return parse_gltf(path, open(path, "rb").read())
    except (ValueError, struct.error, UnicodeDecodeError) as e:
        raise DatasetError(f"{path}: not a glTF file evray dataset can edit ({e})")


def parse_gltf(path, data):
    if data[:4] == b"glTF":
        if len(data) < 20:
            raise DatasetError(f"{path}: a truncated GLB")
        n = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + n].decode("utf-8"))
        off, binary = 20 + n, None
        if off + 8 <= len(data):
            m, kind = struct.unpack_from("<II", data, off)
            if kind == 0x004E4942:
                binary = data[off + 8:off + 8 + m]
        return doc, binary, True
    return json.loads(data.decode("utf-8")), None, False


def write_glb(path, doc, binary):
    js = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary is not None:
        b = binary + b"\0" * (-len(binary) % 4)
        chunks += struct.pack("<II", len(b), 0x004E4942) + b
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
    os.replace(tmp, path)


def apply_edits(doc, edits, spec_dir, where):
    """Applies a clip's edits to a glTF document in place."""
    if "light_intensity" in edits:
        lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
        for li in lights:
            li["intensity"] = li.get("intensity", 1.0) * edits["light_intensity"]
    if "light_offset" in edits:
        rng = random.Random(edits["light_offset_rng"])
        a = edits["light_offset"]
        for node in doc.get("nodes", []):
            if "light" in node.get("extensions", {}).get("KHR_lights_punctual", {}):
                if "matrix" in node:
                    for i in (12, 13, 14):
                        node["matrix"][i] += rng.uniform(-a, a)
                else:
                    t = node.get("translation", [0.0, 0.0, 0.0])
                    node["translation"] = [c + rng.uniform(-a, a) for c in t]
    if "base_color" in edits:
        rng = random.Random(edits["base_color_rng"])
        a = edits["base_color"]
        for m in doc.get("materials", []):
            pbr = m.setdefault("pbrMetallicRoughness", {})
            c = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
            pbr["baseColorFactor"] = [min(1.0, max(0.0, c[i] * (1.0 + rng.uniform(-a, a))))
                                      for i in range(3)] + [c[3]]
    for name, file in edits.get("textures", {}).items():
        images = [im for im in doc.get("images", []) if im.get("name") == name]
        if not images:
            raise DatasetError(f"{where}: the scene has no image named '{name}' to swap")
        path = os.path.join(spec_dir, file)
        try:
            data = open(path, "rb").read()
        except OSError as e:
            raise DatasetError(f"{where}: cannot read texture {path}: {e.strerror}")
        mime = "image/png" if data[:8] == b"\x89PNG\r\n\x1a\n" else \
            "image/jpeg" if data[:3] == b"\xff\xd8\xff" else None
        if mime is None:
            raise DatasetError(f"{where}: {path} is neither PNG nor JPEG")
        for im in images:
            im.pop("bufferView", None)
            im["mimeType"] = mime
            im["uri"] = f"data:{mime};base64," + base64.b64encode(data).decode("ascii")


def moved_uris(doc, src_folder, dst_folder):
    """A .gltf's buffer and image URIs, relative to src_folder, made relative to dst_folder, where
    its edited copy lives (glTF URIs are relative references, not file system paths)."""
    from urllib.parse import quote, unquote
    for key in ("buffers", "images"):
        for item in doc.get(key, []):
            uri = item.get("uri")
            if uri and not uri.startswith("data:"):
                target = os.path.join(src_folder, unquote(uri))
                item["uri"] = quote(os.path.relpath(target, dst_folder))


# ---- one clip ----

def clip_dir(out, k):
    return os.path.join(out, "clips", f"{k:05d}")


def scene_path(out, k):
    return os.path.join(out, "scenes", f"{k:05d}.glb")


def in_dataset(out, path):
    """A path inside the dataset folder as the clip's command gives it: relative (evray runs
    there), so that the run's files, which record their scene, are the same wherever the dataset
    is made."""
    rel = os.path.relpath(path, out)
    return path if rel.startswith("..") else rel


def prepare_scene(job):
    """The clip's scene file (a built-in scene exported, then edited as its parameters say) and
    the extra options it needs."""
    p, out, evray = job["params"], job["out"], job["evray"]
    scene, edits, k = p["scene"], p["edits"], p["clip"]
    os.makedirs(os.path.join(out, "scenes"), exist_ok=True)
    dst = scene_path(out, k)
    if "demo" in scene:
        cmd = [evray, "demo", "--scene", scene["demo"], "--export", dst]
        if scene.get("seed"):
            cmd[4:4] = ["--scene-seed", str(scene["seed"])]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise DatasetError((r.stderr.strip() or r.stdout.strip()).splitlines()[-1])
        src = dst
    else:
        src = os.path.join(job["spec_dir"], scene["file"])
        if not os.path.exists(src):
            raise DatasetError(f"clip {k}: no scene file {src}")
    if not edits:
        return src, []
    doc, binary, glb = read_gltf(src)
    apply_edits(doc, edits, job["spec_dir"], f"clip {k}")
    if glb:
        write_glb(dst, doc, binary)
        return dst, []
    # a .gltf: its buffers and images stay where they are
    moved_uris(doc, os.path.dirname(os.path.abspath(src)), os.path.dirname(dst))
    dst = dst[:-4] + ".gltf"
    with open(dst + ".tmp", "w", encoding="utf-8") as f:
        json.dump(doc, f)
    os.replace(dst + ".tmp", dst)
    return dst, ["--allow-external-files"]


def render_command(job, scene_file, extra):
    p = job["params"]
    out = job["out"]
    cmd = [job["evray"], "render", in_dataset(out, scene_file), "-o",
           in_dataset(out, clip_dir(out, p["clip"])), "--force",
           "--quiet", "--no-preview", "--format", job["format"]]
    if job.get("labels_fps"):
        cmd += ["--labels-fps", str(job["labels_fps"])]
    opts = dict(job["options"])
    opts.update(p["options"])
    for name, v in sorted(opts.items()):
        flag = "--" + name.replace("_", "-")
        if v is True:
            cmd.append(flag)
        elif v is False or v is None:
            continue
        else:
            cmd += [flag, f"{v:.6g}" if isinstance(v, float) else str(v)]
    if job.get("threads"):
        cmd += ["--threads", str(job["threads"])]
    if job.get("backend") and "backend" not in opts:
        cmd += ["--backend", job["backend"]]
    return cmd + extra


def run_clip(job):
    """Runs one clip (on this machine: a local worker thread or a Dask worker): its scene, then
    evray render into its folder. Returns its manifest row."""
    p = job["params"]
    t0 = time.time()
    row = {"clip": p["clip"], "seed": p["seed"], "params": p, "status": "failed"}
    env = dict(os.environ)
    if job.get("gpu") is not None:
        env["CUDA_VISIBLE_DEVICES"] = str(job["gpu"])
    try:
        scene_file, extra = prepare_scene(job)
        cmd = render_command(job, scene_file, extra)
        row["command"] = cmd
        r = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=job["out"])
        if r.returncode != 0:
            lines = (r.stderr.strip() or r.stdout.strip() or f"exit {r.returncode}").splitlines()
            raise DatasetError(lines[-1])
        folder = clip_dir(job["out"], p["clip"])
        info = json.load(open(os.path.join(folder, "run.json")))
        row["files"] = sorted(f for f in os.listdir(folder) if not f.startswith("."))
        row["events"] = int(info["stats"]["events"])
        row["backend"] = info.get("backend")
        row["status"] = "done"
    except Exception as e:  # a clip that fails (its scene unreadable, ...) fails alone
        row["error"] = str(e) if isinstance(e, DatasetError) else f"{type(e).__name__}: {e}"
    row["wall_s"] = round(time.time() - t0, 3)
    return row


# ---- the manifest ----

def read_manifest(out):
    """The latest row of each clip (a dict clip -> row); a torn last line is ignored."""
    rows = {}
    path = os.path.join(out, MANIFEST)
    if not os.path.exists(path):
        return rows
    with open(path, encoding="utf-8") as f:
        for line in f:
            try:
                row = json.loads(line)
            except ValueError:
                continue
            if isinstance(row, dict) and isinstance(row.get("clip"), int):
                rows[row["clip"]] = row
    return rows


def clip_done(out, row):
    return row is not None and row.get("status") == "done" and \
        os.path.exists(os.path.join(clip_dir(out, row["clip"]), "run.json"))


class Manifest:
    """DIR/manifest.jsonl, appended a row at a time as clips finish (flushed and synced)."""

    def __init__(self, out):
        self.f = open(os.path.join(out, MANIFEST), "a", encoding="utf-8")
        self.lock = threading.Lock()

    def add(self, row):
        with self.lock:
            self.f.write(json.dumps(row, sort_keys=True) + "\n")
            self.f.flush()
            os.fsync(self.f.fileno())

    def close(self):
        self.f.close()


# ---- where the jobs run ----

def local_gpus():
    """The GPUs of this machine (their CUDA indices), [] when none."""
    vis = os.environ.get("CUDA_VISIBLE_DEVICES")
    if vis is not None:
        return [g for g in vis.split(",") if g.strip() and g.strip() != "-1"]
    try:
        r = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return []
    return [str(i) for i, line in enumerate(r.stdout.splitlines()) if line.startswith("GPU ")] \
        if r.returncode == 0 else []


class Progress:
    def __init__(self, total, done, events, stream=sys.stderr):
        self.total, self.done, self.events, self.stream = total, done, events, stream
        self.t0, self.ran, self.failed = time.time(), 0, 0
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def update(self, row):
        if row["status"] == "done":
            self.done += 1
            self.ran += 1
            self.events += row.get("events", 0)
        else:
            self.failed += 1
        left = self.total - self.done - self.failed
        el = time.time() - self.t0
        eta = el / self.ran * left if self.ran else float("nan")
        eta_s = "?" if eta != eta else time.strftime("%H:%M:%S", time.gmtime(eta))
        msg = (f"[{self.done}/{self.total} clips] {self.events:,} events, {self.failed} failed, "
               f"ETA {eta_s}")
        if row["status"] != "done":
            print(("\n" if self.tty else "") + f"clip {row['clip']} failed: {row.get('error')}",
                  file=self.stream)
        print(("\r" + msg) if self.tty else msg, end="" if self.tty else "\n", file=self.stream,
              flush=True)

    def finish(self):
        if self.tty:
            print(file=self.stream)


def default_jobs(cores):
    """CPU jobs for this many cores: one per 8 cores (at least one), the cores split among them."""
    jobs = max(1, cores // 8)
    return jobs, max(1, cores // jobs)


def run(spec, out, scheduler=None, gpus=None, jobs=None, only=None, evray=None, progress=True,
        backend=None, per_gpu=1):
    """Runs the dataset of spec (a path or a dict as load_spec returns) into folder out; returns
    the manifest's rows of this run's clips. scheduler: a Dask scheduler's address, or "local:N"
    for a local Dask cluster of N worker processes (None: this machine's GPUs, else its cores).
    only: clip indices to run (remade even when done). per_gpu: clips at once on each GPU."""
    if isinstance(spec, str):
        spec = load_spec(spec)
    evray = find_evray(evray)
    out = os.path.abspath(out)
    os.makedirs(out, exist_ok=True)
    lock = open(os.path.join(out, LOCK), "w")  # held until this run ends (closed or exited)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        lock.close()
        raise DatasetError(f"another evray dataset is running into {out}")
    try:
        return run_locked(spec, out, scheduler, gpus, jobs, only, evray, progress, backend,
                          per_gpu)
    finally:
        lock.close()


def run_locked(spec, out, scheduler, gpus, jobs, only, evray, progress, backend, per_gpu):
    public = {k: v for k, v in spec.items() if not k.startswith("_")}
    copy = os.path.join(out, SPEC_COPY)
    if os.path.exists(copy):
        before = json.load(open(copy))
        if before != public:
            raise DatasetError(f"{out} holds a dataset of another specification "
                               f"({SPEC_COPY} differs): use a new folder")
    else:
        with open(copy + ".tmp", "w") as f:
            json.dump(public, f, indent=1, sort_keys=True)
        os.replace(copy + ".tmp", copy)
    n = spec["clips"]
    if only is not None:
        bad = [k for k in only if not 0 <= k < n]
        if bad:
            raise DatasetError(f"clip {bad[0]} is not in the dataset (0 to {n - 1})")
    rows = read_manifest(out)
    todo = sorted(set(only)) if only is not None else \
        [k for k in range(n) if not clip_done(out, rows.get(k))]
    done_before = 0 if only is not None else n - len(todo)
    events_before = 0 if only is not None else \
        sum(r.get("events", 0) for k, r in rows.items() if k < n and clip_done(out, r))
    base = {"out": out, "evray": os.path.abspath(evray), "spec_dir": spec["_dir"],
            "format": spec.get("format", "h5"), "labels_fps": spec.get("labels_fps"),
            "options": spec.get("options", {})}
    variants = variant_demos(spec, evray)
    jobs_list = [dict(base, params=clip_params(spec, k, variants)) for k in todo]
    prog = Progress(len(todo) + done_before, done_before, events_before) if progress else None
    manifest = Manifest(out)
    finished = []

    def record(row):
        manifest.add(row)
        finished.append(row)
        if prog:
            prog.update(row)

    try:
        if scheduler:
            run_dask(jobs_list, scheduler, record)
        else:
            run_local(jobs_list, gpus, jobs, backend, record, per_gpu)
    finally:
        manifest.close()
        if prog:
            prog.finish()
    return sorted(finished, key=lambda r: r["clip"])


def run_local(jobs_list, gpus, jobs, backend, record, per_gpu=1):
    """per_gpu jobs on each GPU (CUDA_VISIBLE_DEVICES set to it), else CPU jobs sized to the
    cores."""
    found = local_gpus() if backend != "cpu" else []
    if gpus is not None:
        if gpus > len(found):
            raise DatasetError(f"--gpus {gpus}: this machine has {len(found)}")
        found = found[:gpus]
    cores = os.cpu_count() or 1
    if found:  # the host's cores shared out too: each run would take them all
        threads = max(1, cores // (len(found) * per_gpu))
        slots = [{"gpu": g, "backend": backend or "cuda", "threads": threads}
                 for _ in range(per_gpu) for g in found]
    else:
        n, threads = default_jobs(cores)
        if jobs:
            n, threads = jobs, max(1, cores // jobs)
        slots = [{"threads": threads, "backend": backend or "cpu"} for _ in range(n)]
    free = list(range(len(slots)))
    lock = threading.Lock()

    def one(job):
        with lock:
            s = free.pop()
        try:
            return run_clip(dict(job, **slots[s]))
        finally:
            with lock:
                free.append(s)

    with concurrent.futures.ThreadPoolExecutor(len(slots)) as pool:
        for fut in concurrent.futures.as_completed([pool.submit(one, j) for j in jobs_list]):
            record(fut.result())


def run_dask(jobs_list, scheduler, record):
    """The clips as tasks of a Dask cluster (dask.distributed): each worker runs evray on its own
    machine (the dataset folder and the program must be on a file system they share)."""
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise DatasetError("--scheduler needs Dask: pip install 'dask[distributed]'")
    cluster = None
    if scheduler.startswith("local:"):
        try:
            workers = int(scheduler[6:])
        except ValueError:
            raise DatasetError(f"--scheduler {scheduler}: local:N, N the worker count")
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        futures = [client.submit(run_clip, j, pure=False, key=f"evray-clip-{j['params']['clip']}")
                   for j in jobs_list]
        for fut in as_completed(futures):
            record(fut.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


# ---- reading a dataset back ----

def _read_events(path):
    try:
        from evray import read  # the package's reader: any format evray writes
        return read(path)
    except ImportError:
        pass
    if path.endswith(".npy"):
        import numpy as np
        return np.load(path)
    if path.endswith(".h5"):
        import h5py
        import numpy as np
        with h5py.File(path, "r") as f:
            e = f["events"]
            a = np.empty(len(e["t"]), dtype=[("x", "<u2"), ("y", "<u2"), ("t", "<i8"), ("p", "i1")])
            for k in ("x", "y", "t", "p"):
                a[k] = e[k][:]
            return a
    raise DatasetError(f"{path}: reading it needs the evray package (pip install evray)")


class EventDataset:
    """The finished clips of a dataset folder as a map-style dataset: len() and [i], as PyTorch's
    DataLoader takes one (no torch needed here). Item i is a dict: events (a NumPy structured
    array: x, y, t in microseconds, p), clip, seed, params (what it drew), folder, labels (the
    path of labels.h5, or None). transform, if given, is applied to each item."""

    def __init__(self, root, transform=None, event_file=None):
        self.root = os.path.abspath(root)
        if not os.path.exists(os.path.join(self.root, SPEC_COPY)):
            raise DatasetError(f"{root} is not a dataset folder (no {SPEC_COPY})")
        rows = read_manifest(self.root)
        self.rows = [rows[k] for k in sorted(rows) if clip_done(self.root, rows[k])]
        self.transform = transform
        self.event_file = event_file

    def __len__(self):
        return len(self.rows)

    def __getitem__(self, i):
        row = self.rows[i]
        folder = clip_dir(self.root, row["clip"])
        names = [self.event_file] if self.event_file else \
            [f for f in row.get("files", []) if f.startswith("events")]
        if not names:
            raise DatasetError(f"clip {row['clip']}: no event file")
        labels = os.path.join(folder, "labels.h5")
        item = {"events": _read_events(os.path.join(folder, names[0])), "clip": row["clip"],
                "seed": row["seed"], "params": row["params"], "folder": folder,
                "labels": labels if os.path.exists(labels) else None}
        return self.transform(item) if self.transform else item

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]


# ---- the command ----

def main(argv=None):
    ap = argparse.ArgumentParser(prog="evray dataset", description=(
        "Runs the clips of a dataset specification (YAML or JSON) as evray jobs: on every local "
        "GPU (one job each), else on the cores, or on a Dask cluster; DIR/manifest.jsonl grows a "
        "row per finished clip, and a second run finishes only what is missing."))
    ap.add_argument("spec")
    ap.add_argument("-o", "--out", required=True, help="the dataset folder")
    ap.add_argument("--scheduler", help="a Dask scheduler's address, or local:N (N workers here)")
    ap.add_argument("--gpus", type=int, help="use only the first N GPUs of this machine")
    ap.add_argument("--jobs", type=int, help="CPU jobs at once (default: one per 8 cores)")
    ap.add_argument("--per-gpu", type=int, default=1,
                    help="clips at once on each GPU (default 1; a small clip leaves a GPU idle)")
    ap.add_argument("--backend", choices=["cpu", "cuda"], help="the backend of every clip")
    ap.add_argument("--only", help="clip indices to run (remade even when done): K[,K...]")
    ap.add_argument("--evray", help="the evray program (default: $EVRAY, else evray on PATH)")
    ap.add_argument("--list", action="store_true", help="print each clip's parameters and stop")
    a = ap.parse_args(argv)
    try:
        if a.jobs is not None and a.jobs < 1:
            raise DatasetError("--jobs needs a whole number from 1")
        if a.gpus is not None and a.gpus < 1:
            raise DatasetError("--gpus needs a whole number from 1")
        if a.per_gpu < 1:
            raise DatasetError("--per-gpu needs a whole number from 1")
        spec = load_spec(a.spec)
        only = None
        if a.only:
            try:
                only = [int(x) for x in a.only.split(",")]
            except ValueError:
                raise DatasetError(f"--only takes clip indices K[,K...] (got '{a.only}')")
        if a.list:
            variants = variant_demos(spec, find_evray(a.evray))
            for k in (only if only is not None else range(spec["clips"])):
                print(json.dumps(clip_params(spec, k, variants), sort_keys=True))
            return 0
        rows = run(spec, a.out, scheduler=a.scheduler, gpus=a.gpus, jobs=a.jobs, only=only,
                   evray=a.evray, backend=a.backend, per_gpu=a.per_gpu)
    except DatasetError as e:
        print(f"evray dataset: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("\nevray dataset: interrupted; run the same command again to finish the missing clips",
              file=sys.stderr)
        return 130
    failed = [r for r in rows if r["status"] != "done"]
    out = os.path.abspath(a.out)
    done = [r for k, r in read_manifest(out).items() if k < spec["clips"] and clip_done(out, r)]
    print(f"evray dataset: {len(done)} of {spec['clips']} clips done ({len(rows) - len(failed)} in "
          f"this run), {sum(r.get('events', 0) for r in done):,} events, in {a.out}",
          file=sys.stderr)
    if failed:
        print(f"evray dataset: {len(failed)} of {len(rows)} clips failed (manifest.jsonl says why); "
              "run the same command again to retry them", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
