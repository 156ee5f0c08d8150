#!/usr/bin/env bash
# Vertex-merging benchmarks behind docs/merging.md (long statistical runs; not part of
# the test command). Usage: scripts/bench-merging.sh [seconds] [threads]
#
# 1. The caustic seen through the glass sphere of the `caustic` suite scene: PT, BDPT and
#    VCM at equal time, relMSE and mean ratio in the pixel rectangle 85,180-155,222
#    (the floor caustic and its image through the sphere) and over the whole image.
# 2. Memory per pass of PPM/BPM/VCM on every suite scene (one pass each).
# 3. Bias against radius on the built-in glass-spheres scene: PPM and BPM at fixed radii
#    (α = 1) against a long progressive VCM render, whole-image and caustic-rectangle
#    mean ratios.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-30}
THREADS=${2:-2}
SCENES=../shared/scenes
OUT=${OUT:-target/bench-merging}
mkdir -p "$OUT"
cargo build --release -q -p ember-cli
EMBER=target/release/ember

echo "## 1. Caustic through glass, ${SECONDS_EACH} s each on ${THREADS} threads"
REGION=85,180,155,222
for e in pt bdpt vcm; do
  $EMBER render $SCENES/caustic/scene.xml -e $e --time "$SECONDS_EACH" --threads "$THREADS" -o "$OUT/caustic-$e.exr" 2>&1 | grep -E "^passes" | sed "s/^/$e /"
  echo "$e region: $($EMBER compare "$OUT/caustic-$e.exr" $SCENES/caustic/reference.exr --region $REGION | grep -E 'relMSE|mean ratio' | tr -s ' ' | tr '\n' ' ')"
  echo "$e image:  $($EMBER compare "$OUT/caustic-$e.exr" $SCENES/caustic/reference.exr | grep -E 'relMSE|mean ratio' | tr -s ' ' | tr '\n' ' ')"
done

echo "## 2. Memory per pass (one pass, default settings)"
for scene in $SCENES/*/; do
  name=$(basename "$scene")
  for e in ppm vcm; do
    $EMBER render "$scene/scene.xml" -e $e --spp 1 --threads "$THREADS" -o "$OUT/mem-$name-$e.exr" 2>&1 | grep -E "memory per pass" | sed "s/^/$name /"
  done
done

echo "## 3. Bias against radius, glass-spheres 128x128"
$EMBER render --builtin glass-spheres --width 128 --height 128 -e vcm --time $((SECONDS_EACH * 4)) --threads "$THREADS" -o "$OUT/glass-ref.exr" 2>&1 | grep -E "^passes"
for r in 0.005 0.01 0.02 0.04 0.08; do
  for e in ppm bpm; do
    $EMBER render --builtin glass-spheres --width 128 --height 128 -e $e --alpha 1 --radius $r --time "$SECONDS_EACH" --threads "$THREADS" -o "$OUT/glass-$e-$r.exr" > /dev/null 2>&1
    echo "$e r=$r image: $($EMBER compare "$OUT/glass-$e-$r.exr" "$OUT/glass-ref.exr" | grep -E 'relMSE|mean ratio' | tr -s ' ' | tr '\n' ' ')"
  done
done
