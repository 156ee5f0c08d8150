"""The complete description from Python (issue 55): `ember.scene_from_arrays` with per-vertex
normals and uvs, dict materials (a textured rough plastic, a checkerboard-textured
diffuse), bitmap and checkerboard textures, an environment map, a thin lens, a tent filter
and a vertical field of view renders bit-identically to the same scene written as Mitsuba
3 XML (OBJ meshes, an 8-bit PNG, a PFM) read by `ember.load_file`; the camera sits at the
origin (the reader recentres scenes on the camera, the description does not:
docs/embedding.md). And a table of bad inputs for the new keys, each refused with a
ValueError naming it.

Injected bugs seen failing here (each run once, reverted), in host-python/src/scene.rs:
- the uvs handed to the description as (v, u) (`[t[1], t[0]]`): the XML identity fails
  (PT: 1596 of 1728 pixels differ; BDPT: 1608);
- `Fields::finish` not called for lights (unknown keys accepted), in the same build:
  the table's "light unknown key" row fails (did not raise);
- the envmap's `scale` read but not stored: the identity fails (1728 of 1728 pixels);
- `roughplastic`'s `alpha` read but not stored (0.1 kept): the identity fails (PT: 1598
  pixels; BDPT: 1608) and so does the table's "alpha value" row;
and in host-python/python/ember/__init__.py, the filter's radius dropped (0, Mitsuba's
default for the kind): the identity fails (1728 pixels) and so does "filter radius".
"""

import struct
import zlib

import numpy as np
import pytest

import ember

W, H = 48, 36
FLOOR = [[-3.0, -1.0, 0.5], [-3.0, -1.0, 6.0], [3.0, -1.0, 6.0], [3.0, -1.0, 0.5]]
FLOOR_NORMALS = [[0.1, 1.0, 0.0], [-0.1, 1.0, 0.05], [0.0, 0.9, -0.1], [0.2, 1.0, 0.1]]
FLOOR_UVS = [[0.0, 0.0], [0.0, 3.0], [3.0, 3.0], [3.0, 0.0]]
WALL = [[-3.0, -1.0, 6.0], [-3.0, 3.0, 6.0], [3.0, 3.0, 6.0], [3.0, -1.0, 6.0]]
WALL_NORMALS = [[0.0, 0.0, -1.0]] * 4
WALL_UVS = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]
QUAD = [[0, 1, 2], [0, 2, 3]]
CHECKER = ((0.7, 0.2, 0.1), (0.1, 0.3, 0.6))
ALPHA, APERTURE, FOCUS, TENT, FOV_Y, ENV_SCALE = 0.2, 0.04, 3.0, 1.25, 50.0, 1.5
TARGET = (0.1, -0.25, 1.0)
# A quarter turn about +y, row-major.
ENV_ROTATION = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]


def albedo_bytes():
    """The PNG's 4 x 4 RGB bytes (sRGB)."""
    return np.array([[40 + 13 * i, 200 - 9 * i, 90 + 37 * (i % 5)] for i in range(16)], dtype=np.uint8).reshape(4, 4, 3)


def sky():
    """The environment map's 16 x 8 linear texels: a gradient with a bright patch."""
    s = np.zeros((8, 16, 3), dtype=np.float32)
    for y in range(8):
        for x in range(16):
            s[y, x] = (40.0, 36.0, 30.0) if (x, y) == (5, 2) else (0.3 + 0.05 * y, 0.4 + 0.02 * x, 0.8 - 0.07 * y)
    return s


def f(x):
    """A float32 as text that reads back as the same float32."""
    return repr(float(np.float32(x)))


def v3(v):
    return ", ".join(f(x) for x in v)


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write_pfm(path, rgb):
    h, w, _ = rgb.shape
    path.write_bytes(f"PF\n{w} {h}\n-1.0\n".encode() + np.ascontiguousarray(rgb[::-1], dtype="<f4").tobytes())


