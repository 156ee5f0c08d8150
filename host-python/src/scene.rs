//! Scenes: a Mitsuba 3 XML file read as `ember render` reads it (its `-D` parameters,
//! width and height overrides), or arrays built through the C API's scene description
//! (`ember_capi::SceneDesc`, the checks `ember_scene_create` runs); kept prepared (built,
//! its BVH over it) for the renders that take it at its own resolution.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyo3::prelude::*;

use ember_capi::ffi::EmberCamera;
use ember_capi::{MaterialDesc, SceneData, SceneDesc};
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
    let data = SceneData::from_desc(desc).map_err(|e| Error::Value(e.message))?;
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

/// A scene from arrays through the C API's description and its checks (every index and
/// value): float32 positions and uint32 index triples as bytes, a material per triangle,
/// emitted radiance per triangle (or none), point lights and a pinhole camera
/// (origin, target, up, horizontal field of view in degrees, width, height).
#[pyfunction]
#[pyo3(signature = (positions, triangles, triangle_materials, emission, materials, point_lights, camera))]
pub fn scene_from_arrays(
    py: Python<'_>,
    positions: &[u8],
    triangles: &[u8],
    triangle_materials: Vec<u32>,
    emission: &[u8],
    materials: Vec<(String, [f32; 3], f32)>,
    point_lights: Vec<([f32; 3], [f32; 3])>,
    camera: ([f32; 3], [f32; 3], [f32; 3], f32, u32, u32),
) -> PyResult<Scene> {
    let (origin, target, up, fov_degrees, width, height) = camera;
    let desc = SceneDesc {
        positions: crate::pixels_of(positions, "positions")?,
        triangles: triples_u32(triangles, "triangles")?,
        triangle_materials,
        triangle_emission: crate::pixels_of(emission, "emission")?,
        materials: materials.into_iter().enumerate().map(|(i, m)| material(i, m)).collect::<Result<_, _>>()?,
        point_lights,
        camera: EmberCamera { origin, target, up, fov_degrees, width, height },
        // The first description's camera: horizontal field of view, pinhole, box filter.
        ..SceneDesc::default()
    };
    let prepared = py.detach(|| prepare_arrays(&desc))?;
    Ok(Scene { source: Source::Arrays(Box::new(desc)), prepared: Arc::new(prepared) })
}
