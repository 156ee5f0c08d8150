//! SPCBPT: subspace-based probabilistic connections (Su, Li, Wang 2022), on top of the
//! LVCBPT iteration ([`super::lvcbpt`]).
//!
//! Eye and light sub-paths are classified by their end vertices into subspaces
//! (κ_E, κ_L: nearest of contribution-sampled centroids under the distance of eq. 18,
//! fitted by decision trees, [`crate::subspace`]). Per iteration M light paths are traced
//! and their cacheable vertices (index ≥ 1, non-Dirac surfaces, and with light-source
//! bins their first vertices) are bucketed by κ_L.
//! Each camera vertex z (t ≥ 2) makes N connections by two-stage sampling (section 6.1):
//! 1. a light subspace l with probability Γ'(l | κ_E(z)), where Γ' is the trained
//!    Γ(· | e) restricted to the subspaces NON-EMPTY in this iteration and renormalised
//!    (an empty subspace can produce nothing; dividing by the unrestricted Γ while
//!    sampling the restricted one is the public code's error);
//! 2. a vertex y of subspace l with probability P_r(y) = f_y/p_y / S_l, S_l the sum of
//!    f/p (RGB sum of the sub-path throughput β) over the subspace's vertices.
//!
//! The resampled estimate of the connection is f(ȲZ̄) / (p(Z̄) p(Ȳ) · N · M · Γ' · P_r):
//! BOTH sub-path pdfs (eq. 10 as printed omits p(Ȳ)); β of each sub-path already holds
//! its f/p, so the code divides the joined value by N·M·Γ'·P_r.
//!
//! MIS (eqs. 11, 12) uses the trained Γ(l | e) itself, NOT the pass's restricted Γ':
//! the weights must be a deterministic function of the path. Which subspaces are empty
//! depends on the pass's light paths, and a connected light vertex always makes its own
//! subspace non-empty while the camera-side strategies of the same path see a random
//! occupancy; with Γ' in the counts the weights of a path sum to one only per pass, not
//! in expectation, and the image is biased (measured: +21 % on the Cornell box with
//! M = 32 light paths over 128 subspaces, `tests/tests/spcbpt_agreement.rs`). The
//! connection ESTIMATE divides by the true (restricted, renormalised) stage-1 pmf, so it
//! stays exact, and an empty subspace is never sampled: no energy is lost.
//!
//! Light-source vertices (section 7.2.1): when every light has a surface (triangles,
//! spheres), about 20 % of the light subspaces are bins of positions on the lights
//! ([`LightSourceBins`]: per light ∝ power, cells of the inverse of its position
//! sampler), each light path's first vertex y₀ is cached in its bin with stage-2 weight
//! Le/p(y₀) ([`cache_weight`]), and s = 1 is a Γ-sampled connection to a cached y₀
//! ([`path::connect_light_source`]) instead of next-event estimation: Γ learns which
//! parts of which lights each eye subspace sees. With a point, spot or infinite light
//! (no position to bin or no surface to connect to) s = 1 stays next-event estimation.
//!
//! MIS counts: the balance heuristic over strategies with counts per camera
//! sample: s = 0 and, without light-source bins, s = 1 (next-event estimation) count 1;
//! with bins s = 1 counts N · Γ(bin(x₀) | κ_E(x₁)) · W₁ / Q(bin), W₁ = Le/p(x₀) (an
//! emitter hit by a camera path is binned exactly like a light path's y₀ there, so all
//! strategies of a path agree); t = 1 (light tracing) M/(W·H); a Γ-connection of split s' counts
//! N · Γ(κ_L(x_{s'−1}) | κ_E(x_{s'})) · W(x₀…x_{s'−1}) / Q(κ_L), the paper's
//! expected-value form of M·p(Ȳ)·Γ·P_r with S_l ≈ M·Q_l (eq. 19) and W the light
//! prefix's f/p. W is recomputed for every split from the path itself ([`light_prefix_weights`];
//! Dirac vertices count 1, no Russian roulette) so that all strategies of one path
//! see the same counts and the weights sum to one exactly. Ratios of the sub-path
//! densities come from BDPT's O(n) walk ([`path::mis::mis_weight_counted`]). The count
//! table is built only for a connection that carries light (nothing for an occluded
//! one), in place from the two sub-paths (no joined copy). Everything of a split that
//! lies on one sub-path is computed once: the labels, prefix-weight factors and
//! N·Γ/Q of the camera sub-path's splits once per camera path ([`CameraLabels`]), the
//! labels, prefix weights and whole counts of every light vertex once per pass
//! ([`PrefixMemo`], with the light paths). A connection then classifies two vertices,
//! evaluates two prefix-weight factors and looks Γ up for the three splits around it;
//! the other entries are reads and one multiplication ([`counts`]). The memos change no
//! count and no pixel (`tests/tests/spcbpt_mis.rs` compares the tables bit for bit).
//!
//! Cross-iteration reuse (section 7.4, [`Retained`]): with M0 > 0 each light subspace k
//! keeps a FIFO of the last M0 of its cacheable vertices (with their light prefixes:
//! the scene is static, so prefixes of older passes stay valid) and stage 2 samples from
//! the retained set. Let M_k(j) be the number of vertices generated in k over passes
//! 1..j (retained or not) and M_r,k the number retained. The light paths are iid, so
//! their order is exchangeable and each generated vertex is retained with probability
//! M_r,k / M_k(j); hence Σ_{y retained} g(y) · M_k(j)/M_r,k estimates Σ_{y generated} g(y)
//! without bias, and that sum over j·M paths estimates j·M times the per-path
//! expectation. A connection to y thus divides by
//! N · j·M · (M_r,k / M_k(j)) · Γ'(k | e) · P_r(y | k)   (`PassCache::effective_paths`
//! holds j·M·M_r,k/M_k(j); without reuse it is M). The paper's eq. 20 carries an extra
//! M_r inside the sum, inconsistent with its own retention probability M_r/M. The MIS
//! counts do not change: S_k over the retained set ≈ (M_r,k/M_k(j))·j·M·Q_k, so
//! j·M·(M_r/M_k)·p(Ȳ)·N·Γ·W/S_k ≈ N·Γ·W/Q_k as before.

