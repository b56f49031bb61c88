#!/bin/sh
# On the GPU machine (after scripts/gpu-pack.sh here): the CUDA tests, compute-sanitizer, and the
# benchmark of the eye demo at 1280x720. Logs go to $OUT (or ./gpu-out).
set -u
cd "$(dirname "$0")/.."
scripts/gpu-unpack.sh
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
python3 tests/test_cuda_bvh_cache.py "$E" > "$OUT/test_cuda_bvh_cache.log" 2>&1; echo "test_cuda_bvh_cache exit $?" >> "$OUT/test_cuda_bvh_cache.log"
python3 tests/test_skip.py "$E" > "$OUT/test_skip.log" 2>&1; echo "test_skip exit $?" >> "$OUT/test_skip.log"
python3 tests/test_bench.py "$E" > "$OUT/test_bench.log" 2>&1; echo "test_bench exit $?" >> "$OUT/test_bench.log"
# deforming meshes: analytic edges and the blink scene, on the GPU (--backend auto picks it)
python3 tests/test_deform.py "$E" > "$OUT/test_deform.log" 2>&1; echo "test_deform exit $?" >> "$OUT/test_deform.log"
python3 tests/test_blink.py "$E" > "$OUT/test_blink.log" 2>&1; echo "test_blink exit $?" >> "$OUT/test_blink.log"
# memcheck over segments that skip (the eye in a fixation) and that trace (a saccade), ideal and davis346
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene eye --backend cuda --res 96x72 --duration 0.5 \
    --start 0.9 -o "$OUT/cs-eye" --no-preview -q > "$OUT/sanitizer.log" 2>&1; echo "memcheck exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene eye --backend cuda --res 96x72 --duration 0.3 \
    --sensor davis346 --start 0.9 -o "$OUT/cs-eye2" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck davis346 exit $?" >> "$OUT/sanitizer.log"
# a segment's events in many pieces (the hidden EVR_EVENT_PIECE), event ids on
EVR_EVENT_PIECE=257 compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene eye --backend cuda --res 96x72 \
    --duration 0.5 --start 0.9 --event-ids -o "$OUT/cs-pieces" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck pieces exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool racecheck --error-exitcode 3 "$E" demo --scene square --backend cuda --res 64x64 --duration 0.1 \
    -o "$OUT/cs-sq" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "racecheck exit $?" >> "$OUT/sanitizer.log"
# deforming meshes: per-segment vertex keys and trees (morph-target lids, a skinned finger)
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene blink --backend cuda --res 96x54 \
    --duration 0.6 -o "$OUT/cs-blink" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck blink exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool racecheck --error-exitcode 3 "$E" demo --scene blink --backend cuda --res 64x36 \
    --duration 0.5 -o "$OUT/cs-blink2" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "racecheck blink exit $?" >> "$OUT/sanitizer.log"
# global illumination on the GPU (photon pass, sort, gathers)
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene cornell --gi photon --backend cuda --res 96x72 \
    --duration 0.3 -o "$OUT/cs-gi" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck gi exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool racecheck --error-exitcode 3 "$E" demo --scene cornell --gi photon --backend cuda --res 64x48 \
    --duration 0.2 -o "$OUT/cs-gi2" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "racecheck gi exit $?" >> "$OUT/sanitizer.log"
# the blurred estimate (--gi-blur: its gather and blur kernels, the lookups)
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene cornell --gi photon --gi-blur 4 --backend cuda \
    --res 96x72 --duration 0.3 -o "$OUT/cs-blur" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck blur exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool racecheck --error-exitcode 3 "$E" demo --scene cornell --gi photon --gi-blur 4 --backend cuda \
    --res 64x48 --duration 0.2 -o "$OUT/cs-blur2" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "racecheck blur exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool initcheck --error-exitcode 3 "$E" demo --scene cornell --gi photon --backend cuda \
    --res 64x48 --duration 0.2 -o "$OUT/cs-blur3" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "initcheck gi exit $?" >> "$OUT/sanitizer.log"
# every material feature (normal maps, glass, MASK/BLEND, a sphere light's glint), a camera path
# and label frames (the label kernel) under memcheck
python3 tests/all_materials.py /tmp/evray-am > /dev/null
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" render /tmp/evray-am/all_materials.gltf --backend cuda --res 64x48 \
    --duration 1.0 -o "$OUT/cs-am" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck all_materials exit $?" >> "$OUT/sanitizer.log"
compute-sanitizer --tool memcheck --error-exitcode 3 "$E" demo --scene square --backend cuda --res 64x48 --duration 0.3 \
    --camera-path orbit+shake --labels-fps 30 -o "$OUT/cs-path" --no-preview -q >> "$OUT/sanitizer.log" 2>&1; echo "memcheck path+labels exit $?" >> "$OUT/sanitizer.log"
# CPU and CUDA labels.h5 compared by gpu-carry/labels_compare (beside $E; no h5py here)
python3 tests/test_cuda_labels.py "$E" > "$OUT/test_cuda_labels.log" 2>&1; echo "test_cuda_labels exit $?" >> "$OUT/test_cuda_labels.log"
# issue 7's figure: the eye at 1280x720, 10 samples per frame, 30 fps, the whole 30 s, ideal
# sensor, change-driven sampling against brute force in the same run, with the identity check
"$E" bench --scene eye --backend cuda --res 1280x720 --samples-per-frame 10 --vs-brute > "$OUT/bench.log" 2>&1
echo "bench exit $?" >> "$OUT/bench.log"
"$E" bench --scene eye-drift --backend cuda --res 1280x720 --samples-per-frame 10 --duration 3 --vs-brute >> "$OUT/bench.log" 2>&1
echo "bench exit $?" >> "$OUT/bench.log"
# issue 5's cost: the Cornell box with and without GI
for gi in none photon; do
    "$E" bench --scene cornell --backend cuda --res 1280x720 --samples-per-frame 10 --duration 2 --gi "$gi" >> "$OUT/bench.log" 2>&1
    echo "bench gi $gi exit $?" >> "$OUT/bench.log"
done
cat "$OUT"/*.log
