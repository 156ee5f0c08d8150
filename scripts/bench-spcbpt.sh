#!/usr/bin/env bash
# Issue 18: LVCBPT against SPCBPT, passes and time to a fixed relMSE, preprocessing counted.
#
#   scripts/bench-spcbpt.sh PASSES SEEDS THREADS [OPTION...]
#
# Renders every scene of $SCENES (default: ajar enclosed door) with every entry of
# $RUNS (default "lvcbpt=lvcbpt spcbpt=spcbpt"; an entry is
# LABEL=ESTIMATOR[:OPTIONS][@BINARY], options comma-separated, e.g.
# "sp-n12=spcbpt:--connections,12", or "old=spcbpt@/tmp/old/ember" for another build)
# for PASSES passes under seeds
# 1..SEEDS, with `--no-plan` (the estimator asked for, not the plan's choice) and the
# trailing OPTIONs. The binary is $EMBER (default target/release/ember). relMSE and MAPE
# against the scene's reference; door (scripts/scenes/door, issue 18's door-like scene)
# has no stored reference: one is rendered into target/door/reference.exr on first use
# (BDPT, 2 x 240 s on THREADS threads, the two halves averaged; their difference is
# printed as the reference's own noise).
#
# Output: $OUT (default target/bench-spcbpt)/results.csv (one row per render) and a summary per scene
# and run: mean relMSE, setup and time per pass over seeds; passes and seconds to the
# scene's target relMSE (half of what the first run reaches in PASSES passes, i.e. that
# run's relMSE at 2 x PASSES), extrapolated as relMSE ∝ 1/passes (unbiased estimators),
# setup counted once; and the ratio to the first run.
set -euo pipefail
cd "$(dirname "$0")/.."
passes=${1:?passes}
seeds=${2:?seeds}
threads=${3:?threads}
shift 3
ember=${EMBER:-target/release/ember}
scenes=${SCENES:-ajar enclosed door}
runs=${RUNS:-lvcbpt=lvcbpt spcbpt=spcbpt}
out=${OUT:-target/bench-spcbpt}
mkdir -p "$out"
csv=$out/results.csv
[ -x "$ember" ] || cargo build --release -p ember-cli

scene_file() { if [ "$1" = door ]; then echo scripts/scenes/door/scene.xml; else echo ../shared/scenes/$1/scene.xml; fi; }
reference() {
    if [ "$1" != door ]; then echo ../shared/scenes/$1/reference.exr; return; fi
    if [ ! -f target/door/reference.exr ]; then
        mkdir -p target/door
        for s in 101 102; do
            "$ember" render scripts/scenes/door/scene.xml -e bdpt --no-plan --time 240 --threads "$threads" --seed $s \
                -o target/door/ref-$s.exr > target/door/ref-$s.log 2>&1
        done
        python3 - <<'EOF' >&2
import OpenEXR, Imath, numpy as np
def load(p):
    f = OpenEXR.InputFile(p); dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w) for c in "RGB"], -1).astype(np.float64), w, h
a, w, h = load("target/door/ref-101.exr"); b, _, _ = load("target/door/ref-102.exr")
ref = (a + b) / 2
print("door reference: half-vs-half relMSE %.3g (the reference's own relMSE is about a quarter)" % ((a - b) ** 2 / (ref ** 2 + 1e-2)).mean())
hdr = OpenEXR.Header(w, h); hdr["channels"] = {c: Imath.Channel(Imath.PixelType(Imath.PixelType.FLOAT)) for c in "RGB"}
o = OpenEXR.OutputFile("target/door/reference.exr", hdr)
o.writePixels({c: ref[..., i].astype(np.float32).tobytes() for i, c in enumerate("RGB")}); o.close()
EOF
    fi
    echo target/door/reference.exr
}

echo "scene,run,seed,passes,setup_s,total_s,relmse,mape,occluded,occluded_value" > "$csv"
for scene in $scenes; do
    file=$(scene_file "$scene")
    ref=$(reference "$scene")
    for seed in $(seq 1 "$seeds"); do
        # Runs interleaved within a seed, so load drifts hit them alike.
        for run in $runs; do
            label=${run%%=*}
            spec=${run#*=}
            bin=$ember
            if [[ $spec == *@* ]]; then bin=${spec#*@}; spec=${spec%%@*}; fi
            est=${spec%%:*}
            opts=()
            if [ "$spec" != "$est" ]; then IFS=, read -r -a opts <<< "${spec#*:}"; fi
            log=$out/$scene-$label-$seed.log
            "$bin" render "$file" -e "$est" --no-plan --spp "$passes" --threads "$threads" --seed "$seed" \
                "${opts[@]}" "$@" -o "$out/$scene-$label-$seed.exr" > "$log" 2>&1
            read -r total setup < <(sed -n 's/^time *\([0-9.]*\) s (\([0-9.]*\) s setup.*/\1 \2/p' "$log")
            read -r occ occv < <(sed -n 's/^connect.*: \([0-9.]*\) % occluded, \([0-9.]*\) % of the value.*/\1 \2/p' "$log")
            cmp=$("$ember" compare "$out/$scene-$label-$seed.exr" "$ref")
            rel=$(echo "$cmp" | awk '/^relMSE/ {print $2}')
            mape=$(echo "$cmp" | awk '/^MAPE/ {print $2}')
            echo "$scene,$label,$seed,$passes,$setup,$total,$rel,$mape,${occ:-},${occv:-}" | tee -a "$csv"
        done
    done
done

python3 - "$csv" <<'EOF'
import csv, sys
from collections import defaultdict
rows = list(csv.DictReader(open(sys.argv[1])))
by = defaultdict(list)
order = []
for r in rows:
    key = (r["scene"], r["run"])
    if key not in by:
        order.append(key)
    by[key].append(r)
print("\n| scene | run | relMSE at %s passes | occluded (by value) | setup s | s per pass | passes to target | s to target | passes ratio | time ratio |" % rows[0]["passes"])
print("|---|---|---|---|---|---|---|---|---|---|")
first = {}
for scene, run in order:
    rs = by[(scene, run)]
    n = len(rs)
    p = float(rs[0]["passes"])
    rel = sum(float(r["relmse"]) for r in rs) / n
    setup = sum(float(r["setup_s"]) for r in rs) / n
    per_pass = sum(float(r["total_s"]) - float(r["setup_s"]) for r in rs) / n / p
    occ = rs[0]["occluded"] and "%.1f %% (%.1f %%)" % (sum(float(r["occluded"]) for r in rs) / n, sum(float(r["occluded_value"]) for r in rs) / n) or "-"
    if scene not in first:
        first[scene] = (rel / 2, None, None)
    target = first[scene][0]
    need = p * rel / target
    secs = setup + per_pass * need
    if first[scene][1] is None:
        first[scene] = (target, need, secs)
    _, n0, s0 = first[scene]
    print("| %s | %s | %.3e | %s | %.2f | %.3f | %.0f | %.1f | %.2f | %.2f |" % (scene, run, rel, occ, setup, per_pass, need, secs, n0 / need, s0 / secs))
print("\n(target per scene: half the first run's mean relMSE; ratios: first run / this run, so > 1 means fewer passes or less time)")
EOF
