#!/usr/bin/env bash
# Build the browser module and put it where the page loads it (host-wasm/www/), so the
# page works with no copy step:
#
#   scripts/build-wasm.sh            build host-wasm/www/ember_wasm.wasm
#   scripts/build-wasm.sh serve      build, then serve host-wasm/www on 127.0.0.1:8000
set -euo pipefail
cd "$(dirname "$0")/.."
TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
rustup target add wasm32-unknown-unknown >/dev/null 2>&1 || true
# No debug info in the module (the workspace's release profile keeps line tables).
CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true \
  cargo build --release -p ember-wasm --lib --target wasm32-unknown-unknown
cp "$TARGET_DIR/wasm32-unknown-unknown/release/ember_wasm.wasm" host-wasm/www/ember_wasm.wasm.tmp
mv host-wasm/www/ember_wasm.wasm.tmp host-wasm/www/ember_wasm.wasm
echo "module: host-wasm/www/ember_wasm.wasm ($(stat -c %s host-wasm/www/ember_wasm.wasm) bytes)"
if [ "${1:-}" = serve ]; then
  echo "open http://127.0.0.1:8000/index.html"
  exec python3 -m http.server --bind 127.0.0.1 8000 --directory host-wasm/www
fi
