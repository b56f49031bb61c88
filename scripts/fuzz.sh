#!/bin/sh
# Fuzzing with libFuzzer (clang, AddressSanitizer, UBSan): builds tests/fuzz's targets in
# build-fuzz, writes their seed corpora (tests/fuzz/make_seeds.py) and runs each target.
#
#   scripts/fuzz.sh [SECONDS [TARGET...]]
#
# SECONDS per target (default 60; the acceptance of issue 29 asks 1800, on one core), TARGET:
# scene, scene_assimp, events_h5, events_text, events_camera (default: all). Each target's
# corpus grows in build-fuzz/corpus/TARGET; what a target finds (crash-*, leak-*, oom-*,
# timeout-*) is left in build-fuzz/found/TARGET: minimize it (fuzz_TARGET -minimize_crash=1),
# fix the bug and add the input to tests/fuzz/regress/TARGET/, which the test suite replays.
# The summary line of each run (executions, coverage) goes to build-fuzz/TARGET.log.
set -eu
cd "$(dirname "$0")/.."
secs="${1:-60}"
[ $# -gt 0 ] && shift
targets="${*:-scene scene_assimp events_h5 events_text events_camera}"
command -v clang >/dev/null || { echo "fuzz: clang is needed (Debian: apt-get install clang)" >&2; exit 1; }
scripts/deps.sh
if [ ! -x build/evray ]; then
    cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DEVR_CUDA=OFF >/dev/null
    cmake --build build -j"$(nproc)" --target evray
fi
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEVR_FUZZ=ON \
    -DEVR_CUDA=OFF -DEVR_WERROR=OFF >/dev/null
for t in $targets; do
    cmake --build build-fuzz -j"$(nproc)" --target "fuzz_$t"
done
python3 tests/fuzz/make_seeds.py build/evray build-fuzz/seeds >/dev/null
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1"
export LSAN_OPTIONS="suppressions=$(pwd)/tests/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Assimp (other formats) and HDF5 read a file in a child process first (src/io/child_job.c): its
# time limit below libFuzzer's -timeout, so that a hang there is what evray reports, not a finding
export EVR_IMPORT_SECONDS=8
for t in $targets; do
    mkdir -p "build-fuzz/corpus/$t" "build-fuzz/found/$t"
    echo "== fuzz_$t: $secs s" >&2
    # -rss_limit_mb: an input that needs more than 2 GB is a finding (issue 31: a 2.6 KB GLB
    # took 4.2 GB); -timeout: one input may take at most 10 s. -fork=1: one worker process (one
    # core) that the campaign outlives, so it goes on after a finding and keeps them all.
    # a target with no regression inputs yet has no folder of them (libFuzzer exits on one missing)
    regress=""
    [ -d "tests/fuzz/regress/$t" ] && regress="tests/fuzz/regress/$t"
    # shellcheck disable=SC2086
    "build-fuzz/tests/fuzz_$t" -max_total_time="$secs" -rss_limit_mb=2048 -malloc_limit_mb=2048 \
        -timeout=10 -max_len=65536 -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
        -print_final_stats=1 -artifact_prefix="build-fuzz/found/$t/" \
        "build-fuzz/corpus/$t" "build-fuzz/seeds/$t" $regress \
        >"build-fuzz/$t.log" 2>&1 || echo "fuzz_$t stopped on a finding: build-fuzz/found/$t" >&2
    grep -E "^#[0-9]+: cov:" "build-fuzz/$t.log" | tail -1 >&2
    echo "findings: $(ls "build-fuzz/found/$t" | wc -l) in build-fuzz/found/$t" >&2
done
