//! Light sub-paths stored contiguously, and cache entries pointing into them: the
//! per-pass light-vertex store of LVCBPT and SPCBPT.

use alloc::vec::Vec;

use super::{SubPath, Vertex, VertexKind, light_subpath, vertex_budgets};
use crate::geometry::RayQuery;
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::transport::{Counters, RenderParams};

/// Light sub-paths of one pass (or of one chunk of it), vertices stored contiguously.
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "wire", derive(serde::Serialize, serde::Deserialize))]
pub struct LightPaths {
    pub vertices: Vec<Vertex>,
    /// Index of each path's first vertex in `vertices`.
    pub starts: Vec<u32>,
}

impl LightPaths {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.starts.clear();
    }
    /// Number of paths held.
    pub fn len(&self) -> usize {
        self.starts.len()
    }
    pub fn is_empty(&self) -> bool {
        self.starts.is_empty()
    }
    /// Append one path.
    pub fn push(&mut self, path: &[Vertex]) {
        self.starts.push(self.vertices.len() as u32);
        self.vertices.extend_from_slice(path);
    }
    /// Append another store's paths (chunks merged in index order by the host).
    pub fn append(&mut self, other: &LightPaths) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.starts.extend(other.starts.iter().map(|s| s + base));
    }
    /// Vertices of path `i`.
    pub fn path(&self, i: usize) -> &[Vertex] {
        let start = self.starts[i] as usize;
        let end = self.starts.get(i + 1).map_or(self.vertices.len(), |&e| e as usize);
        &self.vertices[start..end]
    }
    pub fn size_bytes(&self) -> usize {
        self.vertices.capacity() * core::mem::size_of::<Vertex>() + self.starts.capacity() * 4
    }
}

/// A cached light vertex: the prefix `vertices[start .. start + s]` of a light path,
/// whose last vertex is the one connected to (s ≥ 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CacheEntry {
    pub start: u32,
    pub s: u32,
}

impl CacheEntry {
    /// The light sub-path y₀…y_{s−1} of this entry.
    #[inline]
    pub fn subpath<'a>(&self, paths: &'a LightPaths) -> &'a [Vertex] {
        &paths.vertices[self.start as usize..(self.start + self.s) as usize]
    }
}

/// Append to `out` an entry for every cacheable vertex of `paths` after the light
/// source, in path order: LVCBPT's connection cache, VCM's photons.
pub fn cacheable_entries(scene: &Scene, paths: &LightPaths, out: &mut Vec<CacheEntry>) {
    for i in 0..paths.len() {
        let start = paths.starts[i];
        for (k, v) in paths.path(i).iter().enumerate().skip(1) {
            if is_cacheable(scene, v) {
                out.push(CacheEntry { start, s: k as u32 + 1 });
            }
        }
    }
}

/// May light vertex `v` (not the light-source vertex) be cached for connections, or
/// merged at (a non-Dirac surface point)?
#[inline]
pub fn is_cacheable(scene: &Scene, v: &Vertex) -> bool {
    v.kind == VertexKind::Surface && v.is_connectible(scene)
}

/// Trace the light sub-path of light-path index `index` (its own random stream).
pub fn trace_light_subpath<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    stream: Stream,
    index: u32,
    pass: u32,
    counters: &mut Counters,
) -> SubPath {
    let (_, max_light) = vertex_budgets(params);
    let mut rng = SampleStream::for_sample(params.seed, stream, index, pass, 0);
    light_subpath(scene, tracer, params, max_light, &mut rng, counters)
}
