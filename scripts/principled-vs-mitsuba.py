#!/usr/bin/env python3
"""Per-block agreement of ember's PT and Mitsuba 3's `path` (scalar_rgb) on
scripts/scenes/principled/scene.xml (four `principled` spheres under an area light).

    scripts/principled-vs-mitsuba.py EMBER_BINARY [SPP=64] [SEEDS=8]

Each renderer makes SEEDS images at SPP samples per pixel on seeds of its own; per 8×8
block and channel a Welch z of the two sets' means, two-sided normal p, against a Šidák
bound of 1 % over all blocks and channels. Prints the largest |z| with its block, the
verdict, and the ratio of means per sphere's column of blocks. Needs mitsuba and numpy.
"""
import os
import subprocess
import sys
import tempfile
from math import erf, sqrt

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))


def load(path):
    """An EXR as an (h, w, 3) array, through Mitsuba's own reader."""
    import mitsuba as mi

    return np.array(mi.Bitmap(path))[:, :, :3]


ember = sys.argv[1]
spp = int(sys.argv[2]) if len(sys.argv) > 2 else 64
seeds = int(sys.argv[3]) if len(sys.argv) > 3 else 8
scene = os.environ.get("SCENE", os.path.join(here, "scenes", "principled", "scene.xml"))
B = 8


def blocks(images):
    a = np.stack(images)
    h, w = a.shape[1] // B * B, a.shape[2] // B * B
    return a[:, :h, :w].reshape(len(images), h // B, B, w // B, B, 3).mean((2, 4))


def mitsuba_images(tmp):
    import mitsuba as mi

    out = []
    for s in range(seeds):
        sc = mi.load_file(scene, spp=str(spp))
        img = np.array(mi.render(sc, spp=spp, seed=100 + s))
        out.append(img[:, :, :3])
    return out


def ember_images(tmp):
    out = []
    for s in range(seeds):
        path = f"{tmp}/e{s}.exr"
        cmd = [ember, "render", scene, "-e", "pt", "--spp", str(spp), "--threads", "2", "--seed", str(700 + s), "--no-plan", "-o", path]
        subprocess.run(cmd, check=True, capture_output=True)
        out.append(load(path))
    return out


import mitsuba as mi  # noqa: E402

mi.set_variant("scalar_rgb")
with tempfile.TemporaryDirectory() as tmp:
    e = blocks(ember_images(tmp))
    m = blocks(mitsuba_images(tmp))
me, mm = e.mean(0), m.mean(0)
se = np.sqrt(e.var(0, ddof=1) / seeds + m.var(0, ddof=1) / seeds)
z = np.where(se > 0, (me - mm) / np.where(se > 0, se, 1), 0.0)
n = z.size
alpha = 1 - (1 - 0.01) ** (1 / n)
p = np.vectorize(lambda x: 1 - erf(abs(x) / sqrt(2)))(z)
worst = np.unravel_index(np.argmax(np.abs(z)), z.shape)
print(f"blocks {z.shape[0]}x{z.shape[1]} x 3 channels, spp {spp}, seeds {seeds} each")
print(f"largest |z| {abs(z[worst]):.2f} at block (row, col, channel) {worst}, smallest p {p.min():.2e}, Šidák α {alpha:.2e}")
print("verdict:", "AGREE" if p.min() >= alpha else "DISAGREE")
cols = z.shape[1]
for name, (c0, c1) in zip("ABCD", [(0, cols // 4), (cols // 4, cols // 2), (cols // 2, 3 * cols // 4), (3 * cols // 4, cols)]):
    r = me[:, c0:c1].sum() / mm[:, c0:c1].sum()
    print(f"sphere {name} columns {c0}..{c1}: ember/mitsuba mean ratio {r:.4f}, largest |z| {np.abs(z[:, c0:c1]).max():.2f}")
print(f"image mean ratio ember/mitsuba {me.sum() / mm.sum():.4f}")
