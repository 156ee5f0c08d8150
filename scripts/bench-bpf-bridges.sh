#!/usr/bin/env bash
# Bidirectional path filtering with and without bridge segments (the segment paper's
# Fig. 7 analogue, docs/bidirectional-filtering.md; a long run, not part of the test
# command). Usage: scripts/bench-bpf-bridges.sh [passes] [seconds] [seeds] [threads]
#
# 160×120 (the 320×240 references averaged over 2×2 blocks by scripts/exr-block-ratio.py,
# which needs numpy and OpenEXR), a fixed kernel (α = 1) at the default r₀ as the paper
# used, β = 0.25, on ajar and enclosed; each setting at equal samples (PASSES passes)
# and at equal time (SECONDS per render, setup included), relMSE averaged over seeds.
# Prints one line per setting: scene, setting, mean relMSE, its spread over seeds, mean
# passes, mean seconds, mean ratio of image means.
set -euo pipefail
cd "$(dirname "$0")/.."
PASSES=${1:-16}
SECONDS_EACH=${2:-20}
SEEDS=${3:-3}
THREADS=${4:-2}
SCENES=../shared/scenes
OUT=${OUT:-target/bench-bpf-bridges}
mkdir -p "$OUT"
cargo build --release -q -p ember-cli
EMBER=target/release/ember

# run NAME SCENE ARGS...: SEEDS renders at 160×120, one summary line.
run() {
  local name=$1 scene=$2
  shift 2
  local rels="" passes="" ratios="" times=""
  for seed in $(seq 1 "$SEEDS"); do
    local exr="$OUT/$scene-$name-$seed.exr" log
    log=$($EMBER render "$SCENES/$scene/scene.xml" --width 160 --height 120 --threads "$THREADS" --seed "$seed" --alpha 1 -o "$exr" "$@" 2>/dev/null)
    passes="$passes $(echo "$log" | awk '/^passes/ {print $2}')"
    times="$times $(echo "$log" | awk '/^time/ {print $2}')"
    local m
    m=$(scripts/exr-block-ratio.py "$exr" "$SCENES/$scene/reference.exr")
    rels="$rels $(echo "$m" | awk '{print $2}')"
    ratios="$ratios $(echo "$m" | awk '{print $5}')"
  done
  python3 - "$scene" "$name" "$rels" "$passes" "$times" "$ratios" <<'PY'
import sys, statistics as st
scene, name, rels, passes, times, ratios = sys.argv[1], sys.argv[2], *[list(map(float, a.split())) for a in sys.argv[3:]]
spread = st.stdev(rels) if len(rels) > 1 else 0.0
print(f"| {scene} | {name} | {st.mean(rels):.4g} | {spread:.2g} | {st.mean(passes):.1f} | {st.mean(times):.1f} | {st.mean(ratios):.3f} |")
PY
}

echo "## With and without bridges: ${PASSES} passes, and ${SECONDS_EACH} s; ${SEEDS} seeds, ${THREADS} threads"
echo "| scene | setting | relMSE | sd | passes | s | mean ratio |"
echo "|---|---|---|---|---|---|---|"
for scene in ajar enclosed; do
  for reuse in every bridges; do
    run "$reuse, ${PASSES} passes" $scene -e bpf --filter-reuse $reuse --spp "$PASSES"
    run "$reuse, ${SECONDS_EACH} s" $scene -e bpf --filter-reuse $reuse --time "$SECONDS_EACH"
  done
done
