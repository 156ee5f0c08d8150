#!/usr/bin/env python3
"""A (merging) estimator's squared relative bias at full size (docs/plan.md).

    scripts/merging-bias.py SCENE ESTIMATOR PASSES SEEDS      e.g. enclosed ppm 23 8

SEEDS full-size renders of PASSES passes; the bias² of their mean against the reference,
with the mean's noise subtracted, over 32x32-pixel blocks (the race's 8x8 pilot blocks)
and per pixel, and the mean relMSE of one render. Needs numpy and OpenEXR; EMBER names
the binary.
"""
# blocks) and per pixel, from N seeds at a fixed pass count, with the noise subtracted.
import os
import subprocess
import sys

import numpy as np

os.makedirs("/tmp/sp", exist_ok=True)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from importlib import import_module
load = import_module("exr-block-ratio").load
E = os.environ.get("EMBER", "target/release/ember")
scene, est, spp, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
ref = load(f"../shared/scenes/{scene}/reference.exr")
ims = []
for s in range(n):
    p = f"/tmp/sp/bias-{scene}-{est}-{s}.exr"
    subprocess.run([E, "render", f"../shared/scenes/{scene}/scene.xml", "-e", est, "--spp", spp, "--threads", "2", "--seed", str(700 + s), "-o", p], check=True, capture_output=True)
    ims.append(load(p))
a = np.stack(ims)
m = a.mean(0)
H, W = ref.shape[:2]
B = 32
def blocks(x):
    h, w = H // B * B, W // B * B
    return x[..., :h, :w, :].reshape(*x.shape[:-3], h // B, B, w // B, B, 3).mean((-4, -2))
rb = blocks(ref)
ab = blocks(a)
mb = ab.mean(0)
vb = ab.var(0, ddof=1) / n
block_bias = (((mb - rb) ** 2 - vb) / (rb ** 2 + 0.01)).mean()
vp = a.var(0, ddof=1) / n
pixel_bias = (((m - ref) ** 2 - vp) / (ref ** 2 + 0.01)).mean()
rel = np.mean([(((x - ref) ** 2) / (ref ** 2 + 0.01)).mean() for x in a])
print(f"{scene} {est} {spp} passes x {n}: relMSE per render {rel:.3e}; bias² over 32x32 blocks {block_bias:.3e}, per pixel {pixel_bias:.3e}")
