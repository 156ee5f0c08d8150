//! Scenes: a Mitsuba 3 XML file read as `ember render` reads it (its `-D` parameters,
//! width and height overrides), or arrays built through the C API's scene description
//! (`ember_capi::SceneDesc`, the checks `ember_scene_create` runs); kept prepared (built,
//! its BVH over it) for the renders that take it at its own resolution.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use ember_capi::ffi::EmberCamera;
use ember_capi::ffi::desc::{
    CEnum, EmberBsdf, EmberBsdfKind, EmberFilterKind, EmberFovAxis, EmberLens, EmberLight, EmberLightKind, EmberMicrofacet, EmberPixelFilter,
    EmberTextureFilter, EmberTextureKind, EmberTextureSlot, EmberWrapMode,
};
use ember_capi::scene::{default_bsdf, default_light, default_texture};
use ember_capi::{MaterialDesc, SceneData, SceneDesc, TextureDesc};
use ember_formats::mitsuba;
use ember_host::scene::PreparedScene;

use crate::Error;

/// A missing file is `FileNotFoundError`, named; the readers' own messages say the rest.
pub fn check_exists(path: &Path) -> Result<(), Error> {
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(Error::NotFound(format!("{}: no such file", path.display()))),
        _ => Ok(()),
    }
}

/// `path` read and prepared with the parameters `defines` and the film size overrides,
/// as the command line's `setup::prepare_file` does.
pub fn prepare(path: &Path, defines: &[(String, String)], width: Option<u32>, height: Option<u32>) -> Result<PreparedScene, Error> {
    check_exists(path)?;
    let options = mitsuba::LoadOptions { defaults: defines.to_vec(), width, height };
    let loaded = mitsuba::load_scene(path, &options).map_err(|e| Error::Value(e.to_string()))?;
    let mut prepared = PreparedScene::build(path.display().to_string(), loaded.builder, loaded.max_depth, loaded.spp, loaded.warnings).map_err(Error::Value)?;
    prepared.inputs = std::iter::once(path.to_path_buf()).chain(loaded.inputs).collect();
    Ok(prepared)
}

/// Where a scene came from, to build it again at another size.
#[derive(Debug)]
pub enum Source {
    /// A scene file with its parameters.
    File { path: PathBuf, defines: Vec<(String, String)> },
    /// Arrays, through the C API's scene description.
    Arrays(Box<SceneDesc>),
}

/// A scene, loaded. Renders at another size build it again at that size: a file is read
/// again, as `ember render --width` does; arrays are built again with the camera resized.
#[pyclass(module = "ember._ember", frozen)]
#[derive(Debug)]
pub struct Scene {
    pub source: Source,
    pub prepared: Arc<PreparedScene>,
}

/// `desc` built by the C API's checks ([`SceneData::from_desc`]) and prepared.
fn prepare_arrays(desc: &SceneDesc) -> Result<PreparedScene, Error> {
    let data = SceneData::from_desc(desc).map_err(|e| Error::Value(python_names(e.message)))?;
    let SceneData { scene, geometry, .. } = data;
    Ok(PreparedScene::new("arrays".into(), scene, &geometry, Default::default(), None, None, Vec::new()))
}

impl Scene {
    /// This scene at `width` × `height` (one alone keeps the film's aspect ratio).
    pub fn resized(&self, width: Option<u32>, height: Option<u32>) -> Result<PreparedScene, Error> {
        match &self.source {
            Source::File { path, defines } => prepare(path, defines, width, height),
            Source::Arrays(desc) => {
                let mut desc = desc.as_ref().clone();
                (desc.camera.width, desc.camera.height) = mitsuba::film_size((desc.camera.width, desc.camera.height), width, height);
                prepare_arrays(&desc)
            }
        }
    }
}

