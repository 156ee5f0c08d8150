#!/usr/bin/env bash
# The browser module's size per feature set of the core (docs/features.md): host-wasm
# built for wasm32-unknown-unknown in release, stripped, as scripts/build-wasm.sh builds
# it, with no estimator family, each family alone, and all (the default). Prints a
# Markdown table (raw and gzip -9 bytes); leaves host-wasm/www/ untouched.
#
#   scripts/feature-sizes.sh
set -euo pipefail
cd "$(dirname "$0")/.."
TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
rustup target add wasm32-unknown-unknown >/dev/null 2>&1 || true
module="$TARGET_DIR/wasm32-unknown-unknown/release/ember_wasm.wasm"
echo "| features of host-wasm | estimators | .wasm bytes | gzip -9 bytes |"
echo "|---|---|---:|---:|"
for features in "" bdpt lvcbpt spcbpt merging segments filtering default; do
  if [ "$features" = default ]; then args=(); else args=(--no-default-features ${features:+--features "$features"}); fi
  CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true \
    cargo build -q --release -p ember-wasm --lib --target wasm32-unknown-unknown "${args[@]}"
  case $features in
    "") what="pt lt" ;;
    bdpt) what="pt lt bdpt" ;;
    lvcbpt) what="pt lt lvcbpt" ;;
    spcbpt) what="pt lt spcbpt" ;;
    merging) what="pt lt ppm bpm vcm" ;;
    segments) what="pt lt bdpt spt slt sbdpt" ;;
    filtering) what="pt lt mvf phf bpf" ;;
    default) what="all 14" ;;
  esac
  echo "| ${features:-none} | $what | $(stat -c %s "$module") | $(gzip -9 -c "$module" | wc -c) |"
done