pub mod counts;
pub mod model_file;
pub mod oracle;
mod phases;
pub mod prepare;

pub use phases::{Spcbpt, SpcbptReport};

use counts::finite;
pub use counts::{CameraLabels, CameraSplit, Factor, PrefixMemo, counts, light_prefix_weights, memoize_light_path, path_counts, scalar};

use alloc::boxed::Box;
use alloc::collections::VecDeque;
use alloc::vec::Vec;
use core::ops::Range;

use crate::alias::AliasTable;
use crate::geometry::RayQuery;
use crate::math::Vec3;
use crate::path::{self, CacheEntry, LightPaths, LightPointSample, Vertex, VertexKind, Weighted, is_cacheable, trace_light_subpath};
use crate::rng::{SampleStream, Stream};
use crate::scene::{Context, Scene};
use crate::spectrum::Rgb;
use crate::subspace::{DecisionTree, LightSourceBins, SubpathFeature, SubspaceMatrix};
use crate::transport::{Counters, RenderParams, Splat};

/// Vertices of a full path (light end first), bounded like BDPT's sub-paths.
pub type FullPath = heapless::Vec<Vertex, { 2 * path::MAX_VERTICES }>;

/// κ_E and κ_L. Light subspaces 0..`n_light_surface` are the tree's (surface vertices
/// seen from their predecessor); with `sources`, ids `n_light_surface..n_light` are the
/// light-source bins of the light paths' first vertices (section 7.2.1).
#[derive(Clone, Debug)]
pub struct Classifier {
    pub eye: DecisionTree,
    pub light: DecisionTree,
    pub n_eye: u32,
    /// Subspaces of the light tree.
    pub n_light_surface: u32,
    /// Light-source bins, when light-source vertices are cached and Γ-sampled.
    pub sources: Option<LightSourceBins>,
    /// All light subspaces (tree + bins): Γ's row count.
    pub n_light: u32,
}

/// Feature of vertex `v` as a sub-path end whose previous vertex is at `prev`.
#[inline]
pub fn feature(v: &Vertex, prev: Vec3) -> SubpathFeature {
    SubpathFeature::new(v.p, v.frame.n, (prev - v.p).normalize_or_zero())
}

