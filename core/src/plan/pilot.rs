//! The plan's pilot: a few thousand camera and light sub-paths, measuring what the
//! scene description cannot say.
//!
//! Sample `i` of `n` takes one camera sub-path through pixel ⌊i·P/n⌋ (P pixels, so the
//! samples spread over the image) and one light sub-path, both from the render's seed
//! on a pass index no render uses ([`PILOT_PASS`]). It counts:
//!
//! - camera rays that reach an emitter before any non-Dirac vertex (emitters seen
//!   directly or through glass and mirrors);
//! - connections: every non-Dirac camera vertex is joined to one light vertex chosen
//!   uniformly from the cacheable vertices of the sample's light path (LVCBPT's
//!   uniform choice), and a connection whose shadow ray is blocked is occluded;
//! - light samples: next-event estimation at every non-Dirac camera vertex (the s = 1
//!   strategies of the BDPT sample below), occluded or not;
//! - energy by technique and by path length: the sample is also a BDPT sample (every
//!   (s, t) strategy of the two sub-paths, balance-heuristic weights), and each
//!   weighted contribution's luminance goes to its technique (emission s = 0, light
//!   sample s = 1, light tracing t = 1, connection s, t ≥ 2) and to its length in
//!   segments. Per sample these estimate the image mean: a camera-side value as it is,
//!   a t = 1 splat over the W·H light paths a BDPT pass has. The shadow rays of each
//!   technique are counted too: the cost the core can see without a clock.
//!
//! A connection or light sample with zero throughput before visibility traces no ray
//! and is not counted. The function is over an index range, so hosts chunk it like any
//! phase; the counts of chunks sum the same in any order, the energies when summed in
//! chunk order.

use core::ops::AddAssign;
#[cfg(feature = "path")]
use core::ops::Range;

#[cfg(feature = "path")]
use crate::geometry::RayQuery;
#[cfg(feature = "path")]
use crate::path::{self, LightPointSample, is_cacheable, trace_light_subpath, vertex_budgets};
#[cfg(feature = "path")]
use crate::rng::{SampleStream, Stream};
#[cfg(feature = "path")]
use crate::scene::Context;
#[cfg(feature = "path")]
use crate::transport::{Counters, RenderParams};

/// The pass index the pilot's random streams use (no render reaches it).
pub const PILOT_PASS: u32 = u32::MAX - 7;
/// Pilot samples by default.
pub const DEFAULT_SAMPLES: u32 = 4096;

/// The techniques the energy is split by.
pub const TECHNIQUES: [&str; 4] = ["emission", "light samples", "light tracing", "connections"];
/// Path lengths the energy is split by: 1, 2, …, the last bucket holding all longer ones.
pub const LENGTHS: usize = 8;

/// What the pilot counted.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PilotStats {
    /// Camera and light sub-path pairs.
    pub samples: u64,
    /// Camera rays that reached an emitter before a non-Dirac vertex.
    pub emitter_seen: u64,
    /// Connections tried (a shadow ray traced).
    pub connections: u64,
    /// Of them, occluded.
    pub occluded: u64,
    /// Light samples tried (a shadow ray traced).
    pub light_samples: u64,
    /// Of them, occluded.
    pub light_samples_occluded: u64,
    /// Rays traced.
    pub rays: u64,
    /// Σ luminance of the weighted BDPT contributions per technique ([`TECHNIQUES`]),
    /// as image-mean estimates.
    pub energy: [f64; 4],
    /// The same per path length in segments (1 … [`LENGTHS`], the last: longer).
    pub energy_by_length: [f64; LENGTHS],
    /// Shadow rays per technique.
    pub shadow_rays: [u64; 4],
}

impl PilotStats {
    /// Share of connections occluded (0 without any).
    pub fn occluded_share(&self) -> f64 {
        if self.connections == 0 { 0.0 } else { self.occluded as f64 / self.connections as f64 }
    }
    /// Share of light samples occluded (0 without any).
    pub fn light_sample_occluded_share(&self) -> f64 {
        if self.light_samples == 0 { 0.0 } else { self.light_samples_occluded as f64 / self.light_samples as f64 }
    }
    /// The shares of the energy per technique (zeros without energy).
    pub fn technique_shares(&self) -> [f64; 4] {
        let total: f64 = self.energy.iter().sum();
        self.energy.map(|e| if total > 0.0 { e / total } else { 0.0 })
    }
    /// The shares of the energy per path length.
    pub fn length_shares(&self) -> [f64; LENGTHS] {
        let total: f64 = self.energy_by_length.iter().sum();
        self.energy_by_length.map(|e| if total > 0.0 { e / total } else { 0.0 })
    }
    /// Share of camera rays that saw an emitter directly.
    pub fn emitter_seen_share(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.emitter_seen as f64 / self.samples as f64 }
    }
}

