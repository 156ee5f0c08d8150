#!/usr/bin/env bash
# Instructions per sample (callgrind) for a list of estimators on the built-in Cornell
# box, 64×64, one thread: the difference between a render of HI and of LO passes, so
# scene loading and setup phases cancel. Repeatable where wall time is not.
#   scripts/callgrind-per-sample.sh BINARY [ESTIMATOR...]   (default: pt lt bdpt vcm bpf)
set -euo pipefail
bin=${1:?usage: callgrind-per-sample.sh BINARY [ESTIMATOR...]}; shift
estimators=("$@"); [ ${#estimators[@]} -gt 0 ] || estimators=(pt lt bdpt vcm bpf)
lo=${LO:-2}; hi=${HI:-6}; side=64
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
count() { # estimator passes -> total instructions
  valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$bin" render --builtin cornell-box \
    -e "$1" --width $side --height $side --spp "$2" --threads 1 --seed 1 -o "$tmp/o.exr" >/dev/null 2>&1
  grep -m1 '^summary:' "$tmp/cg.out" | awk '{print $2}'
}
for e in "${estimators[@]}"; do
  a=$(count "$e" "$lo"); b=$(count "$e" "$hi")
  echo "$e $(( (b - a) / ((hi - lo) * side * side) ))"
done
