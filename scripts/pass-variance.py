#!/usr/bin/env python3
"""An estimator's per-pass variance term at the pilot's size and at full size, from
independent runs (docs/plan.md, the merging drift).

    scripts/pass-variance.py SCENE ESTIMATOR PASSES SEEDS      e.g. enclosed ppm 8 8

2·SEEDS runs at a quarter of the resolution per axis and SEEDS at full size, PASSES
passes each; the term is the variance over runs times PASSES over (reference^2 + 0.01),
averaged over pixels. Needs numpy and OpenEXR; EMBER names the binary.
"""
import os
import subprocess
import sys

import numpy as np

os.makedirs("/tmp/sp", exist_ok=True)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from importlib import import_module
load = import_module("exr-block-ratio").load
E = os.environ.get("EMBER", "target/release/ember")
scene, est, spp, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
ref = load(f"../shared/scenes/{scene}/reference.exr")
H, W = ref.shape[:2]
D = 4
h, w = H // D, W // D
mu = ref[:h*D, :w*D].reshape(h, D, w, D, 3).mean((1, 3))
def run(width, height, s):
    p = f"/tmp/sp/var-{scene}-{est}-{width}-{s}.exr"
    subprocess.run([E, "render", f"../shared/scenes/{scene}/scene.xml", "-e", est, "--width", str(width), "--height", str(height), "--spp", str(spp), "--threads", "2", "--seed", str(900 + s), "-o", p], check=True, capture_output=True)
    return load(p)
pil = np.stack([run(w, h, s) for s in range(2 * n)])
ful = np.stack([run(W, H, s) for s in range(n)])
tp = (pil.var(0, ddof=1) * spp / (mu ** 2 + 0.01)).mean()
tf = (ful.var(0, ddof=1) * spp / (ref ** 2 + 0.01)).mean()
print(f"{scene} {est}: per-pass variance term over {spp} passes: pilot {tp:.4f}, full {tf:.4f}, ratio {tp / tf:.2f}")
