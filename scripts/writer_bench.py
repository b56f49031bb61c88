#!/usr/bin/env python3
"""Whether each event writer keeps up with the render (docs/benchmarks.md, "Writers"): the built-in
eye run once per format and program, the formats and programs alternating, round after round, and
each run set against events.h5's run of the same program in the same round; the programs' order
turns from round to round.

    scripts/writer_bench.py EVRAY [BASE_EVRAY] [--formats h5,aedat4,rosbag] [--rounds 2] [--warm]
                            [--dir /dev/shm] [--res 1280x720] [--duration 30] [--backend cuda]

Each run is `evray demo --scene eye --backend B --res R --samples-per-frame 10 --duration D -o
DIR/writer-bench --no-preview -q --format F`; the figures come from its run.json. Prints one
Markdown row per run: format, program, wall seconds, the render's wait for the writer, the writer
thread's busy time, the wall against events.h5's in that round, the run's peak resident set, the
files' bytes and the first 16 hex digits of their sha256 (files of equal digits are
byte-identical). A run folder on tmpfs (the default) leaves the disk out of it."""
import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile


def find(obj, key):
    """The first value of key anywhere in run.json's objects."""
    if isinstance(obj, dict):
        if key in obj:
            return obj[key]
        for v in obj.values():
            r = find(v, key)
            if r is not None:
                return r
    return None


def digest(paths):
    h = hashlib.sha256()
    for p in paths:
        with open(p, "rb") as f:
            while True:
                b = f.read(1 << 24)
                if not b:
                    break
                h.update(b)
    return h.hexdigest()[:16]


def run(evray, fmt, a, out):
    shutil.rmtree(out, ignore_errors=True)
    cmd = [evray, "demo", "--scene", "eye", "--backend", a.backend, "--res", a.res,
           "--samples-per-frame", "10", "--duration", str(a.duration), "-o", out, "--no-preview",
           "-q", "--format", fmt]
    with tempfile.TemporaryFile(mode="w+") as err:
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)  # this run's own peak memory
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode != 0:
            err.seek(0)
            sys.exit("writer_bench: %s failed: %s" % (" ".join(cmd), err.read().strip()[-300:]))
    with open(os.path.join(out, "run.json")) as f:
        rj = json.load(f)
    files = sorted(os.path.join(out, n) for n in os.listdir(out) if n.startswith("events"))
    return {"wall": find(rj, "wall_seconds"), "wait": find(rj, "time_write_wait_seconds"),
            "busy": find(rj, "time_write_thread_seconds"), "peak_mb": usage.ru_maxrss // 1024,
            "bytes": sum(os.path.getsize(p) for p in files), "sha": digest(files)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("evray")
    ap.add_argument("base", nargs="?", help="a second program, run beside the first")
    ap.add_argument("--formats", default="h5,aedat4,aedat4-zstd,evt2,evt3,dat,rosbag,npy")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--dir", default="/dev/shm")
    ap.add_argument("--res", default="1280x720")
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--backend", default="cuda")
    ap.add_argument("--warm", action="store_true",
                    help="first one unmeasured run of each format (a fresh machine's first "
                         "gigabytes on tmpfs run slow)")
    a = ap.parse_args()
    programs = [("base", a.base)] if a.base else []
    programs.append(("new" if a.base else "evray", a.evray))
    formats = a.formats.split(",")
    if "h5" in formats:
        formats.remove("h5")
    out = os.path.join(a.dir, "writer-bench")
    print("| round | `--format` | program | wall s | wait s | writer busy s | / h5 | peak MB | bytes "
          "| sha256 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    h5_wall = {}  # each program's events.h5 run of this round
    if a.warm:
        for fmt in ["h5"] + formats:
            run(programs[0][1], fmt, a, out)
    for r in range(1, a.rounds + 1):
        for fmt in ["h5"] + formats:
            # the programs' order turns round by round: the first run after another format's
            # can be the slower one
            for name, evray in programs if r % 2 else programs[::-1]:
                m = run(evray, fmt, a, out)
                if fmt == "h5":
                    h5_wall[name], ratio = m["wall"], ""
                else:
                    ratio = "%.3fx" % (m["wall"] / h5_wall[name])
                print("| %d | %s | %s | %.3f | %.2f | %.2f | %s | %d | %d | %s |" % (
                    r, fmt, name, m["wall"], m["wait"], m["busy"], ratio, m["peak_mb"],
                    m["bytes"], m["sha"]), flush=True)
    shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