def write_obj(path, positions, normals, uvs):
    sp = lambda v: " ".join(f(x) for x in v)
    lines = [f"v {sp(p)}" for p in positions] + [f"vt {sp(t)}" for t in uvs] + [f"vn {sp(n)}" for n in normals]
    lines += ["f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in t) for t in QUAD]
    path.write_text("\n".join(lines) + "\n")


def write_xml(d):
    write_obj(d / "floor.obj", FLOOR, FLOOR_NORMALS, FLOOR_UVS)
    write_obj(d / "wall.obj", WALL, WALL_NORMALS, WALL_UVS)
    write_png(d / "albedo.png", albedo_bytes())
    write_pfm(d / "sky.pfm", sky())
    row = lambda r: f"{v3(r).replace(',', '')} 0"
    matrix = " ".join(row(r) for r in ENV_ROTATION) + " 0 0 0 1"
    (d / "scene.xml").write_text(f"""<scene version="3.0.0">
  <sensor type="thinlens">
    <float name="fov" value="{f(FOV_Y)}"/><string name="fov_axis" value="y"/>
    <float name="aperture_radius" value="{f(APERTURE)}"/><float name="focus_distance" value="{f(FOCUS)}"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="{v3(TARGET)}" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>
      <rfilter type="tent"><float name="radius" value="{f(TENT)}"/></rfilter></film>
  </sensor>
  <bsdf type="roughplastic" id="floor"><string name="distribution" value="ggx"/><float name="alpha" value="{f(ALPHA)}"/>
    <texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="albedo.png"/></texture></bsdf>
  <bsdf type="diffuse" id="wall">
    <texture type="checkerboard" name="reflectance">
      <rgb name="color0" value="{v3(CHECKER[0])}"/><rgb name="color1" value="{v3(CHECKER[1])}"/>
      <transform name="to_uv"><scale x="4" y="4"/></transform>
    </texture>
  </bsdf>
  <shape type="obj"><string name="filename" value="floor.obj"/><boolean name="flip_tex_coords" value="false"/><ref id="floor"/></shape>
  <shape type="obj"><string name="filename" value="wall.obj"/><boolean name="flip_tex_coords" value="false"/><ref id="wall"/></shape>
  <emitter type="envmap"><string name="filename" value="sky.pfm"/><float name="scale" value="{f(ENV_SCALE)}"/>
    <transform name="to_world"><matrix value="{matrix}"/></transform></emitter>
</scene>
""")
    return d / "scene.xml"


def arrays(**edits):
    """The scene's arguments to `scene_from_arrays`; `edits` replace some."""
    args = dict(
        positions=np.array(FLOOR + WALL, dtype=np.float32),
        triangles=np.array(QUAD + [[i + 4 for i in t] for t in QUAD], dtype=np.uint32),
        triangle_materials=[0, 0, 1, 1],
        normals=np.array(FLOOR_NORMALS + WALL_NORMALS, dtype=np.float32),
        uvs=np.array(FLOOR_UVS + WALL_UVS, dtype=np.float32),
        materials=[
            {"type": "roughplastic", "distribution": "ggx", "alpha": ALPHA, "diffuse_reflectance": {"texture": 0}},
            {"type": "diffuse", "reflectance": {"texture": 1}},
        ],
        textures=[
            # As Mitsuba decodes an 8-bit PNG: byte / 255, then the sRGB curve.
            {"type": "bitmap", "data": albedo_bytes().astype(np.float32) / np.float32(255.0), "srgb": True},
            {"type": "checkerboard", "color0": CHECKER[0], "color1": CHECKER[1], "to_uv": [[4, 0, 0], [0, 4, 0], [0, 0, 1]]},
            {"type": "bitmap", "data": sky()},
        ],
        lights=[{"type": "envmap", "texture": 2, "scale": ENV_SCALE, "to_world": ENV_ROTATION}],
        camera=dict(origin=(0, 0, 0), target=TARGET, up=(0, 1, 0), fov=FOV_Y, fov_axis="y", width=W, height=H,
                    aperture_radius=APERTURE, focus_distance=FOCUS, filter={"type": "tent", "radius": TENT}),
    )
    args.update(edits)
    return args


@pytest.mark.parametrize("estimator", ["pt", "bdpt"])
def test_complete_arrays_render_as_the_same_scene_in_xml(tmp_path, estimator):
    from_xml = ember.load_file(write_xml(tmp_path))
    from_arrays = ember.scene_from_arrays(**arrays())
    assert (from_arrays.width, from_arrays.height) == (W, H)
    run = lambda s: ember.render(s, estimator, spp=3, seed=11, max_depth=-1, no_plan=True)
    want, got = run(from_xml), run(from_arrays)
    assert got.shape == want.shape == (H, W, 3)
    assert float(got.mean()) > 0.0
    differing = int(np.count_nonzero((got.view(np.uint32) != want.view(np.uint32)).any(axis=2)))
    assert differing == 0, f"{differing} of {W * H} pixels differ from the XML scene's"


def test_old_tuple_materials_still_work_beside_dicts():
    scene = ember.scene_from_arrays(**arrays(materials=[("diffuse", (0.5, 0.5, 0.5)), {"type": "twosided", "bsdf": {"type": "conductor"}}],
                                             textures=[{"type": "bitmap", "data": sky()}], lights=[{"type": "envmap", "texture": 0}]))
    assert ember.render(scene, spp=1).shape == (H, W, 3)


def _with_material(m):
    return {"materials": [m, {"type": "diffuse"}]}


def _with_light(light):
    return {"lights": [light]}


def _camera(**extra):
    c = dict(arrays()["camera"])
    c.update(extra)
    return {"camera": c}


BAD = [
    ("normals shape", {"normals": np.zeros((3, 3))}, r"normals must be 8 x 3"),
    ("uvs shape", {"uvs": np.zeros((8, 3))}, r"uvs must be 8 x 2"),
    ("zero normal", {"normals": np.zeros((8, 3))}, r"normals\[0\] is zero"),
    ("material type", _with_material({"type": "velvet"}), r"materials\[0\]\['type'\]: no type 'velvet' \(diffuse, conductor, .*principled, twosided\)"),
    ("material no type", _with_material({"alpha": 0.1}), r"materials\[0\] has no 'type'"),
    ("material unknown key", _with_material({"type": "roughplastic", "roughness": 0.3}), r"materials\[0\]: unknown key 'roughness' \(known here: .*'alpha'"),
    ("key of another kind", _with_material({"type": "plastic", "alpha": 0.3}), r"materials\[0\]: unknown key 'alpha'"),
    ("distribution", _with_material({"type": "roughconductor", "distribution": "phong"}), r"materials\[0\]\['distribution'\]: no type 'phong' \(beckmann, ggx\)"),
    ("alpha value", _with_material({"type": "roughplastic", "alpha": -1.0}), r"materials\[0\]\.alpha -1 .*"),
    ("colour type", _with_material({"type": "diffuse", "reflectance": "red"}), r"materials\[0\]\['reflectance'\] is not a colour"),
    ("negative colour", _with_material({"type": "diffuse", "reflectance": (1, -1, 1)}),
     r"materials\[0\]\.diffuse is negative or not finite \(in Python: 'reflectance'"),
    ("texture index", _with_material({"type": "diffuse", "reflectance": {"texture": 9}}), r"materials\[0\]\.textures\[0\] .* 9 is neither -1 nor a texture index"),
    ("texture dict key", _with_material({"type": "diffuse", "reflectance": {"texture": 0, "scale": 2}}), r"materials\[0\]\['reflectance'\]: unknown key 'scale'"),
    ("principled value", _with_material({"type": "principled", "metallic": 2.0}), r"materials\[0\]\.principled\.metallic 2 is outside \[0, 1\]"),
    ("twosided no bsdf", _with_material({"type": "twosided"}), r"materials\[0\] \(twosided\) has no 'bsdf'"),
    ("texture type", {"textures": [{"type": "noise"}]}, r"textures\[0\]\['type'\]: no type 'noise' \(bitmap, checkerboard\)"),
    ("texture unknown key", {"textures": [{"type": "checkerboard", "color2": 1.0}]}, r"textures\[0\]: unknown key 'color2'"),
    ("bitmap no data", {"textures": [{"type": "bitmap"}]}, r"textures\[0\] \(bitmap\) has no 'data'"),
    ("bitmap shape", {"textures": [{"type": "bitmap", "data": np.zeros((4, 4, 2))}]}, r"textures\[0\]\['data'\] must be H x W x 3 or H x W"),
    ("wrap mode", {"textures": [{"type": "bitmap", "data": np.zeros((2, 2)), "wrap_mode": "wrap"}]},
     r"textures\[0\]\['wrap_mode'\]: no type 'wrap' \(repeat, mirror, clamp\)"),
    ("to_uv shape", {"textures": [{"type": "checkerboard", "to_uv": [1, 2, 3]}]}, r"textures\[0\]\['to_uv'\] is not a matrix of 2 or 3 x 3"),
    ("light type", _with_light({"type": "area"}), r"lights\[0\]\['type'\]: no type 'area' \(point, spot, directional, constant, envmap\)"),
    ("light unknown key", _with_light({"type": "point", "irradiance": 1.0}), r"lights\[0\]: unknown key 'irradiance' \(known here: 'intensity', 'position'\)"),
    ("spot cutoff", _with_light({"type": "spot", "cutoff_angle": 200.0}), r"lights\[0\]\.cutoff_angle 200 is outside \(0, 180\]"),
    ("directional zero", _with_light({"type": "directional", "direction": (0, 0, 0)}), r"lights\[0\]\.direction is zero"),
    ("envmap no texture", _with_light({"type": "envmap"}), r"lights\[0\] \(envmap\) has no 'texture'"),
    ("envmap checkerboard", _with_light({"type": "envmap", "texture": 1}), r"lights\[0\]\.texture 1 is a checkerboard"),
    ("envmap rotation", _with_light({"type": "envmap", "texture": 2, "to_world": [[2, 0, 0], [0, 1, 0], [0, 0, 1]]}), r"lights\[0\]\.to_world is not a rotation"),
    ("fov axis", _camera(fov_axis="z"), r"camera\['fov_axis'\]: no type 'z' \(x, y, smaller, larger, diagonal\)"),
    ("camera unknown key", _camera(aperture=0.1), r"camera: unknown key 'aperture'"),
    ("focus distance", _camera(focus_distance=0.0), r"lens\.focus_distance 0 is not positive .*\(in Python: camera 'aperture_radius' / 'focus_distance'\)"),
    ("filter type", _camera(filter={"type": "lanczos"}), r"camera\['filter'\]\['type'\]: no type 'lanczos' \(box, tent, gaussian\)"),
    ("filter key", _camera(filter={"type": "gaussian", "radius": 1.0}), r"camera\['filter'\]: unknown key 'radius' \(a gaussian filter takes 'stddev'\)"),
    ("filter radius", _camera(filter={"type": "tent", "radius": -1.0}), r"filter\.radius -1 is negative"),
]


@pytest.mark.parametrize("name,edits,message", BAD, ids=[b[0] for b in BAD])
def test_bad_complete_inputs_are_refused_with_the_key_named(name, edits, message):
    with pytest.raises(ValueError, match=message):
        ember.scene_from_arrays(**arrays(**edits))
