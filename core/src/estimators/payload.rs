//! What the estimators' chunks carry beyond camera samples, splats and counters
//! ([`crate::render::ChunkOutput::data`]): one enum, [`PhaseData`], whose variants are the
//! estimators' own plain data (light sub-paths, SPCBPT's memos, features, sums and
//! training records, path filtering's chunk buffers), and the protocol's types bound to
//! it ([`ChunkOutput`], [`PhaseBuffers`]). The render protocol is generic over this type
//! and never names it; the registry's [`super::Renderer`] uses it for every estimator,
//! and the wire encoding (`render::wire`) moves it between address spaces.

use alloc::vec::Vec;

use crate::alias::AliasTable;
use crate::render::Payload;
use types::{FilterChunk, LightPaths, PrefixMemo, SubpathFeature, TrainingSet};

/// A chunk's output as every estimator of the registry fills it.
pub type ChunkOutput = crate::render::ChunkOutput<PhaseData>;
/// Chunk outputs kept across phases and passes, for the registry's estimators.
pub type PhaseBuffers = crate::render::PhaseBuffers<PhaseData>;

/// The types [`PhaseData`] carries: the estimators' own where their cargo feature is on,
/// else [`Absent`]. Every build has the same variants in the same order, so the wire
/// format's variant numbers (`render::wire`) do not depend on the features: a variant
/// whose payload is absent cannot be made, and its bytes are refused, never misread.
pub mod types {
    #[cfg(not(all(feature = "path", feature = "spcbpt", feature = "subspace", feature = "filtering")))]
    use super::Absent;

    #[cfg(feature = "path")]
    pub use crate::path::LightPaths;
    /// Light sub-paths (feature `path`).
    #[cfg(not(feature = "path"))]
    pub type LightPaths = Absent;

    #[cfg(feature = "spcbpt")]
    pub use crate::estimators::spcbpt::PrefixMemo;
    /// SPCBPT's per-vertex memos (feature `spcbpt`).
    #[cfg(not(feature = "spcbpt"))]
    pub type PrefixMemo = Absent;

    #[cfg(feature = "subspace")]
    pub use crate::subspace::{SubpathFeature, TrainingSet};
    /// SPCBPT's classification features (feature `subspace`).
    #[cfg(not(feature = "subspace"))]
    pub type SubpathFeature = Absent;
    /// SPCBPT's training records (feature `subspace`).
    #[cfg(not(feature = "subspace"))]
    pub type TrainingSet = Absent;

    #[cfg(feature = "filtering")]
    pub use crate::estimators::filter::FilterChunk;
    /// Path filtering's chunk buffers (feature `filtering`).
    #[cfg(not(feature = "filtering"))]
    pub type FilterChunk = Absent;
}

/// The payload of a [`PhaseData`] variant whose estimators this build leaves out: a type
/// with no values, so the variant cannot be made (see [`types`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub enum Absent {}

impl Absent {
    /// What [`ChunkOutput::reset`] calls on every payload; never runs.
    pub fn clear(&mut self) {
        match *self {}
    }
}

/// Estimator-specific plain data a chunk produces.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub enum PhaseData {
    /// Nothing beyond samples and splats.
    #[default]
    None,
    /// Light sub-paths of the chunk.
    LightPaths {
        /// The paths' vertices, contiguous.
        paths: LightPaths,
        /// One SPCBPT prefix memo per vertex (empty for LVCBPT).
        memo: Vec<PrefixMemo>,
    },
    /// Light sub-paths with one f64 per vertex (VCM's prefix sums of its MIS weights).
    PathsWithSums {
        /// The paths' vertices, contiguous.
        paths: LightPaths,
        /// One value per vertex, parallel to `paths.vertices`.
        sums: Vec<f64>,
    },
    /// A count (LVCBPT's cacheable vertices).
    Count(u64),
    /// Classification features with their weights, per-block brightness sums and
    /// sample counts (SPCBPT preprocessing).
    Features {
        /// Sub-path end features.
        features: Vec<SubpathFeature>,
        /// Their weights (f/p).
        weights: Vec<f32>,
        /// Brightness sums per pixel block.
        blocks: Vec<f64>,
        /// Samples per pixel block.
        block_samples: Vec<u32>,
    },
    /// Sums per slot (SPCBPT's Q).
    Sums(Vec<f64>),
    /// Training records (SPCBPT's dataset).
    Training(TrainingSet),
    /// Multi-vertex filtering's per-chunk buffers (nodes, denominators, rows, radiance).
    Filter(alloc::boxed::Box<FilterChunk>),
    /// Stage-1 tables and norms for a range of eye subspaces (SPCBPT).
    GammaTables {
        /// Γ(· | e) restricted to the pass's non-empty subspaces, per eye subspace.
        tables: Vec<Option<AliasTable>>,
        /// The restricted column sums.
        norms: Vec<f32>,
    },
}

