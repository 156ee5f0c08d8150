//! A scene ready to render ([`PreparedScene`]: what the estimators read and the ray
//! queries over its geometry), its hash, and what a render of it needs in memory. How
//! the scene was obtained (a file, a built-in scene, an engine's arrays) is the host's.

use std::path::PathBuf;

use ember_core::estimators::{EstimatorConfig, MemoryEstimate};
use ember_core::scene::{BuildWarnings, Scene, SceneBuilder, SceneGeometry};

use crate::accel::Accel;

/// A scene ready to render: what the estimators read and the ray queries.
#[derive(Debug)]
pub struct PreparedScene {
    pub name: String,
    pub scene: Scene,
    pub accel: Accel,
    /// The depth the scene file asks for (Mitsuba's `max_depth`), if any.
    pub max_depth: Option<i32>,
    /// The sample count the scene file asks for, if any.
    pub spp: Option<u32>,
    pub warnings: Vec<String>,
    /// The files the scene was read from: the scene file, its meshes, textures and
    /// environment maps (outputs never overwrite them); empty for a built-in scene.
    pub inputs: Vec<PathBuf>,
}

impl PreparedScene {
    /// The scene `name` built into `scene` and `geometry` (its ray queries built here),
    /// with the reader's `notes` and the builder's `warnings` turned into notes.
    pub fn new(
        name: String,
        scene: Scene,
        geometry: &SceneGeometry,
        warnings: BuildWarnings,
        max_depth: Option<i32>,
        spp: Option<u32>,
        mut notes: Vec<String>,
    ) -> Self {
        // Dropped triangles are reported by the scene reader, shape by shape with their
        // cause (the built-in scenes drop none); a count here repeated them.
        // Only what was really dropped (the core counts no light it keeps). A light of any
        // power, even one too bright for f32, is selectable, so there is no selection only
        // when no emitter is left.
        if warnings.dark_lights > 0 {
            notes.push(format!("{} lights emit nothing and were dropped (an emitting mesh counts once per triangle)", warnings.dark_lights));
        }
        if scene.light_selection.is_none() {
            notes.push("the scene has no light: the image will be black".into());
        }
        let accel = Accel::new(geometry);
        Self { name, scene, accel, max_depth, spp, warnings: notes, inputs: Vec::new() }
    }

    /// [`Self::new`] on `builder` built; the builder's refusal names the scene. Every host
    /// that reads a scene file prepares it through here (the command line's
    /// `setup::prepare_file`, the Python package's `load_file`).
    pub fn build(name: String, builder: SceneBuilder, max_depth: Option<i32>, spp: Option<u32>, notes: Vec<String>) -> Result<Self, String> {
        let (scene, geometry, warnings) = builder.build().map_err(|e| format!("{name}: {e}"))?;
        Ok(Self::new(name, scene, &geometry, warnings, max_depth, spp, notes))
    }

    /// FNV-1a of the built scene's full content: the camera, materials and lights (their
    /// `Debug` form: f32s print as their shortest round-trip decimal) and every triangle
    /// and sphere the queries see (raw bits). Equal for equal scenes however they were
    /// written, different when any value that reaches the renderer differs. Computed on
    /// demand (split renders and trained models check it), not for every render.
    pub fn hash(&self) -> u64 {
        scene_hasher(&self.scene, &self.accel).value()
    }

    /// What `config` would hold for this scene's film ([`crate::memory::need`]).
    pub fn memory_need(&self, config: &EstimatorConfig) -> (u64, MemoryEstimate) {
        crate::memory::need(&self.scene.camera, config)
    }

    /// What the loaded geometry holds, by [`GEOMETRY_BYTES_PER_TRIANGLE`].
    pub fn geometry_bytes(&self) -> u64 {
        (self.accel.triangle_count() as u64 + self.accel.sphere_count() as u64) * GEOMETRY_BYTES_PER_TRIANGLE
    }
}

/// Bytes the loaded geometry holds per triangle: the scene's triangle records, the
/// accelerator's leaf-ordered copies and attributes and its BVH (measured on a
/// 2 M-triangle mesh: about 435 bytes each).
pub const GEOMETRY_BYTES_PER_TRIANGLE: u64 = 435;

/// The hasher behind [`PreparedScene::hash`], fed with `scene` and `accel`'s geometry, for
/// hosts that add what else their renders read (the C API: its triangle numbering).
pub fn scene_hasher(scene: &Scene, accel: &Accel) -> ember_core::fnv::Fnv1a {
    let mut h = ember_core::fnv::Fnv1a::new();
    // Writing to the hasher cannot fail.
    let _ = std::fmt::Write::write_fmt(&mut h, format_args!("{scene:?}"));
    accel.hash_geometry(&mut h);
    h
}
