"""ember, a light-transport renderer: Mitsuba 3 scenes in, NumPy images out.

    import ember
    scene = ember.load_file("../shared/scenes/cornell-box/scene.xml", spp=16)
    image = ember.render(scene, estimator="bdpt", spp=16)      # float32, H x W x 3
    ember.compare(image, ember.read_exr("reference.exr")).rel_mse

Renders are the ``ember render`` command's, bit for bit, for the same arguments: the
same scene reader, estimator options (checked by the core's table, under the command
line's names with ``_`` for ``-``), scene plan, setup and passes. The GIL is released
while a pass renders; Ctrl-C raises ``KeyboardInterrupt`` when the pass in progress
ends. ``render_progressive`` renders pass by pass for notebooks and keeps the image so
far when interrupted. ``help(ember.render)`` lists the estimators and their options.
"""

from __future__ import annotations

import numbers
import os
from typing import Dict, Iterator, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from . import _ember
from ._ember import Scene

__all__ = [
    "ArgumentTypeError",
    "Curve",
    "Metrics",
    "Pass",
    "Progressive",
    "Scene",
    "compare",
    "convergence",
    "estimators",
    "load_file",
    "read_exr",
    "reference_floor",
    "render",
    "render_progressive",
    "scene_from_arrays",
    "version",
]

U32_MAX = 2**32 - 1
U64_MAX = 2**64 - 1


class ArgumentTypeError(TypeError, ValueError):
    """An argument of the wrong type (a ``TypeError`` and a ``ValueError``)."""


class Pass(NamedTuple):
    """One pass of a progressive render: passes so far and seconds since it was asked for."""

    passes: int
    elapsed: float


class Metrics(NamedTuple):
    """``ember compare``'s numbers (docs: host-formats/src/metrics.rs)."""

    rel_mse: float
    mape: float
    mae: float
    mean_ratio: float
    worst_share: float


class Curve(NamedTuple):
    """Error against time of one estimator, averaged over seeds, one entry per checkpoint."""

    seconds: np.ndarray
    rel_mse: np.ndarray
    mape: np.ndarray
    passes: np.ndarray


def version() -> str:
    """The library's version and build."""
    return _ember.version()


def estimators() -> Dict[str, str]:
    """The estimators this build renders, by name, with their summaries."""
    return {name: summary for name, summary, compiled in _ember.estimators() if compiled}


# --- argument checks: types here, values in the core -------------------------------


def _whole(name: str, value, low: int, high: int) -> Optional[int]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(f"{name} must be a whole number, got {type(value).__name__} {value!r}")
    value = int(value)
    if not low <= value <= high:
        raise ValueError(f"{name} = {value} is outside its allowed range {low} to {high}")
    return value


def _seconds(name: str, value) -> Optional[float]:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{name} must be a number of seconds, got {type(value).__name__} {value!r}")
    return float(value)


def _option_text(name: str, value) -> str:
    """A keyword option's value as the command line's text (floats round-trip exactly)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, numbers.Real)):
        raise ArgumentTypeError(f"option {name} must be a number or a name, got {type(value).__name__} {value!r}")
    if isinstance(value, numbers.Integral):
        return str(int(value))
    return repr(float(value))


def _path(name: str, value) -> str:
    if not isinstance(value, (str, os.PathLike)):
        raise ArgumentTypeError(f"{name} must be a path (str or os.PathLike), got {type(value).__name__} {value!r}")
    return os.fspath(value)


def _image_array(name: str, image) -> np.ndarray:
    """`image` as a C-contiguous float32 H x W x 3 array with finite values."""
    try:
        array = np.ascontiguousarray(image, dtype=np.float32)
    except (TypeError, ValueError) as e:
        raise ArgumentTypeError(f"{name} must be an H x W x 3 array of numbers: {e}") from None
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"{name} must be H x W x 3, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} holds NaN or infinite values")
    return array


def _as_image(width: int, height: int, data: bytearray) -> np.ndarray:
    return np.frombuffer(data, dtype=np.float32).reshape(height, width, 3)


# --- scenes and renders -------------------------------------------------------------


def load_file(path, **defines) -> Scene:
    """Read a Mitsuba 3 XML scene; keywords set its parameters, as ``mitsuba -D``.

    ``ember.load_file("scene.xml", spp=64, resx=128)`` is ``ember render scene.xml -D
    spp=64 -D resx=128``. Raises ``FileNotFoundError`` for a missing file and
    ``ValueError`` for a file the reader refuses (its message gives file:line:column).
    """
    pairs = []
    for key, value in defines.items():
        if isinstance(value, bool) or not isinstance(value, (str, numbers.Real)):
            raise ArgumentTypeError(f"scene parameter {key} must be a string or a number, got {type(value).__name__}")
        pairs.append((key, value if isinstance(value, str) else str(value)))
    return _ember.load_file(_path("path", path), pairs)


_CAMERA_KEYS = ("origin", "target", "up", "fov", "width", "height", "fov_axis", "aperture_radius", "focus_distance", "filter")


def _per_vertex(name, values, count, width):
    if values is None:
        return b""
    a = np.ascontiguousarray(values, dtype=np.float32)
    if a.shape != (count, width):
        raise ValueError(f"{name} must be {count} x {width} (one per position), got shape {a.shape}")
    return a.tobytes()


def _bitmap(i, texture):
    """A bitmap texture's ``data`` apart: (float32 bytes, width, height, channels)."""
    if not isinstance(texture, dict) or texture.get("type") != "bitmap":
        return None
    if "data" not in texture:
        return None
    data = np.asarray(texture["data"])
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[:, :, 0]
    if data.ndim not in (2, 3) or (data.ndim == 3 and data.shape[2] != 3) or data.dtype.kind not in "fiu":
        raise ValueError(f"textures[{i}]['data'] must be H x W x 3 or H x W numbers, got shape {data.shape} of {data.dtype}")
    height, width = data.shape[:2]
    channels = 3 if data.ndim == 3 else 1
    return np.ascontiguousarray(data, dtype=np.float32).tobytes(), width, height, channels


