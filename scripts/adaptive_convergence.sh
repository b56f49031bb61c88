#!/bin/sh
# Issue 3: uniform against adaptive sampling on the eye, ideal sensor. F1 (100 us tolerance) against
# a dense reference (uniform, 1000 samples per frame); samples taken, samples per pixel per second
# and wall time of every run (one at a time).
#   scripts/adaptive_convergence.sh EVRAY [RES] [START] [DURATION] [BACKEND] [UNIFORM_SPFS] [ADAPTIVE_SETTINGS]
# ADAPTIVE_SETTINGS: ';'-separated option sets, e.g. "--adapt-frac 0.25;--adapt-frac 0.5 --min-dt 40e-6"
set -eu
E=${1:-build/evray}
RES=${2:-160x120}
START=${3:-0.2}
DUR=${4:-1.0}
BACKEND=${5:-cpu}
SPFS=${6:-10 20 50 100 200}
ADAPT=${7:-"--adapt-frac 0.25"}
T=$(mktemp -d)
run() { dir=$1; shift; "$E" demo --scene eye --res "$RES" --start "$START" --duration "$DUR" --backend "$BACKEND" \
        --no-preview --format h5 -q -o "$T/$dir" "$@"; }
report() {
    "$E" compare "$T/ref/events.h5" "$T/$1/events.h5" --tol-us 100 --json | python3 -c "
import json, sys
r = json.load(sys.stdin); s = json.load(open('$T/$1/run.json'))['stats']
print('$2'.ljust(44), s['samples'], round(s['samples_per_pixel_per_second'], 1), s['events'], round(s['wall_seconds'], 2),
      round(r['f1'], 4), round(r['precision'], 4), round(r['recall'], 4), r['median_dt_us'])"
}
run ref --samples-per-frame 1000
echo "eye $RES, $START..$(python3 -c "print($START + $DUR)") s, $BACKEND, reference: uniform 1000 samples per frame"
echo "sampling samples samples/pixel/s events wall_s F1 precision recall median_dt_us"
for n in $SPFS; do
    run "u$n" --samples-per-frame "$n"
    report "u$n" "uniform $n/frame"
done
i=0
echo "$ADAPT" | tr ';' '\n' | while read -r opts; do
    i=$((i + 1))
    # shellcheck disable=SC2086
    run "a$i" --sampling adaptive $opts
    report "a$i" "adaptive $opts"
done
rm -rf "$T"