impl Classifier {
    /// `sources` must number its bins from `n_light_surface` on.
    pub fn new(eye: DecisionTree, n_eye: u32, light: DecisionTree, n_light_surface: u32, sources: Option<LightSourceBins>) -> Self {
        let n_light = n_light_surface + sources.as_ref().map_or(0, |b| b.bin_count());
        Self { eye, light, n_eye, n_light_surface, sources, n_light }
    }
    #[inline]
    pub fn eye_of(&self, z: &Vertex, prev: Vec3) -> u32 {
        self.eye.classify(&feature(z, prev)).min(self.n_eye.saturating_sub(1))
    }
    #[inline]
    pub fn light_of(&self, y: &Vertex, prev: Vec3) -> u32 {
        self.light.classify(&feature(y, prev)).min(self.n_light_surface.saturating_sub(1))
    }
    /// The light-source bin of a vertex on a light (a light path's first vertex, or an
    /// emitting surface a camera path hit); `None` without bins or off the lights.
    #[inline]
    pub fn light_source_of(&self, scene: &Scene, y: &Vertex) -> Option<u32> {
        let bins = self.sources.as_ref()?;
        let id = y.light_id()?;
        let light = scene.lights.get(id as usize)?;
        Some(bins.classify(id, light.position_uv(y.p)))
    }
    pub fn size_bytes(&self) -> usize {
        self.eye.size_bytes() + self.light.size_bytes() + self.sources.as_ref().map_or(0, |b| b.size_bytes())
    }
}

/// Light-source bins for SPCBPT, if this scene can use them: `budget` bins (raised to
/// the number of lights) numbered from `first_id`, given to lights ∝ power. Light-source
/// vertices are cached and Γ-sampled (replacing next-event estimation) only when every
/// light has a surface (triangles, spheres): a point or spot light is one Dirac point
/// that NEE already samples exactly, and a light at infinity has no position to cache.
/// `Err` says why not.
pub fn light_source_bins(scene: &Scene, budget: u32, first_id: u32) -> Result<LightSourceBins, &'static str> {
    if budget == 0 {
        return Err("no bins requested");
    }
    if scene.lights.is_empty() {
        return Err("the scene has no lights");
    }
    if !scene.lights.iter().all(|l| l.has_area()) {
        return Err("a light without a surface (point, spot, directional, environment) needs next-event estimation");
    }
    if scene.lights.len() > budget as usize {
        return Err("more emitting triangles than light-source bins");
    }
    let powers: Vec<f32> = scene.lights.iter().map(|l| l.power()).collect();
    Ok(LightSourceBins::new(&powers, budget, first_id))
}

/// Everything preprocessing produces: κ, Q per light subspace, Γ.
#[derive(Clone, Debug)]
pub struct Model {
    pub classifier: Classifier,
    /// Q_l: expected Σ f/p of subspace l's vertices per light path (eq. 19).
    pub q: Vec<f32>,
    pub gamma: SubspaceMatrix,
    /// N.
    pub connections: u32,
}

impl Model {
    /// Are light-source vertices cached and Γ-sampled (s = 1 through the cache instead of
    /// next-event estimation)?
    #[inline]
    pub fn caches_light_sources(&self) -> bool {
        self.classifier.sources.is_some()
    }
}

/// The stage-2 weight f/p of a cached light prefix ending at its last vertex: the
/// sub-path throughput β, or, for a light-source vertex alone (whose β is the emitted
/// radiance), Le / p(y₀) with p(y₀) = light selection × position density (`pdf_fwd`).
#[inline]
pub fn cache_weight(prefix: &[Vertex]) -> f32 {
    match prefix {
        [] => 0.0,
        [y0] => {
            if y0.pdf_fwd.is_positive() {
                finite(scalar(y0.beta) / y0.pdf_fwd.value())
            } else {
                0.0
            }
        }
        [.., last] => finite(scalar(last.beta)),
    }
}

