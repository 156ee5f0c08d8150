#!/usr/bin/env bash
# Fuzz targets of issue 8 (fuzz/, its own workspace): replay the committed seeds, then
# fuzz each target for a fixed number of inputs (about 25 s each here), at most
# FUZZ_SECONDS (default 60). Exits non-zero on any crash.
#
# Reproducible by default: a fixed libFuzzer seed, a fresh working corpus (the committed
# seeds only) and a fixed input count make a run explore the same inputs on every
# machine for the same build (toolchain and code: any change to the code under test
# changes the path libFuzzer takes); a slower machine stops at the time cap, after a
# prefix of the same sequence. Run this script on the commit you submit.
# So whatever CI can find, a local run of this script finds first. (A time-only budget
# let CI, faster that day, run past anything tried locally and find an EXR header bomb.)
#
#   scripts/test-fuzz.sh                              # all targets
#   FUZZ_RUNS=0 FUZZ_SECONDS=600 FUZZ_SEED=0 FUZZ_KEEP_CORPUS=1 scripts/test-fuzz.sh exr_reader
#                                                     # exploratory: 10 min, random seed,
#                                                     # corpus kept in fuzz/corpus/
#
# Installs cargo-fuzz if missing. Uses nightly where rustup has it (sanitizer-free
# builds are still instrumented for coverage); on a stable-only toolchain it falls back to
# `cargo fuzz run -s none` (no sanitizer), which cargo-fuzz supports on stable.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"

SECONDS_PER_TARGET="${FUZZ_SECONDS:-60}"
# Inputs per target (≈ 25 s at the rates measured here: material 320k/s, light 460k/s,
# parser 13k/s, EXR reader ~60k/s, image readers 17k/s; weights 1.8k/s, so ≈ 55 s, with bidirectional
# filtering's weights on one input in four, 3.4k/s without them); FUZZ_RUNS overrides all
# (0 = unbounded).
declare -A RUNS=([material_sampling]=8000000 [light_sampling]=11000000 [mis_weights]=100000 [mitsuba_parser]=330000 [exr_reader]=1500000 [image_readers]=400000 [model_file]=200000 [partial_reader]=400000 [wire_decode]=3000000)
# A fixed libFuzzer seed makes a CI run explore the same inputs first (a crash it finds
# reproduces); FUZZ_SEED=0 lets libFuzzer pick one, for longer exploratory runs.
SEED="${FUZZ_SEED:-1}"
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
    TARGETS=(material_sampling light_sampling mis_weights mitsuba_parser exr_reader image_readers model_file partial_reader wire_decode)
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
    if [ "${FUZZ_KEEP_CORPUS:-0}" != 1 ]; then
        rm -rf "$work"
    fi
    mkdir -p "$work" "artifacts/$t"
    runs="${FUZZ_RUNS:-${RUNS[$t]:-0}}"
    [ "$runs" = 0 ] && runs=-1   # libFuzzer: -runs=-1 is unbounded, -runs=0 only replays
    echo "test-fuzz: $t: replaying $(ls "$seeds" | wc -l) seeds"
    if ! cargo "${TOOLCHAIN[@]}" fuzz run -O "${SANITIZER[@]}" "$t" "$seeds" -- -runs=0; then
        echo "test-fuzz: $t: a committed seed fails"; status=1; continue
    fi
    echo "test-fuzz: $t: fuzzing $runs inputs (-1: unbounded), at most ${SECONDS_PER_TARGET}s, seed $SEED"
    if ! cargo "${TOOLCHAIN[@]}" fuzz run -O "${SANITIZER[@]}" "$t" "$work" "$seeds" -- \
        -runs="$runs" -max_total_time="$SECONDS_PER_TARGET" -seed="$SEED" -rss_limit_mb=2048 -print_final_stats=1; then
        echo "test-fuzz: $t: CRASH (input in fuzz/artifacts/$t/)"; status=1
    fi
done
exit $status
