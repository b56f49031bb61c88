#!/bin/bash
# On the GPU machine (after scripts/gpu-pack.sh, with the build to compare against in
# gpu-carry/evray-base): the figures of docs/benchmarks.md's "Deforming meshes": the eye's 30 s
# by both builds alternating, the skinned tube against its rigid twin (tests/deform_assets.py
# --bench) on CUDA and on the host's cores, and the blink scene. Output in $OUT/bench.txt.
set -u
cd "$(dirname "$0")/.."
scripts/gpu-unpack.sh
OUT="${OUT:-gpu-out}"; mkdir -p "$OUT"
export LD_LIBRARY_PATH="$PWD/gpu-carry/lib"
export PATH="$PATH:/usr/local/cuda/bin"
E="$PWD/gpu-carry/evray"; B="$PWD/gpu-carry/evray-base"
nvidia-smi -L > "$OUT/env.txt"; nproc >> "$OUT/env.txt"
python3 tests/deform_assets.py --bench /tmp/bench > /dev/null
J='import json,sys; d=json.load(sys.stdin); print("wall %.3f render %.3f events %d samples/s %.3g" % (d["wall_seconds"], d["render_seconds"], d["events"], d.get("equivalent_samples_per_second", d.get("samples_per_second", 0))))'
R='import json,sys; r=json.load(open(sys.argv[1]))["stats"]; print("wall %.3f render %.3f traced %d traced/s %.4g eq/s %.4g motion %.3f events %d" % (r["wall_seconds"], r["time_render_seconds"], r["samples_traced"], r["traced_samples_per_second"], r["equivalent_samples_per_second"], r["time_motion_seconds"], r["events"]))'
{
for i in 1 2; do for b in evray-base evray; do
  echo "eye-30s $b $(gpu-carry/$b bench --backend cuda --res 1280x720 --json --scene eye --samples-per-frame 10 2>/dev/null | python3 -c "$J")"
done; done
for be in cuda cpu; do for i in 1 2; do for n in skinned rigid; do
  res=1280x720; [ $be = cpu ] && res=640x360
  "$E" render /tmp/bench/bench_arm_$n.gltf -o /tmp/arm-$be-$n --force --res $res --duration 1 --samples-per-frame 10 --format npy --no-preview --quiet --backend $be
  echo "arm $be $res $n $(python3 -c "$R" /tmp/arm-$be-$n/run.json)"
done; done; done
for be in cuda cpu; do
  res=1280x720
  "$E" demo --scene blink -o /tmp/blink-$be --force --res $res --duration 1 --samples-per-frame 10 --format npy --no-preview --quiet --backend $be
  echo "blink $be $res $(python3 -c "$R" /tmp/blink-$be/run.json)"
done
"$E" bench --scene blink --backend cuda --res 1280x720 --samples-per-frame 10 --duration 3.6 --vs-brute 2>&1 | tail -3
} > "$OUT/bench.txt" 2>&1
cat "$OUT/bench.txt"
