"""Writes the fuzz targets' seed corpora: make_seeds.py EVRAY OUTDIR makes OUTDIR/TARGET/ for
every target in tests/fuzz (fuzz_TARGET.c), from the scenes the tests already write (the
built-in scenes exported as GLB, tests/data/import, tests/import_assets.py, deform_assets.py,
material_assets.py; .gltf files whose data is external are made self-contained), small files of
the other formats Assimp reads, and the event files of one short run in every format evray
writes (and its bag again with bz2 chunks), and its labels.h5. The seeds are small (a few KB each): libFuzzer mutates them from there.

Standard library only; EVRAY is the built program (it exports the demos and writes the event
files)."""
import base64
import bz2
import glob
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
TESTS = os.path.dirname(HERE)
sys.path.insert(0, TESTS)
import gltf_build  # noqa: E402
import import_assets  # noqa: E402
import deform_assets  # noqa: E402
import material_assets  # noqa: E402

MAX_SEED = 64 * 1024  # larger files slow the fuzzer down more than they add


def embed(path):
    """A .gltf's text with external buffers and images turned into data: URIs (None when one
    is missing); a GLB as it is."""
    with open(path, "rb") as f:
        raw = f.read()
    if raw[:4] == b"glTF":
        return raw
    doc = json.loads(raw)
    for key in ("buffers", "images"):
        for item in doc.get(key, []):
            uri = item.get("uri")
            if uri is None or uri.startswith("data:"):
                continue
            p = os.path.join(os.path.dirname(path), uri)
            if not os.path.isfile(p):
                return None
            with open(p, "rb") as f:
                item["uri"] = gltf_build.data_uri(f.read())
    return json.dumps(doc, separators=(",", ":")).encode()


def scene_seeds(evray, work, out):
    files = []
    for name in subprocess.run([evray, "demo", "--list"], capture_output=True, text=True,
                               check=True).stdout.split():
        p = os.path.join(work, name + ".glb")
        subprocess.run([evray, "demo", "--scene", name, "--export", p], capture_output=True,
                       check=True)
        files.append(p)
    files += sorted(glob.glob(os.path.join(TESTS, "data", "import", "*.gl*")))
    for module in (import_assets, deform_assets, material_assets):
        d = os.path.join(work, module.__name__)
        files += [p for p in module.write_all(d).values() if p.endswith((".gltf", ".glb"))]
    n = 0
    for p in files:
        data = embed(p)
        if data is None or len(data) > MAX_SEED:
            continue
        ext = ".glb" if data[:4] == b"glTF" else ".gltf"
        with open(os.path.join(out, "%03d_%s%s" % (n, os.path.splitext(os.path.basename(p))[0], ext)), "wb") as f:
            f.write(data)
        n += 1
    return n


# one triangle in each of the other formats; the first byte is the target's hint index
# (fuzz_scene_assimp.c: obj, dae, ply, stl, off, fbx, 3ds, x)
OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1/1 2/2/1 3/3/1\n"
PLY = (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
       b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
PLY_BIN = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
           b"property float y\nproperty float z\nelement face 1\n"
           b"property list uchar int vertex_indices\nend_header\n" +
           struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2))
STL = (b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       b"endloop\nendfacet\nendsolid t\n")
STL_BIN = (b"\0" * 80 + struct.pack("<I", 1) + struct.pack("<12f", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0) +
           b"\0\0")
OFF = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
X = (b"xof 0302txt 0032\nMesh {\n3;\n0.0;0.0;0.0;,\n1.0;0.0;0.0;,\n0.0;1.0;0.0;;\n1;\n3;0,1,2;;\n}\n")


def assimp_seeds(out):
    seeds = [(0, "tri.obj", OBJ), (2, "tri.ply", PLY), (2, "tri_bin.ply", PLY_BIN),
             (3, "tri.stl", STL), (3, "tri_bin.stl", STL_BIN), (4, "tri.off", OFF),
             (7, "tri.x", X)]
    for p in sorted(glob.glob(os.path.join(TESTS, "data", "import", "*.dae"))):
        with open(p, "rb") as f:
            seeds.append((1, os.path.basename(p), f.read()))
    for k, (hint, name, data) in enumerate(seeds):
        with open(os.path.join(out, "%03d_%s" % (k, name)), "wb") as f:
            f.write(bytes([hint]) + data)
    return len(seeds)