#[pymethods]
impl Scene {
    /// The scene file (`None` for a scene of arrays).
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        match &self.source {
            Source::File { path, .. } => Some(path.clone()),
            Source::Arrays(_) => None,
        }
    }
    /// The film's width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.prepared.scene.camera.width()
    }
    /// The film's height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.prepared.scene.camera.height()
    }
    /// The integrator's `max_depth` in the file (`None`: not given; -1: unbounded).
    #[getter]
    fn max_depth(&self) -> Option<i32> {
        self.prepared.max_depth
    }
    /// The sampler's `sample_count` in the file, the passes a render without `spp` or
    /// `time` takes.
    #[getter]
    fn spp(&self) -> Option<u32> {
        self.prepared.spp
    }
    /// What the reader noted (an unused parameter, dropped triangles, no light).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.prepared.warnings.clone()
    }
    /// The `-D` parameters it was read with.
    #[getter]
    fn defines(&self) -> Vec<(String, String)> {
        match &self.source {
            Source::File { defines, .. } => defines.clone(),
            Source::Arrays(_) => Vec::new(),
        }
    }
    fn __repr__(&self) -> String {
        format!("<ember.Scene {} {}x{}>", self.prepared.name, self.width(), self.height())
    }
}

/// Read a Mitsuba 3 XML scene with parameters `defines` ((name, value) pairs, `-D`).
#[pyfunction]
pub fn load_file(py: Python<'_>, path: PathBuf, defines: Vec<(String, String)>) -> PyResult<Scene> {
    let prepared = py.detach(|| prepare(&path, &defines, None, None))?;
    Ok(Scene { source: Source::File { path, defines }, prepared: Arc::new(prepared) })
}

/// Native-endian u32 bytes as triples; refused unless a whole number of triples.
fn triples_u32(bytes: &[u8], what: &str) -> Result<Vec<[u32; 3]>, Error> {
    if !bytes.len().is_multiple_of(12) {
        return Err(Error::Value(format!("{what}: {} bytes are not a whole number of uint32 triples", bytes.len())));
    }
    let value = |b: &[u8]| u32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
    Ok(bytes.chunks_exact(12).map(|t| [value(&t[0..4]), value(&t[4..8]), value(&t[8..12])]).collect())
}

/// A material of the description: ("diffuse", rgb, _), ("mirror", rgb, _), ("glass", _, ior).
fn material(i: usize, (kind, colour, ior): (String, [f32; 3], f32)) -> Result<MaterialDesc, Error> {
    match kind.as_str() {
        "diffuse" => Ok(MaterialDesc::Diffuse(colour)),
        "mirror" => Ok(MaterialDesc::Mirror(colour)),
        "glass" => Ok(MaterialDesc::Glass(ior)),
        other => Err(Error::Value(format!("material {i}: no kind '{other}' (diffuse, mirror, glass)"))),
    }
}

/// A dict of the Python caller's (a material, texture or light), read key by key; the
/// keys never read are refused by [`Fields::finish`], named.
struct Fields<'py> {
    dict: Bound<'py, PyDict>,
    what: String,
    read: Vec<String>,
}

