#!/bin/sh
# Two builds' CPU cost on one machine, alternating, one thread each (user seconds are steadier
# than wall time on a shared machine): the eye at 346x260 for 2 s, uniform, davis346 and GI.
#   scripts/cpu-compare.sh BASE_BINARY NEW_BINARY [ROUNDS]
set -eu
base="$1"; new="$2"; rounds="${3:-3}"
d=$(mktemp -d)
user_s() {
    /usr/bin/time -f %U -o "$d/time" "$@" -o "$d/run" --force --no-preview --quiet --format npy --threads 1 >/dev/null 2>&1
    printf '%s %s\n' "$(cat "$d/time")" "$(md5sum < "$d/run/events.npy" | cut -c1-8)"
}
for case in "eye 2 --scene eye" "eye-davis346 2 --scene eye --sensor davis346" "cornell-gi 1 --scene cornell --gi photon"; do
    set -- $case
    name="$1"; dur="$2"; shift 2
    i=0
    while [ "$i" -lt "$rounds" ]; do
        for b in "$base" "$new"; do
            echo "$name $(basename "$b") $(user_s "$b" demo "$@" --backend cpu --res 346x260 --duration "$dur")"
        done
        i=$((i + 1))
    done
done
rm -rf "$d"
