#!/usr/bin/env bash
# Thread scaling: the same renders (fixed passes) on 1, 2, 4, 8, ... threads, alternating
# thread counts within each round, and a check that every thread count writes the same
# image bytes (an image must not depend on the thread count).
#
#   scripts/bench-scaling.sh [EMBER] [SCENES] [OUT] [ROUNDS] [THREADS...]
#
# EMBER: the binary (default target/release/ember), or several separated by ':' to compare
# them interleaved (each render alternates between them); SCENES: a folder holding the suite's
# scene folders (default ../shared/scenes); OUT: where the table and images go (default
# /tmp/scaling); ROUNDS: repeats (default 2); THREADS: thread counts (default 1 2 4 8 16).
# Prints one line per render and, per (binary, scene, estimator, threads), the median
# render seconds, the speed-up over the same binary's one thread, and whether the image's
# bytes equal the first binary's on one thread. Reference images are not needed.
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

IFS=: read -r -a BINARIES <<<"$EMBER"
log="$OUT/runs.txt"
: >"$log"
for r in $(seq 1 "$ROUNDS"); do
  for c in "${CASES[@]}"; do
    read -r sc est spp <<<"$c"
    for t in "${THREADS[@]}"; do
      for b in "${!BINARIES[@]}"; do
        img="$OUT/$sc-$est-b$b-t$t.exr"
        line=$("${BINARIES[$b]}" render "$SCENES/$sc/scene.xml" -e "$est" --spp "$spp" --threads "$t" --no-plan -o "$img" 2>/dev/null | grep '^time')
        secs=$(sed -E 's/.*\(([0-9.]+) s setup, ([0-9.]+) s rendering\).*/\2/' <<<"$line")
        hash=$(sha256sum "$img" | cut -c1-16)
        echo "$r $b $sc $est $spp $t $secs $hash" | tee -a "$log"
      done
    done
  done
done

echo
echo "binary scene estimator passes threads median_s speedup bytes_equal"
python3 - "$log" <<'PY'
import sys, statistics, collections
runs = collections.defaultdict(list)
hashes = collections.defaultdict(set)
for line in open(sys.argv[1]):
    r, b, sc, est, spp, t, secs, h = line.split()
    runs[(b, sc, est, spp, int(t))].append(float(secs))
    hashes[(sc, est, spp, b, int(t))].add(h)
for k in sorted(runs, key=lambda k: (k[1], k[2], k[0], k[4])):
    b, sc, est, spp, t = k
    t0 = min(tt for (bb, s, e, p, tt) in runs if (bb, s, e, p) == (b, sc, est, spp))
    base, m = statistics.median(runs[(b, sc, est, spp, t0)]), statistics.median(runs[k])
    first = hashes.get((sc, est, spp, "0", t0), set())
    same = "yes" if hashes[(sc, est, spp, b, t)] == first and len(first) == 1 else "NO"
    print(f"{b} {sc} {est} {spp} {t} {m:.3f} {base / m:.2f} {same}")
PY