/// The footprint setup phase of the estimators with a radius in pixel footprints:
/// measure chunk `out.items` into its sums.
#[cfg(any(feature = "merging", feature = "segments", feature = "filtering"))]
pub(crate) fn map_footprint<Q: crate::geometry::RayQuery + ?Sized>(scene: &crate::scene::Scene, tracer: &Q, out: &mut ChunkOutput) {
    let f = crate::merge::Footprint::measure(scene, tracer, out.items.clone());
    out.data.sums(2).copy_from_slice(&f.sums());
}

/// The footprint of a whole phase, from its chunks' sums ([`map_footprint`]).
#[cfg(any(feature = "merging", feature = "segments", feature = "filtering"))]
pub(crate) fn reduce_footprint(outputs: &[ChunkOutput]) -> crate::merge::Footprint {
    let mut f = crate::merge::Footprint::default();
    for out in outputs {
        if let PhaseData::Sums(s) = &out.data {
            f.add(crate::merge::Footprint::from_sums(s));
        }
    }
    f
}

impl Payload for PhaseData {
    fn clear(&mut self) {
        match self {
            PhaseData::None => {}
            PhaseData::LightPaths { paths, memo } => {
                paths.clear();
                memo.clear();
            }
            PhaseData::PathsWithSums { paths, sums } => {
                paths.clear();
                sums.clear();
            }
            PhaseData::Count(n) => *n = 0,
            PhaseData::Features { features, weights, blocks, block_samples } => {
                features.clear();
                weights.clear();
                blocks.clear();
                block_samples.clear();
            }
            PhaseData::Sums(s) => s.clear(),
            PhaseData::Training(t) => t.clear(),
            PhaseData::GammaTables { tables, norms } => {
                tables.clear();
                norms.clear();
            }
            PhaseData::Filter(chunk) => chunk.clear(),
        }
    }
}

impl PhaseData {
    /// The filtering buffers of this chunk (switching the data to them if needed).
    #[cfg(feature = "filtering")]
    pub fn filter_chunk(&mut self) -> &mut FilterChunk {
        if !matches!(self, PhaseData::Filter(_)) {
            *self = PhaseData::Filter(alloc::boxed::Box::default());
        }
        match self {
            PhaseData::Filter(chunk) => chunk,
            _ => unreachable!("just set"),
        }
    }

    /// The light-path store of this chunk (switching the data to it if needed).
    #[cfg(feature = "path")]
    pub fn light_paths(&mut self) -> (&mut LightPaths, &mut Vec<PrefixMemo>) {
        if !matches!(self, PhaseData::LightPaths { .. }) {
            *self = PhaseData::LightPaths { paths: LightPaths::new(), memo: Vec::new() };
        }
        match self {
            PhaseData::LightPaths { paths, memo } => (paths, memo),
            _ => unreachable!("set just above"),
        }
    }

    /// The light paths and per-vertex sums of this chunk (switching the data to them if
    /// needed).
    #[cfg(feature = "path")]
    pub fn paths_with_sums(&mut self) -> (&mut LightPaths, &mut Vec<f64>) {
        if !matches!(self, PhaseData::PathsWithSums { .. }) {
            *self = PhaseData::PathsWithSums { paths: LightPaths::new(), sums: Vec::new() };
        }
        match self {
            PhaseData::PathsWithSums { paths, sums } => (paths, sums),
            _ => unreachable!("set just above"),
        }
    }