def bz2_bag(data):
    """The bag with each chunk's data compressed by bz2, as rosbag writes it (the chunk infos'
    offsets go stale; the reader goes record by record)."""
    out, at = [data[:13]], 13
    while at + 8 <= len(data):
        hl = struct.unpack_from("<I", data, at)[0]
        dl = struct.unpack_from("<I", data, at + 4 + hl)[0]
        head, body = data[at + 4:at + 4 + hl], data[at + 8 + hl:at + 8 + hl + dl]
        at += 8 + hl + dl
        if head[4:8] != b"op=\x05":
            out.append(data[at - 8 - hl - dl:at])
            continue
        c = bz2.compress(body)
        fields = [b"op=\x05", b"compression=bz2", b"size=" + struct.pack("<I", len(body))]
        head = b"".join(struct.pack("<I", len(f)) + f for f in fields)
        out.append(struct.pack("<I", len(head)) + head + struct.pack("<I", len(c)) + c)
    return b"".join(out)


def event_seeds(evray, work, outs):
    """One short run of the square demo written in every format; the files cut to MAX_SEED
    events' worth where large (a reader must cope with any length anyway)."""
    run = os.path.join(work, "run")
    subprocess.run([evray, "demo", "--scene", "square", "-o", run, "--res", "32x24",
                    "--duration", "0.2", "--format", "all", "--no-preview", "--quiet"], check=True)
    made = {k: 0 for k in outs}

    def put(target, name, data):
        with open(os.path.join(outs[target], "%03d_%s" % (made[target], name)), "wb") as f:
            f.write(data)
        made[target] += 1

    for p in sorted(glob.glob(os.path.join(run, "*"))):
        name = os.path.basename(p)
        with open(p, "rb") as f:
            data = f.read()
        if name.endswith(".h5"):
            put("events_h5", name, data)
        elif name.endswith(".txt"):
            put("events_text", name, b"\0" + data[:MAX_SEED])
            put("events_text", "short_" + name, b"\0" + b"\n".join(data.split(b"\n")[:20]))
        elif name.endswith(".npy"):
            put("events_text", name, b"\1" + data[:MAX_SEED])
        elif name.endswith(".raw"):
            put("events_camera", name, b"\0" + data[:MAX_SEED])
        elif name.endswith(".dat"):
            put("events_camera", name, b"\1" + data[:MAX_SEED])
        elif name.endswith(".bag"):
            put("events_camera", name, b"\2" + data[:MAX_SEED])
            put("events_camera", "bz2_" + name, b"\2" + bz2_bag(data)[:MAX_SEED])
    return made


def labels_seeds(evray, work, out):
    """labels.h5 of a short run of the square demo, with and without normals."""
    n = 0
    for extra in ([], ["--label-normals"]):
        run = os.path.join(work, "labels%d" % n)
        subprocess.run([evray, "demo", "--scene", "square", "-o", run, "--res", "32x24",
                        "--duration", "0.2", "--labels-fps", "10", "--no-preview", "--quiet",
                        *extra], check=True)
        with open(os.path.join(run, "labels.h5"), "rb") as f, \
                open(os.path.join(out, "%03d_labels.h5" % n), "wb") as g:
            g.write(f.read())
        n += 1
    return n


def main():
    evray, outdir = sys.argv[1], sys.argv[2]
    targets = [os.path.basename(p)[5:-2] for p in sorted(glob.glob(os.path.join(HERE, "fuzz_*.c")))]
    outs = {t: os.path.join(outdir, t) for t in targets}
    for d in outs.values():
        os.makedirs(d, exist_ok=True)
    work = tempfile.mkdtemp(prefix="evray-seeds-")
    try:
        counts = {"scene": scene_seeds(evray, work, outs["scene"]),
                  "scene_assimp": assimp_seeds(outs["scene_assimp"])}
        counts["labels_h5"] = labels_seeds(evray, work, outs["labels_h5"])
        counts.update(event_seeds(evray, work, {k: outs[k] for k in
                                                ("events_h5", "events_text", "events_camera")}))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for t in targets:
        print("%-14s %d seeds in %s" % (t, counts.get(t, 0), outs[t]))


if __name__ == "__main__":
    main()