/// Cross-iteration reuse state (section 7.4): per light subspace a FIFO of at most
/// `capacity` (M0) light prefixes ending at a cacheable vertex, and the number of
/// vertices ever generated in the subspace. Updated once per pass, in subspace order and
/// in path order within a subspace (deterministic, independent of the thread count).
#[derive(Debug, Default)]
pub struct Retained {
    /// M0; 0 disables reuse.
    pub capacity: u32,
    pub fifos: Vec<VecDeque<RetainedPrefix>>,
    /// M_k(j): vertices generated in subspace k over the passes so far.
    pub generated: Vec<u64>,
    /// j: passes folded in so far.
    pub passes: u32,
}

/// A retained light prefix y₀…y_{s−1} and its memo.
#[derive(Clone, Debug)]
pub struct RetainedPrefix {
    pub vertices: Box<[Vertex]>,
    pub memo: Box<[PrefixMemo]>,
}

impl Retained {
    pub fn new(capacity: u32) -> Self {
        Self { capacity, ..Self::default() }
    }
    #[inline]
    pub fn enabled(&self) -> bool {
        self.capacity > 0
    }
    pub fn size_bytes(&self) -> usize {
        let per_vertex = core::mem::size_of::<Vertex>() + core::mem::size_of::<PrefixMemo>();
        let prefixes: usize = self
            .fifos
            .iter()
            .map(|f| f.capacity() * core::mem::size_of::<RetainedPrefix>() + f.iter().map(|p| p.vertices.len() * per_vertex).sum::<usize>())
            .sum();
        prefixes + self.fifos.capacity() * core::mem::size_of::<VecDeque<RetainedPrefix>>() + self.generated.capacity() * 8
    }
    /// Fold in one pass whose cacheable vertices are `entries[start[k]..start[k+1]]` for
    /// subspace k (prefixes in `paths`, their memos in `memo`).
    fn push_pass(&mut self, paths: &LightPaths, memo: &[PrefixMemo], entries: &[CacheEntry], start: &[u32]) {
        let n = start.len().saturating_sub(1);
        if self.fifos.len() != n {
            self.fifos = (0..n).map(|_| VecDeque::new()).collect();
            self.generated = alloc::vec![0; n];
        }
        let cap = self.capacity as usize;
        for k in 0..n {
            let bucket = &entries[start[k] as usize..start[k + 1] as usize];
            self.generated[k] += bucket.len() as u64;
            // Only the last `cap` of this pass can survive.
            let skip = bucket.len().saturating_sub(cap);
            let fifo = &mut self.fifos[k];
            for e in &bucket[skip..] {
                if fifo.len() == cap {
                    fifo.pop_front();
                }
                let range = e.start as usize..(e.start + e.s) as usize;
                fifo.push_back(RetainedPrefix { vertices: Box::from(&paths.vertices[range.clone()]), memo: Box::from(&memo[range]) });
            }
        }
        self.passes += 1;
    }
}

/// One iteration's light vertices, bucketed by light subspace, with the tables of the
/// two sampling stages (and, with reuse, the retained vertices of earlier iterations).
#[derive(Debug, Default)]
pub struct PassCache {
    pub paths: LightPaths,
    /// One [`PrefixMemo`] per vertex of `paths` (filled with them by [`trace_light_paths`];
    /// [`build_buckets`] recomputes it if the lengths differ).
    pub memo: Vec<PrefixMemo>,
    /// Cache entries grouped by subspace: subspace l holds `entries[start[l]..start[l+1]]`.
    pub entries: Vec<CacheEntry>,
    pub start: Vec<u32>,
    /// Stage 2 per subspace (None: empty).
    pub vertex_tables: Vec<Option<AliasTable>>,
    /// Stage 1 per eye subspace: Γ(· | e) restricted to non-empty subspaces.
    pub gamma_tables: Vec<Option<AliasTable>>,
    /// Σ over non-empty l of Γ(l | e), per eye subspace (the renormalisation of Γ').
    pub gamma_norm: Vec<f32>,
    /// Cross-iteration reuse; when enabled, stage 2 samples `retained.fifos[l]`.
    pub retained: Retained,
    /// Per subspace, the number of light paths a connection's estimate divides by:
    /// j·M·M_r,k/M_k(j) with reuse, M without.
    pub effective_paths: Vec<f64>,
}

