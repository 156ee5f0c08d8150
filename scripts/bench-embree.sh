#!/usr/bin/env bash
# Our BVH4 against Embree 3.13 on the rays PT asks for, on every suite scene and on a
# procedural scene of a million triangles (host-cli/benches/embree.rs explains the
# method; docs/performance.md, "Our BVH4 against Embree 3.13", the results).
#
# Needs Embree 3's development files: installs Debian's libembree-dev when run as root
# with apt-get, else stops with a message. Extra arguments go to the benchmark binary;
# EMBREE_NOT_ROBUST=1 builds Embree without RTC_SCENE_FLAG_ROBUST, EMBER_BENCH_SCENES=a,b
# (suite folder names, `big`) limits the scenes.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -e /usr/include/embree3/rtcore.h ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get install -y libembree-dev >/dev/null
    else
        echo "bench-embree: Embree 3 is not installed (Debian: apt-get install libembree-dev)" >&2
        exit 1
    fi
fi
cargo bench -p ember-cli --features embree --bench embree -- "$@"
