#!/usr/bin/env bash
# Thread scaling: the same renders (fixed passes) on 1, 2, 4, 8, ... threads, alternating
# thread counts within each round, and a check that every thread count writes the same
# image bytes (an image must not depend on the thread count).
#
#   scripts/bench-scaling.sh [EMBER] [SCENES] [OUT] [ROUNDS] [THREADS...]
#
# EMBER: the binary (default target/release/ember); SCENES: a folder holding the suite's
# scene folders (default ../shared/scenes); OUT: where the table and images go (default
# /tmp/scaling); ROUNDS: repeats (default 2); THREADS: thread counts (default 1 2 4 8 16).
# Prints one line per render and, per (scene, estimator, threads), the median render
# seconds and the speed-up over one thread. Reference images are not needed.
set -euo pipefail
EMBER=${1:-target/release/ember}
SCENES=${2:-../shared/scenes}
OUT=${3:-/tmp/scaling}
ROUNDS=${4:-2}
shift $(( $# < 4 ? $# : 4 ))
THREADS=("$@")
[ ${#THREADS[@]} -gt 0 ] || THREADS=(1 2 4 8 16)
mkdir -p "$OUT"

# scene estimator passes: sized for 3-6 s on one thread of a 2026 server core.
CASES=(
  "cornell-box pt 64"
  "glossy pt 32"
  "veach-bidir pt 32"
  "cornell-box lt 48"
  "veach-bidir lt 16"
  "cornell-box bdpt 8"
  "veach-bidir bdpt 4"
  "cornell-box vcm 2"
)

log="$OUT/runs.txt"
: >"$log"
for r in $(seq 1 "$ROUNDS"); do
  for c in "${CASES[@]}"; do
    read -r sc est spp <<<"$c"
    for t in "${THREADS[@]}"; do
      img="$OUT/$sc-$est-t$t.exr"
      line=$("$EMBER" render "$SCENES/$sc/scene.xml" -e "$est" --spp "$spp" --threads "$t" --no-plan -o "$img" 2>/dev/null | grep '^time')
      secs=$(sed -E 's/.*\(([0-9.]+) s setup, ([0-9.]+) s rendering\).*/\2/' <<<"$line")
      hash=$(sha256sum "$img" | cut -c1-16)
      echo "$r $sc $est $spp $t $secs $hash" | tee -a "$log"
    done
  done
done

echo
echo "scene estimator passes threads median_s speedup bytes_equal_to_1_thread"
python3 - "$log" <<'EOF'
import sys, statistics, collections
runs = collections.defaultdict(list)
hashes = collections.defaultdict(set)
for line in open(sys.argv[1]):
    r, sc, est, spp, t, secs, h = line.split()
    runs[(sc, est, spp, int(t))].append(float(secs))
    hashes[(sc, est, spp, int(t))].add(h)
keys = sorted(runs, key=lambda k: (k[0], k[1], k[3]))
for k in keys:
    base = statistics.median(runs[(k[0], k[1], k[2], min(t for (s, e, p, t) in runs if (s, e, p) == k[:3]))])
    m = statistics.median(runs[k])
    one = hashes[(k[0], k[1], k[2], 1)] if (k[0], k[1], k[2], 1) in hashes else set()
    same = "yes" if hashes[k] == one and len(one) == 1 else "NO"
    print(f"{k[0]} {k[1]} {k[2]} {k[3]} {m:.3f} {base / m:.2f} {same}")
EOF