def scene_from_arrays(positions, triangles, triangle_materials, materials, camera, emission=None, point_lights=(),
                      normals=None, uvs=None, textures=(), lights=()) -> Scene:
    """A scene from arrays, through the C API's scene description (``ember_scene_create2``'s
    checks, docs/embedding.md), so one path serves C and Python. Names and defaults are
    Mitsuba 3's (``ember_bsdf_init``, ``ember_texture_init``, ``ember_light_init``).

    - ``positions``: V x 3 floats; ``triangles``: T x 3 vertex indices (front
      counter-clockwise); ``triangle_materials``: T indices into ``materials``;
    - ``normals``: ``None`` or V x 3 shading normals; ``uvs``: ``None`` or V x 2 texture
      coordinates (v = 0 at an image's top row);
    - ``materials``: dicts ``{"type": <Mitsuba BSDF>, <parameter>: value, ...}``: ``diffuse``
      (``reflectance``), ``conductor``/``roughconductor`` (``eta``, ``k``,
      ``specular_reflectance``), ``dielectric``/``roughdielectric`` (``int_ior``, ``ext_ior``,
      ``specular_reflectance``, ``specular_transmittance``), ``plastic``/``roughplastic``
      (``int_ior``, ``ext_ior``, ``diffuse_reflectance``, ``specular_reflectance``,
      ``nonlinear``), the rough ones with ``distribution`` (``"beckmann"``/``"ggx"``) and
      ``alpha``, ``principled`` (``base_color``, ``roughness``, ``metallic``, ... as Mitsuba
      names them), ``{"type": "twosided", "bsdf": {...}}``. A colour is a number or
      (r, g, b); a textured one (and ``roughness``) may be ``{"texture": index}``. The first
      description's ``("diffuse", (r, g, b))``, ``("mirror", (r, g, b))``, ``("glass", ior)``
      still work;
    - ``textures``: ``{"type": "bitmap", "data": H x W x 3 or H x W floats (row 0 at the top),
      "srgb": bool, "wrap_mode": "repeat"|"mirror"|"clamp", "filter_type":
      "bilinear"|"nearest", "to_uv": 2 x 3 or 3 x 3}`` or ``{"type": "checkerboard",
      "color0", "color1", "to_uv"}``;
    - ``emission``: ``None`` or T x 3 radiance from each triangle's front;
    - ``point_lights``: ``(position, intensity)`` pairs;
    - ``lights``: dicts: ``point`` (``position``, ``intensity``), ``spot`` (``position``,
      ``direction``, ``intensity``, ``cutoff_angle``, ``beam_width``), ``directional``
      (``direction``, ``irradiance``), ``constant`` (``radiance``), ``envmap``
      (``texture``: a bitmap's index, ``scale``, ``to_world``: a 3 x 3 rotation);
    - ``camera``: a dict with ``origin``, ``target``, ``up``, ``fov`` (degrees), ``width``
      and ``height``; optional ``fov_axis`` (``"x"``, default, ``"y"``, ``"smaller"``,
      ``"larger"``, ``"diagonal"``), ``aperture_radius`` and ``focus_distance`` (a thin
      lens; 0: pinhole), ``filter`` (``{"type": "box"}``, default, ``{"type": "tent",
      "radius": r}`` or ``{"type": "gaussian", "stddev": s}``).

    An unknown key or type, or a bad index or value, raises ``ValueError`` naming it
    (``materials[2]['alpha']``; the description's checks name its C fields, with the
    Python keys that set them).
    """
    pos = np.ascontiguousarray(positions, dtype=np.float32)
    tris = np.asarray(triangles)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise ValueError(f"positions must be V x 3, got shape {pos.shape}")
    if tris.ndim != 2 or tris.shape[1] != 3 or not np.issubdtype(tris.dtype, np.integer):
        raise ValueError(f"triangles must be T x 3 whole numbers, got shape {tris.shape} of {tris.dtype}")
    if tris.size and (tris.min() < 0 or tris.max() > U32_MAX):
        raise ValueError("triangles hold a vertex index outside 0 to 4294967295")
    mats = np.asarray(triangle_materials)
    if mats.shape != (tris.shape[0],) or not np.issubdtype(mats.dtype, np.integer) or (mats.size and (mats.min() < 0 or mats.max() > U32_MAX)):
        raise ValueError(f"triangle_materials must be {tris.shape[0]} indices, got shape {mats.shape} of {mats.dtype}")
    emitted = b"" if emission is None else np.ascontiguousarray(emission, dtype=np.float32).reshape(-1, 3).tobytes()
    described = []
    for i, m in enumerate(materials):
        if isinstance(m, dict):
            described.append(m)
            continue
        kind, value = m
        if kind == "glass":
            described.append((kind, (0.0, 0.0, 0.0), float(value)))
        else:
            described.append((kind, tuple(float(c) for c in value), 0.0))
    point = [(tuple(map(float, p)), tuple(map(float, c))) for p, c in point_lights]
    if not isinstance(camera, dict):
        raise ValueError(f"camera must be a dict ({', '.join(_CAMERA_KEYS)})")
    unknown = [k for k in camera if k not in _CAMERA_KEYS]
    if unknown:
        raise ValueError(f"camera: unknown key {', '.join(map(repr, unknown))} (known: {', '.join(_CAMERA_KEYS)})")
    try:
        cam = (tuple(map(float, camera["origin"])), tuple(map(float, camera["target"])), tuple(map(float, camera["up"])),
               float(camera["fov"]), _whole("camera width", camera["width"], 1, 65536), _whole("camera height", camera["height"], 1, 65536))
    except KeyError as e:
        raise ValueError(f"camera has no {e.args[0]} (origin, target, up, fov, width, height)") from None
    pixel_filter = camera.get("filter", {"type": "box"})
    if not isinstance(pixel_filter, dict) or "type" not in pixel_filter:
        raise ValueError("camera['filter'] must be a dict with a 'type' (box, tent, gaussian)")
    radius_key = {"tent": "radius", "gaussian": "stddev"}.get(pixel_filter["type"])
    unknown = [k for k in pixel_filter if k not in ("type", radius_key)]
    if unknown:
        raise ValueError(f"camera['filter']: unknown key {', '.join(map(repr, unknown))} (a {pixel_filter['type']} filter takes "
                         f"{repr(radius_key) if radius_key else 'none'})")
    extra = (str(camera.get("fov_axis", "x")), float(camera.get("aperture_radius", 0.0)), float(camera.get("focus_distance", 0.0)),
             str(pixel_filter["type"]), float(pixel_filter.get(radius_key, 0.0)) if radius_key else 0.0)
    textures = list(textures)
    return _ember.scene_from_arrays(
        pos.tobytes(), np.ascontiguousarray(tris, dtype=np.uint32).tobytes(), [int(m) for m in mats], emitted, described, point, cam,
        _per_vertex("normals", normals, len(pos), 3), _per_vertex("uvs", uvs, len(pos), 2),
        textures, [_bitmap(i, t) for i, t in enumerate(textures)], list(lights), extra,
    )


