#!/usr/bin/env bash
# Seconds per pass of the filters (issue 53's protocol): for each suite scene and each of
# MVF, PhF and BPF, each binary renders 1 and 3 passes at the wave-2 settings given
# explicitly (--beta 0.25 --radius-footprints 4 --max-segments 16; the neighbour budget
# is 64 in every binary, a constant before `--neighbours`), full size, binaries
# interleaved; a pass is (T3 - T1) / 2 of the render seconds.
#   scripts/bench-filter-passes.sh BIN1 BIN2 ... (SCENES, THREADS, ESTIMATORS, OUT in the environment)
set -u
SCENES=${SCENES:-../shared/scenes}
THREADS=${THREADS:-2}
ESTIMATORS=${ESTIMATORS:-mvf phf bpf}
OUT=${OUT:-/tmp/filter-passes}
mkdir -p "$OUT"
log=$OUT/runs.txt
: >"$log"
secs() { sed -nE 's/.*\(([0-9.]+) s setup, ([0-9.]+) s rendering\).*/\2/p'; }
for dir in "$SCENES"/*/; do
  sc=$(basename "$dir")
  for e in $ESTIMATORS; do
    for b in "$@"; do
      t1=$("$b" render "$dir/scene.xml" -e "$e" --spp 1 --threads "$THREADS" --no-plan --beta 0.25 --radius-footprints 4 --max-segments 16 -o "$OUT/x.exr" 2>/dev/null | grep '^time' | secs)
      t3=$("$b" render "$dir/scene.xml" -e "$e" --spp 3 --threads "$THREADS" --no-plan --beta 0.25 --radius-footprints 4 --max-segments 16 -o "$OUT/x.exr" 2>/dev/null | grep '^time' | secs)
      echo "$sc $e $(basename "$b") $t1 $t3" | tee -a "$log"
    done
  done
done
echo
echo "scene estimator binary seconds_per_pass"
awk '{ printf "%s %s %s %.3f\n", $1, $2, $3, ($5 - $4) / 2 }' "$log"
rm -f "$OUT"/x.exr "$OUT"/x.png