    /// The feature buffers of this chunk (switching the data to them if needed).
    #[cfg(feature = "subspace")]
    pub fn features(&mut self) -> (&mut Vec<SubpathFeature>, &mut Vec<f32>, &mut Vec<f64>, &mut Vec<u32>) {
        if !matches!(self, PhaseData::Features { .. }) {
            *self = PhaseData::Features { features: Vec::new(), weights: Vec::new(), blocks: Vec::new(), block_samples: Vec::new() };
        }
        match self {
            PhaseData::Features { features, weights, blocks, block_samples } => (features, weights, blocks, block_samples),
            _ => unreachable!("set just above"),
        }
    }

    /// The sums of this chunk, `n` slots zeroed (switching the data to them if needed).
    pub fn sums(&mut self, n: usize) -> &mut Vec<f64> {
        if !matches!(self, PhaseData::Sums(_)) {
            *self = PhaseData::Sums(Vec::new());
        }
        match self {
            PhaseData::Sums(s) => {
                s.clear();
                s.resize(n, 0.0);
                s
            }
            _ => unreachable!("set just above"),
        }
    }

    /// The training set of this chunk (switching the data to it if needed).
    #[cfg(feature = "subspace")]
    pub fn training(&mut self) -> &mut TrainingSet {
        if !matches!(self, PhaseData::Training(_)) {
            *self = PhaseData::Training(TrainingSet::new());
        }
        match self {
            PhaseData::Training(t) => t,
            _ => unreachable!("set just above"),
        }
    }

    /// Stage-1 tables, `n` zeroed slots, one per item of the chunk (switching if needed).
    pub fn gamma_tables(&mut self, n: usize) -> (&mut [Option<AliasTable>], &mut [f32]) {
        if !matches!(self, PhaseData::GammaTables { .. }) {
            *self = PhaseData::GammaTables { tables: Vec::new(), norms: Vec::new() };
        }
        match self {
            PhaseData::GammaTables { tables, norms } => {
                tables.clear();
                tables.resize(n, None);
                norms.clear();
                norms.resize(n, 0.0);
                (tables, norms)
            }
            _ => unreachable!("set just above"),
        }
    }
}

#[cfg(feature = "wire")]
mod wire {
    #[cfg(feature = "path")]
    use crate::path::{LightPaths, VertexKind};
    use crate::render::wire::{WireError, WirePayload};
    use crate::scene::Scene;

    use super::PhaseData;

    impl WirePayload for PhaseData {
        fn validate(&self, scene: &Scene) -> Result<(), WireError> {
            let data = self;
            // Without the `path` feature the light-path variants have no values (`Absent`).
            #[cfg(not(feature = "path"))]
            let _ = scene;
            match data {
                #[cfg(feature = "path")]
                PhaseData::LightPaths { paths, memo } => {
                    validate_paths(paths, scene)?;
                    if !memo.is_empty() && memo.len() != paths.vertices.len() {
                        return Err(WireError::Invalid("prefix memos are neither one per vertex nor none"));
                    }
                    Ok(())
                }
                #[cfg(feature = "path")]
                PhaseData::PathsWithSums { paths, sums } => {
                    validate_paths(paths, scene)?;
                    if sums.len() != paths.vertices.len() {
                        return Err(WireError::Invalid("vertex sums are not one per vertex"));
                    }
                    Ok(())
                }
                _ => Ok(()),
            }
        }
    }

    /// Path starts ascending within the vertices; materials and lights of the scene.
    #[cfg(feature = "path")]
    fn validate_paths(paths: &LightPaths, scene: &Scene) -> Result<(), WireError> {
        let n = paths.vertices.len() as u64;
        let mut last = 0u64;
        for (i, &s) in paths.starts.iter().enumerate() {
            if (i == 0 && s != 0) || u64::from(s) < last || u64::from(s) > n {
                return Err(WireError::Invalid("light-path starts out of order"));
            }
            last = u64::from(s);
        }
        if paths.starts.is_empty() && n > 0 {
            return Err(WireError::Invalid("light-path vertices without paths"));
        }
        let lights = scene.lights.len() as u64;
        let materials = scene.materials.len() as u64;
        for v in &paths.vertices {
            let light_ok = |id: u32| u64::from(id) < lights;
            let ok = match v.kind {
                VertexKind::Light(id) => light_ok(id),
                VertexKind::Surface => u64::from(v.material) < materials,
                VertexKind::Camera | VertexKind::InfiniteLight => true,
            } && v.emitter.is_none_or(light_ok);
            if !ok {
                return Err(WireError::Invalid("a light-path vertex names a material or light the scene lacks"));
            }
        }
        Ok(())
    }
}

