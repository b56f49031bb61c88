#!/bin/sh
set -u
scripts/gpu-unpack.sh
export LD_LIBRARY_PATH=$PWD/gpu-carry/lib
E=$PWD/gpu-carry/evray
python3 scripts/sampling_table.py $E --backend cuda --res 346x260 --start 0 --duration 3 > $OUT/table.md 2> $OUT/table.err
for s in square disk cornell; do
  python3 scripts/sampling_table.py $E --scene $s --backend cuda --res 346x260 --start 0 --duration 1 --skip u100,u300,adaptive > $OUT/table_$s.md 2>> $OUT/table.err
done