impl PassCache {
    /// An empty cache retaining `reuse` (M0) vertices per subspace across passes
    /// (0: every pass uses only its own light paths).
    pub fn with_reuse(reuse: u32) -> Self {
        Self { retained: Retained::new(reuse), ..Self::default() }
    }
    /// Light prefix (y₀…y_{s−1}) of stage-2 candidate `index` of subspace `l`, and its memo.
    #[inline]
    pub fn candidate(&self, l: usize, index: usize) -> Option<(&[Vertex], &[PrefixMemo])> {
        if self.retained.enabled() {
            self.retained.fifos.get(l)?.get(index).map(|p| (&p.vertices[..], &p.memo[..]))
        } else {
            let entry = self.entries.get(*self.start.get(l)? as usize + index)?;
            let range = entry.start as usize..(entry.start + entry.s) as usize;
            Some((entry.subpath(&self.paths), self.memo.get(range).unwrap_or(&[])))
        }
    }
    #[inline]
    pub fn is_empty_subspace(&self, l: u32) -> bool {
        self.vertex_tables.get(l as usize).is_none_or(|t| t.is_none())
    }
    /// Γ'(l | e): 0 for subspaces empty this iteration.
    #[inline]
    pub fn restricted_gamma(&self, model: &Model, l: u32, e: u32) -> f32 {
        let norm = self.gamma_norm.get(e as usize).copied().unwrap_or(0.0);
        if self.is_empty_subspace(l) || !(norm > 0.0) { 0.0 } else { model.gamma.get(l, e) / norm }
    }
    pub fn size_bytes(&self) -> usize {
        let tables = |t: &Vec<Option<AliasTable>>| {
            t.iter().map(|a| a.as_ref().map_or(0, AliasTable::size_bytes)).sum::<usize>() + t.capacity() * core::mem::size_of::<Option<AliasTable>>()
        };
        self.paths.size_bytes()
            + self.memo.capacity() * core::mem::size_of::<PrefixMemo>()
            + self.entries.capacity() * 8
            + self.start.capacity() * 4
            + tables(&self.vertex_tables)
            + tables(&self.gamma_tables)
            + self.gamma_norm.capacity() * 4
            + self.retained.size_bytes()
            + self.effective_paths.capacity() * 8
    }
}

/// Trace light paths `paths` of pass `pass` into `out` and their vertices' memos into
/// `memo` (both appended; no splats yet: their weights need the iteration's non-empty
/// subspaces).
#[allow(clippy::too_many_arguments)]
pub fn trace_light_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    model: &Model,
    pass: u32,
    paths: Range<u32>,
    out: &mut LightPaths,
    memo: &mut Vec<PrefixMemo>,
) -> Counters {
    let mut counters = Counters::default();
    for index in paths {
        let light = trace_light_subpath(scene, tracer, params, Stream::Light, index, pass, &mut counters);
        out.push(&light);
        memoize_light_path(scene, model, &light, memo);
    }
    counters
}