#[cfg(all(test, feature = "wire"))]
mod wire_tests {
    use super::*;
    use crate::render::Phase;
    use crate::render::wire::{Part, WireError};
    use crate::scene::builtin;
    #[cfg(feature = "path")]
    use crate::{path::VertexKind, scene::Scene, spectrum::Rgb};

    #[test]
    fn refuses_what_it_cannot_trust() {
        let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
        let phase = Phase { name: "camera", id: 0, pass: Some(3), items: 8, chunk: 4, samples: true };
        let mut out = ChunkOutput::default();
        out.reset(0..4);
        out.pixel_buffer();
        let mut film = Vec::new();
        out.encode(&phase, Part::Film, &mut film);
        let mut got = ChunkOutput::default();
        assert_eq!(got.decode(&phase, 0, Part::Film, &film, &scene), Ok(()));
        assert_eq!(got.decode(&phase, 0, Part::State, &film, &scene), Err(WireError::WrongPart(Part::Film)));
        assert!(matches!(got.decode(&phase, 1, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        // The same chunk of the next pass, or of another phase: stale, refused.
        let next = Phase { pass: Some(4), ..phase };
        assert!(matches!(got.decode(&next, 0, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        let other = Phase { id: 1, ..phase };
        assert!(matches!(got.decode(&other, 0, Part::Film, &film, &scene), Err(WireError::WrongChunk { .. })));
        assert_eq!(got.decode(&phase, 0, Part::Film, &film[..film.len() - 1], &scene), Err(WireError::Malformed));
        let mut long = film.clone();
        long.push(0);
        assert_eq!(got.decode(&phase, 0, Part::Film, &long, &scene), Err(WireError::Invalid("trailing bytes")));
        let mut old = film.clone();
        old[4] ^= 1; // the version's varint
        assert_eq!(got.decode(&phase, 0, Part::Film, &old, &scene), Err(WireError::Header));
        #[cfg(feature = "path")]
        refuses_unknown_materials(&scene, &mut got);
    }

    /// The variant numbers do not move with the core's features (docs/features.md):
    /// `Count` is variant 3 in every build, and a build without `path` refuses the
    /// number of `LightPaths`, whose payload it cannot hold, instead of misreading it.
    #[test]
    fn variant_numbers_do_not_depend_on_features() {
        let phase = Phase { name: "probe", id: 0, pass: None, items: 1, chunk: 1, samples: false };
        let mut out = ChunkOutput::default();
        out.reset(0..1);
        out.data = PhaseData::Count(5);
        let mut bytes = Vec::new();
        out.encode(&phase, Part::State, &mut bytes);
        let n = bytes.len();
        assert_eq!(bytes[n - 2..], [3, 5], "Count(5): variant 3, then 5");
        #[cfg(not(feature = "path"))]
        {
            let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
            bytes[n - 2] = 1;
            let mut got = ChunkOutput::default();
            assert_eq!(got.decode(&phase, 0, Part::State, &bytes, &scene), Err(WireError::Malformed));
        }
    }

    #[cfg(feature = "path")]
    fn refuses_unknown_materials(scene: &Scene, got: &mut ChunkOutput) {
        // A light vertex naming a material the scene lacks.
        let light = Phase { name: "light paths", id: 0, pass: Some(0), items: 1, chunk: 1, samples: true };
        let mut paths = ChunkOutput::default();
        paths.reset(0..1);
        let (store, _) = paths.data.light_paths();
        let mut v = crate::path::Vertex::camera(crate::math::Vec3::ZERO, Rgb::ZERO);
        v.kind = VertexKind::Surface;
        v.material = scene.materials.len() as u32;
        store.push(&[v]);
        let mut state = Vec::new();
        paths.encode(&light, Part::State, &mut state);
        assert!(matches!(got.decode(&light, 0, Part::State, &state, scene), Err(WireError::Invalid(_))));
    }
}