def _start(scene, estimator, spp, time, seed, threads, width, height, max_depth, no_plan, options) -> _ember.Render:
    if not isinstance(scene, Scene):
        raise ArgumentTypeError(f"scene must be an ember.Scene (ember.load_file), got {type(scene).__name__}")
    if not isinstance(estimator, str):
        raise ArgumentTypeError(f"estimator must be a name, got {type(estimator).__name__} {estimator!r}")
    if not isinstance(no_plan, bool):
        raise ArgumentTypeError(f"no_plan must be True or False, got {type(no_plan).__name__}")
    pairs = [(name.replace("_", "-"), _option_text(name, value)) for name, value in options.items()]
    return _ember.Render(
        scene,
        estimator,
        pairs,
        _whole("seed", seed, 0, U64_MAX),
        _whole("threads", threads, 1, U32_MAX),
        _whole("width", width, 1, 65536),
        _whole("height", height, 1, 65536),
        _whole("max_depth", max_depth, -1, 2**31 - 1),
        no_plan,
        _whole("spp", spp, 1, U32_MAX),
        _seconds("time", time),
    )


def render(
    scene: Scene,
    estimator: str = "pt",
    spp: Optional[int] = None,
    time: Optional[float] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    max_depth: Optional[int] = None,
    no_plan: bool = False,
    **options,
) -> np.ndarray:
    """(Filled in below from the core's registry.)"""
    r = _start(scene, estimator, spp, time, seed, threads, width, height, max_depth, no_plan, options)
    while r.step():
        pass
    return _as_image(r.width, r.height, r.image_bytes())


