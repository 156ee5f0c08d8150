#!/usr/bin/env python3
"""Per-block agreement of two ember binaries' renders, for a deliberate numeric change.

    scripts/agree-blocks.py OLD NEW SCENE WIDTH SPP ESTIMATOR [SEEDS=8]

SCENE is a suite scene's name or `builtin`. Each binary renders SEEDS images on seeds of
its own (OLD 500.., NEW 600..: disjoint, so the two sets are independent); per 8×8 block
and channel a Welch z of the two sets' means, two-sided normal p, against a Bonferroni
bound of 1 % over all blocks and channels. Prints the largest |z|, the smallest p, the
verdict and the ratio of image means. Needs numpy and the OpenEXR module.
"""
import subprocess
import sys
import tempfile
from math import erf, sqrt

import numpy as np

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from importlib import import_module

load = import_module("exr-block-ratio").load

old, new, scene, width, spp, est = sys.argv[1:7]
seeds = int(sys.argv[7]) if len(sys.argv) > 7 else 8
src = ["--builtin", "cornell-box"] if scene == "builtin" else [f"../shared/scenes/{scene}/scene.xml"]
B = 8


def renders(binary, first_seed, tmp):
    out = []
    for s in range(seeds):
        path = f"{tmp}/{first_seed + s}.exr"
        cmd = [binary, "render", *src, "-e", est, "--width", width, "--spp", spp, "--threads", "2", "--seed", str(first_seed + s), "--no-plan", "-o", path]
        subprocess.run(cmd, check=True, capture_output=True)
        out.append(load(path))
    a = np.stack(out)
    h, w = a.shape[1] // B * B, a.shape[2] // B * B
    return a[:, :h, :w].reshape(seeds, h // B, B, w // B, B, 3).mean((2, 4))


with tempfile.TemporaryDirectory() as tmp:
    a, b = renders(old, 500, tmp), renders(new, 600, tmp)
z = (b.mean(0) - a.mean(0)) / np.sqrt(a.var(0, ddof=1) / seeds + b.var(0, ddof=1) / seeds + 1e-30)
p = min(1 - erf(abs(x) / sqrt(2)) for x in z.ravel())
alpha = 0.01 / z.size
print(f"{est} {scene}: {z.size} block-channels, max |z| {np.abs(z).max():.2f}, min p {p:.2e}, "
      f"alpha {alpha:.1e} -> {'agree' if p > alpha else 'DISAGREE'}; image mean new/old {b.mean() / a.mean():.4f}")
