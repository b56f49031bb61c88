#!/bin/sh
# Issue 3: does uniform sampling converge? F1 (100 us tolerance) of the eye's events at 10..100
# samples per frame against a dense reference (1000 samples per frame), ideal sensor.
#   scripts/convergence.sh EVRAY [RES] [START] [DURATION] [BACKEND]
set -eu
E=${1:-build/evray}
RES=${2:-346x260}
START=${3:-0.2}
DUR=${4:-1.0}
BACKEND=${5:-auto}
T=$(mktemp -d)
run() { "$E" demo --scene eye --res "$RES" --start "$START" --duration "$DUR" --backend "$BACKEND" --no-preview \
        --format h5 -q -o "$T/$1" --samples-per-frame "$1"; }
run 1000
echo "eye $RES, $START..$(python3 -c "print($START + $DUR)") s, reference 1000 samples per frame ($(python3 -c "import json;print(json.load(open('$T/1000/run.json'))['stats']['events'])") events)"
echo "spf  events  wall_s  F1  precision  recall  median_dt_us"
for n in 10 20 50 100; do
    run "$n"
    "$E" compare "$T/1000/events.h5" "$T/$n/events.h5" --tol-us 100 --json | python3 -c "
import json, sys
r = json.load(sys.stdin); s = json.load(open('$T/$n/run.json'))['stats']
print($n, s['events'], round(s['wall_seconds'], 2), round(r['f1'], 4), round(r['precision'], 4), round(r['recall'], 4), r['median_dt_us'])"
done
rm -rf "$T"
