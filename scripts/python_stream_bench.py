"""The cost of streaming events to Python against writing events.h5, one run of each in turn
(rounds interleaved, so that a busy machine slows both alike): the same scene and configuration
run by Simulator.run(out) writing events.h5 (no previews), by Simulator.stream() with a consumer
that only counts the events, and by one that keeps them all (np.concatenate at the end). Prints
each round's wall and CPU seconds (every thread of the process: on a shared machine less noisy
than wall time) and the medians' ratios to the file run. Run it with the Python that
has evray installed (scripts/python-venv.sh makes one):
    build/pyvenv/bin/python scripts/python_stream_bench.py [--scene eye] [--res 346x260]
        [--duration 0.3] [--rounds 3] [--backend auto]"""
import argparse
import resource
import shutil
import statistics
import tempfile
import time

import numpy as np

import evray

ap = argparse.ArgumentParser()
ap.add_argument("--scene", default="eye")
ap.add_argument("--res", default="346x260")
ap.add_argument("--duration", type=float, default=0.3, help="seconds; 0: the whole animation")
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--backend", default="auto")
a = ap.parse_args()
scene = evray.demo(a.scene)
span = {"duration": a.duration} if a.duration > 0 else {}
cfg = evray.Config(res=a.res, no_preview=True, format="h5", backend=a.backend, force=True, **span)
tmp = tempfile.mkdtemp(prefix="evray-bench-")


def file_run():
    sim = evray.Simulator(scene, cfg)
    sim.run(tmp + "/run")
    return sim.stats


def stream_count():
    sim = evray.Simulator(scene, cfg)
    n = 0
    for b in sim.stream():
        n += len(b)
    return sim.stats


def stream_keep():
    sim = evray.Simulator(scene, cfg)
    ev = np.concatenate(list(sim.stream()))
    assert len(ev) == sim.stats["events_on"] + sim.stats["events_off"]
    return sim.stats


ways = {"events.h5": file_run, "stream (count)": stream_count, "stream (keep all)": stream_keep}
def cpu_seconds():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


times = {k: [] for k in ways}
cpu = {k: [] for k in ways}
stats = None
for r in range(a.rounds):
    for k, f in ways.items():
        t, c = time.perf_counter(), cpu_seconds()
        stats = f()
        times[k].append(time.perf_counter() - t)
        cpu[k].append(cpu_seconds() - c)
        print(f"round {r}: {k}: {times[k][-1]:.3f} s, CPU {cpu[k][-1]:.3f} s", flush=True)
shutil.rmtree(tmp, ignore_errors=True)
events = stats["events_on"] + stats["events_off"]
print(f"{a.scene} {a.res} {a.duration} s, {events} events, backend {stats['backend']} ({stats['device']})")
base = statistics.median(times["events.h5"])
cbase = statistics.median(cpu["events.h5"])
print("| way | wall (median) | ratio | CPU (median) | ratio | events/s (wall) |")
for k, v in times.items():
    m, c = statistics.median(v), statistics.median(cpu[k])
    print(f"| {k} | {m:.3f} s | {m / base:.3f} | {c:.3f} s | {c / cbase:.3f} | {events / m / 1e6:.2f} M |")