class Progressive:
    """A render pass by pass: iterate for a ``Pass`` after each; ``image`` is the mean so far.

    Ctrl-C raises ``KeyboardInterrupt`` out of the loop once the pass in progress ends;
    the object keeps every pass done, so ``image`` still holds them.
    """

    def __init__(self, render: _ember.Render):
        self._render = render

    def __iter__(self) -> Iterator[Pass]:
        return self

    def __next__(self) -> Pass:
        if not self._render.step():
            raise StopIteration
        return Pass(self._render.passes, self._render.elapsed)

    @property
    def image(self) -> np.ndarray:
        """The mean image so far (a copy), float32 H x W x 3."""
        r = self._render
        return _as_image(r.width, r.height, r.image_bytes())

    @property
    def passes(self) -> int:
        return self._render.passes

    @property
    def elapsed(self) -> float:
        """Seconds since the render was asked for (reading, plan and setup included)."""
        return self._render.elapsed

    @property
    def done(self) -> bool:
        return self._render.done

    @property
    def estimator(self) -> str:
        """The estimator that renders (after the scene plan)."""
        return self._render.estimator

    @property
    def plan(self) -> list:
        """The scene plan's lines: what it kept and left out, and why."""
        return self._render.plan

    @property
    def setup_seconds(self) -> float:
        return self._render.setup_seconds


def render_progressive(
    scene: Scene,
    estimator: str = "pt",
    spp: Optional[int] = None,
    time: Optional[float] = None,
    seed: int = 0,
    threads: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    max_depth: Optional[int] = None,
    no_plan: bool = False,
    **options,
) -> Progressive:
    """``render``'s arguments; returns a ``Progressive`` that renders a pass per iteration.

        p = ember.render_progressive(scene, "bdpt", time=60)
        for step in p:
            if step.passes % 8 == 0:
                show(p.image)

    The image after n passes equals ``render(..., spp=n)``'s.
    """
    return Progressive(_start(scene, estimator, spp, time, seed, threads, width, height, max_depth, no_plan, options))


# --- images and error ---------------------------------------------------------------


def read_exr(path) -> np.ndarray:
    """An EXR image as float32 H x W x 3 (``FileNotFoundError`` if missing)."""
    width, height, data = _ember.read_exr(_path("path", path))
    return _as_image(width, height, data)


def reference_floor(path) -> Optional[Tuple[float, float]]:
    """A suite reference's own noise, (relMSE, MAPE), from its halves beside it
    (``reference-half-a.exr``, ``-b.exr``): errors near it cannot be ranked. ``None``
    without the halves."""
    return _ember.reference_floor(_path("path", path))


def compare(image, reference) -> Metrics:
    """``ember compare``: relMSE, MAPE (%), MAE, mean ratio (image / reference) and the
    share of the relative squared error held by the 8 worst pixels (fireflies).

    Both H x W x 3 of the same shape, finite (``ValueError`` otherwise).
    """
    a, b = _image_array("image", image), _image_array("reference", reference)
    if a.shape != b.shape:
        raise ValueError(f"image is {a.shape[1]}x{a.shape[0]} but the reference is {b.shape[1]}x{b.shape[0]}")
    return Metrics(*_ember.compare(a.tobytes(), b.tobytes()))