impl<'py> Fields<'py> {
    fn new(obj: &Bound<'py, PyAny>, what: String) -> Result<Self, Error> {
        let dict = obj.cast::<PyDict>().map_err(|_| Error::Value(format!("{what} is not a dict")))?.clone();
        Ok(Fields { dict, what, read: Vec::new() })
    }
    fn raw(&mut self, key: &str) -> Result<Option<Bound<'py, PyAny>>, Error> {
        self.read.push(key.to_string());
        self.dict.get_item(key).map_err(|e| Error::Value(format!("{}['{key}']: {e}", self.what)))
    }
    fn bad(&self, key: &str, want: &str) -> Error {
        Error::Value(format!("{}['{key}'] is not {want}", self.what))
    }
    fn string(&mut self, key: &str) -> Result<Option<String>, Error> {
        self.raw(key)?.map(|v| v.extract::<String>().map_err(|_| self.bad(key, "a string"))).transpose()
    }
    fn float(&mut self, key: &str) -> Result<Option<f32>, Error> {
        self.raw(key)?.map(|v| v.extract::<f32>().map_err(|_| self.bad(key, "a number"))).transpose()
    }
    fn boolean(&mut self, key: &str) -> Result<Option<bool>, Error> {
        self.raw(key)?.map(|v| v.extract::<bool>().map_err(|_| self.bad(key, "True or False"))).transpose()
    }
    fn index(&mut self, key: &str) -> Result<Option<i32>, Error> {
        self.raw(key)?.map(|v| v.extract::<i32>().map_err(|_| self.bad(key, "a texture index"))).transpose()
    }
    fn vec3(&mut self, key: &str) -> Result<Option<[f32; 3]>, Error> {
        self.raw(key)?.map(|v| v.extract::<[f32; 3]>().map_err(|_| self.bad(key, "3 numbers"))).transpose()
    }
    /// A colour: one number (grey) or three.
    fn rgb_of(&self, key: &str, v: &Bound<'py, PyAny>) -> Result<[f32; 3], Error> {
        if let Ok(x) = v.extract::<f32>() {
            return Ok([x; 3]);
        }
        v.extract::<[f32; 3]>().map_err(|_| self.bad(key, "a colour (a number or 3 numbers)"))
    }
    fn rgb(&mut self, key: &str) -> Result<Option<[f32; 3]>, Error> {
        let v = self.raw(key)?;
        v.map(|v| self.rgb_of(key, &v)).transpose()
    }
    /// A colour or `{"texture": index}` (into `slot` of `textures`).
    fn spectrum(&mut self, key: &str, value: &mut [f32; 3], textures: &mut [i32; 4], slot: usize) -> Result<(), Error> {
        let Some(v) = self.raw(key)? else { return Ok(()) };
        if self.texture_ref(key, &v, textures, slot)? {
            return Ok(());
        }
        *value = self.rgb_of(key, &v)?;
        Ok(())
    }
    /// A float or `{"texture": index}` (principled's roughness).
    fn scalar(&mut self, key: &str, value: &mut f32, textures: &mut [i32; 4], slot: usize) -> Result<(), Error> {
        let Some(v) = self.raw(key)? else { return Ok(()) };
        if self.texture_ref(key, &v, textures, slot)? {
            return Ok(());
        }
        *value = v.extract::<f32>().map_err(|_| self.bad(key, "a number or {'texture': index}"))?;
        Ok(())
    }
    /// If `v` (the value of `key`) is `{"texture": index}`: that index into `slot` of
    /// `textures`, and true; false for any other value.
    fn texture_ref(&self, key: &str, v: &Bound<'py, PyAny>, textures: &mut [i32; 4], slot: usize) -> Result<bool, Error> {
        let Ok(d) = v.cast::<PyDict>() else { return Ok(false) };
        let mut inner = Fields::new(d.as_any(), format!("{}['{key}']", self.what))?;
        textures[slot] = inner.index("texture")?.ok_or_else(|| Error::Value(format!("{}['{key}'] has no 'texture'", self.what)))?;
        inner.finish()?;
        Ok(true)
    }
    /// A named value of a C enum (Mitsuba's spelling).
    fn named<T: CEnum>(&mut self, key: &str) -> Result<Option<u32>, Error> {
        let Some(name) = self.string(key)? else { return Ok(None) };
        named::<T>(&name, &format!("{}['{key}']", self.what)).map(Some)
    }
    /// A matrix of `rows` × 3 (`to_uv`: 2 × 3 or 3 × 3, the last row dropped; `to_world`).
    fn matrix(&mut self, key: &str, rows: &[usize]) -> Result<Option<Vec<[f32; 3]>>, Error> {
        let Some(v) = self.raw(key)? else { return Ok(None) };
        let m = v.extract::<Vec<[f32; 3]>>().ok().filter(|m| rows.contains(&m.len()));
        m.map(Some).ok_or_else(|| self.bad(key, &format!("a matrix of {} x 3 numbers", rows.iter().map(|r| r.to_string()).collect::<Vec<_>>().join(" or "))))
    }
    /// Refuses the keys never read.
    fn finish(self) -> Result<(), Error> {
        let mut unknown = Vec::new();
        for key in self.dict.keys() {
            let name = key.extract::<String>().unwrap_or_else(|_| key.to_string());
            if !self.read.contains(&name) {
                unknown.push(format!("'{name}'"));
            }
        }
        if unknown.is_empty() {
            return Ok(());
        }
        let mut known = self.read.iter().filter(|k| k.as_str() != "type").map(|k| format!("'{k}'")).collect::<Vec<_>>();
        known.sort();
        Err(Error::Value(format!("{}: unknown key {} (known here: {})", self.what, unknown.join(", "), known.join(", "))))
    }
}

