#!/usr/bin/env python3
"""Render a Mitsuba 3 scene with `llvm_ad_rgb` and its own `path` integrator settings
(the scene file's), for scripts/bench-mitsuba.sh.

    mitsuba-render.py SCENE.xml SPP THREADS OUT.exr [SEED]

SEED (default 0) is Mitsuba's sampler seed; MI_VARIANT overrides the variant (e.g.
scalar_rgb where LLVM is missing: the same estimator, slower).

Env-lit scenes (a `constant` or `envmap` emitter) are loaded with optimize=False:
Mitsuba 3.9.1's shape merging leaves a mesh with an invalid bounding box, after which
shadow rays toward such an emitter stop short and light leaks into closed rooms.
Prints `spp N seconds S` (render time, startup excluded) on stdout.
"""
import os
import sys
import time

import drjit as dr
import mitsuba as mi

scene_path, spp, threads, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
seed = int(sys.argv[5]) if len(sys.argv) > 5 else 0
mi.set_variant(os.environ.get("MI_VARIANT", "llvm_ad_rgb"))
dr.set_thread_count(threads)
text = open(scene_path).read()
env_lit = 'type="constant"' in text or 'type="envmap"' in text
scene = mi.load_file(scene_path, optimize=not env_lit)
t0 = time.time()
image = mi.render(scene, spp=spp, seed=seed)
dr.eval(image)
mi.util.write_bitmap(out, image)
print(f"spp {spp} seconds {time.time() - t0:.3f}")