def convergence(
    scene: Scene,
    reference,
    estimators: Sequence[str] = ("pt", "bdpt"),
    budget: float = 16.0,
    seeds: int = 1,
    threads: Optional[int] = None,
    max_depth: Optional[int] = None,
    no_plan: bool = False,
    **options,
) -> Dict[str, Curve]:
    """Error against time, as ``ember convergence``: each estimator and seed renders with
    its own clock (plan and setup counted), snapshotted at 1, 1.41, 2, 2.83, … s up to
    ``budget``; relMSE and MAPE against ``reference`` (an array, or an EXR path) averaged
    over seeds 0..seeds-1. The scene renders at its own size, which must be the reference's.

    Returns ``{estimator: Curve(seconds, rel_mse, mape, passes)}``, NumPy arrays. As the
    command line does, the estimators of one seed run interleaved, checkpoint by
    checkpoint, so a busy machine slows all alike.
    """
    if isinstance(reference, (str, os.PathLike)):
        reference = read_exr(reference)
    ref = _image_array("reference", reference)
    if isinstance(estimators, str) or not all(isinstance(e, str) for e in estimators):
        raise ArgumentTypeError("estimators must be a sequence of names")
    if len(set(estimators)) != len(estimators):
        raise ValueError(f"estimators {list(estimators)} names one twice")
    seeds = _whole("seeds", seeds, 1, 1000)
    targets = _ember.checkpoints(_seconds("budget", budget))
    if not isinstance(scene, Scene):
        raise ArgumentTypeError(f"scene must be an ember.Scene (ember.load_file), got {type(scene).__name__}")
    if (scene.height, scene.width) != ref.shape[:2]:
        raise ValueError(f"the scene renders {scene.width}x{scene.height} but the reference is {ref.shape[1]}x{ref.shape[0]}")
    sums = {e: np.zeros((len(targets), 4)) for e in estimators}
    ref_bytes = ref.tobytes()
    for seed in range(seeds):
        runs, clocks = [], []
        for e in estimators:
            runs.append(_start(scene, e, U32_MAX, None, seed, threads, None, None, max_depth, no_plan, options))
            clocks.append(runs[-1].elapsed)
        for i, target in enumerate(targets):
            for k, (name, r) in enumerate(zip(estimators, runs)):
                # The run's own clock: the seconds it has had, not the wall clock.
                while clocks[k] < target or r.passes == 0:
                    before = r.elapsed
                    if not r.step():
                        break
                    clocks[k] += r.elapsed - before
                m = _ember.compare(bytes(r.image_bytes()), ref_bytes)
                sums[name][i] += (clocks[k], m[0], m[1], r.passes)
    return {e: Curve(*(sums[e] / seeds).T) for e in estimators}


def _render_doc() -> str:
    lines = [
        "Render ``scene`` and return the mean image: float32, C-contiguous, H x W x 3, linear RGB.",
        "",
        "The ``ember render`` command's image for the same arguments, bit for bit:",
        "",
        "- ``estimator``: a name below (``auto``, the pilot race, is the command line's).",
        "- ``spp``: passes (samples per pixel) [default: unlimited under ``time``; else the",
        f"  scene file's ``sample_count``; else {_ember.DEFAULT_SPP}].",
        "- ``time``: seconds from the call (reading, plan and setup included); the pass running",
        "  when it expires is finished. With ``spp`` too, whichever comes first stops.",
        "- ``seed``; ``threads`` [default: every core; capped at 4 x the cores and 1024];",
        "  ``width``/``height`` (one alone keeps the film's aspect ratio); ``max_depth``",
        "  (Mitsuba's: -1 unbounded) [default: the scene's]; ``no_plan``: render every technique",
        "  as asked (the scene plan otherwise leaves out what the scene cannot use).",
        "- ``**options``: the estimators' options, the command line's names with ``_`` for ``-``",
        "  (``radius_footprints=4``, ``beta=0.25``), checked by the core: a bad value raises",
        "  ``ValueError`` naming the option, and so does an unknown option or estimator;",
        "  a wrong type ``ember.ArgumentTypeError`` (a TypeError and a ValueError); a render",
        "  that would not fit in memory ``MemoryError``.",
        "",
        "The GIL is released while a pass renders; Ctrl-C raises KeyboardInterrupt when the",
        "pass in progress ends (``render_progressive`` keeps the image so far).",
        "",
        "Estimators:",
    ]
    for name, summary, compiled in _ember.estimators():
        lines.append(f"  {name:<8} {summary}{'' if compiled else ' (not in this build)'}")
    lines += ["", "Options (values; the estimators they apply to):"]
    for name, values, help_text, applies, _choices in _ember.estimator_options():
        lines.append(f"  {name.replace('-', '_')} = {values}  [{', '.join(applies)}]")
        lines.append(f"      {help_text}")
    return "\n".join(lines)


render.__doc__ = _render_doc()
