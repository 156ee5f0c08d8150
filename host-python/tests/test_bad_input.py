"""Bad inputs raise the exception the issue names, never crash the interpreter.

Each row: a call, the exception it must raise and a fragment its message must hold
(the option's name). Injected bugs seen failing here: the type checks of `_whole` without
the `bool` case (`spp=True` rendered one pass); `option_error` without the Python name
(`beta=nan` said only "bpf beta = NaN", no `beta=` prefix... the fragment `beta=nan`
failed); `check_exists` removed (a missing file was a ValueError, not FileNotFoundError).
"""

import math

import numpy as np
import pytest

import ember


@pytest.fixture(scope="module")
def scene(scenes):
    return ember.load_file(scenes / "cornell-box" / "scene.xml")


def small(scene, **kw):
    args = dict(spp=1, width=8, height=8)
    args.update(kw)
    return lambda: ember.render(scene, **args)


ROWS = [
    # (name, make the call from (scene, scenes dir), exception, fragment of the message)
    ("spp as text", lambda s, d: small(s, spp="4"), ember.ArgumentTypeError, "spp"),
    ("spp as float", lambda s, d: small(s, spp=4.0), TypeError, "spp"),
    ("spp as bool", lambda s, d: small(s, spp=True), ValueError, "spp"),
    ("spp zero", lambda s, d: small(s, spp=0), ValueError, "spp"),
    ("spp past u32", lambda s, d: small(s, spp=2**40), ValueError, "spp"),
    ("seed negative", lambda s, d: small(s, seed=-1), ValueError, "seed"),
    ("threads zero", lambda s, d: small(s, threads=0), ValueError, "threads"),
    ("width zero", lambda s, d: small(s, width=0), ValueError, "width"),
    ("height huge", lambda s, d: small(s, height=70000), ValueError, "height"),
    ("max_depth -2", lambda s, d: small(s, max_depth=-2), ValueError, "max_depth"),
    ("time NaN", lambda s, d: small(s, time=math.nan), ValueError, "time"),
    ("time negative", lambda s, d: small(s, time=-1.0), ValueError, "time"),
    ("time as text", lambda s, d: small(s, time="1"), TypeError, "time"),
    ("no_plan as int", lambda s, d: small(s, no_plan=1), TypeError, "no_plan"),
    ("beta NaN", lambda s, d: small(s, estimator="bpf", beta=math.nan), ValueError, "beta=nan"),
    ("beta out of range", lambda s, d: small(s, estimator="bpf", beta=-1), ValueError, "beta"),
    ("beta as list", lambda s, d: small(s, estimator="bpf", beta=[1]), TypeError, "beta"),
    ("beta infinite", lambda s, d: small(s, estimator="bpf", beta=math.inf), ValueError, "beta"),
    ("radius_footprints negative", lambda s, d: small(s, estimator="vcm", radius_footprints=-1), ValueError, "radius_footprints"),
    ("light_paths as float", lambda s, d: small(s, estimator="vcm", light_paths=2.5), ValueError, "light_paths"),
    ("subspaces for pt, out of range", lambda s, d: small(s, subspaces=1), ValueError, "subspaces"),
    ("two radius rules", lambda s, d: small(s, estimator="vcm", radius=0.1, radius_scene=0.01), ValueError, "radius"),
    ("kernel not a name", lambda s, d: small(s, estimator="spt", kernel="box"), ValueError, "kernel"),
    ("radius larger than the scene", lambda s, d: small(s, estimator="bpf", radius=100.0), ValueError, "radius"),
    ("unknown option", lambda s, d: small(s, frobnicate=1), ValueError, "frobnicate"),
    ("unknown estimator", lambda s, d: small(s, estimator="mlt"), ValueError, "mlt"),
    ("auto estimator", lambda s, d: small(s, estimator="auto"), ValueError, "auto"),
    ("estimator as int", lambda s, d: small(s, estimator=3), TypeError, "estimator"),
    ("scene as path", lambda s, d: small(str(d / "cornell-box" / "scene.xml")), TypeError, "scene"),
    ("missing scene file", lambda s, d: lambda: ember.load_file(d / "nowhere" / "scene.xml"), FileNotFoundError, "nowhere"),
    ("scene path as int", lambda s, d: lambda: ember.load_file(3), TypeError, "path"),
    ("not a scene file", lambda s, d: lambda: ember.load_file(d / "cornell-box" / "reference.exr"), ValueError, "reference.exr"),
    ("scene parameter as list", lambda s, d: lambda: ember.load_file(d / "cornell-box" / "scene.xml", spp=[1]), TypeError, "spp"),
    ("missing EXR", lambda s, d: lambda: ember.read_exr(d / "nowhere.exr"), FileNotFoundError, "nowhere"),
    ("compare shapes", lambda s, d: lambda: ember.compare(np.zeros((4, 4, 3)), np.zeros((4, 5, 3))), ValueError, "reference"),
    ("compare NaN", lambda s, d: lambda: ember.compare(np.full((2, 2, 3), np.nan), np.zeros((2, 2, 3))), ValueError, "NaN"),
    ("compare text", lambda s, d: lambda: ember.compare("image", np.zeros((2, 2, 3))), TypeError, "image"),
    ("compare 2-D", lambda s, d: lambda: ember.compare(np.zeros((2, 2)), np.zeros((2, 2))), ValueError, "H x W x 3"),
    ("convergence budget NaN", lambda s, d: lambda: ember.convergence(s, np.zeros((256, 256, 3)), budget=math.nan), ValueError, "time budget"),
    ("convergence reference size", lambda s, d: lambda: ember.convergence(s, np.zeros((4, 4, 3)), budget=1.0), ValueError, "reference"),
    ("convergence same estimator twice", lambda s, d: lambda: ember.convergence(s, np.zeros((256, 256, 3)), ["pt", "pt"]), ValueError, "twice"),
]


@pytest.mark.parametrize("row", ROWS, ids=[r[0] for r in ROWS])
def test_bad_input_raises_the_named_exception(scene, scenes, row):
    _, make, exception, fragment = row
    with pytest.raises(exception) as info:
        make(scene, scenes)()
    assert fragment in str(info.value), f"{type(info.value).__name__}: {info.value}"


def test_the_renderer_still_renders_after_refusals(scene):
    """A refused call leaves nothing behind: the next render is whole."""
    for bad in [dict(beta=math.nan, estimator="bpf"), dict(spp=0)]:
        with pytest.raises(ValueError):
            small(scene, **bad)()
    assert small(scene)().shape == (8, 8, 3)
