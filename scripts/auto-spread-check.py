#!/usr/bin/env python3
"""The spread correction of `--estimator auto` (host-cli/src/auto/spread.rs) checked offline.

    scripts/auto-spread-check.py SCENE ESTIMATORS TRIALS      e.g. veach-mis bdpt,pt 2

Renders each estimator at the pilot's size (a quarter per axis; 32 seeds x 4 passes) and
at full size (12 seeds x 2 passes) and prints its per-pass variance term (per pixel,
variance over (reference^2 + 0.01), averaged) at full size, at the pilot's size read the
old way, and corrected with the exact spread from the reference; then, per trial, the
corrected term with the spread estimated from three independent full-size PT passes as
the race does, shrunk by 0, 1 and 2 standard errors (the race uses 1). Needs numpy and
OpenEXR; EMBER names the binary (default target/release/ember); renders go to /tmp/sp.
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
S = "../shared/scenes/%s/scene.xml"
scene = sys.argv[1]
ests = sys.argv[2].split(",")
trials = int(sys.argv[3])
ref = load("../shared/scenes/%s/reference.exr" % scene)
H, W = ref.shape[:2]
D = 4
h, w = H // D, W // D
def render(est, width, height, spp, seed):
    p = f"/tmp/sp/{scene}-{est}-{width}-{spp}-{seed}.exr"
    if not os.path.exists(p):
        cmd = [E, "render", S % scene, "-e", est, "--width", str(width), "--height", str(height), "--spp", str(spp), "--threads", "2", "--seed", str(seed), "--no-plan", "-o", p]
        subprocess.run(cmd, check=True, capture_output=True)
    return load(p)
def blocks(a):
    return a[:h*D, :w*D].reshape(h, D, w, D, 3).transpose(0, 2, 1, 3, 4).reshape(h, w, D*D, 3)
rb = blocks(ref)
S_ref = (rb**2).mean(2) - rb.mean(2)**2
mu = rb.mean(2)
eps = 0.01
def var_over_seeds(est, width, height, spp, n, base):
    ims = np.stack([render(est, width, height, spp, base + s) for s in range(n)])
    return ims.mean(0), ims.var(0, ddof=1) * spp
_, vpt = var_over_seeds("pt", w, h, 4, 32, 300)
res = {}
for est in ests:
    pm, pv = var_over_seeds(est, w, h, 4, 32, 300)
    fm, fv = var_over_seeds(est, W, H, 2, 12, 500)
    res[est] = (pv, (fv / (ref**2 + eps)).mean())
    print(f"{est}: full {res[est][1]:.4f} naive {(pv / (mu**2 + eps)).mean():.4f} ref-corrected {(np.maximum(pv - S_ref, 0) / (mu**2 + S_ref + eps)).mean():.4f}")
for t in range(trials):
    X = [blocks(render("pt", W, H, 1, 1000 + 3 * t + k)) for k in range(3)]
    pairs = [(0, 1), (0, 2), (1, 2)]
    S_hat = np.mean([(X[a] * X[b]).mean(2) - X[a].mean(2) * X[b].mean(2) for a, b in pairs], 0)
    vb = np.maximum(vpt - np.maximum(S_hat, 0), 0); se = np.sqrt((vb**2 / 3 + 4 / 3 * np.maximum(S_hat, 0) * vb) / 16)
    for k in (0, 1, 2):
        Su = np.maximum(S_hat - k * se, 0)
        line = " ".join(f"{est} {(np.maximum(res[est][0] - Su, 0) / (mu**2 + Su + eps)).mean():.4f}" for est in ests)
        print(f"  trial {t} shrink {k}: S mean {Su.mean():.4g} (ref {S_ref.mean():.4g}): {line}")