/// The value of `T` named `name`, or an error naming `what` and the names.
fn named<T: CEnum>(name: &str, what: &str) -> Result<u32, Error> {
    T::NAMES
        .iter()
        .position(|n| *n == name)
        .map(|i| T::ALL[i].value())
        .ok_or_else(|| Error::Value(format!("{what}: no type '{name}' ({})", T::NAMES.join(", "))))
}

/// A material given as a dict of Mitsuba 3's BSDF `type` and parameter names (defaults:
/// `ember_bsdf_init`'s); `twosided` wraps another as Mitsuba's does (`{"type":
/// "twosided", "bsdf": {...}}`).
fn bsdf_dict(i: usize, obj: &Bound<'_, PyAny>, two_sided: bool) -> Result<EmberBsdf, Error> {
    let what = if two_sided { format!("materials[{i}]['bsdf']") } else { format!("materials[{i}]") };
    let mut d = Fields::new(obj, what.clone())?;
    let kind = d.string("type")?.ok_or_else(|| Error::Value(format!("{what} has no 'type'")))?;
    if kind == "twosided" && !two_sided {
        let inner = d.raw("bsdf")?.ok_or_else(|| Error::Value(format!("{what} (twosided) has no 'bsdf'")))?;
        d.finish()?;
        return bsdf_dict(i, &inner, true);
    }
    let k = named::<EmberBsdfKind>(&kind, &format!("{what}['type']")).map_err(|_| {
        let wrapper = if two_sided { "" } else { ", twosided" };
        Error::Value(format!("{what}['type']: no type '{kind}' ({}{wrapper})", EmberBsdfKind::NAMES.join(", ")))
    })?;
    let k = EmberBsdfKind::ALL[k as usize];
    let mut b = default_bsdf(k);
    b.two_sided = u32::from(two_sided);
    let t = &mut b.textures;
    let (diffuse, spec_r, spec_t, rough) = (
        EmberTextureSlot::Diffuse as usize,
        EmberTextureSlot::SpecularReflectance as usize,
        EmberTextureSlot::SpecularTransmittance as usize,
        EmberTextureSlot::Roughness as usize,
    );
    use EmberBsdfKind as K;
    let rough_kind = matches!(k, K::RoughConductor | K::RoughDielectric | K::RoughPlastic);
    if rough_kind {
        if let Some(v) = d.named::<EmberMicrofacet>("distribution")? {
            b.distribution = v;
        }
        if let Some(v) = d.float("alpha")? {
            b.alpha = v;
        }
    }
    match k {
        K::Diffuse => d.spectrum("reflectance", &mut b.diffuse, t, diffuse)?,
        K::Conductor | K::RoughConductor => {
            d.spectrum("specular_reflectance", &mut b.specular_reflectance, t, spec_r)?;
            b.eta = d.rgb("eta")?.unwrap_or(b.eta);
            b.k = d.rgb("k")?.unwrap_or(b.k);
        }
        K::Dielectric | K::RoughDielectric | K::Plastic | K::RoughPlastic => {
            b.int_ior = d.float("int_ior")?.unwrap_or(b.int_ior);
            b.ext_ior = d.float("ext_ior")?.unwrap_or(b.ext_ior);
            d.spectrum("specular_reflectance", &mut b.specular_reflectance, t, spec_r)?;
            if matches!(k, K::Dielectric | K::RoughDielectric) {
                d.spectrum("specular_transmittance", &mut b.specular_transmittance, t, spec_t)?;
            } else {
                d.spectrum("diffuse_reflectance", &mut b.diffuse, t, diffuse)?;
                if let Some(v) = d.boolean("nonlinear")? {
                    b.nonlinear = u32::from(v);
                }
            }
        }
        K::Principled => {
            d.spectrum("base_color", &mut b.diffuse, t, diffuse)?;
            let p = &mut b.principled;
            d.scalar("roughness", &mut p.roughness, t, rough)?;
            for (key, field) in [
                ("anisotropic", &mut p.anisotropic),
                ("metallic", &mut p.metallic),
                ("spec_tint", &mut p.spec_tint),
                ("sheen", &mut p.sheen),
                ("sheen_tint", &mut p.sheen_tint),
                ("flatness", &mut p.flatness),
                ("clearcoat", &mut p.clearcoat),
                ("clearcoat_gloss", &mut p.clearcoat_gloss),
                ("spec_trans", &mut p.spec_trans),
                ("eta", &mut p.eta),
                ("diffuse_reflectance_sampling_rate", &mut p.diffuse_reflectance_sampling_rate),
                ("main_specular_sampling_rate", &mut p.main_specular_sampling_rate),
                ("clearcoat_sampling_rate", &mut p.clearcoat_sampling_rate),
            ] {
                if let Some(v) = d.float(key)? {
                    *field = v;
                }
            }
        }
    }
    d.finish()?;
    Ok(b)
}