/// Bucket the cacheable vertices of `cache.paths` by κ_L and build the stage-2 tables.
pub fn build_buckets(scene: &Scene, model: &Model, cache: &mut PassCache) {
    let n_light = model.classifier.n_light as usize;
    if cache.memo.len() != cache.paths.vertices.len() {
        cache.memo.clear();
        for i in 0..cache.paths.len() {
            memoize_light_path(scene, model, cache.paths.path(i), &mut cache.memo);
        }
    }
    let mut labelled: Vec<(u32, CacheEntry)> = Vec::new();
    for i in 0..cache.paths.len() {
        let start = cache.paths.starts[i];
        let path = cache.paths.path(i);
        let memo = &cache.memo[start as usize..start as usize + path.len()];
        // y₀ has a label only when it goes to a light-source bin (a light path may also
        // be empty: its emission sample failed).
        if let Some(y0) = memo.first().filter(|m| m.light != u32::MAX) {
            labelled.push((y0.light, CacheEntry { start, s: 1 }));
        }
        for k in 1..path.len() {
            if is_cacheable(scene, &path[k]) {
                labelled.push((memo[k].light, CacheEntry { start, s: k as u32 + 1 }));
            }
        }
    }
    // Stable counting sort by subspace.
    cache.start.clear();
    cache.start.resize(n_light + 1, 0);
    for (l, _) in &labelled {
        cache.start[*l as usize + 1] += 1;
    }
    for l in 0..n_light {
        cache.start[l + 1] += cache.start[l];
    }
    let mut fill = cache.start.clone();
    cache.entries.clear();
    cache.entries.resize(labelled.len(), CacheEntry { start: 0, s: 0 });
    for (l, e) in labelled {
        cache.entries[fill[l as usize] as usize] = e;
        fill[l as usize] += 1;
    }
    cache.vertex_tables.clear();
    cache.effective_paths.clear();
    let light_paths = cache.paths.len() as f64;
    let mut weights: Vec<f32> = Vec::new();
    if cache.retained.enabled() {
        cache.retained.push_pass(&cache.paths, &cache.memo, &cache.entries, &cache.start);
        let r = &cache.retained;
        for l in 0..n_light {
            weights.clear();
            weights.extend(r.fifos[l].iter().map(|p| cache_weight(&p.vertices)));
            cache.vertex_tables.push(AliasTable::new(&weights));
            let (kept, generated) = (r.fifos[l].len() as f64, r.generated[l] as f64);
            cache.effective_paths.push(if kept > 0.0 { r.passes as f64 * light_paths * kept / generated } else { 0.0 });
        }
    } else {
        for l in 0..n_light {
            let bucket = &cache.entries[cache.start[l] as usize..cache.start[l + 1] as usize];
            weights.clear();
            weights.extend(bucket.iter().map(|e| cache_weight(e.subpath(&cache.paths))));
            cache.vertex_tables.push(AliasTable::new(&weights));
            cache.effective_paths.push(light_paths);
        }
    }
}

/// Stage-1 tables for eye subspaces `eyes` into `tables` / `norms` (one slot each).
pub fn build_gamma_tables(model: &Model, cache: &PassCache, eyes: Range<u32>, tables: &mut [Option<AliasTable>], norms: &mut [f32]) {
    let mut weights: Vec<f32> = Vec::new();
    for ((e, table), norm) in eyes.zip(tables.iter_mut()).zip(norms.iter_mut()) {
        weights.clear();
        weights.extend(model.gamma.column(e).iter().enumerate().map(|(l, &g)| if cache.is_empty_subspace(l as u32) { 0.0 } else { g }));
        *norm = weights.iter().map(|&w| w as f64).sum::<f64>() as f32;
        *table = AliasTable::new(&weights);
    }
}

/// Join sub-paths into a full path, light end first (`sampled` replaces an endpoint). The
/// render loop does not join ([`counts`] reads the sub-paths in place); the training set
/// and the tests do.
pub fn join(light: &[Vertex], camera: &[Vertex], sampled: Option<Vertex>, s: usize, t: usize) -> FullPath {
    let mut x = FullPath::new();
    for i in 0..s {
        let v = match sampled {
            Some(v) if s == 1 && i == 0 => Some(v),
            _ => light.get(i).copied(),
        };
        if let Some(v) = v {
            let _ = x.push(v);
        }
    }
    for i in (0..t).rev() {
        let v = match sampled {
            Some(v) if t == 1 && i == 0 => Some(v),
            _ => camera.get(i).copied(),
        };
        if let Some(v) = v {
            let _ = x.push(v);
        }
    }
    x
}

/// What SPCBPT's strategies read: the scene and ray queries, the model, and the light
/// tracing strategy's count M/(W·H).
#[derive(Debug)]
pub struct Strategies<'a, Q: ?Sized> {
    /// Scene and ray queries.
    pub ctx: Context<'a, Q>,
    /// κ, Q, Γ.
    pub model: &'a Model,
    /// M/(W·H).
    pub light_tracing: f64,
}

