"""scripts/timeline_summary.py on a hand-made timeline (the CUDA backend's EVR_TIMELINE format):
the GPU's idle time between renders, the host's waits and own work, and clear errors for files
that are not timelines."""
import json
import os
import subprocess
import sys

import evrtest as T

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "timeline_summary.py")
tmp = T.tmpdir()


def summary(text, *extra):
    path = os.path.join(tmp, "tl.txt")
    with open(path, "w") as f:
        f.write(text)
    return subprocess.run([sys.executable, SCRIPT, path, *extra], capture_output=True, text=True)


HEAD = "seg sub0 sub1 col0 counted copied col1 g_start g_rendered g_sort g_copied n\n"
# three segments: renders 0.1-0.3, 0.35-0.45 (idle 0.05 before), 0.45-0.65 (none); rows out of order
rows = ("1 0.20 0.21 0.50 0.50 0.52 0.60 0.35 0.45 0.46 0.50 300\n"
        "0 0.00 0.10 0.30 0.31 0.35 0.40 0.10 0.30 0.31 0.34 1000\n"
        "2 0.40 0.42 0.70 0.71 0.72 0.80 0.45 0.65 0.66 0.70 0\n")
p = summary(HEAD + rows, "--json")
T.check(p.returncode == 0, f"a timeline is summed up ({p.stderr.strip()})")
s = json.loads(p.stdout) if p.returncode == 0 else {}
want = {"segments": 3, "events": 1300, "span": 0.80, "gpu_render": 0.50, "gpu_idle": 0.05, "gpu_idle_first": 0.05,
        "gpu_sort_copy": 0.11, "host_submit": 0.13, "host_wait_render": 0.02, "host_wait_sort_copy": 0.07,
        "host_collect_own": 0.21, "host_between_calls": 0.80 - 0.13 - 0.30}
for key, value in want.items():
    T.check(abs(s.get(key, -1.0) - value) < 1e-9, f"{key}: {s.get(key)} (expected {value})")
text = summary(HEAD + rows)
T.check(text.returncode == 0 and "3 segments, 1300 events" in text.stdout, f"the text summary ({text.stdout!r})")

# an incomplete timeline's note is a comment, not a row
p = summary(HEAD + rows + "# incomplete: out of memory for the timeline\n", "--json")
T.check(p.returncode == 0 and json.loads(p.stdout)["segments"] == 3, "a comment line is not a segment")

for what, text in (("not a timeline", "hello\n"), ("a short row", HEAD + "0 0.1 0.2\n"),
                   ("a row of words", HEAD + "0 a b c d e f g h i j k\n"), ("no segments", HEAD)):
    p = summary(text)
    T.check(p.returncode != 0 and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr,
            f"{what}: a one-line error ({p.stderr.strip()!r})")

T.finish("test_timeline_summary")
