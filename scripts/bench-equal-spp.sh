#!/usr/bin/env bash
# Our PT against Mitsuba 3's `path` at equal samples per pixel: the variance of one
# sample, which throughput does not enter (scripts/bench-mitsuba.sh compares at equal time).
#   scripts/bench-equal-spp.sh SCENE SPP SEEDS [THREADS]
# Renders SEEDS independent images with each renderer (our seeds 1000.., Mitsuba's the
# same numbers) and prints each one's relMSE against the scene's reference and their mean.
# Needs `pip install mitsuba`; without Debian's libllvm19, MI_VARIANT=scalar_rgb.
# EMBER (default target/release/ember) picks the binary.
set -eu
cd "$(dirname "$0")/.."
scene=$1; spp=$2; seeds=$3; threads=${4:-2}
EMBER=${EMBER:-target/release/ember}
S=${SCENES:-../shared/scenes}
OUT=${OUT:-target/bench-equal-spp}
mkdir -p "$OUT"
ref="$S/$scene/reference.exr"
rel() { "$EMBER" compare "$1" "$ref" | awk '$1 == "relMSE" { print $2 }'; }
mean() { python3 -c "import sys; v = [float(x) for x in sys.argv[1:]]; print(f'{sum(v) / len(v):.4e}')" "$@"; }
mi=(); ours=()
for s in $(seq 1000 $((1000 + seeds - 1))); do
  python3 scripts/mitsuba-render.py "$S/$scene/scene.xml" "$spp" "$threads" "$OUT/$scene-mi-$s.exr" "$s" > /dev/null
  "$EMBER" render "$S/$scene/scene.xml" -e pt --spp "$spp" --threads "$threads" --seed "$s" --no-plan -o "$OUT/$scene-ours-$s.exr" > /dev/null 2>&1
  mi+=("$(rel "$OUT/$scene-mi-$s.exr")"); ours+=("$(rel "$OUT/$scene-ours-$s.exr")")
done
echo "$scene at $spp spp, $seeds seeds: relMSE"
echo "  mitsuba ${mi[*]}  mean $(mean "${mi[@]}")"
echo "  ours    ${ours[*]}  mean $(mean "${ours[@]}")"
