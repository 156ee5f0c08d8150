#!/usr/bin/env bash
# Side-by-side: our PT against Mitsuba 3's `llvm_ad_rgb` `path` at equal wall time
# (startup included) on every suite scene, same threads; optionally a second ember
# binary (EMBER_BEFORE, e.g. a build of an older commit) in the same interleaved run.
#
#   scripts/bench-mitsuba.sh [SECONDS=10] [THREADS=2]
#
# Needs `pip install mitsuba` and Debian's libllvm19. For each scene: Mitsuba is timed
# at 16 and 64 spp to calibrate its rate, then run at the spp that fills SECONDS
# (process start to exit, measured); ember then gets that same measured wall time with
# `--time` (which counts from its own start). Prints per scene: spp, relMSE and MAPE of
# each against the scene's reference, and the ratios. Outputs under $OUT (default
# target/bench-mitsuba).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_BUDGET=${1:-10}
THREADS=${2:-2}
SCENES=${SCENES:-../shared/scenes}
OUT=${OUT:-target/bench-mitsuba}
mkdir -p "$OUT"
cargo build --release -p ember-cli >/dev/null 2>&1
cp target/release/ember "$OUT/ember"
EMBER="$OUT/ember"
# Binaries older than the scene plan (e.g. c05c2ce, the one issue 24 was filed on) know
# no --no-plan.
BEFORE_FLAGS=""
if [ -n "${EMBER_BEFORE:-}" ] && "$EMBER_BEFORE" render --help 2>/dev/null | grep -q -- --no-plan; then BEFORE_FLAGS="--no-plan"; fi
now() { date +%s.%N; }
metric() { # IMAGE REFERENCE FIELD
  "$EMBER" compare "$1" "$2" | awk -v f="$3" '$1 == f { print $2 }'
}
printf '%-12s %9s %9s %10s %10s %9s %9s %8s %8s' scene mi_spp ours_spp mi_relMSE ours_relMSE mi_MAPE ours_MAPE relMSE_x spp_x
[ -n "${EMBER_BEFORE:-}" ] && printf ' %9s %9s' before_spp after/before
printf '\n'
for dir in "$SCENES"/*/; do
  name=$(basename "$dir")
  scene="$dir/scene.xml"; ref="$dir/reference.exr"
  [ -f "$scene" ] && [ -f "$ref" ] || continue
  # Calibrate Mitsuba's rate from 16 and 64 spp (the difference cancels its JIT
  # compilation), then fill the budget less ~1.5 s of process start and scene loading.
  c16=$(python3 scripts/mitsuba-render.py "$scene" 16 "$THREADS" "$OUT/$name-mi-cal.exr" | awk '{print $4}')
  c64=$(python3 scripts/mitsuba-render.py "$scene" 64 "$THREADS" "$OUT/$name-mi-cal.exr" | awk '{print $4}')
  spp=$(python3 -c "
rate = 48 / max($c64 - $c16, 1e-3); fixed = max($c16 - 16 / rate, 0.0)
print(max(16, int(rate * max(0.5, $SECONDS_BUDGET - 1.5 - fixed))))")
  t0=$(now); python3 scripts/mitsuba-render.py "$scene" "$spp" "$THREADS" "$OUT/$name-mi.exr" >/dev/null; t1=$(now)
  wall=$(python3 -c "print(f'{$t1 - $t0:.2f}')")
  ours_spp=$("$EMBER" render "$scene" -e pt --time "$wall" --threads "$THREADS" --no-plan -o "$OUT/$name-ours.exr" 2>/dev/null | awk '$1 == "passes" { print $2 }')
  mi_rel=$(metric "$OUT/$name-mi.exr" "$ref" relMSE); ours_rel=$(metric "$OUT/$name-ours.exr" "$ref" relMSE)
  line=$(printf '%-12s %9s %9s %10s %10s %9s %9s' "$name" "$spp" "$ours_spp" "$mi_rel" "$ours_rel" \
    "$(metric "$OUT/$name-mi.exr" "$ref" MAPE)" "$(metric "$OUT/$name-ours.exr" "$ref" MAPE)")
  ratio=$(python3 -c "print(f'{float(\"$ours_rel\") / float(\"$mi_rel\"):.2f}')")
  sppx=$(python3 -c "print(f'{$ours_spp/$spp:.2f}')")
  line="$line $(printf '%8s %8s' "$ratio" "$sppx")"
  if [ -n "${EMBER_BEFORE:-}" ]; then
    before=$("$EMBER_BEFORE" render "$scene" -e pt --time "$wall" --threads "$THREADS" $BEFORE_FLAGS -o "$OUT/$name-before.exr" 2>/dev/null | awk '$1 == "passes" { print $2 }')
    line="$line $(printf ' %9s %9s' "$before" "$(python3 -c "print(f'{$ours_spp/max($before,1):.2f}')")")"
  fi
  echo "$line (wall $wall s)"
done
