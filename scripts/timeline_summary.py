#!/usr/bin/env python3
"""Sums up a CUDA run's per-segment timeline (EVR_TIMELINE=FILE evray ...; docs/architecture.md):
where the GPU idled between renders and what the host did meanwhile.

    scripts/timeline_summary.py FILE [--json]

All times in seconds. GPU idle is the time between one segment's render end and the next one's
start; host times are the main thread's inside the backend (submit; collect: waiting for the
render's count, waiting for the sort and copy, then its own work: decoding the keys), and the
loop's work between backend calls (handing events to the writers, planning waits)."""
import json
import sys

FIELDS = ("seg", "sub0", "sub1", "col0", "counted", "copied", "col1", "g_start", "g_rendered", "g_sort", "g_copied", "n")


def load(path):
    """The timeline's rows as dicts, in segment order; a clear error for anything else."""
    with open(path) as f:
        lines = [l.split() for l in f if l.strip() and not l.startswith("#")]
    if not lines or tuple(lines[0]) != FIELDS:
        raise SystemExit(f"{path}: not an evray timeline (its first line must be: {' '.join(FIELDS)})")
    rows = []
    for k, l in enumerate(lines[1:], 2):
        if len(l) != len(FIELDS):
            raise SystemExit(f"{path}: line {k} has {len(l)} fields, expected {len(FIELDS)}")
        try:
            rows.append({name: float(v) for name, v in zip(FIELDS, l)})
        except ValueError:
            raise SystemExit(f"{path}: line {k} is not numbers")
    if not rows:
        raise SystemExit(f"{path}: no segments")
    return sorted(rows, key=lambda r: r["seg"])


def summarize(rows, first=100):
    gaps = [max(0.0, b["g_start"] - a["g_rendered"]) for a, b in zip(rows, rows[1:])]
    s = {
        "segments": len(rows),
        "events": int(sum(r["n"] for r in rows)),
        "span": rows[-1]["col1"] - rows[0]["sub0"],
        "gpu_render": sum(r["g_rendered"] - r["g_start"] for r in rows),
        "gpu_idle": sum(gaps),
        "gpu_idle_first": sum(gaps[:first - 1]),
        "gpu_sort_copy": sum(r["g_copied"] - r["g_sort"] for r in rows),
        "host_submit": sum(r["sub1"] - r["sub0"] for r in rows),
        "host_wait_render": sum(r["counted"] - r["col0"] for r in rows),
        "host_wait_sort_copy": sum(r["copied"] - r["counted"] for r in rows),
        "host_collect_own": sum(r["col1"] - r["copied"] for r in rows),
    }
    s["host_between_calls"] = s["span"] - s["host_submit"] - sum(r["col1"] - r["col0"] for r in rows)
    return s


def main(argv):
    args = [a for a in argv if a != "--json"]
    if len(args) != 1:
        raise SystemExit("usage: timeline_summary.py FILE [--json]")
    s = summarize(load(args[0]))
    if "--json" in argv:
        print(json.dumps(s))
        return
    print(f"{s['segments']} segments, {s['events']} events, {s['span']:.4f} s from the first submit to the last collect")
    print(f"GPU: renders {s['gpu_render']:.4f} s, idle between them {s['gpu_idle']:.4f} s "
          f"({s['gpu_idle_first']:.4f} s of it in the first 100 segments), sorts and copies {s['gpu_sort_copy']:.4f} s")
    print(f"host: submits {s['host_submit']:.4f} s, waiting for renders {s['host_wait_render']:.4f} s, for sorts and "
          f"copies {s['host_wait_sort_copy']:.4f} s, collect's own work {s['host_collect_own']:.4f} s, "
          f"between calls {s['host_between_calls']:.4f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
