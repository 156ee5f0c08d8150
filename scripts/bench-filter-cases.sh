#!/usr/bin/env bash
# Our PT against Mitsuba 3's `path` at equal samples per pixel on scenes-extra/textured,
# over the six cases box/tent/gaussian pixel filter x pinhole/thin-lens camera
# (docs/pixel-filters.md). Edits copies of the scene in $OUT, never the shared input.
#   scripts/bench-filter-cases.sh [SPP [REF_SPP [SEEDS]]]      (default 64 512 2)
# Each case's reference is a Mitsuba render at REF_SPP (seed 4242), made once into $REF
# and reused. Prints, per case and seed, both relMSEs against it and ours/Mitsuba, then
# each case's mean ratio. Needs `pip install mitsuba` (MI_VARIANT=scalar_rgb without
# libLLVM; DRJIT_LIBLLVM_PATH to pick one); EMBER (default target/release/ember) picks
# our binary; CASES (e.g. "pinhole-box lens-tent") a subset.
set -eu
cd "$(dirname "$0")/.."
spp=${1:-64}; ref_spp=${2:-512}; seeds=${3:-2}
EMBER=${EMBER:-target/release/ember}
SCENE=${SCENE:-../shared/scenes-extra/textured}
OUT=${OUT:-target/bench-filter-cases}
REF=${REF:-$OUT/ref}
THREADS=${THREADS:-2}
CASES=${CASES:-pinhole-box pinhole-tent pinhole-gaussian lens-box lens-tent lens-gaussian}
mkdir -p "$OUT" "$REF"
ln -sfn "$(realpath "$SCENE")/textures" "$OUT/textures"
# The case's scene: the camera (thin lens as given, or a pinhole) and the filter.
make_case() {
  python3 - "$SCENE/scene.xml" "$1" "$2" "$OUT/$1-$2.xml" <<'EOF'
import re, sys
src, cam, filt, out = sys.argv[1:]
s = open(src).read()
if cam == "pinhole":
    s = s.replace('type="thinlens"', 'type="perspective"')
    s = re.sub(r'\s*<float name="(aperture_radius|focus_distance)"[^>]*/>', '', s)
s = re.sub(r'<rfilter type="[a-z]+"\s*/>', f'<rfilter type="{filt}"/>', s)
open(out, "w").write(s)
EOF
}
rel() { "$EMBER" compare "$1" "$2" | awk '$1 == "relMSE" { print $2 }'; }
printf '%-18s %5s %12s %12s %8s\n' case seed mitsuba ours ratio
for c in $CASES; do
  make_case "${c%%-*}" "${c#*-}"
  xml="$OUT/$c.xml"; ref="$REF/$c-$ref_spp.exr"
  [ -f "$ref" ] || python3 scripts/mitsuba-render.py "$xml" "$ref_spp" "$THREADS" "$ref" 4242 > /dev/null
  ratios=()
  for s in $(seq 1000 $((1000 + seeds - 1))); do
    python3 scripts/mitsuba-render.py "$xml" "$spp" "$THREADS" "$OUT/$c-mi-$s.exr" "$s" > /dev/null
    "$EMBER" render "$xml" -e pt --spp "$spp" --threads "$THREADS" --seed "$s" --no-plan -o "$OUT/$c-ours-$s.exr" > /dev/null 2>&1
    mi=$(rel "$OUT/$c-mi-$s.exr" "$ref"); ours=$(rel "$OUT/$c-ours-$s.exr" "$ref")
    r=$(python3 -c "print(f'{$ours / $mi:.3f}')")
    ratios+=("$r")
    printf '%-18s %5s %12s %12s %8s\n' "$c" "$s" "$mi" "$ours" "$r"
  done
  echo "$c mean ratio $(python3 -c "import sys; v = [float(x) for x in sys.argv[1:]]; print(f'{sum(v) / len(v):.3f}')" "${ratios[@]}")"
done
