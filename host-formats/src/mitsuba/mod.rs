//! Mitsuba 3 XML scene reader: the subset the benchmark suite uses, read strictly.
//!
//! [`load_scene`] parses a `scene.xml` (roxmltree), substitutes `$name` parameters,
//! instantiates every plugin into an [`ember_core::scene::SceneBuilder`] and returns it
//! with the integrator's `max_depth`, the sampler's `sample_count` and the film size.
//! The conventions are Mitsuba 3's, as listed in `shared/scenes/README.md`: camera space
//! (left, up, forward), unit-sized shapes placed by `to_world`, transforms applied in
//! the order written, named conductors resolved as Mitsuba's `scalar_rgb` variant does.
//!
//! # Strictness
//! Like Mitsuba, a property no plugin reads is an error ("unreferenced property"), and so
//! is an unknown element, plugin type or attribute, a malformed number, a broken `ref`, a
//! missing mesh file or a non-finite mesh vertex. Every error names the file, the line
//! and column, and what is supported there (and the `-D name=value` that supplied a bad
//! value). Only regular files are read (scene, meshes, images), each at most
//! [`MAX_INPUT_BYTES`]; places in the text become lines and columns only for messages
//! ([`positions`]), so loading is linear in the file's size. Things Mitsuba would do that ember does not
//! model (a non-`independent` sampler, an integrator type
//! other than `path`, ...) are accepted with a warning in [`LoadedScene::warnings`];
//! nothing in a file is ignored silently.
//!
//! # Supported subset
//! - `scene` (`version` 2.x or 3.x), `default` + `$name` / `${name}` substitution in
//!   every attribute (overridable like `mitsuba -D`), `id` / `ref` (declared before use).
//! - Shapes: `obj`, `ply` (ascii, binary_little_endian), `rectangle`, `cube`, `sphere`,
//!   `disk` (tessellated into 128 triangles); `to_world`, `flip_normals`, `face_normals`;
//!   one nested or referenced `bsdf` (default: `diffuse` 0.5, black for an emitter, as Mitsuba 3), one `area`
//!   emitter and one absorbing `interior` medium (`homogeneous`, albedo 0; scattering
//!   and exterior media are refused).
//! - BSDFs: `diffuse`, `conductor`, `roughconductor`, `dielectric`, `roughdielectric`,
//!   `plastic`, `roughplastic`, `twosided` (one nested BSDF).
//! - Textures (nested in a BSDF or referenced, named for the colour parameter they set:
//!   `reflectance`, `diffuse_reflectance`, `specular_reflectance`,
//!   `specular_transmittance`): `bitmap` (PNG, 8 or 16 bits, and JPEG, 8 bits, baseline
//!   or progressive, sRGB-decoded unless `raw`; OpenEXR, Radiance RGBE and PFM linear;
//!   `filter_type`, `wrap_mode`, `to_uv`) and `checkerboard` (`color0`,
//!   `color1`, `to_uv`). Meshes carry their texture coordinates (OBJ `vt`, PLY `u`/`v`,
//!   `flip_tex_coords`).
//! - Emitters: `area`, `point`, `spot`, `directional`, `constant`, `envmap` (any image
//!   format a bitmap reads).
//! - `sensor` `perspective` and `thinlens` (`aperture_radius`, `focus_distance`;
//!   `near_clip` and `far_clip` are checked but not modelled, with a warning: ember's
//!   camera does not clip) with `hdrfilm` and any `sampler`; `rfilter` `box`, `tent`
//!   (`radius`), `gaussian` (`stddev`; also a film without `rfilter`, as in Mitsuba);
//!   any `integrator` (only `max_depth` is read; `volpath` is rendered as `path`, with a
//!   warning saying so).
//! - Values: `float`, `integer`, `boolean`, `string`, `rgb`, `spectrum` (one value),
//!   `point`, `vector`, `transform` (`translate`, `rotate`, `scale`, `matrix`, `lookat`).

// `!(x > 0.0)` is used on purpose throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod build;
mod images;
mod materials;
mod media;
mod mesh;
mod ply;
mod positions;
mod progress;
mod props;
mod shapes;
mod textures;
mod transform;
mod xml;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_errors;
#[cfg(test)]
mod tests_images;
#[cfg(test)]
mod tests_media;
#[cfg(test)]
mod tests_principled;
#[cfg(test)]
mod tests_textures;

pub use images::decode_image_bytes;
use std::fmt;
use std::path::{Path, PathBuf};

use ember_core::scene::SceneBuilder;

use crate::files::{MAX_INPUT_BYTES, read_bounded};
use positions::Positions;
pub(crate) use progress::Progress;

/// A scene read from a Mitsuba XML file, ready for [`SceneBuilder::build`].
#[derive(Debug)]
pub struct LoadedScene {
    /// Materials, shapes, lights and the camera (already at the final resolution).
    pub builder: SceneBuilder,
    /// The integrator's `max_depth` with Mitsuba's meaning (−1 = unbounded; 1 = only
    /// directly visible emitters); `None` when the file has no integrator or no
    /// `max_depth`.
    pub max_depth: Option<i32>,
    /// The sampler's `sample_count`; `None` when the file does not give one (Mitsuba's
    /// default would be 4).
    pub spp: Option<u32>,
    /// Film width in pixels (after the [`LoadOptions`] override).
    pub width: u32,
    /// Film height in pixels (after the [`LoadOptions`] override).
    pub height: u32,
    /// Things accepted but not modelled, dropped geometry, unused declarations.
    pub warnings: Vec<String>,
    /// The sensor's position in the file's world frame. The builder holds the scene
    /// camera-centred (every transform composed in f64 with the translation by minus
    /// this, then rounded to f32), so a point `p` of the file is at `p - world_origin`
    /// in the builder. Zero when the camera sits at the origin.
    pub world_origin: glam::DVec3,
    /// Every file the scene reads besides itself (meshes, textures, environment maps).
    pub inputs: Vec<std::path::PathBuf>,
}

