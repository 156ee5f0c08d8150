//! Scenes: a Mitsuba 3 XML file read as `ember render` reads it (its `-D` parameters,
//! width and height overrides), kept prepared (built, its BVH over it) for the renders
//! that take it at its own resolution.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyo3::prelude::*;

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

/// A scene file, loaded. Renders at another size read the file again with that size, as
/// `ember render --width` does.
#[pyclass(module = "ember._ember", frozen)]
#[derive(Debug)]
pub struct Scene {
    pub path: PathBuf,
    pub defines: Vec<(String, String)>,
    pub prepared: Arc<PreparedScene>,
}

#[pymethods]
impl Scene {
    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
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
        self.defines.clone()
    }
    fn __repr__(&self) -> String {
        format!("<ember.Scene {} {}x{}>", self.path.display(), self.width(), self.height())
    }
}

/// Read a Mitsuba 3 XML scene with parameters `defines` ((name, value) pairs, `-D`).
#[pyfunction]
pub fn load_file(py: Python<'_>, path: PathBuf, defines: Vec<(String, String)>) -> PyResult<Scene> {
    let prepared = py.detach(|| prepare(&path, &defines, None, None))?;
    Ok(Scene { path, defines, prepared: Arc::new(prepared) })
}
