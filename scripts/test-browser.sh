#!/usr/bin/env bash
# The browser test (issue 7): builds the wasm module, serves host-wasm/www on 127.0.0.1,
# renders built-in scenes in headless Debian chromium (playwright-core) and checks each
# image against the native CLI's render of the same scene, seed and passes
# (ember-wasm-compare: pixels equal up to rounding except paths diverging at tied hits,
# and a Šidák-corrected z-test per 8×8 block). Fails if the module does not load, a
# worker errors, the page logs an error, the canvas is blank or the images disagree.
# Artifacts (screenshots, PFM, EXR, per-case JSON): target/browser-artifacts/.
# Injected bugs it was seen to catch (docs/wasm.md): the page dropping worker 1's splat
# film (lt/bdpt cases disagree, block |z| 8-10); a worker throwing on pass 2 (console and
# page errors); a wrong module URL (404: module not loaded, canvas blank).
#
#   scripts/test-browser.sh          the test (64×64, 4 passes, 2 workers per case)
#   scripts/test-browser.sh bench    also measure samples/s (1 worker vs all cores) at 128×128
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
rustup target add wasm32-unknown-unknown >/dev/null
# No debug info in the module (the workspace's release profile keeps line tables).
CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true \
  cargo build --release -p ember-wasm --lib --target wasm32-unknown-unknown
cp "$TARGET_DIR/wasm32-unknown-unknown/release/ember_wasm.wasm" host-wasm/www/ember_wasm.wasm
echo "module: $(stat -c %s host-wasm/www/ember_wasm.wasm) bytes"

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

SIZE=64 PASSES=4 SEED=7
scene_index() { case $1 in cornell-box) echo 0;; glass-spheres) echo 1;; esac; }
est_index() { case $1 in pt) echo 0;; lt) echo 1;; bdpt) echo 2;; esac; }
CASES=("cornell-box pt" "cornell-box lt" "glass-spheres bdpt" "glass-spheres pt")

step "native renders ($SIZE×$SIZE, $PASSES passes, seed $SEED)"
JSON="["
for c in "${CASES[@]}"; do
  set -- $c
  "$EMBER" render --builtin "$1" -e "$2" --spp $PASSES --seed $SEED --width $SIZE --height $SIZE \
    -o "$ART/$1-$2-native.exr" >/dev/null
  Q="scene=$(scene_index "$1")&estimator=$(est_index "$2")&width=$SIZE&height=$SIZE&passes=$PASSES&seed=$SEED&workers=2"
  JSON+="{\"name\":\"$1-$2\",\"query\":\"$Q\",\"timeoutS\":60},"
done
JSON="${JSON%,}]"

step "browser renders (headless chromium)"
node host-wasm/tests/browser.mjs "http://127.0.0.1:$PORT" "$ART" "$JSON"

step "browser vs native"
STATUS=0
for c in "${CASES[@]}"; do
  set -- $c
  echo "-- $1 / $2"
  "$CHECK" "$ART/$1-$2.pfm" "$ART/$1-$2-native.exr" || STATUS=1
done

if [ "$MODE" = bench ] || [ "${BENCH:-}" = 1 ]; then
  # Interleaved rounds (the machine may be shared): native 1 thread, browser 1 worker,
  # native all threads, browser one worker per core; compare the best of the rounds.
  step "throughput at 128×128, 8 passes: browser workers vs native CLI threads"
  B=128 BP=8
  for round in 1 2 3; do
    for c in "cornell-box pt" "glass-spheres bdpt"; do
      set -- $c
      for w in 1 0; do
        t=$([ $w = 1 ] && echo 1 || nproc)
        printf 'round %s native  %s %s %s thread(s): ' "$round" "$1" "$2" "$t"
        "$EMBER" render --builtin "$1" -e "$2" --spp $BP --seed 1 --width $B --height $B --threads "$t" \
          -o "$ART/bench-native.exr" 2>&1 | grep -E "^samples" || true
        Q="scene=$(scene_index "$1")&estimator=$(est_index "$2")&width=$B&height=$B&passes=$BP&seed=1&workers=$w"
        printf 'round %s browser ' "$round"
        node host-wasm/tests/browser.mjs "http://127.0.0.1:$PORT" "$ART" \
          "[{\"name\":\"bench-$1-$2-w$w\",\"query\":\"$Q\",\"timeoutS\":300,\"noDownload\":true}]"
      done
    done
  done
fi

[ $STATUS -eq 0 ] && echo "browser test passed" || echo "browser test FAILED"
exit $STATUS