/// Caller-side overrides.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Parameter values that replace the file's `<default>` ones (like `mitsuba -D
    /// name=value`); a parameter the file never uses gives a warning.
    pub defaults: Vec<(String, String)>,
    /// Film width override, replacing the file's `width`; alone, the height follows
    /// the file's aspect ratio ([`film_size`]).
    pub width: Option<u32>,
    /// Film height override, replacing the file's `height`; alone, the width follows
    /// the file's aspect ratio ([`film_size`]).
    pub height: Option<u32>,
}

/// The film size under `width`/`height` overrides of a `file` film: both replace both;
/// one alone keeps the file's aspect ratio, the other side rounded to the nearest pixel
/// (at least 1, saturating at `u32::MAX`); neither keeps the file's.
pub fn film_size(file: (u32, u32), width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let scaled = |side: u32, num: u32, den: u32| (side as f64 * num as f64 / den.max(1) as f64).round().max(1.0) as u32;
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, scaled(w, file.1, file.0)),
        (None, Some(h)) => (scaled(h, file.0, file.1), h),
        (None, None) => file,
    }
}

/// A problem in a scene file, with where it is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneFileError {
    /// The scene file (XML) the problem was found in.
    pub file: PathBuf,
    /// 1-based line of the element or attribute at fault, when known.
    pub line: Option<u32>,
    /// 1-based column, when known.
    pub column: Option<u32>,
    pub message: String,
}

impl fmt::Display for SceneFileError {
    /// `file:line:col: message` (the position parts that are known).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneFileError {}

/// A place in the XML text: a byte offset, turned into a line and column by
/// [`positions::Positions`] only when a message shows it (resolving every place the
/// parser records made loading quadratic); or the line and column the XML parser reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Loc {
    Offset(usize),
    At { line: u32, col: u32 },
}

/// An error before it is tied to its file.
#[derive(Clone, Debug)]
pub(crate) struct Fail {
    pub loc: Option<Loc>,
    pub message: String,
}

impl Fail {
    pub fn at(loc: Loc, message: impl Into<String>) -> Self {
        Self { loc: Some(loc), message: message.into() }
    }
    pub fn nowhere(message: impl Into<String>) -> Self {
        Self { loc: None, message: message.into() }
    }
}

pub(crate) type Res<T> = Result<T, Fail>;

/// Read a Mitsuba 3 scene file; see the module documentation for the subset accepted.
/// A scene that takes over a second to load reports its progress on stderr.
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneFileError> {
    let mut progress = Progress::stderr(path);
    let nowhere = |message: String| SceneFileError { file: path.to_path_buf(), line: None, column: None, message };
    let bytes = read_input(path).map_err(|e| nowhere(format!("cannot read the scene file: {e}")))?;
    let text = String::from_utf8(bytes).map_err(|e| nowhere(format!("the scene file is not valid UTF-8 (byte {})", e.utf8_error().valid_up_to())))?;
    load_text(&text, path, options, &mut progress)
}

/// [`load_scene`] on text already in memory (no file is read except the meshes it
/// names, relative to `file`'s directory); errors name `file`. The entry point for
/// callers that hold the XML as a string, and for the parser's fuzz target.
pub fn load_scene_from_str(text: &str, file: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneFileError> {
    load_text(text, file, options, &mut Progress::stderr(file))
}

/// Parse and instantiate `text`, the contents of `file` (relative mesh paths resolve
/// against its directory); places are resolved into lines and columns only for the error.
pub(crate) fn load_text(text: &str, file: &Path, options: &LoadOptions, progress: &mut Progress) -> Result<LoadedScene, SceneFileError> {
    let positions = Positions::new(text);
    load_positions(&positions, file, options, progress)
}

/// [`load_text`] with the caller's [`Positions`] (tests count its resolutions).
pub(crate) fn load_positions(positions: &Positions, file: &Path, options: &LoadOptions, progress: &mut Progress) -> Result<LoadedScene, SceneFileError> {
    let base_dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    let result = xml::parse(positions, &options.defaults).and_then(|parsed| {
        progress.parsed(parsed.objs.iter().filter(|o| o.tag == xml::Tag::Shape).count());
        build::instantiate(parsed, positions, &base_dir, options, progress)
    });
    result.map_err(|f| {
        let (at, message) = positions.resolve(f);
        SceneFileError { file: file.to_path_buf(), line: at.map(|a| a.0), column: at.map(|a| a.1), message }
    })
}

/// The bytes of an input file (scene, mesh, image), refused unless it is a regular file
/// of at most [`MAX_INPUT_BYTES`] ([`read_bounded`]): `/dev/zero`, a FIFO or a directory
/// would otherwise be read until memory runs out, or block.
pub(crate) fn read_input(path: &Path) -> Result<Vec<u8>, String> {
    read_bounded(path, MAX_INPUT_BYTES)
}
