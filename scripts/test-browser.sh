#!/usr/bin/env bash
# The browser test (issues 7, 19): builds the wasm module, serves host-wasm/www on
# 127.0.0.1 and, in headless Debian chromium (playwright-core), renders every estimator
# in the core's list (ember-wasm-compare --estimators) through the core's render
# protocol on two Web Workers. Each image is checked against sixteen native CLI renders of
# the same scene and passes with seeds *different* from the browser's (ember-wasm-compare
# independent: a Šidák-corrected t-test per 8×8 block and channel, the noise taken from
# the sixteen, so that kernel estimators' correlated pixels are held to the right bound;
# no NaN, not blank). Fails if the
# module does not load, a worker errors, the page logs an error, the canvas is blank or
# the images disagree. One more case renders with the page dropping one light-path chunk
# (fault=drop-light-chunk) and must end in the page's error, not in an image.
# Artifacts (screenshots, PFM, EXR, per-case JSON): target/browser-artifacts/.
# Injected bugs it was seen to catch (docs/wasm.md): the page dropping a light-path chunk
# (the fault case, run without its expectation: "reduced without chunk 1"); the page
# dropping worker 1's splat film (lt/bdpt cases disagree, block |z| 8-10); a worker
# throwing on pass 2 (console and page errors); a wrong module URL (404: module not
# loaded, canvas blank).
#
#   scripts/test-browser.sh          the test (48×48, 4 passes, 2 workers per case)
#   scripts/test-browser.sh bench    also measure samples/s per estimator: 1 worker
#                                    against the native CLI on 1 thread, at 128×128
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
MODE=${1:-}
TARGET_DIR=${CARGO_TARGET_DIR:-$ROOT/target}
ART=$ROOT/target/browser-artifacts
step() { printf '\n==> %s\n' "$*"; }

step "chromium"
if [ ! -x /usr/bin/chromium ]; then
  SUDO=; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi
/usr/bin/chromium --version

step "playwright-core (npm, host-wasm/tests)"
if [ ! -d host-wasm/tests/node_modules/playwright-core ]; then
  (cd host-wasm/tests && npm ci --no-audit --no-fund --loglevel=error)
fi

step "wasm module (release, wasm32-unknown-unknown, simd128)"
scripts/build-wasm.sh

step "native CLI and checker"
cargo build --release -p ember-cli -p ember-wasm --bins
EMBER=$TARGET_DIR/release/ember
CHECK=$TARGET_DIR/release/ember-wasm-compare

rm -rf "$ART"; mkdir -p "$ART"
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1]); s.close()')
python3 -m http.server --bind 127.0.0.1 "$PORT" --directory host-wasm/www >"$ART/http.log" 2>&1 &
SERVER=$!
trap 'kill $SERVER 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$PORT/index.html" >/dev/null && break; sleep 0.1; done

SIZE=48 PASSES=4 BROWSER_SEED=1234567
NATIVE_SEEDS=($(seq 101 116))
scene_index() { case $1 in cornell-box) echo 0;; glass-spheres) echo 1;; esac; }
mapfile -t ESTIMATORS < <("$CHECK" --estimators)
CASES=()
for e in "${ESTIMATORS[@]}"; do CASES+=("cornell-box $e"); done
CASES+=("glass-spheres bdpt" "glass-spheres spcbpt")

step "native renders ($SIZE×$SIZE, $PASSES passes, seeds ${NATIVE_SEEDS[*]}; the browser's seed is $BROWSER_SEED)"
JSON="["
for c in "${CASES[@]}"; do
  set -- $c
  for seed in "${NATIVE_SEEDS[@]}"; do
    # --no-plan: the page renders each estimator whole (it does not plan), so the native
    # side must too (planned VCM leaves merging out, a different biased estimator).
    "$EMBER" render --builtin "$1" -e "$2" --spp $PASSES --seed $seed --width $SIZE --height $SIZE --threads 2 --no-plan \
      -o "$ART/$1-$2-native-$seed.exr" >/dev/null 2>&1
  done
  Q="scene=$(scene_index "$1")&estimator=$2&width=$SIZE&height=$SIZE&passes=$PASSES&seed=$BROWSER_SEED&workers=2"
  JSON+="{\"name\":\"$1-$2\",\"query\":\"$Q\",\"timeoutS\":120},"
done
Q="scene=0&estimator=lvcbpt&width=$SIZE&height=$SIZE&passes=2&seed=1&workers=2&fault=drop-light-chunk"
JSON+="{\"name\":\"fault-drop-light-chunk\",\"query\":\"$Q\",\"timeoutS\":60,\"expectError\":\"reduced without chunk 1\"},"
# Form validation: the page refuses, naming the field, and starts nothing.
JSON+="{\"name\":\"bad-seed\",\"query\":\"scene=0&estimator=pt&seed=1.5\",\"timeoutS\":20,\"expectError\":\"seed \\\"1.5\\\"\"},"
JSON+="{\"name\":\"bad-workers\",\"query\":\"scene=0&estimator=pt&seed=-3&workers=-1\",\"timeoutS\":20,\"expectError\":\"workers \\\"-1\\\"\"}"
JSON="${JSON%,}]"

step "browser renders (headless chromium)"
node host-wasm/tests/browser.mjs "http://127.0.0.1:$PORT" "$ART" "$JSON"

step "browser vs native"
STATUS=0
for c in "${CASES[@]}"; do
  set -- $c
  echo "-- $1 / $2"
  "$CHECK" "$ART/$1-$2.pfm" independent "$ART/$1-$2-native-"*.exr || STATUS=1
done

if [ "$MODE" = bench ] || [ "${BENCH:-}" = 1 ]; then
  # Per estimator: native CLI on 1 thread against the browser with 1 worker, then the
  # browser with 2 workers, interleaved (the machine may be shared); 128×128, 8 passes,
  # setup included in both. Samples/s as each reports it.
  step "throughput at 128×128, 8 passes: browser workers against the native CLI"
  B=128 BP=8
  for e in "${ESTIMATORS[@]}"; do
    for round in 1 2; do
      printf '%s round %s native 1 thread: ' "$e" "$round"
      "$EMBER" render --builtin cornell-box -e "$e" --spp $BP --seed 1 --width $B --height $B --threads 1 --no-plan \
        -o "$ART/bench-native.exr" 2>&1 | grep -E "^samples" || echo
      for w in 1 2; do
        Q="scene=0&estimator=$e&width=$B&height=$B&passes=$BP&seed=1&workers=$w"
        printf '%s round %s browser ' "$e" "$round"
        node host-wasm/tests/browser.mjs "http://127.0.0.1:$PORT" "$ART" \
          "[{\"name\":\"bench-$e-w$w\",\"query\":\"$Q\",\"timeoutS\":300,\"noDownload\":true}]"
      done
    done
  done
fi

[ $STATUS -eq 0 ] && echo "browser test passed" || echo "browser test FAILED"
exit $STATUS
