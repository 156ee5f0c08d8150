#!/usr/bin/env bash
# PT and LT samples/s of an old binary against one new binary run with each SIMD
# instruction set the machine offers (EMBER_SIMD), interleaved render by render:
#   scripts/bench-simd.sh OLD NEW SCENES OUT [SETS...]   (SETS default: sse avx2 avx512)
# Each set runs through a small wrapper that exports EMBER_SIMD; then bench-ab.sh with
# ROUNDS=3 SPP=24 on every scene of SCENES, writing OUT/ab-pt.txt and OUT/ab-lt.txt
# (scene, then ksamples/s of OLD, each set, OLD, each set, ...). The table in
# docs/performance.md ("The ray queries' instruction set") came from this on the lent
# 16-core machine with OLD = cd08858.
set -u
old=${1:?OLD}; new=${2:?NEW}; scenes=${3:?SCENES}; out=${4:?OUT}; shift 4
sets=("$@"); [ ${#sets[@]} -gt 0 ] || sets=(sse avx2 avx512)
mkdir -p "$out"
new=$(realpath "$new")
bins=("$old")
for s in "${sets[@]}"; do
  printf '#!/bin/sh\nEMBER_SIMD=%s exec "%s" "$@"\n' "$s" "$new" > "$out/ember-$s"
  chmod +x "$out/ember-$s"
  bins+=("$out/ember-$s")
done
for est in pt lt; do
  ROUNDS=3 SPP=24 ESTIMATOR=$est SCENES="$scenes" OUT="$out/ab-$est" scripts/bench-ab.sh "${bins[@]}" > "$out/ab-$est.txt" 2>&1
done
rm -f "$out"/ab-*/*.exr "$out"/ab-*/*.png
