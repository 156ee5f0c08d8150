#!/usr/bin/env bash
# Equal-time runs in parallel on a many-core machine (issue 53's tables), in one command:
#   scripts/bench-equal-time.sh BIN SCENES JOBS OUT
# BIN: an ember binary; SCENES: folders SCENE/scene.xml + SCENE/reference.exr; JOBS: a
# file of lines `LABEL SCENE ESTIMATOR SEED [render options...]` ('#' starts a comment);
# OUT: results folder. Each job is `ember render --time $BUDGET --threads $THREADS --seed
# SEED`, then `ember compare` against the reference; PARALLEL jobs run at once (default:
# cores / THREADS), so keep PARALLEL x THREADS at or below the cores: each run then has its
# threads to itself (memory bandwidth and the last-level cache are still shared; say so
# beside any table made this way). BUDGET defaults to 60 s, THREADS to 2.
# Writes OUT/equal-time.tsv: label, scene, estimator, seed, passes, seconds, relMSE, mean
# ratio, options; each line as its job ends, so a run cut short keeps what it did.
set -u
bin=${1:?BIN}; scenes=${2:?SCENES}; jobs=${3:?JOBS}; out=${4:?OUT}
budget=${BUDGET:-60}; threads=${THREADS:-2}
parallel=${PARALLEL:-$(($(nproc) / threads))}
[ "$parallel" -ge 1 ] || parallel=1
mkdir -p "$out"
tsv=$out/equal-time.tsv
printf 'label\tscene\testimator\tseed\tpasses\tseconds\trelmse\tmean_ratio\toptions\n' >"$tsv"
export bin scenes out budget threads tsv
one() {
  local label=$1 scene=$2 e=$3 seed=$4; shift 4
  local tag="$label-$scene-$e-$seed" img
  img=$(mktemp -d)/x.exr
  local report
  report=$("$bin" render "$scenes/$scene/scene.xml" -e "$e" --time "$budget" --threads "$threads" --seed "$seed" "$@" -o "$img" 2>&1)
  local passes secs cmp rel ratio
  passes=$(sed -n 's/^passes *\([0-9]*\).*/\1/p' <<<"$report")
  secs=$(sed -n 's/^time *\([0-9.]*\) s.*/\1/p' <<<"$report")
  cmp=$("$bin" compare "$img" "$scenes/$scene/reference.exr" 2>&1)
  rel=$(sed -n 's/^relMSE *\([^ ]*\).*/\1/p' <<<"$cmp")
  ratio=$(sed -n 's/^mean ratio *\([^ ]*\).*/\1/p' <<<"$cmp")
  [ -n "$rel" ] || { echo "$tag failed: $report $cmp" >>"$out/errors.txt"; rel=NA; }
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$scene" "$e" "$seed" "${passes:-NA}" "${secs:-NA}" "$rel" "${ratio:-NA}" "$*" >>"$tsv"
  rm -rf "$(dirname "$img")"
}
export -f one
grep -v '^\s*#' "$jobs" | grep -v '^\s*$' | xargs -P "$parallel" -L 1 bash -c 'one "$@"' _
