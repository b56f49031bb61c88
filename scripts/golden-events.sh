#!/bin/sh
# Prints one line per case: the md5 of events.npy for a matrix of short runs over every built-in
# scene (ideal and davis346, uniform and adaptive, with and without GI). Two builds whose lists
# are equal give byte-identical events: a restructuring is checked by diffing the lists.
#   scripts/golden-events.sh BINARY BACKEND [OUTDIR] > list.txt
set -eu
bin="$1"
backend="$2"
work="${3:-$(mktemp -d)}"
mkdir -p "$work"
run_case() {
    name="$1"; shift
    d="$work/$name"
    rm -rf "$d"
    "$bin" demo -o "$d" --backend "$backend" --format npy --no-preview --quiet --seed 7 "$@" >/dev/null 2>"$d.err" ||
        { echo "$name FAILED: $(head -c 300 "$d.err")"; return 0; }
    printf '%s %s\n' "$name" "$(md5sum < "$d/events.npy" | cut -d' ' -f1)"
}
for scene in $("$bin" demo --list); do
    case "$scene" in
        city) dur=0.1; res=64x48 ;;
        *) dur=0.4; res=64x48 ;;
    esac
    run_case "$scene-ideal" --scene "$scene" --res "$res" --duration "$dur"
    run_case "$scene-davis346" --scene "$scene" --res "$res" --duration "$dur" --sensor davis346
    run_case "$scene-adaptive" --scene "$scene" --res "$res" --duration "$dur" --sampling adaptive
    run_case "$scene-noskip" --scene "$scene" --res "$res" --duration "$dur" --no-skip
done
run_case eye-saccade-ideal --scene eye --res 96x72 --start 0.9 --duration 0.5
run_case eye-saccade-davis346-adaptive --scene eye --res 96x72 --start 0.9 --duration 0.5 --sensor davis346 --sampling adaptive
run_case cornell-gi --scene cornell --gi photon --res 64x48 --duration 0.4
run_case cornell-gi-davis346 --scene cornell --gi photon --res 64x48 --duration 0.4 --sensor davis346
run_case cornell-gi-adaptive --scene cornell --gi photon --res 64x48 --duration 0.3 --sampling adaptive
run_case cornell-gi-max8 --scene cornell --gi photon --res 64x48 --duration 0.4 --gather-max 8
run_case cornell-gi-wide --scene cornell --gi photon --res 160x120 --duration 0.2
run_case cornell-still-gi --scene cornell-still --gi photon --res 64x48 --duration 0.3
# evray still (CPU only): direct light, photon mapping and path tracing share the shading code
if [ "$backend" = cpu ]; then
    for gi in none photon path; do
        for scene in cornell eye; do
            f="$work/still-$scene-$gi.pfm"
            "$bin" still --scene "$scene" --gi "$gi" --res 64x48 --spp 4 --time 0.2 -o "$f" >/dev/null 2>&1 ||
                { echo "still-$scene-$gi FAILED"; continue; }
            printf 'still-%s-%s %s\n' "$scene" "$gi" "$(md5sum < "$f" | cut -d' ' -f1)"
        done
    done
fi
