#!/usr/bin/env bash
# Fuzz targets of issue 8 (fuzz/, its own workspace): replay the committed seeds, then
# fuzz each target for FUZZ_SECONDS (default 30). Exits non-zero on any crash.
#
#   scripts/test-fuzz.sh                 # all targets, 30 s each
#   FUZZ_SECONDS=5 scripts/test-fuzz.sh material_sampling
#
# Installs cargo-fuzz if missing. Uses nightly where rustup has it (sanitizer-free
# builds are still instrumented for coverage); on a stable-only toolchain it falls back to
# `cargo fuzz run -s none` (no sanitizer), which cargo-fuzz supports on stable.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"

SECONDS_PER_TARGET="${FUZZ_SECONDS:-30}"
# A fixed libFuzzer seed makes a CI run explore the same inputs first (a crash it finds
# reproduces); FUZZ_SEED=0 lets libFuzzer pick one, for longer exploratory runs.
SEED="${FUZZ_SEED:-1}"
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
    TARGETS=(material_sampling light_sampling mis_weights mitsuba_parser exr_reader)
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "test-fuzz: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

TOOLCHAIN=()
SANITIZER=(-s none)
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    TOOLCHAIN=(+nightly)
fi
echo "test-fuzz: toolchain ${TOOLCHAIN[*]:-default (stable)}, sanitizer none, ${SECONDS_PER_TARGET}s per target"

# Debug assertions and overflow checks stay on (fuzz/Cargo.toml's release profile).
cargo "${TOOLCHAIN[@]}" fuzz build -O "${SANITIZER[@]}"

status=0
for t in "${TARGETS[@]}"; do
    seeds="seeds/$t"
    work="corpus/$t"   # grows while fuzzing; ignored by git
    mkdir -p "$work" "artifacts/$t"
    echo "test-fuzz: $t: replaying $(ls "$seeds" | wc -l) seeds"
    if ! cargo "${TOOLCHAIN[@]}" fuzz run -O "${SANITIZER[@]}" "$t" "$seeds" -- -runs=0; then
        echo "test-fuzz: $t: a committed seed fails"; status=1; continue
    fi
    echo "test-fuzz: $t: fuzzing for ${SECONDS_PER_TARGET}s"
    if ! cargo "${TOOLCHAIN[@]}" fuzz run -O "${SANITIZER[@]}" "$t" "$work" "$seeds" -- \
        -max_total_time="$SECONDS_PER_TARGET" -seed="$SEED" -rss_limit_mb=2048 -print_final_stats=1; then
        echo "test-fuzz: $t: CRASH (input in fuzz/artifacts/$t/)"; status=1
    fi
done
exit $status
