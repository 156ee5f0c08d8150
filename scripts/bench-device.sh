#!/usr/bin/env bash
# The lent 16-core machine's measurements in one command (issue 52's "thread scaling"
# and the PT/LT samples-per-second table on a quiet machine):
#   scripts/bench-device.sh NEW OLD SCENES OUT
# NEW, OLD: ember binaries (stripped copies travel with the tree, e.g. target/dev/);
# SCENES: the suite's scene folders (references not needed); OUT: results folder.
# 1. scripts/bench-scaling.sh with both binaries interleaved at 1, 2, 4, 8, 16 threads;
# 2. scripts/bench-ab.sh for PT and LT (48 passes at 160 px wide, 1 thread, NEW then OLD,
#    twice per scene).
# Each part writes its table as it goes, so a run cut short still leaves what it did.
set -u
new=${1:?NEW binary}; old=${2:?OLD binary}; scenes=${3:?SCENES}; out=${4:?OUT}
mkdir -p "$out"
nproc >"$out/machine.txt"; lscpu >>"$out/machine.txt" 2>/dev/null || true
for est in pt lt; do
  SPP=48 ESTIMATOR=$est SCENES="$scenes" OUT="$out/ab-$est" scripts/bench-ab.sh "$new" "$old" >"$out/ab-$est.txt" 2>&1
done
scripts/bench-scaling.sh "$new:$old" "$scenes" "$out/scaling" 1 1 2 4 8 16 >"$out/scaling.txt" 2>&1
rm -f "$out"/scaling/*.exr "$out"/ab-*/*.exr