/// A bitmap's pixels as the Python half hands them: (float32 bytes, width, height,
/// channels).
type BitmapData = (Vec<u8>, u32, u32, u32);

/// A texture given as a dict (Mitsuba 3's `bitmap` or `checkerboard`); a bitmap's
/// pixels come apart, checked and flattened by the Python half: (floats as bytes, width,
/// height, channels).
fn texture_dict(i: usize, obj: &Bound<'_, PyAny>, pixels: Option<BitmapData>) -> Result<TextureDesc, Error> {
    let what = format!("textures[{i}]");
    let mut d = Fields::new(obj, what.clone())?;
    let kind = d.string("type")?.ok_or_else(|| Error::Value(format!("{what} has no 'type'")))?;
    let k = named::<EmberTextureKind>(&kind, &format!("{what}['type']"))?;
    let k = EmberTextureKind::ALL[k as usize];
    let init = default_texture(k);
    let mut t = TextureDesc {
        kind: init.kind,
        pixels: Vec::new(),
        width: 0,
        height: 0,
        channels: init.channels,
        srgb: init.srgb,
        wrap_mode: init.wrap_mode,
        filter: init.filter,
        color0: init.color0,
        color1: init.color1,
        to_uv: init.to_uv,
    };
    match k {
        EmberTextureKind::Bitmap => {
            d.raw("data")?;
            let (bytes, width, height, channels) = pixels.ok_or_else(|| Error::Value(format!("{what} (bitmap) has no 'data'")))?;
            t.pixels = floats_of(&bytes, &format!("{what}['data']"))?;
            (t.width, t.height, t.channels) = (width, height, channels);
            if let Some(v) = d.boolean("srgb")? {
                t.srgb = u32::from(v);
            }
            if let Some(v) = d.named::<EmberWrapMode>("wrap_mode")? {
                t.wrap_mode = v;
            }
            if let Some(v) = d.named::<EmberTextureFilter>("filter_type")? {
                t.filter = v;
            }
        }
        EmberTextureKind::Checkerboard => {
            t.color0 = d.rgb("color0")?.unwrap_or(t.color0);
            t.color1 = d.rgb("color1")?.unwrap_or(t.color1);
        }
    }
    if let Some(m) = d.matrix("to_uv", &[2, 3])? {
        t.to_uv = [m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2]];
    }
    d.finish()?;
    Ok(t)
}

