"""ROS1 bags of dvs_msgs/EventArray read back by rosbags (installed by scripts/test-venv.sh into
build/venv, never the system Python), its types registered from the .msg text of dvs_msgs, not
from the bag's own definition. Every event must come back identical (x, y, t in us, polarity) to
events.npy; each message on /dvs/events of type dvs_msgs/EventArray with the registered type's
md5sum, the run's width and height, seq counting from 0, header.stamp and the record time its last
event's time, and its events within one 30 Hz window. evray's reader gives the same events
(evray convert, also h5 -> bag -> h5), and one line for a truncated bag. Bags rosbags writes with compressed chunks
(bz2, lz4; many chunks) read back identical through evray convert, and a corrupt compressed chunk
gives one line. Skips (77) when the environment is missing or unusable."""
import json
import os
import subprocess
import sys

import numpy as np

import evrtest as T

venv_python = T.oracle_python(["numpy", "rosbags.rosbag1", "rosbags.typesys"])

# dvs_msgs' types registered in a rosbags typestore, from their .msg text
TYPES = r'''
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
'''

# rosbags in the virtual environment: prints one JSON object describing what it read.
ORACLE = TYPES + r'''
import json, sys
import numpy as np
from rosbags.rosbag1 import Reader
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

# rosbags writing the run's events as dvs_msgs/EventArray messages at 30 Hz, in chunks of 64 KB
# (its chunk_threshold attribute: 1 MB by default) compressed by bz2 and lz4
WRITER = TYPES + r'''
import sys
import numpy as np
from rosbags.rosbag1 import Writer
T = store.types
Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]
Event, EventArray = T["dvs_msgs/msg/Event"], T["dvs_msgs/msg/EventArray"]
ref = np.load(sys.argv[1])
W, H = int(sys.argv[3]), int(sys.argv[4])

def stamp(us):
    return Time(sec=int(us) // 1_000_000, nanosec=int(us) % 1_000_000 * 1000)

win = ref["t"].astype(np.int64) * 30 // 1_000_000
msgs = []
for seq, part in enumerate(np.split(ref, np.nonzero(np.diff(win))[0] + 1)):
    evs = [Event(x=int(e["x"]), y=int(e["y"]), ts=stamp(e["t"]), polarity=bool(e["p"])) for e in part]
    msgs.append((int(part["t"][-1]), EventArray(header=Header(seq=seq, stamp=stamp(part["t"][-1]), frame_id=""),
                                                height=H, width=W, events=evs)))
for name in ("BZ2", "LZ4"):
    w = Writer(sys.argv[2] % name)
    w.set_compression(getattr(Writer.CompressionFormat, name))
    w.chunk_threshold = 64 << 10
    w.open()
    conn = w.add_connection("/dvs/events", "dvs_msgs/msg/EventArray", typestore=store)
    for t, m in msgs:
        w.write(conn, t * 1000, store.serialize_ros1(m, "dvs_msgs/msg/EventArray"))
    w.close()
'''

d = T.tmpdir()
run = os.path.join(d, "run")
W, H = 64, 48
T.run("demo", "--scene", "eye", "-o", run, "--res", f"{W}x{H}", "--duration", "1",
      "--format", "h5,npy,rosbag", "--no-preview", "--quiet")
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

# evray convert's round trip: h5 -> bag -> h5 (read back as npy)
conv, back_h5, back = (os.path.join(d, n) for n in ("conv.bag", "back.h5", "back2.npy"))
T.run("convert", os.path.join(run, "events.h5"), conv, "--quiet")
T.run("convert", conv, back_h5, "--quiet")
T.run("convert", back_h5, back, "--quiet")
b = np.load(back)
T.check(len(b) == len(ref) and all(np.array_equal(b[k], ref[k]) for k in "txyp"),
        "evray convert events.h5 -> bag -> h5: every event identical")

# bad input through the program: one line, exit 1, no crash
bad = os.path.join(d, "bad.bag")
with open(os.path.join(run, "events.bag"), "rb") as f:
    data = f.read()
with open(bad, "wb") as f:
    f.write(data[:-1])
r = T.run("compare", bad, os.path.join(run, "events.npy"), expect=1)
T.check("truncated" in r.stderr and len(r.stderr.strip().splitlines()) == 1, "a truncated bag: one line")

# compressed chunks, as rosbags writes them
cbag = os.path.join(d, "c_%s.bag")
r = subprocess.run([venv_python, "-c", WRITER, os.path.join(run, "events.npy"), cbag, str(W), str(H)],
                   capture_output=True, text=True)
if r.returncode != 0:
    print(r.stderr, file=sys.stderr)
T.check(r.returncode == 0, "rosbags writes bags with bz2 and lz4 chunks")
for name in ("BZ2", "LZ4"):
    path = cbag % name
    if not os.path.exists(path):
        continue
    data = open(path, "rb").read()
    chunks = data.count(b"compression=" + name.lower().encode())
    T.check(chunks > 5, f"{name}: a bag of many compressed chunks ({chunks})")
    out = os.path.join(d, f"c_{name}.npy")
    T.run("convert", path, out, "--quiet")
    b = np.load(out)
    ok = len(b) == len(ref) and all(np.array_equal(b[k], ref[k]) for k in "txyp")
    T.check(ok, f"evray reads rosbags' {name} chunks: every event identical")
    if ok:
        print(f"evray: rosbags' bag of {chunks} {name} chunks: every event identical")
    # the first chunk's compressed data with its magic changed (lz4 frames carry no checksum
    # here: a byte changed inside may decode to other bytes): one line naming it, no crash
    magic = b"BZh" if name == "BZ2" else b"\x04\x22\x4d\x18"
    at = data.index(magic, data.index(b"compression=" + name.lower().encode()))
    with open(bad, "wb") as f:
        f.write(data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1:])
    r = T.run("compare", bad, os.path.join(run, "events.npy"), expect=1)
    T.check(f"corrupt {name.lower()} ROS bag chunk" in r.stderr and len(r.stderr.strip().splitlines()) == 1,
            f"a corrupt {name} chunk: one line ({r.stderr.strip()})")
T.finish("test_rosbag")
