#!/bin/sh
# Runs a short eye (48x36, 0.5 s, one thread) under valgrind's memcheck twice and fails on any
# error (about 6 minutes):
#   1. with Embree's incoherent packet traversal (the hidden EVR_EMBREE_INCOHERENT) and no
#      suppressions: every value evray hands Embree, and everything else, is checked;
#   2. as evray runs (coherent packets) with scripts/valgrind-embree.supp, which hides only what
#      Embree 3.13's coherent traversal reports inside itself (run 1 shows it is Embree's).
# Usage: scripts/valgrind-eye.sh [build/evray]
set -eu
evray=${1:-build/evray}
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
check() { # label, log
    summary=$(grep -o 'ERROR SUMMARY: .*' "$2" | tail -1)
    echo "valgrind, $1: $summary"
    case "$summary" in
    "ERROR SUMMARY: 0 errors"*) ;;
    *) grep -v '^==[0-9]*== *$' "$2" | head -60; return 1 ;;
    esac
}
run() { # log, valgrind options...
    log=$1
    shift
    valgrind --error-exitcode=0 --track-origins=yes --num-callers=30 "$@" "$evray" -o "$out/run" \
        --force --res 48x36 --duration 0.5 --quiet --no-preview --threads 1 >"$log" 2>&1 ||
        { tail -30 "$log"; exit 1; }
}
EVR_EMBREE_INCOHERENT=1 run "$out/incoherent.log"
check "incoherent packets, no suppressions" "$out/incoherent.log"
run "$out/coherent.log" --suppressions="$here/valgrind-embree.supp"
check "coherent packets, Embree's own reports suppressed" "$out/coherent.log"
grep -o 'suppressed: [0-9,]* from [0-9,]*' "$out/coherent.log" | tail -1 | sed 's/^/valgrind, coherent packets: /'
