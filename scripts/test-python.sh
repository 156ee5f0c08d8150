#!/usr/bin/env bash
# The Python package (host-python, issue 55) as a user installs it: a fresh virtual
# environment, `pip install ./host-python` (maturin builds the extension in the
# workspace's target folder, reusing what `cargo build --release` built), the import
# one-liner of the README, the pytest suite (bit-identity with `ember render`, the bad
# inputs, Ctrl-C) and the example that plots relMSE against time. Prints the seconds each
# part took (docs/python.md records them).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
python="${PYTHON:-python3}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
t0=$(date +%s)

"$python" -m venv "$work/venv"
venv="$work/venv/bin"
"$venv/pip" install -q --disable-pip-version-check ./host-python numpy pytest matplotlib
t1=$(date +%s)
echo "python: venv and pip install ./host-python numpy pytest matplotlib: $((t1 - t0)) s"

"$venv/python" -c "import ember; print(ember.render(ember.load_file('../shared/scenes/cornell-box/scene.xml'), spp=4).shape)"

# The `ember` command the bit-identity tests compare with: the workspace tests built it
# (`cargo build -p ember-cli` alone would rebuild its dependencies with other features).
# Each artefact is built where it is missing or older than a source it is made from (the
# workspace tests do not relink the C library, and a stale one from before a numeric
# change fails the array test on a warm tree).
stale() { [ ! -e "$1" ] || [ -n "$(find core host host-capi host-cli host-formats Cargo.toml -newer "$1" \( -name '*.rs' -o -name Cargo.toml \) -print -quit)" ]; }
if stale "$CARGO_TARGET_DIR/release/ember"; then cargo build --release -q -p ember-cli; fi
# The C library the array-scene test hands the same arrays to (ctypes).
if stale "$CARGO_TARGET_DIR/release/libember_capi.so"; then cargo build --release -q -p ember-capi; fi
"$venv/python" -m pytest -q -p no:cacheprovider host-python/tests
t2=$(date +%s)
echo "python: the one-liner and pytest: $((t2 - t1)) s"

"$venv/python" host-python/examples/error_vs_time.py --budget 2 -o "$work/relmse.png"
test -s "$work/relmse.png"
t3=$(date +%s)
echo "python: the example: $((t3 - t2)) s; in all $((t3 - t0)) s"
