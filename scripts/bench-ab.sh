#!/usr/bin/env bash
# PT samples per second of two (or more) ember binaries on every suite scene, interleaved:
#   scripts/bench-ab.sh BIN_A BIN_B
# ESTIMATOR=lt (say) measures another estimator.
# Each scene at 160 pixels wide, SPP passes (default 8), 1 thread, --no-plan; A then B,
# ROUNDS times (default 2).
# Prints: scene, then ksamples/s of A, B, A, B (the CLI's Msamples/s converted).
set -u
cd "$(dirname "$0")/.."
S=${SCENES:-../shared/scenes}
OUT=${OUT:-target/bench-ab}
mkdir -p "$OUT"
for sc in $(ls $S); do
  [ -f $S/$sc/scene.xml ] || continue
  line="$sc"
  for r in $(seq 1 ${ROUNDS:-2}); do for b in "$@"; do
    v=$($b render $S/$sc/scene.xml -e ${ESTIMATOR:-pt} --width 160 --spp ${SPP:-8} --threads 1 --no-plan -o "$OUT/ab.exr" 2>/dev/null | awk '$1 == "samples" { v = $2; if ($3 ~ /^Msamples/) v *= 1000; print v }')
    line="$line $v"
  done; done
  echo $line
done