impl<Q: RayQuery + ?Sized> Strategies<'_, Q> {
    /// Strategy (s, t) with SPCBPT's MIS weight (`value` weighted, not divided by any
    /// selection probability); `sampled` is the resampled endpoint (s = 1 or t = 1).
    pub fn evaluate(&self, light: &[Vertex], camera: &[Vertex], s: usize, t: usize, u: LightPointSample, counters: &mut Counters) -> Option<Weighted> {
        self.evaluate_labelled(light, camera, None, &[], s, t, u, counters)
    }

    /// [`Self::evaluate`] with the camera sub-path's precomputed labels (`camera` must be
    /// a prefix of the path the labels were computed on) and the light prefix's memo
    /// (`light_memo`, one entry per vertex of `light[..s]`; ignored unless it has exactly
    /// s entries).
    ///
    /// Connecting and weighting are separate steps: the connection gives the unweighted
    /// f/p and the resampled endpoint; only a connection that carries light pays for the
    /// path's count table (an occluded or black one costs none), and the weight is one
    /// MIS walk with those counts.
    pub fn evaluate_labelled(
        &self,
        light: &[Vertex],
        camera: &[Vertex],
        labels: Option<&CameraLabels>,
        light_memo: &[PrefixMemo],
        s: usize,
        t: usize,
        u: LightPointSample,
        counters: &mut Counters,
    ) -> Option<Weighted> {
        let (scene, model) = (self.ctx.scene, self.model);
        let c = connect_unweighted(&self.ctx, model, light, camera, s, t, u, counters)?;
        // The memo describes light[..s]; a resampled light endpoint (NEE) is not in it.
        let memo_applies = light_memo.len() == s && (s != 1 || cached_source(model, light, s));
        // The full path: the sub-paths as they are, a resampled endpoint replacing its own.
        let one: [Vertex; 1];
        let (light, camera) = (light.get(..s).unwrap_or(light), camera.get(..t).unwrap_or(camera));
        let (light_x, camera_x) = match c.sampled {
            Some(v) if s == 1 => {
                one = [v];
                (&one[..], camera)
            }
            Some(v) if t == 1 => {
                one = [v];
                (light, &one[..])
            }
            _ => (light, camera),
        };
        let mut table = [0.0f64; 2 * path::MAX_VERTICES + 1];
        counts(scene, model, self.light_tracing, light_x, if memo_applies { light_memo } else { &[] }, camera_x, labels, &mut table);
        let count = |s2: usize, _t2: usize| table.get(s2).copied().unwrap_or(0.0);
        let weight = path::mis::mis_weight_counted(scene, light, camera, c.sampled.as_ref(), s, t, &count);
        Some(c.weighted(weight))
    }
}

/// Splat the t = 1 strategies of light paths `paths` (indices into `cache.paths`) to
/// `splat`; the host scales by 1/M.
pub fn splat_light_paths<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    model: &Model,
    cache: &PassCache,
    light_tracing: f64,
    pass: u32,
    paths: Range<u32>,
    splat: &mut dyn FnMut(Splat),
) -> Counters {
    let mut counters = Counters::default();
    let strategies = Strategies { ctx: Context { scene, tracer }, model, light_tracing };
    for i in paths {
        let light = cache.paths.path(i as usize);
        let start = cache.paths.starts[i as usize] as usize;
        let memo = cache.memo.get(start..start + light.len()).unwrap_or(&[]);
        let mut lens = crate::camera::lens_stream(params.seed, i, pass);
        for s in 2..=light.len() {
            if !params.max_depth.allows(s as u32) {
                break;
            }
            let u = LightPointSample::lens(&scene.camera, &mut lens);
            let c = strategies.evaluate_labelled(&light[..s], &[], None, memo.get(..s).unwrap_or(&[]), s, 1, u, &mut counters);
            if let Some(Weighted { value, film: Some(film), .. }) = c {
                splat(Splat { film, value: counters.sanitize(value) });
            }
        }
    }
    counters
}

/// Is strategy s = 1 on `light` the light path's own first vertex (a cached light-source
/// vertex, s = 1 through the cache) rather than a fresh light sample?
#[inline]
fn cached_source(model: &Model, light: &[Vertex], s: usize) -> bool {
    s == 1 && light.len() == 1 && model.caches_light_sources()
}

/// Connect strategy (s, t) without its MIS weight: a cached light-source vertex through
/// [`path::connect_light_source`], anything else through [`path::connect`] (`u` drives
/// a fresh light sample for s = 1 by next-event estimation). The renderer and the oracle
/// diagnostic connect through this one function.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn connect_unweighted<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    model: &Model,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    u: LightPointSample,
    counters: &mut Counters,
) -> Option<path::Connection> {
    if cached_source(model, light, s) {
        path::connect_light_source(ctx, &light[0], camera, t, counters)
    } else {
        path::connect(ctx, light, camera, s, t, u, counters)
    }
}