/// A light given as a dict: Mitsuba 3's emitter `type` and parameter names (the
/// colour is `intensity`, `irradiance` or `radiance` by kind; a spot is placed by
/// `position` and `direction`, an envmap's image is `texture`, a bitmap's index).
fn light_dict(i: usize, obj: &Bound<'_, PyAny>) -> Result<EmberLight, Error> {
    let what = format!("lights[{i}]");
    let mut d = Fields::new(obj, what.clone())?;
    let kind = d.string("type")?.ok_or_else(|| Error::Value(format!("{what} has no 'type'")))?;
    let k = named::<EmberLightKind>(&kind, &format!("{what}['type']"))?;
    let k = EmberLightKind::ALL[k as usize];
    let mut l = default_light(k);
    use EmberLightKind as L;
    if matches!(k, L::Point | L::Spot) {
        l.position = d.vec3("position")?.unwrap_or(l.position);
    }
    if matches!(k, L::Spot | L::Directional) {
        l.direction = d.vec3("direction")?.unwrap_or(l.direction);
    }
    let colour_key = match k {
        L::Point | L::Spot => Some("intensity"),
        L::Directional => Some("irradiance"),
        L::Constant => Some("radiance"),
        L::Envmap => None,
    };
    if let Some(key) = colour_key {
        l.color = d.rgb(key)?.unwrap_or(l.color);
    }
    if k == L::Spot {
        l.cutoff_angle = d.float("cutoff_angle")?.unwrap_or(l.cutoff_angle);
        l.beam_width = d.float("beam_width")?.unwrap_or(l.beam_width);
    }
    if k == L::Envmap {
        l.texture = d.index("texture")?.ok_or_else(|| Error::Value(format!("{what} (envmap) has no 'texture' (a bitmap's index)")))?;
        l.scale = d.float("scale")?.unwrap_or(l.scale);
        if let Some(m) = d.matrix("to_world", &[3])? {
            l.to_world = [m[0], m[1], m[2]];
        }
    }
    d.finish()?;
    Ok(l)
}

/// The description's C field names in a message of `from_desc`, followed by the
/// Python keys that set them.
fn python_names(message: String) -> String {
    const NAMES: &[(&str, &str)] = &[
        (".textures[0] (", "the texture of 'reflectance', 'diffuse_reflectance' or 'base_color'"),
        (".textures[1] (", "the texture of 'specular_reflectance'"),
        (".textures[2] (", "the texture of 'specular_transmittance'"),
        (".textures[3] (", "the texture of 'roughness'"),
        (".principled.", "the key after 'principled.'"),
        (".diffuse", "'reflectance', 'diffuse_reflectance' or 'base_color'"),
        (".color ", "'intensity', 'irradiance' or 'radiance'"),
        (".texture ", "'texture'"),
        (".pixels", "'data'"),
        (".filter ", "'filter_type'"),
        ("lens.", "camera 'aperture_radius' / 'focus_distance'"),
        ("filter.", "camera 'filter'"),
        ("fov_axis", "camera 'fov_axis'"),
    ];
    match NAMES.iter().find(|(c, _)| message.contains(c)) {
        Some((_, py)) => format!("{message} (in Python: {py})"),
        None => message,
    }
}

/// Native-endian f32 bytes as floats.
fn floats_of(bytes: &[u8], what: &str) -> Result<Vec<f32>, Error> {
    if !bytes.len().is_multiple_of(4) {
        return Err(Error::Value(format!("{what}: {} bytes are not a whole number of float32", bytes.len())));
    }
    Ok(bytes.chunks_exact(4).map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect())
}

