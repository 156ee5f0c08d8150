"""A scene from arrays goes through the C API's description: the same arrays handed to
`ember_scene_create` (the C library, through ctypes) and to `ember.scene_from_arrays`
render the same bits, so one path is tested from C and from Python (issue 55).

Injected bugs seen failing here: `scene_from_arrays` handing the camera's width and
height swapped to the description (the image shapes differed, then every pixel); the
Python half dropping the emission (`emitted = b""`: the identity failed, the lit scene
went black but for the point light).
"""

import ctypes
import os
from pathlib import Path

import numpy as np
import pytest

import ember
from conftest import REPO

F3 = ctypes.c_float * 3


class Material(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_uint32), ("color", F3), ("ior", ctypes.c_float)]


class PointLight(ctypes.Structure):
    _fields_ = [("position", F3), ("intensity", F3)]


class Camera(ctypes.Structure):
    _fields_ = [("origin", F3), ("target", F3), ("up", F3), ("fov_degrees", ctypes.c_float), ("width", ctypes.c_uint32), ("height", ctypes.c_uint32)]


class SceneDesc(ctypes.Structure):
    _fields_ = [
        ("positions", ctypes.POINTER(ctypes.c_float)), ("vertex_count", ctypes.c_uint32),
        ("indices", ctypes.POINTER(ctypes.c_uint32)), ("triangle_count", ctypes.c_uint32),
        ("triangle_materials", ctypes.POINTER(ctypes.c_uint32)), ("triangle_emission", ctypes.POINTER(ctypes.c_float)),
        ("materials", ctypes.POINTER(Material)), ("material_count", ctypes.c_uint32),
        ("point_lights", ctypes.POINTER(PointLight)), ("point_light_count", ctypes.c_uint32),
        ("camera", Camera),
    ]


class Settings(ctypes.Structure):
    _fields_ = [
        ("estimator", ctypes.c_char_p), ("seed", ctypes.c_uint64), ("max_depth", ctypes.c_int32), ("threads", ctypes.c_uint32),
        ("light_paths", ctypes.c_uint32), ("connections", ctypes.c_uint32), ("radius_footprints", ctypes.c_float), ("options", ctypes.c_char_p),
    ]


# A floor, a back wall (mirror), a glass slab's front and an emitting quad above; a point light.
POSITIONS = np.array(
    [[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1],          # floor
     [-1, 0, -1], [1, 0, -1], [1, 2, -1], [-1, 2, -1],        # back wall
     [-0.3, 0, 0], [0.3, 0, 0], [0.3, 0.8, 0], [-0.3, 0.8, 0],  # glass pane
     [-0.4, 1.9, -0.4], [0.4, 1.9, -0.4], [0.4, 1.9, 0.4], [-0.4, 1.9, 0.4]],  # light, facing down
    dtype=np.float32,
)
TRIANGLES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [8, 9, 10], [8, 10, 11], [12, 13, 14], [12, 14, 15]], dtype=np.uint32)
TRIANGLE_MATERIALS = np.array([0, 0, 1, 1, 2, 2, 0, 0], dtype=np.uint32)
EMISSION = np.zeros((8, 3), dtype=np.float32)
EMISSION[6:] = [8.0, 7.0, 6.0]
MATERIALS = [("diffuse", (0.7, 0.6, 0.5)), ("mirror", (0.9, 0.9, 0.9)), ("glass", 1.5)]
LIGHTS = [((0.5, 1.5, 1.0), (2.0, 2.0, 2.0))]
CAMERA = dict(origin=(0.0, 1.0, 3.5), target=(0.0, 0.8, 0.0), up=(0.0, 1.0, 0.0), fov=45.0, width=24, height=18)
KINDS = {"diffuse": 0, "mirror": 1, "glass": 2}


def c_library():
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    path = target / "release" / "libember_capi.so"
    if not path.exists():
        pytest.fail(f"the C library is not built at {path} (cargo build --release -p ember-capi)")
    return ctypes.CDLL(str(path))


def c_render(estimator, seed, passes):
    lib = c_library()
    mats = (Material * len(MATERIALS))(*[
        Material(KINDS[k], F3(*(v if k != "glass" else (0, 0, 0))), v if k == "glass" else 0.0) for k, v in MATERIALS
    ])
    lights = (PointLight * len(LIGHTS))(*[PointLight(F3(*p), F3(*c)) for p, c in LIGHTS])
    cam = Camera(F3(*CAMERA["origin"]), F3(*CAMERA["target"]), F3(*CAMERA["up"]), CAMERA["fov"], CAMERA["width"], CAMERA["height"])
    as_f = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_float))
    as_u = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
    desc = SceneDesc(as_f(POSITIONS), len(POSITIONS), as_u(TRIANGLES), len(TRIANGLES), as_u(TRIANGLE_MATERIALS), as_f(EMISSION),
                     mats, len(MATERIALS), lights, len(LIGHTS), cam)
    scene, renderer = ctypes.c_uint64(), ctypes.c_uint64()
    assert lib.ember_scene_create(ctypes.byref(desc), ctypes.byref(scene)) == 0
    settings = Settings(estimator.encode(), seed, -1, 2, 0, 0, 0.0, b"")
    assert lib.ember_renderer_create(scene, ctypes.byref(settings), None, ctypes.byref(renderer)) == 0
    assert lib.ember_render_passes(renderer, passes) == 0
    image = np.zeros((CAMERA["height"], CAMERA["width"], 3), dtype=np.float32)
    assert lib.ember_renderer_image(renderer, image.ctypes.data_as(ctypes.POINTER(ctypes.c_float)), ctypes.c_size_t(image.size)) == 0
    lib.ember_renderer_destroy(renderer)
    lib.ember_scene_destroy(scene)
    return image


def python_scene():
    return ember.scene_from_arrays(POSITIONS, TRIANGLES, TRIANGLE_MATERIALS, MATERIALS, CAMERA, emission=EMISSION, point_lights=LIGHTS)


@pytest.mark.parametrize("estimator", ["pt", "bdpt"])
def test_arrays_render_as_the_c_api_renders_them(estimator):
    want = c_render(estimator, 5, 2)
    got = ember.render(python_scene(), estimator, spp=2, seed=5, max_depth=-1, no_plan=True)
    assert got.shape == want.shape
    assert float(got.mean()) > 0.0
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


def test_array_scene_resizes_and_refuses_bad_indices():
    scene = python_scene()
    assert (scene.width, scene.height, scene.path) == (24, 18, None)
    assert ember.render(scene, spp=1, width=12).shape == (9, 12, 3)
    with pytest.raises(ValueError, match="past the 16 positions"):
        ember.scene_from_arrays(POSITIONS, TRIANGLES + 10, TRIANGLE_MATERIALS, MATERIALS, CAMERA)
    with pytest.raises(ValueError, match="material 7 is past"):
        ember.scene_from_arrays(POSITIONS, TRIANGLES, TRIANGLE_MATERIALS + 7, MATERIALS, CAMERA)
    with pytest.raises(ValueError, match="no kind 'plastic'"):
        ember.scene_from_arrays(POSITIONS, TRIANGLES, TRIANGLE_MATERIALS, [("plastic", (1, 1, 1))] * 3, CAMERA)
    with pytest.raises(ValueError, match="not finite"):
        ember.scene_from_arrays(POSITIONS * np.nan, TRIANGLES, TRIANGLE_MATERIALS, MATERIALS, CAMERA)
