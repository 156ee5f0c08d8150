#!/usr/bin/env bash
# The C API as a C program uses it (docs/embedding.md): builds the static library, then
# compiles host-capi/c/render.c (a scene from arrays, rendered with the program's own
# ray-tracing callbacks and with the built-in BVH), host-capi/c/scene2.c (the complete
# description: a textured rough plastic, an environment map, a thin lens) and
# host-capi/c/errors.c (every error path) with AddressSanitizer and UBSan, and runs
# them; scene2's image must be the bits of `ember render` on the same scene in XML,
# which scene2 writes; then the Rust example embedding the core with its own RayQuery
# (host-capi/examples/custom_tracer.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p ember-capi
OUT=target/capi
mkdir -p "$OUT"
CC=${CC:-cc}
SAN=(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
if ! echo 'int main(void){return 0;}' | "$CC" -x c "${SAN[@]}" -o "$OUT/probe" - 2>/dev/null; then
    echo "test-capi: $CC has no AddressSanitizer/UBSan here; building without them"
    SAN=()
fi
for prog in render scene2 errors; do
    "$CC" -std=c11 -Wall -Wextra -Werror -O1 -g "${SAN[@]}" -I host-capi/include \
        "host-capi/c/$prog.c" target/release/libember_capi.a -lpthread -ldl -lm -o "$OUT/$prog"
done
# Rust's global thread pool and thread-locals are alive at exit: leak checking would
# report them, not the C program's leaks.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
"$OUT/errors"
"$OUT/render" "$OUT/box"
# The complete description against the command line on the same scene in XML: the same
# estimator, seed, passes and threads as scene2.c's (PT, seed 5, 4 passes, 2 threads).
rm -rf "$OUT/scene2-files" && mkdir -p "$OUT/scene2-files"
"$OUT/scene2" "$OUT/scene2-files"
cargo run --release -q -p ember-capi --example same_as_cli -- "$OUT/scene2-files/c.pfm" \
    render "$OUT/scene2-files/scene.xml" -e pt --spp 4 --seed 5 --threads 2 -o "$OUT/scene2-files/cli.exr"
# The Rust side of embedding: the core with a ray tracer of its own.
cargo run --release -q -p ember-capi --example custom_tracer
echo "test-capi: OK"
