#!/usr/bin/env bash
# The project's test command (README). Installs what it needs, then builds and runs
# every test with optimisation, then the browser test (host-wasm) and the fuzz targets.
# Takes about 15 minutes on 2 cores from cold.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "toolchain targets for the no_std proof, rustfmt and clippy"
rustup target add thumbv7em-none-eabihf x86_64-unknown-none wasm32-unknown-unknown aarch64-unknown-linux-gnu >/dev/null
rustup component add rustfmt clippy >/dev/null

step "formatting (rustfmt.toml) and lints (clippy, warnings denied)"
cargo fmt --check
cargo clippy --workspace --all-targets -- -D warnings
# ember-host as the browser's module takes it: no `threads` (driver, interrupts), wasm32.
cargo clippy -p ember-host --no-default-features --target wasm32-unknown-unknown -- -D warnings

step "one home per role (issue 49): no import cycles in the core or the hosts, a protocol that names no estimator, a C library without the CLI's or the file formats' crates"
scripts/import-cycles.py core/src host/src host-formats/src host-cli/src host-capi/src host-wasm/src host-python/src
if grep -rnE 'crate::(estimators|path|subspace|segment|merge|plan)\b' core/src/render/; then
  echo "core/src/render (the protocol) names an estimator or an estimator's data (above)"; exit 1
fi
if cargo tree -q -p ember-capi -e normal | grep -E ' (clap|roxmltree|tobj|exr|png|indicatif) v'; then
  echo "ember-capi links a crate of the command line or the file formats (above)"; exit 1
fi

step "core builds with no std at all, with every feature and with each alone (docs/features.md)"
cargo build --release -p ember-core --target thumbv7em-none-eabihf
cargo build --release -p ember-core --target x86_64-unknown-none
for features in "" bdpt lvcbpt spcbpt merging segments filtering mmis path hash-grid subspace wire; do
  echo "ember-core, no default features${features:+, feature $features}"
  cargo check -q -p ember-core --target x86_64-unknown-none --no-default-features ${features:+--features "$features"}
done
cargo build --release -p ember-core --target thumbv7em-none-eabihf --no-default-features
# AArch64 (glam's NEON in the host's BVH4 traversal): the core and the host type-check.
cargo check -q -p ember-core -p ember-host --target aarch64-unknown-linux-gnu

step "workspace tests (optimised)"
cargo test --release --workspace

step "the Python package: a fresh venv, pip install ./host-python, the import one-liner, pytest, the example (docs/python.md)"
scripts/test-python.sh

step "Embree's ray queries against ours (feature embree: our FFI, its lints, its test)"
if [ ! -e /usr/include/embree3/rtcore.h ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  apt-get install -y libembree-dev >/dev/null || { apt-get update >/dev/null && apt-get install -y libembree-dev >/dev/null; } || true
fi
if [ -e /usr/include/embree3/rtcore.h ]; then
  cargo clippy -p ember-host -p ember-cli --all-targets --features ember-cli/embree -- -D warnings
  cargo test --release -p ember-host --features embree --test embree
else
  echo "skipped: Embree 3 is not installed (apt-get install libembree-dev, as root)"
fi

step "the C API from C: the example and the error table under AddressSanitizer and UBSan"
scripts/test-capi.sh

step "the renderer in a real browser (host-wasm, headless chromium)"
scripts/test-browser.sh

step "fuzz targets: committed seeds replayed, then 30 s of fuzzing each"
scripts/test-fuzz.sh

step "a split render on a real Slurm (one-node cluster, 4-task array, merge job)"
if [ "$(id -u)" = 0 ]; then
  scripts/test-slurm.sh
else
  echo "skipped: scripts/test-slurm.sh needs root (it installs slurm-wlm and starts slurmd)"
fi
