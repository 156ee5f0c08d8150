#!/usr/bin/env python3
"""Mean ratio of a low-resolution render to a reference averaged over blocks.

    scripts/exr-block-ratio.py TEST.exr REFERENCE.exr

The reference's resolution must be an integer multiple of the test's (the box filter's
pixel measurement at the lower resolution). Prints relMSE (as `ember compare` computes
it), the ratio of means over the whole image, over the brightest 5 % of the reference's
pixels and over the rest. Needs numpy and the OpenEXR module (pip install OpenEXR).
"""
import sys

import Imath
import numpy as np
import OpenEXR


def load(path):
    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w) for c in "RGB"], -1).astype(np.float64)


def main():
    test, ref = load(sys.argv[1]), load(sys.argv[2])
    s = ref.shape[0] // test.shape[0]
    if s * test.shape[0] != ref.shape[0] or s * test.shape[1] != ref.shape[1]:
        sys.exit("the reference's resolution is not a multiple of the test's")
    ref = ref.reshape(test.shape[0], s, test.shape[1], s, 3).mean((1, 3))
    rel = ((test - ref) ** 2 / (ref**2 + 1e-2)).mean()
    lum = ref.mean(-1)
    bright = lum > np.percentile(lum, 95)
    print(f"relMSE {rel:.5f}  mean ratio {test.mean() / ref.mean():.4f}  "
          f"brightest 5 % {test[bright].mean() / ref[bright].mean():.4f}  rest {test[~bright].mean() / ref[~bright].mean():.4f}")


if __name__ == "__main__":
    main()
