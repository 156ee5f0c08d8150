//! What the page's own module instance does: it holds the core's film, fed with the
//! workers' plain outputs, and lists the scenes and estimators, so the page has no film
//! and no estimator list of its own.
//!
//! The page writes a worker's camera band or splats into the input buffer
//! (`ember_film_input(floats)` returns its address), then calls `ember_film_camera` or
//! `ember_film_splats`; `ember_film_end_pass(scale)` commits the pass; `ember_film_image()`
//! resolves the mean image (3 × f32 per pixel, row 0 at the top).

use core::cell::RefCell;

use ember_core::Rgb;
use ember_core::integrator::Splat;
use ember_core::math::Vec2;
use ember_core::render::{EstimatorKind, Film};

use crate::{SCENES, SetupError, supported};

/// The core's film with the page's input and output buffers.
#[derive(Debug)]
pub struct PageFilm {
    pub film: Film,
    input: Vec<f32>,
    camera: Vec<Rgb>,
    splats: Vec<Splat>,
    image: Vec<f32>,
}

impl PageFilm {
    /// A black `width × height` film.
    pub fn new(width: u32, height: u32) -> Result<Self, SetupError> {
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err(SetupError::BadResolution);
        }
        Ok(Self { film: Film::new(width, height), input: Vec::new(), camera: Vec::new(), splats: Vec::new(), image: Vec::new() })
    }

    /// The input buffer, `floats` long (zeroed).
    pub fn input(&mut self, floats: usize) -> &mut [f32] {
        self.input.clear();
        self.input.resize(floats, 0.0);
        &mut self.input
    }

    /// Stage camera values (3 floats per pixel) for pixels `first..`.
    pub fn camera(&mut self, first: u32, values: &[f32]) {
        self.camera.clear();
        self.camera.extend(values.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])));
        self.film.set_camera_samples(first..first.saturating_add(self.camera.len() as u32), &self.camera);
    }

    /// Stage splats (5 floats each: film x, y, r, g, b), after those staged before.
    pub fn splats(&mut self, values: &[f32]) {
        self.splats.clear();
        self.splats.extend(values.chunks_exact(5).map(|c| Splat { film: Vec2::new(c[0], c[1]), value: Rgb::new(c[2], c[3], c[4]) }));
        self.film.push_splats(&self.splats);
    }

    /// Stage camera values from the input buffer.
    fn camera_from_input(&mut self, first: u32) {
        let values = core::mem::take(&mut self.input);
        self.camera(first, &values);
        self.input = values;
    }

    /// Stage splats from the input buffer.
    fn splats_from_input(&mut self) {
        let values = core::mem::take(&mut self.input);
        self.splats(&values);
        self.input = values;
    }

    /// The mean image, 3 × f32 per pixel.
    pub fn image(&mut self) -> &[f32] {
        self.image.clear();
        self.image.extend(self.film.to_rgb_f32().into_iter().flatten());
        &self.image
    }
}

thread_local! {
    static FILM: RefCell<Option<PageFilm>> = const { RefCell::new(None) };
}

fn with_film<T>(default: T, f: impl FnOnce(&mut PageFilm) -> T) -> T {
    FILM.with_borrow_mut(|film| film.as_mut().map_or(default, f))
}

/// A new black film; 0, or −[`SetupError::BadResolution`].
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_new(width: u32, height: u32) -> i32 {
    match PageFilm::new(width, height) {
        Ok(f) => {
            FILM.with_borrow_mut(|slot| *slot = Some(f));
            0
        }
        Err(e) => -(e as i32),
    }
}

/// Address of an input buffer of `floats` f32 (valid until the next film call).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_input(floats: u32) -> usize {
    with_film(0, |f| f.input(floats as usize).as_mut_ptr() as usize)
}

/// Stage the input buffer as camera values of pixels `first..`.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_camera(first: u32) {
    with_film((), |f| f.camera_from_input(first));
}

/// Stage the input buffer as splats.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_splats() {
    with_film((), |f| f.splats_from_input());
}

/// Commit the staged pass, splats multiplied by `scale`.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_end_pass(scale: f64) {
    with_film((), |f| f.film.end_pass(scale));
}

/// Address of the mean image (3 × f32 per pixel), resolved now.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_image() -> usize {
    with_film(0, |f| f.image().as_ptr() as usize)
}

/// Passes committed.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_passes() -> u32 {
    with_film(0, |f| f.film.passes())
}

/// Samples and splats discarded as invalid radiance (f64: exact up to 2⁵³).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_discarded() -> f64 {
    with_film(0.0, |f| f.film.discarded() as f64)
}

/// Number of estimators (`EstimatorKind::ALL`).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_count() -> u32 {
    EstimatorKind::ALL.len() as u32
}

/// Address and length (`ember_estimator_name_len`) of estimator `i`'s name (UTF-8).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_name(i: u32) -> usize {
    EstimatorKind::from_index(i).map_or(0, |e| e.name().as_ptr() as usize)
}

/// Length in bytes of estimator `i`'s name.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_name_len(i: u32) -> u32 {
    EstimatorKind::from_index(i).map_or(0, |e| e.name().len() as u32)
}

/// Can the page run estimator `i` (1) or not yet (0)?
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_supported(i: u32) -> u32 {
    EstimatorKind::from_index(i).is_some_and(supported) as u32
}

/// Number of built-in scenes.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_scene_count() -> u32 {
    SCENES.len() as u32
}

/// Address of scene `i`'s name (UTF-8; length from `ember_scene_name_len`).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_scene_name(i: u32) -> usize {
    SCENES.get(i as usize).map_or(0, |s| s.as_ptr() as usize)
}

/// Length in bytes of scene `i`'s name.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_scene_name_len(i: u32) -> u32 {
    SCENES.get(i as usize).map_or(0, |s| s.len() as u32)
}