/// The camera's additions to version 1's: (fov_axis, aperture_radius, focus_distance,
/// filter type, filter radius or standard deviation; 0: Mitsuba's default).
type CameraExtra = (String, f32, f32, String, f32);

/// A scene from arrays through the C API's description and its checks (every index and
/// value): float32 positions and uint32 index triples as bytes, a material per triangle,
/// emitted radiance per triangle (or none), point lights and a camera (origin, target,
/// up, field of view in degrees, width, height; then `CameraExtra`); optional per-vertex
/// normals and uvs (float32 bytes, empty: none), materials as version 1's tuples or
/// dicts (Mitsuba's names), textures as dicts with their pixels apart, lights as dicts.
#[pyfunction]
#[pyo3(signature = (positions, triangles, triangle_materials, emission, materials, point_lights, camera, normals=Vec::new(), uvs=Vec::new(), textures=Vec::new(), texture_pixels=Vec::new(), lights=Vec::new(), camera_extra=None))]
#[allow(clippy::too_many_arguments)]
pub fn scene_from_arrays(
    py: Python<'_>,
    positions: &[u8],
    triangles: &[u8],
    triangle_materials: Vec<u32>,
    emission: &[u8],
    materials: Vec<Bound<'_, PyAny>>,
    point_lights: Vec<([f32; 3], [f32; 3])>,
    camera: ([f32; 3], [f32; 3], [f32; 3], f32, u32, u32),
    normals: Vec<u8>,
    uvs: Vec<u8>,
    textures: Vec<Bound<'_, PyAny>>,
    texture_pixels: Vec<Option<BitmapData>>,
    lights: Vec<Bound<'_, PyAny>>,
    camera_extra: Option<CameraExtra>,
) -> PyResult<Scene> {
    let (origin, target, up, fov_degrees, width, height) = camera;
    let materials = materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            if m.is_instance_of::<PyDict>() {
                bsdf_dict(i, m, false).map(MaterialDesc::Bsdf)
            } else {
                let old =
                    m.extract::<(String, [f32; 3], f32)>().map_err(|_| Error::Value(format!("materials[{i}] is neither a dict nor (kind, colour, ior)")))?;
                material(i, old)
            }
        })
        .collect::<Result<_, _>>()?;
    let normals = floats_of(&normals, "normals")?;
    let uvs = floats_of(&uvs, "uvs")?;
    let mut pixels = texture_pixels.into_iter();
    let textures = textures.iter().enumerate().map(|(i, t)| texture_dict(i, t, pixels.next().flatten())).collect::<Result<_, _>>()?;
    let lights = lights.iter().enumerate().map(|(i, l)| light_dict(i, l)).collect::<Result<_, _>>()?;
    let mut desc = SceneDesc {
        positions: crate::pixels_of(positions, "positions")?,
        normals: normals.chunks_exact(3).map(|n| [n[0], n[1], n[2]]).collect(),
        uvs: uvs.chunks_exact(2).map(|t| [t[0], t[1]]).collect(),
        triangles: triples_u32(triangles, "triangles")?,
        triangle_materials,
        triangle_emission: crate::pixels_of(emission, "emission")?,
        materials,
        textures,
        point_lights,
        lights,
        camera: EmberCamera { origin, target, up, fov_degrees, width, height },
        // Without the extra: the first description's camera (horizontal field of view,
        // pinhole, box filter).
        ..SceneDesc::default()
    };
    if let Some((fov_axis, aperture_radius, focus_distance, filter, radius)) = camera_extra {
        desc.fov_axis = named::<EmberFovAxis>(&fov_axis, "camera['fov_axis']")?;
        desc.lens = EmberLens { aperture_radius, focus_distance };
        desc.filter = EmberPixelFilter { kind: named::<EmberFilterKind>(&filter, "camera['filter']['type']")?, radius };
    }
    let prepared = py.detach(|| prepare_arrays(&desc))?;
    Ok(Scene { source: Source::Arrays(Box::new(desc)), prepared: Arc::new(prepared) })
}
