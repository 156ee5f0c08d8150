#!/usr/bin/env bash
# Bidirectional path filtering's parameter sweeps behind docs/bidirectional-filtering.md
# (the segment paper's Fig. 5 and Fig. 6 analogues; long statistical runs, not part of
# the test command). Usage: scripts/bench-bpf-sweeps.sh [seconds] [seeds] [threads]
#
# At equal time, 80×60 (the 320×240 references averaged over 4×4 blocks, by
# scripts/exr-block-ratio.py, which needs numpy and OpenEXR), on ajar, caustic and
# enclosed, relMSE averaged over seeds:
# 1. kernel size: r₀ = 1, 2, 4 (default), 8 pixel footprints, β = 0.25;
# 2. light paths per camera path: β = 0 (MVF's segments), 0.125, 0.25, 0.5, 1, 2, with
#    BPM beside it at the same time.
# Prints one line per setting: scene, setting, mean relMSE, its spread over seeds, mean
# passes, mean ratio of image means.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-10}
SEEDS=${2:-3}
THREADS=${3:-2}
SCENES=../shared/scenes
OUT=${OUT:-target/bench-bpf-sweeps}
mkdir -p "$OUT"
cargo build --release -q -p ember-cli
EMBER=target/release/ember

# run NAME SCENE ARGS...: SEEDS renders at 80×60 for SECONDS_EACH, one summary line.
run() {
  local name=$1 scene=$2
  shift 2
  local rels="" passes="" ratios=""
  for seed in $(seq 1 "$SEEDS"); do
    local exr="$OUT/$scene-$name-$seed.exr"
    local p
    p=$($EMBER render "$SCENES/$scene/scene.xml" --width 80 --height 60 --time "$SECONDS_EACH" --threads "$THREADS" --seed "$seed" -o "$exr" "$@" 2>/dev/null | awk '/^passes/ {print $2}')
    local m
    m=$(scripts/exr-block-ratio.py "$exr" "$SCENES/$scene/reference.exr")
    rels="$rels $(echo "$m" | awk '{print $2}')"
    ratios="$ratios $(echo "$m" | awk '{print $5}')"
    passes="$passes $p"
  done
  python3 - "$scene" "$name" "$rels" "$passes" "$ratios" <<'PY'
import sys, statistics as st
scene, name, rels, passes, ratios = sys.argv[1], sys.argv[2], *[list(map(float, a.split())) for a in sys.argv[3:]]
spread = st.stdev(rels) if len(rels) > 1 else 0.0
print(f"| {scene} | {name} | {st.mean(rels):.4g} | {spread:.2g} | {st.mean(passes):.1f} | {st.mean(ratios):.3f} |")
PY
}

echo "## Kernel size (β = 0.25), ${SECONDS_EACH} s, ${SEEDS} seeds, ${THREADS} threads"
echo "| scene | r₀ | relMSE | sd | passes | mean ratio |"
echo "|---|---|---|---|---|---|"
for scene in ajar caustic enclosed; do
  for k in 1 2 4 8; do
    run "r0=${k}fp" $scene -e bpf --radius-footprints $k
  done
done

echo "## Light paths per camera path, ${SECONDS_EACH} s, ${SEEDS} seeds, ${THREADS} threads"
echo "| scene | setting | relMSE | sd | passes | mean ratio |"
echo "|---|---|---|---|---|---|"
for scene in ajar caustic enclosed; do
  for b in 0 0.125 0.25 0.5 1 2; do
    run "β=$b" $scene -e bpf --beta $b
  done
  run "bpm" $scene -e bpm
done