/// One of the N two-stage draws of an eye vertex whose stage-1 table is `stage1`
/// (eq. 9): the light subspace, the candidate light prefix and its memo, and the
/// probability N · M_eff · Γ'(l | e) · P_r(y | l) its connection divides by.
#[derive(Clone, Copy, Debug)]
pub struct Draw<'a> {
    pub subspace: usize,
    pub light: &'a [Vertex],
    pub memo: &'a [PrefixMemo],
    pub probability: f32,
}

/// Draw a light sub-path for one connection from `u1` (stage 1) and `u2` (stage 2);
/// `None` where the chosen subspace or candidate is missing or the probability is not
/// positive. The renderer and the oracle diagnostic draw through this one function.
#[inline]
pub fn draw<'a>(model: &Model, cache: &'a PassCache, stage1: &AliasTable, u1: f32, u2: f32) -> Option<Draw<'a>> {
    let pick = stage1.sample(u1);
    let stage2 = cache.vertex_tables.get(pick.index)?.as_ref()?;
    let chosen = stage2.sample(u2);
    let (light, memo) = cache.candidate(pick.index, chosen.index)?;
    let paths = cache.effective_paths.get(pick.index).copied().unwrap_or(0.0) as f32;
    let probability = model.connections as f32 * paths * pick.pmf * chosen.pmf;
    (probability > 0.0).then_some(Draw { subspace: pick.index, light, memo, probability })
}

/// One SPCBPT sample for each pixel of `pixels` into `out` (t ≥ 2 strategies).
pub fn render_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    model: &Model,
    cache: &PassCache,
    light_paths: u32,
    pass: u32,
    pixels: Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    let n_pixels = width * scene.camera.height().max(1);
    let light_tracing = light_paths as f64 / n_pixels as f64;
    let strategies = Strategies { ctx: Context { scene, tracer }, model, light_tracing };
    let (max_camera, _) = path::vertex_budgets(params);
    for (slot, pixel) in out.iter_mut().zip(pixels) {
        let camera = path::pixel_camera_subpath(scene, tracer, params, pixel, pass, max_camera, &mut counters);
        let labels = CameraLabels::new(scene, model, &camera);
        let mut aux = SampleStream::for_sample(params.seed, Stream::Aux, pixel, pass, 0);
        let mut l = Rgb::ZERO;
        for t in 2..=camera.len() {
            if !params.max_depth.allows(t as u32 - 1) {
                break;
            }
            for s in 0..=1usize {
                let (u_light, u_point) = (aux.next_f32(), aux.next_2d());
                // s = 1 comes from the cache's light-source bins when the model has them.
                if s == 1 && (!params.max_depth.allows(t as u32) || model.caches_light_sources()) {
                    continue;
                }
                if let Some(c) = strategies.evaluate_labelled(&[], &camera[..t], Some(&labels), &[], s, t, LightPointSample { u_light, u_point }, &mut counters)
                {
                    l += counters.sanitize(c.value);
                }
            }
            let z = &camera[t - 1];
            if z.kind != VertexKind::Surface || !z.is_connectible(scene) {
                continue;
            }
            let e = labels.eye.get(t - 1).copied().unwrap_or(u32::MAX);
            let Some(Some(stage1)) = cache.gamma_tables.get(e as usize) else { continue };
            for _ in 0..model.connections {
                let (u1, u2) = (aux.next_f32(), aux.next_f32());
                let Some(Draw { light, memo, probability, .. }) = draw(model, cache, stage1, u1, u2) else { continue };
                let s = light.len();
                if !params.max_depth.allows((s + t - 1) as u32) {
                    continue;
                }
                if let Some(c) = strategies.evaluate_labelled(light, &camera[..t], Some(&labels), memo, s, t, LightPointSample::default(), &mut counters) {
                    l += counters.sanitize(c.value / probability);
                }
            }
        }
        *slot = l;
    }
    counters
}
