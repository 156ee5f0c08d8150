//! `ember._ember`: the Rust half of the Python package `ember` (PyO3, abi3). The Python
//! half (`python/ember/__init__.py`) checks argument types, turns keyword options into
//! the command line's `name=value` text and NumPy arrays into bytes; this half loads
//! scenes ([`scene`]), renders them pass by pass with the GIL released ([`session`]) and
//! compares images, through the same code the `ember` command runs: the Mitsuba reader
//! and metrics of `ember-formats`, and `ember-host`'s setup (options checked by the core,
//! the scene plan, the memory check) and driver. So an image is the CLI's, bit for bit.
//!
//! What code here may do: what a library may (no printing, no exit, no signal handlers:
//! Ctrl-C is Python's, seen between passes). Errors leave as typed Python exceptions
//! ([`Error`]). No `unsafe` of its own: PyO3's macros write what the C API needs.

use pyo3::exceptions::{PyFileNotFoundError, PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyByteArray;

use ember_core::estimators::{EstimatorKind, options};

mod scene;
mod session;

/// What a call can fail with, each a Python exception.
#[derive(Debug)]
pub enum Error {
    /// A file that is not there (`FileNotFoundError`).
    NotFound(String),
    /// A value refused: an option, an estimator, a scene file's content (`ValueError`).
    Value(String),
    /// The render would not fit in memory (`MemoryError`).
    Memory(String),
    /// Anything else (the render threads could not start: `RuntimeError`).
    Runtime(String),
}

impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e {
            Error::NotFound(m) => PyFileNotFoundError::new_err(m),
            Error::Value(m) => PyValueError::new_err(m),
            Error::Memory(m) => PyMemoryError::new_err(m),
            Error::Runtime(m) => PyRuntimeError::new_err(m),
        }
    }
}

/// Every estimator of the core's registry: (name, summary, compiled in this build).
#[pyfunction]
fn estimators() -> Vec<(&'static str, &'static str, bool)> {
    EstimatorKind::ALL.iter().map(|k| (k.name(), k.summary(), k.is_compiled())).collect()
}

/// One row of [`estimator_options`]: (name as the command line spells it, values in
/// words, help, the estimators it applies to, the names a choice takes).
type OptionRow = (&'static str, &'static str, &'static str, Vec<&'static str>, Vec<&'static str>);

/// Every estimator option of the core's table.
#[pyfunction]
fn estimator_options() -> Vec<OptionRow> {
    options::all()
        .iter()
        .map(|o| {
            let choices = match o.value {
                options::ValueKind::Choice(names) => names.to_vec(),
                _ => Vec::new(),
            };
            (o.name, o.range, o.help, o.applies.iter().map(|k| k.name()).collect(), choices)
        })
        .collect()
}

/// Pixels as native-endian f32 bytes (the Python half views them as an H×W×3 array).
fn pixel_bytes<'py>(py: Python<'py>, pixels: &[[f32; 3]]) -> Bound<'py, PyByteArray> {
    let bytes: Vec<u8> = pixels.iter().flatten().flat_map(|v| v.to_ne_bytes()).collect();
    PyByteArray::new(py, &bytes)
}

/// Native-endian f32 bytes as pixels; refused unless a whole number of pixels.
fn pixels_of(bytes: &[u8], what: &str) -> Result<Vec<[f32; 3]>, Error> {
    if !bytes.len().is_multiple_of(12) {
        return Err(Error::Value(format!("{what}: {} bytes are not a whole number of RGB float32 pixels", bytes.len())));
    }
    let value = |b: &[u8]| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
    Ok(bytes.chunks_exact(12).map(|p| [value(&p[0..4]), value(&p[4..8]), value(&p[8..12])]).collect())
}

/// `ember compare`'s numbers for two images of the same size (float32 RGB bytes):
/// (relMSE, MAPE in %, MAE, mean ratio, share of the relative squared error in the
/// worst pixels).
#[pyfunction]
fn compare(test: &[u8], reference: &[u8]) -> PyResult<(f64, f64, f64, f64, f64)> {
    let (test, reference) = (pixels_of(test, "image")?, pixels_of(reference, "reference")?);
    if test.len() != reference.len() {
        return Err(Error::Value(format!("the image has {} pixels but the reference {}", test.len(), reference.len())).into());
    }
    let m = ember_formats::metrics::compare(&test, &reference);
    Ok((m.rel_mse, m.mape, m.mae, m.mean_ratio, m.worst8_share))
}

/// Read an EXR image: (width, height, float32 RGB bytes).
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<(u32, u32, Bound<'py, PyByteArray>)> {
    scene::check_exists(&path)?;
    let image = py.detach(|| ember_formats::image_io::read_exr(&path)).map_err(|e| Error::Value(e.to_string()))?;
    Ok((image.width, image.height, pixel_bytes(py, &image.pixels)))
}

/// The noise floor of a suite reference, (relMSE, MAPE), from its two halves beside it
/// (`reference-half-a.exr`, `-b.exr`); `None` without them.
#[pyfunction]
fn reference_floor(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Option<(f64, f64)>> {
    scene::check_exists(&path)?;
    let reference = py.detach(|| ember_formats::error_time::Reference::load(&path)).map_err(Error::Value)?;
    Ok(reference.floor)
}

/// The snapshot times of an error-against-time record: 1, 1.41, 2, 2.83, … seconds below
/// `budget`, then `budget` (`ember convergence`'s).
#[pyfunction]
fn checkpoints(budget: f64) -> PyResult<Vec<f64>> {
    let budget = ember_host::setup::check_seconds(budget, budget).map_err(Error::Value)?;
    Ok(ember_formats::error_time::checkpoints(budget))
}

/// The library's version and build (as `ember --version` and partial images record it).
#[pyfunction]
fn version() -> String {
    ember_host::program_version()
}

#[pymodule]
fn _ember(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::Scene>()?;
    m.add_class::<session::Render>()?;
    m.add_function(wrap_pyfunction!(scene::load_file, m)?)?;
    m.add_function(wrap_pyfunction!(scene::scene_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(estimators, m)?)?;
    m.add_function(wrap_pyfunction!(estimator_options, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(reference_floor, m)?)?;
    m.add_function(wrap_pyfunction!(checkpoints, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add("DEFAULT_SPP", ember_host::setup::DEFAULT_SPP)?;
    Ok(())
}