impl AddAssign for PilotStats {
    fn add_assign(&mut self, o: Self) {
        self.samples += o.samples;
        self.emitter_seen += o.emitter_seen;
        self.connections += o.connections;
        self.occluded += o.occluded;
        self.light_samples += o.light_samples;
        self.light_samples_occluded += o.light_samples_occluded;
        self.rays += o.rays;
        for k in 0..4 {
            self.energy[k] += o.energy[k];
            self.shadow_rays[k] += o.shadow_rays[k];
        }
        for k in 0..LENGTHS {
            self.energy_by_length[k] += o.energy_by_length[k];
        }
    }
}

/// Run pilot samples `samples` of `total` (see the module notes). Needs the `path`
/// feature (any bidirectional family); without it the plan decides from the facts alone.
#[cfg(feature = "path")]
pub fn map<Q: RayQuery + ?Sized>(ctx: &Context<'_, Q>, params: &RenderParams, samples: Range<u32>, total: u32) -> PilotStats {
    let scene = ctx.scene;
    let camera = &scene.camera;
    let pixels = (camera.width() as u64 * camera.height() as u64).max(1);
    let (max_camera, _) = vertex_budgets(params);
    let mut stats = PilotStats::default();
    let mut counters = Counters::default();
    for i in samples {
        let pixel = ((i as u64 * pixels) / total.max(1) as u64).min(pixels - 1) as u32;
        let cam = path::pixel_camera_subpath(scene, ctx.tracer, params, pixel, PILOT_PASS, max_camera, &mut counters);
        let light = trace_light_subpath(scene, ctx.tracer, params, Stream::Light, i, PILOT_PASS, &mut counters);
        stats.samples += 1;
        for v in cam.iter().skip(1) {
            if v.is_light() {
                stats.emitter_seen += 1;
                break;
            }
            if v.is_connectible(scene) {
                break;
            }
        }
        bdpt_energy(ctx, params, &light, &cam, i, pixels, &mut stats, &mut counters);
        let cacheable: heapless::Vec<usize, { path::MAX_VERTICES }> = (1..light.len()).filter(|&k| is_cacheable(scene, &light[k])).collect();
        let mut rng = SampleStream::for_sample(params.seed, Stream::Aux, i, 0, PILOT_PASS);
        for t in 2..=cam.len() {
            let pick = rng.next_f32();
            if cacheable.is_empty() || !cam[t - 1].is_connectible(scene) || cam[t - 1].kind != path::VertexKind::Surface {
                continue;
            }
            // One uniformly chosen cached light vertex (s ≥ 2).
            let k = cacheable[((pick * cacheable.len() as f32) as usize).min(cacheable.len() - 1)];
            let before = counters.rays;
            let hit = path::connect(ctx, &light[..=k], &cam, k + 1, t, LightPointSample::default(), &mut counters).is_some();
            if counters.rays > before {
                stats.connections += 1;
                stats.occluded += u64::from(!hit);
            }
        }
    }
    stats.rays = counters.rays;
    stats
}

/// Sample `i`'s BDPT strategies, weighted, into `stats`' energies, with its light samples' occlusion (module notes).
#[cfg(feature = "path")]
#[allow(clippy::too_many_arguments)]
fn bdpt_energy<Q: RayQuery + ?Sized>(
    ctx: &Context<'_, Q>,
    params: &RenderParams,
    light: &[path::Vertex],
    cam: &[path::Vertex],
    i: u32,
    pixels: u64,
    stats: &mut PilotStats,
    counters: &mut Counters,
) {
    let mut rng = SampleStream::for_sample(params.seed, Stream::Aux, i, 1, PILOT_PASS);
    for t in 1..=cam.len() {
        for s in 0..=light.len() {
            let segments = s + t - 1;
            if (s == 1 && t == 1) || segments < 1 || !params.max_depth.allows(segments as u32) {
                continue;
            }
            let technique = match (s, t) {
                (0, _) => 0,
                (1, _) => 1,
                (_, 1) => 2,
                _ => 3,
            };
            let u = LightPointSample { u_light: rng.next_f32(), u_point: rng.next_2d() };
            let before = counters.rays;
            let c = path::connect(ctx, light, cam, s, t, u, counters);
            let traced = counters.rays - before;
            stats.shadow_rays[technique] += traced;
            // The light samples' occlusion is read off next-event estimation here, where
            // the strategy traces its ray anyway.
            if s == 1 && traced > 0 {
                stats.light_samples += 1;
                stats.light_samples_occluded += u64::from(c.is_none());
            }
            let Some(c) = c else { continue };
            let weight = path::mis::mis_weight(ctx.scene, light, cam, c.sampled.as_ref(), s, t);
            let mut e = c.weighted(weight).value.luminance() as f64;
            if !e.is_finite() || e < 0.0 {
                continue;
            }
            if c.film.is_some() {
                e /= pixels as f64;
            }
            stats.energy[technique] += e;
            stats.energy_by_length[(segments - 1).min(LENGTHS - 1)] += e;
        }
    }
}
