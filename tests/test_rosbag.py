"""ROS1 bags of dvs_msgs/EventArray read back by rosbags (installed by scripts/test-venv.sh into
build/venv, never the system Python), its types registered from the .msg text of dvs_msgs, not
from the bag's own definition. Every event must come back identical (x, y, t in us, polarity) to
events.npy; each message on /dvs/events of type dvs_msgs/EventArray with the registered type's
md5sum, the run's width and height, seq counting from 0, header.stamp and the record time its last
event's time, and its events within one 30 Hz window. evray's reader gives the same events
(evray convert), and one line for a truncated bag. Skips (77) when the environment is missing or
unusable."""
import json
import os
import subprocess
import sys

import numpy as np

import evrtest as T

venv_python = T.oracle_python(["numpy", "rosbags.rosbag1", "rosbags.typesys"])

# rosbags in the virtual environment: prints one JSON object describing what it read.
ORACLE = r'''
import json, sys
import numpy as np
from rosbags.rosbag1 import Reader
from rosbags.typesys import Stores, get_typestore, get_types_from_msg

EVENT = """uint16 x
uint16 y
time ts
bool polarity
"""
EVENT_ARRAY = """Header header
uint32 height
uint32 width
Event[] events
"""
store = get_typestore(Stores.ROS1_NOETIC)
types = {}
types.update(get_types_from_msg(EVENT, "dvs_msgs/msg/Event"))
types.update(get_types_from_msg(EVENT_ARRAY, "dvs_msgs/msg/EventArray"))
store.register(types)
md5 = store.generate_msgdef("dvs_msgs/msg/EventArray", ros_version=1)[1]

out = {"md5": md5, "connections": [], "messages": []}
t, x, y, p = [], [], [], []
with Reader(sys.argv[1]) as bag:
    for c in bag.connections:
        out["connections"].append([c.topic, c.msgtype, c.digest])
    for c, time_ns, raw in bag.messages():
        m = store.deserialize_ros1(raw, c.msgtype)
        stamp = m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
        ts = [e.ts.sec * 1_000_000_000 + e.ts.nanosec for e in m.events]
        out["messages"].append([c.topic, m.header.seq, stamp, time_ns, m.width, m.height, len(m.events),
                                min(ts) if ts else -1, max(ts) if ts else -1])
        t += ts
        x += [e.x for e in m.events]
        y += [e.y for e in m.events]
        p += [int(e.polarity) for e in m.events]
np.savez(sys.argv[2], t=np.array(t, np.int64), x=np.array(x, np.int64), y=np.array(y, np.int64),
         p=np.array(p, np.int64))
print(json.dumps(out))
'''

d = T.tmpdir()
run = os.path.join(d, "run")
W, H = 64, 48
T.run("demo", "--scene", "eye", "-o", run, "--res", f"{W}x{H}", "--duration", "1",
      "--format", "npy,rosbag", "--no-preview", "--quiet")
ref = np.load(os.path.join(run, "events.npy"))
T.check(len(ref) > 1000, f"a run of many events ({len(ref)})")

got = os.path.join(d, "got.npz")
r = subprocess.run([venv_python, "-c", ORACLE, os.path.join(run, "events.bag"), got],
                   capture_output=True, text=True)
if r.returncode != 0:
    print(r.stderr, file=sys.stderr)
T.check(r.returncode == 0, "rosbags reads events.bag")
info = json.loads(r.stdout)
T.check(info["md5"] == "5e8beee5a6c107e504c2e78903c224b8", f"dvs_msgs/EventArray's md5sum ({info['md5']})")
T.check(info["connections"] == [["/dvs/events", "dvs_msgs/msg/EventArray", info["md5"]]],
        f"one connection: /dvs/events, dvs_msgs/EventArray, its md5sum ({info['connections']})")

g = np.load(got)
T.check(len(g["t"]) == len(ref), f"every event read ({len(g['t'])} of {len(ref)})")
same = (len(g["t"]) == len(ref) and np.array_equal(g["t"], ref["t"].astype(np.int64) * 1000)
        and np.array_equal(g["x"], ref["x"].astype(np.int64))
        and np.array_equal(g["y"], ref["y"].astype(np.int64))
        and np.array_equal(g["p"] > 0, ref["p"] > 0))
T.check(same, "every event identical (x, y, t, polarity) to events.npy")

msgs = info["messages"]
T.check(len(msgs) > 10, f"messages at 30 Hz ({len(msgs)})")
ok = all(m[0] == "/dvs/events" and m[1] == i and m[2] == m[8] and m[3] == m[8] and m[4] == W
         and m[5] == H and m[6] > 0 and m[7] // 1000 * 30 // 1_000_000 == m[8] // 1000 * 30 // 1_000_000
         for i, m in enumerate(msgs))
T.check(ok, "each message: seq from 0, stamp and record time its last event's, the run's size, "
        "one 30 Hz window")
print(f"rosbags: events.bag: {len(ref)} events in {len(msgs)} messages, every event identical")

# evray's own reader: npy -> bag -> npy gives the same events
back = os.path.join(d, "back.npy")
T.run("convert", os.path.join(run, "events.bag"), back, "--quiet")
b = np.load(back)
T.check(len(b) == len(ref) and all(np.array_equal(b[k], ref[k]) for k in "txyp"),
        "evray convert events.bag -> npy: every event identical")

# bad input through the program: one line, exit 1, no crash
bad = os.path.join(d, "bad.bag")
with open(os.path.join(run, "events.bag"), "rb") as f:
    data = f.read()
with open(bad, "wb") as f:
    f.write(data[:-1])
r = T.run("compare", bad, os.path.join(run, "events.npy"), expect=1)
T.check("truncated" in r.stderr and len(r.stderr.strip().splitlines()) == 1, "a truncated bag: one line")
T.finish("test_rosbag")
