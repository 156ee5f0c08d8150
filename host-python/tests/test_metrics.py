"""ember.compare is `ember compare`, and ember.convergence returns its record as arrays.

Injected bugs seen failing here: `Metrics` fields in the order (rel_mse, mae, mape, …)
(the MAPE and MAE checks); `convergence` recording each checkpoint's target instead of
the seconds the run had when it was taken (the seconds check).
"""

import subprocess

import numpy as np
import pytest

import ember


def test_compare_is_the_cli_compare(cli, scenes, tmp_path):
    folder = scenes / "cornell-box"
    test = folder / "reference-half-a.exr"
    out = subprocess.run([str(cli), "compare", str(test), str(folder / "reference.exr")], check=True, capture_output=True, text=True).stdout
    printed = {line.split()[0]: float(line.split()[1]) for line in out.splitlines() if line.split()[0] in ("relMSE", "MAPE", "MAE")}
    m = ember.compare(ember.read_exr(test), ember.read_exr(folder / "reference.exr"))
    assert m.rel_mse == pytest.approx(printed["relMSE"], rel=1e-5)
    assert m.mape == pytest.approx(printed["MAPE"], rel=1e-3)
    assert m.mae == pytest.approx(printed["MAE"], rel=1e-5)
    assert 0.0 < m.worst_share < 1.0 and m.mean_ratio == pytest.approx(1.0, abs=0.05)
    same = ember.compare(np.ones((2, 2, 3)), np.ones((2, 2, 3)))
    assert (same.rel_mse, same.mape, same.mae, same.mean_ratio) == (0.0, 0.0, 0.0, 1.0)


def test_convergence_returns_arrays_per_estimator(scenes):
    folder = scenes / "cornell-box"
    scene = ember.load_file(folder / "scene.xml")
    curves = ember.convergence(scene, folder / "reference.exr", ["pt", "lt"], budget=1.0)
    assert list(curves) == ["pt", "lt"]
    for name, c in curves.items():
        assert all(isinstance(a, np.ndarray) and a.shape == (1,) for a in c), name
        # Each run's own clock: it stops at the first pass boundary past the checkpoint.
        assert 1.0 < c.seconds[0] < 6.0, (name, c.seconds)
        assert c.passes[0] >= 1 and 0.0 < c.rel_mse[0] < 1.0 and c.mape[0] > 0.0, (name, c)
