#!/bin/bash
# On the GPU machine: a build against the build before it, in one run on one GPU. Expects
# gpu-carry/evray (new), gpu-carry/evray-base (before) and gpu-carry/lib, and the list the base
# made (scripts/golden-events.sh BASE cuda) in gpu-carry/cuda-base.txt. Writes to $OUT (or
# ./gpu-out): the new build's list and its diff from the base's (empty: byte-identical events),
# and timings of both builds alternating (wall s, render s, events), so ratios come from one run.
set -u
cd "$(dirname "$0")/.."
OUT="${OUT:-gpu-out}"
mkdir -p "$OUT"
export LD_LIBRARY_PATH="$PWD/gpu-carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
nvidia-smi -L > "$OUT/env.txt" 2>&1
scripts/golden-events.sh gpu-carry/evray cuda /tmp/gold-new > "$OUT/gold-new.txt" 2>&1
diff "$OUT/gold-new.txt" gpu-carry/cuda-base.txt > "$OUT/gold-diff.txt"
echo "golden diff exit $?" >> "$OUT/env.txt"
J='import json,sys; d=json.load(sys.stdin); print(d["wall_seconds"], d["render_seconds"], d["events"])'
bench() { gpu-carry/"$1" bench --backend cuda --res 1280x720 --json "${@:2}" 2>/dev/null | python3 -c "$J"; }
for i in 1 2 3; do
    for b in evray-base evray; do
        echo "eye-30s $b $(bench "$b" --scene eye --samples-per-frame 10)" >> "$OUT/bench.txt"
    done
done
for b in evray-base evray evray-base evray; do
    echo "eye-10s-davis346 $b $(bench "$b" --scene eye --samples-per-frame 10 --duration 10 --sensor davis346)" >> "$OUT/bench.txt"
    echo "eye-3s-adaptive $b $(bench "$b" --scene eye --duration 3 --sampling adaptive)" >> "$OUT/bench.txt"
    echo "cornell-2s-gi $b $(bench "$b" --scene cornell --samples-per-frame 10 --duration 2 --gi photon)" >> "$OUT/bench.txt"
    echo "city-3s $b $(bench "$b" --scene city --samples-per-frame 10 --duration 3)" >> "$OUT/bench.txt"
done
cat "$OUT/env.txt" "$OUT/gold-diff.txt" "$OUT/bench.txt"
