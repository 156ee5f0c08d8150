#!/usr/bin/env bash
# `--estimator auto` against every estimator it races, at equal time on every suite scene
# (docs/plan.md; a long statistical run, not part of the test command).
# Usage: scripts/bench-auto.sh [seconds] [seeds] [threads] [estimators]
#
# Per scene and seed, auto and the fixed estimators render one after the other (so a
# load on the machine slows them alike), each `ember render --time SECONDS` from program
# start (scene loading, preprocessing and auto's pilot race included), then
# `ember compare` against the scene's Mitsuba reference. Writes one CSV line per render
# to $OUT/auto.csv and prints per scene the seed-averaged relMSE of each estimator, the
# best fixed one, auto's ratio to it and what auto chose.
#
# With BASE=path/to/another/ember, the estimator name `base` renders `-e auto` with that
# binary, interleaved with the others (an A/B of two versions of auto in one run), and
# the table gains base's ratio to the best fixed estimator. The `auto ...` lines of each
# auto render go to $OUT/<scene>-<estimator>-<seed>.log.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-10}
SEEDS=${2:-4}
THREADS=${3:-2}
ESTIMATORS=${4:-auto,pt,lt,bdpt,ppm,bpm}
SCENES=${SCENES:-../shared/scenes}
OUT=${OUT:-target/bench-auto}
mkdir -p "$OUT"
cargo build --release -q -p ember-cli
# A copy, so that a build during the run cannot change the binary under it.
cp target/release/ember "$OUT/ember"
EMBER=$OUT/ember
if [ -n "${BASE:-}" ]; then cp "$BASE" "$OUT/ember-base"; fi
CSV="$OUT/auto.csv"
echo "scene,estimator,seed,relmse,mape,passes,chosen" > "$CSV"
for dir in "$SCENES"/*/; do
  scene=$(basename "$dir")
  [ -f "$dir/scene.xml" ] || continue
  for seed in $(seq 1 "$SEEDS"); do
    for e in ${ESTIMATORS//,/ }; do
      exr="$OUT/$scene-$e-$seed.exr"
      bin=$EMBER est=$e
      if [ "$e" = base ]; then bin=$OUT/ember-base est=auto; fi
      log=$($bin render "$dir/scene.xml" -e "$est" --time "$SECONDS_EACH" --threads "$THREADS" --seed "$seed" -o "$exr" 2>&1)
      passes=$(echo "$log" | awk '/^passes/ {print $2}')
      chosen=$(echo "$log" | awk '/^auto +renders with/ {print $4}')
      if [ "$est" = auto ]; then echo "$log" | grep -E '^(auto|continues|time|passes)' > "$OUT/$scene-$e-$seed.log"; fi
      m=$($EMBER compare "$exr" "$dir/reference.exr")
      rel=$(echo "$m" | awk '/^relMSE/ {print $2}')
      mape=$(echo "$m" | awk '/^MAPE/ {print $2}')
      echo "$scene,$e,$seed,$rel,$mape,$passes,${chosen:-$e}" | tee -a "$CSV"
    done
  done
done
python3 - "$CSV" <<'PY'
import csv, sys, collections
rows = list(csv.DictReader(open(sys.argv[1])))
by = collections.defaultdict(list)
chosen = collections.defaultdict(list)
for r in rows:
    by[(r["scene"], r["estimator"])].append(float(r["relmse"]))
    if r["estimator"] in ("auto", "base"):
        chosen[(r["scene"], r["estimator"])].append(r["chosen"])
scenes = sorted({r["scene"] for r in rows})
ests = list(dict.fromkeys(r["estimator"] for r in rows))
autos = [e for e in ("auto", "base") if e in ests]
print("| scene | " + " | ".join(ests) + " | best fixed | " + " | ".join(f"{a} / best | {a} chose" for a in autos) + " |")
print("|---" * (len(ests) + 2 + 2 * len(autos)) + "|")
for s in scenes:
    mean = {e: sum(by[(s, e)]) / len(by[(s, e)]) for e in ests if by[(s, e)]}
    fixed = {e: v for e, v in mean.items() if e not in autos}
    cells = " | ".join(f"{mean[e]:.3e}" for e in ests)
    if not fixed:
        print(f"| {s} | {cells} | (none) |")
        continue
    best = min(fixed, key=fixed.get)
    ratios = " | ".join(f"{mean.get(a, float('nan')) / fixed[best]:.2f} | {', '.join(chosen[(s, a)])}" for a in autos)
    print(f"| {s} | {cells} | {best} | {ratios} |")
PY
