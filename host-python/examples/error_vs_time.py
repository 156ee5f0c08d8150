"""Error against time in a notebook's way: load a suite scene, run three estimators on
their own clocks, plot relMSE against seconds (log-log) with matplotlib, write a PNG.

    python host-python/examples/error_vs_time.py --scene cornell-box --budget 8 -o relmse.png

`scripts/test.sh` runs it with a 2 s budget (the curve is short; the plot is the point).
"""

import argparse
from pathlib import Path

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after the backend is chosen)

import ember  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", type=Path, default=REPO.parent / "shared" / "scenes")
    parser.add_argument("--scene", default="cornell-box")
    parser.add_argument("--estimators", default="pt,bdpt,vcm")
    parser.add_argument("--budget", type=float, default=8.0, help="seconds per estimator")
    parser.add_argument("--seeds", type=int, default=1)
    parser.add_argument("-o", "--output", type=Path, default=Path("relmse.png"))
    args = parser.parse_args()

    folder = args.scenes / args.scene
    scene = ember.load_file(folder / "scene.xml")
    reference = folder / "reference.exr"
    estimators = args.estimators.split(",")
    curves = ember.convergence(scene, reference, estimators, budget=args.budget, seeds=args.seeds)

    fig, ax = plt.subplots(figsize=(6, 4))
    for name, curve in curves.items():
        ax.loglog(curve.seconds, curve.rel_mse, marker="o", label=name)
        print(f"{name:5} {int(curve.passes[-1]):5d} passes in {curve.seconds[-1]:6.2f} s: relMSE {curve.rel_mse[-1]:.4e}")
    floor = ember.reference_floor(reference)
    if floor is not None:
        ax.axhline(floor[0], color="gray", linestyle="--", label="reference noise")
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("seconds (setup included)")
    ax.set_ylabel("relMSE")
    ax.set_title(f"{args.scene}: relMSE against time")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.output, dpi=100)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
