#!/bin/sh
# On the GPU machine (after scripts/gpu-pack.sh here): the CUDA tests, compute-sanitizer, and the
# benchmark of the eye demo at 1280x720. Logs go to $OUT (or ./gpu-out).
set -u
cd "$(dirname "$0")/.."
OUT="${OUT:-gpu-out}"
mkdir -p "$OUT"
export LD_LIBRARY_PATH="$PWD/gpu-carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
E="$PWD/gpu-carry/evray"
export PATH="$PATH:/usr/local/cuda/bin"
{
    nvidia-smi -L
    ldd "$E" | grep "not found"
    "$E" --version
} > "$OUT/env.log" 2>&1
python3 tests/test_cuda.py "$E" > "$OUT/test_cuda.log" 2>&1; echo "test_cuda exit $?" >> "$OUT/test_cuda.log"
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene eye --backend cuda --res 96x72 --duration 0.2 \
    -o "$OUT/cs-eye" --no-preview -q > "$OUT/sanitizer.log" 2>&1; echo "memcheck exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool racecheck --error-exitcode 3 "$E" demo --scene square --backend cuda --res 64x64 --duration 0.1 \
    -o "$OUT/cs-sq" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "racecheck exit $?" >> "$OUT/sanitizer.log"
for spf in 10; do
    "$E" demo --scene eye --backend cuda --res 1280x720 --samples-per-frame $spf -o "$OUT/bench-eye-720-$spf" \
        --no-preview --format h5 > "$OUT/bench.log" 2>&1
done
"$E" demo --scene eye --backend cpu --res 1280x720 --samples-per-frame 10 --duration 0.5 -o "$OUT/bench-eye-720-cpu" \
    --no-preview --format h5 >> "$OUT/bench.log" 2>&1
cat "$OUT"/*.log
