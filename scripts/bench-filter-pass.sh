#!/usr/bin/env bash
# Seconds per pass of the filtering estimators, two binaries interleaved (issue 53):
# a pass timed as (time of N passes − time of 1 pass) / (N − 1), from each render's
# "rendering" seconds, at the wave-2 settings given explicitly.
#
#   scripts/bench-filter-pass.sh OLD_BINARY NEW_BINARY [SCENE...]
#
# Environment: ESTIMATORS (default "mvf phf bpf"), N (default 3), THREADS (default 2),
# ROUNDS (default 1), SCENES_DIR (default ../shared/scenes), EXTRA (more options for both).
set -euo pipefail
old=$1 new=$2
shift 2
here=$(cd "$(dirname "$0")/.." && pwd)
dir=${SCENES_DIR:-$here/../shared/scenes}
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(ajar caustic cornell-box enclosed glossy spot_mirror veach-bidir veach-mis window_env)
n=${N:-3}
settings=(--beta 0.25 --radius-footprints 4 --max-segments 16 --threads "${THREADS:-2}" ${EXTRA:-})
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
seconds() { # binary scene estimator passes
  "$1" render "$dir/$2/scene.xml" -e "$3" --spp "$4" "${settings[@]}" -o "$tmp/out.exr" 2>/dev/null |
    sed -n 's/^time .*, \([0-9.]*\) s rendering.*/\1/p'
}
printf '%-12s %-4s %10s %10s %7s\n' scene est old_s/pass new_s/pass speedup
for scene in "${scenes[@]}"; do
  for e in ${ESTIMATORS:-mvf phf bpf}; do
    declare -A per=()
    for round in $(seq "${ROUNDS:-1}"); do
      for which in old new; do
        b=${!which}
        t1=$(seconds "$b" "$scene" "$e" 1)
        tn=$(seconds "$b" "$scene" "$e" "$n")
        per[$which]="${per[$which]:-} $(echo "($tn - $t1) / ($n - 1)" | bc -l)"
      done
    done
    # The fastest round of each (the least disturbed by other jobs).
    o=$(printf '%s\n' ${per[old]} | sort -g | head -1)
    w=$(printf '%s\n' ${per[new]} | sort -g | head -1)
    printf '%-12s %-4s %10.3f %10.3f %7.2f\n' "$scene" "$e" "$o" "$w" "$(echo "$o / $w" | bc -l)"
  done
done
