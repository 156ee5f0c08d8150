#!/usr/bin/env bash
# The filters' passes on a lent many-core machine (issue 53), in one command:
#   scripts/bench-filter-device.sh NEW OLD SCENES OUT
# NEW, OLD: ember binaries (NEW prints a `phases` line); SCENES: the suite's scene folders;
# OUT: results folder. At the wave-2 settings (--beta 0.25 --radius-footprints 4
# --max-segments 16, neighbour budget 64: OLD's constant) on ajar at its full size:
# 1. MVF, PhF and BPF at 16, 8, 4 and 2 threads, 1 and 3 passes each (a pass's seconds are
#    (T3 - T1) / 2), with NEW's seconds per phase: how much of a pass stays serial;
# 2. OLD the same at 16 threads;
# 3. BPF, MVF and PhF at the segment paper's 1200x800, 2 passes on 16 threads.
# Each line is written as it comes, so a run cut short keeps what it did.
set -u
new=${1:?NEW binary}; old=${2:?OLD binary}; scenes=${3:?SCENES}; out=${4:?OUT}
mkdir -p "$out"
nproc >"$out/machine.txt"
S=$scenes/ajar/scene.xml
W=(--beta 0.25 --radius-footprints 4 --max-segments 16)
log=$out/filter-passes.txt
: >"$log"
run() { # label binary estimator threads passes [more args]
  local label=$1 bin=$2 e=$3 t=$4 n=$5; shift 5
  "$bin" render "$S" -e "$e" --spp "$n" --threads "$t" --no-plan "${W[@]}" "$@" -o "$out/x.exr" 2>&1 |
    grep -E "^(time|phases|$e )" | tr '\n' ' ' | sed "s/^/$label $e threads $t passes $n | /" >>"$log"
  echo >>"$log"
}
for e in mvf phf bpf; do
  for t in 16 8 4 2; do
    for n in 1 3; do run new "$new" "$e" "$t" "$n" --neighbours 64; done
  done
  for n in 1 3; do run old "$old" "$e" 16 "$n"; done
done
for e in bpf mvf phf; do run paper "$new" "$e" 16 2 --neighbours 64 --width 1200 --height 800; done
rm -f "$out"/x.exr "$out"/x.png
