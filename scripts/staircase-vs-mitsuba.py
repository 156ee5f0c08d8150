#!/usr/bin/env python3
"""Bitterli's Modern Hall as published (niklassanden/ReSTIR_GI_DR, scenes/staircase2,
no edit) through ember's PT and Mitsuba 3's own integrator (`volpath`), issue 56:

    staircase-vs-mitsuba.py SCENE.xml EMBER_BINARY [RES=128] [SPP=128] [SEEDS=8] [REF_SPP=4096]

Both render SEEDS images of RES x RES at SPP on disjoint seeds; per 16x16 block and
channel a Welch z of the two sets' means against a Sidak-corrected 1 % bound; the image
means' ratio; and relMSE (eps 1e-2) of each set against one Mitsuba render at REF_SPP
(Mitsuba's own reference, which favours Mitsuba a little). Needs `pip install mitsuba`
and, for `llvm_ad_rgb`, Debian's libllvm19 (DRJIT_LIBLLVM_PATH; MI_VARIANT overrides).
"""
import os
import subprocess
import sys
import tempfile
from math import erf, sqrt

import drjit as dr
import mitsuba as mi
import numpy as np

scene_path, ember = sys.argv[1], sys.argv[2]
res, spp, seeds, ref_spp = (int(a) for a in (sys.argv[3:] + ["128", "128", "8", "4096"][len(sys.argv) - 3 :])[:4])
mi.set_variant(os.environ.get("MI_VARIANT", "llvm_ad_rgb"))
dr.set_thread_count(2)
tmp = tempfile.mkdtemp()


def load(path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False))


scene = mi.load_file(scene_path, resx=res, resy=res)
theirs = [np.array(mi.render(scene, spp=spp, seed=1000 + s))[..., :3] for s in range(seeds)]
ref = sum(np.array(mi.render(scene, spp=512, seed=77000 + k))[..., :3] for k in range(ref_spp // 512)) / (ref_spp // 512)
ours = []
for s in range(seeds):
    out = f"{tmp}/ours-{s}.exr"
    cmd = [ember, "render", scene_path, "-e", "pt", "--width", str(res), "--height", str(res), "--spp", str(spp), "--seed", str(2000 + s), "--threads", "2", "-o", out]
    subprocess.run(cmd, check=True, capture_output=True)
    ours.append(load(out))
ours, theirs = np.array(ours), np.array(theirs)

B = 16
n_by, n_bx = res // B, res // B


def blocks(a):
    return a[:, : n_by * B, : n_bx * B, :].reshape(a.shape[0], n_by, B, n_bx, B, 3).mean(axis=(2, 4))


bo, bt = blocks(ours), blocks(theirs)
z = (bo.mean(0) - bt.mean(0)) / np.sqrt(bo.var(0, ddof=1) / seeds + bt.var(0, ddof=1) / seeds + 1e-30)
p = np.array([1 - erf(abs(x) / sqrt(2)) for x in z.ravel()])
alpha = 1 - 0.99 ** (1 / p.size)
print(f"blocks: {p.size} tests, largest |z| {np.abs(z).max():.2f}, smallest p {p.min():.2e}, Sidak bound {alpha:.2e}: {'agree' if p.min() > alpha else 'DISAGREE'}")
print(f"image mean ours / Mitsuba {ours.mean() / theirs.mean():.4f}")


def relmse(img):
    return np.mean((img - ref) ** 2 / (ref**2 + 1e-2))


ro, rt = np.mean([relmse(i) for i in ours]), np.mean([relmse(i) for i in theirs])
print(f"relMSE at {spp} spp against Mitsuba at {ref_spp}: ours {ro:.4e}, Mitsuba {rt:.4e}, ratio {ro / rt:.3f}")
