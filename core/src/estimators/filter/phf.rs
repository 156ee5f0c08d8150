//! Photon filtering (PhF): the light-side counterpart of [`super::mvf`], recursive MMIS
//! over segments sampled sequentially from the lights (West et al. 2022, §6; Wang et al.
//! 2025, §5), then photon density estimation at the first non-Dirac camera vertex.
//!
//! Each light node u carries A(u), the flux arriving along its segment: the emission's
//! β₀ / N_L for a first hit, and for a segment s = (w, u) continuing node w
//! ([`super::weights::Neighbourhood::light_row`])
//!
//!   A(u) = |n_w·ŝ| / D(s) · Σ_{u'} K(w → u') f_r(u'; ŝ, −ŝ_{u'}) A(u'),
//!
//! every segment arriving in w's kernel continued by s, D(s) summing the continuations
//! conditioned on every node whose kernel covers w (the same denominators as MVF's,
//! without light samples). The BSDF is the one where the reused segment arrives, at u'
//! (its frame, its material), as MVF's rows take the BSDF of the node whose arrival they
//! keep (eq. 6: f_r at the end y_i of the arriving segment). Taken at w instead, it is
//! the lobe that drew ŝ: where neighbours' lobes do not overlap w's (a glossy surface
//! curving within the kernel), D(s) holds little more than w's own technique while every
//! arrival in the kernel meets that lobe, and the flux leaving w was counted once per
//! arrival (spot_mirror's walls 45× too bright; `host-cli/tests/filter_scenes.rs`).
//!
//! A camera vertex c then gathers Σ_u K(c → u) f_r(c; ω_o, −ŝ_u) A(u) / ∫K, the last kernel of the segment path,
//! normalised over the part of the disk that lies on surfaces (16 stratified rays):
//! without it the estimate falls short within r of every edge, PPM's boundary bias.
//! Both kernels are the same disk, shrinking over passes (the reuse kernels appear in
//! ratios, numerator and denominators alike, and need no normalisation).
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `footprint` | W·H pixels (none unless r₀ is in pixel footprints) | mean footprint → r₀ |
//! | pass 0 | `light paths` | N_L = W·H | nodes appended, grid built for r_pass |
//! | pass 1 | `denominators` | nodes | D of each node's continuation |
//! | pass 2 | `filter` | nodes | rows appended; A₀ = base flux |
//! | pass 3 … 2 + d | `propagate` | nodes | A_i from A_{i−1} |
//! | pass 3 + d | `camera` | W·H | camera samples staged; pass committed (factor 1) |
//!
//! d = (segments per path) − 2 sweeps: the camera's segment and the light path's first
//! are not filtered. The camera side follows Dirac and near-specular bounces to the first
//! other vertex, as progressive photon mapping does (`gather_pixels`).

use super::nodes::{near_specular, scale_kernels, trace_light_nodes};
use super::pass::{CHUNK, FilterPass, node_chunk, phase};
use crate::bsdf::TransportMode;
use crate::camera::CameraPass;
use crate::estimators::FilterConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::merge::progressive_radius;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage};
use crate::rng::{SampleStream, Stream};
use crate::scene::Scene;
use crate::segment::Kernel;
use crate::spectrum::Rgb;
use crate::transport::walk::{Layout, Leave, PathState, Roulette, Walk, emitted, environment};
use crate::transport::{Counters, RenderParams, SurfacePoint};

/// The camera side's walk: radiance, the lobe and direction of each bounce next in the
/// stream after the primary ray's numbers, no roulette (it ends at its first diffuse vertex).
const CAMERA_WALK: Walk = Walk { mode: TransportMode::Radiance, layout: Layout { per_bounce: 3, light: 0, lobe: 0, roulette: 0 } };
/// Dirac bounces the camera side follows at most.
const MAX_CAMERA_BOUNCES: u32 = 16;
/// Rays per side of the stratified estimate of the gather kernel's surface share.
const SHARE_STRATA: u32 = 4;
/// Last key of that estimate's random stream (`Stream::Aux`, index = pixel).
const GATHER_SHARE_KEY: u32 = 0x5f00;

/// Photon filtering configured for one film, with the current pass's light nodes.
#[derive(Clone, Debug)]
pub struct Phf {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: FilterConfig,
    /// r₀ (set by the setup phase).
    pub r0: f32,
    /// Segments per path (camera segment included).
    pub segments: u32,
    pixels: u32,
    /// The pass's light nodes (`links`: each node's predecessor; `values`: base flux).
    pub pass: FilterPass,
    sweeps: u8,
    cursor: Cursor,
}

impl Phf {
    /// The estimator for a film of `pixels` pixels (r₀ is set by the setup phase).
    pub fn new(params: RenderParams, config: FilterConfig, pixels: u32) -> Self {
        let segments = config.segments(params.max_depth);
        let sweeps = segments.saturating_sub(2) as u8;
        Self { params, config, r0: 0.0, segments, pixels, pass: FilterPass::with_links_per_node(), sweeps, cursor: Cursor::new(1, 4 + sweeps) }
    }

    /// The kernel radius of global pass `pass`.
    pub fn radius(&self, pass: u32) -> f32 {
        progressive_radius(self.r0, self.config.alpha, pass)
    }

    /// Light paths per pass, N_L.
    pub fn light_paths(&self) -> u32 {
        self.pixels.max(1)
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Phf {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let (nodes, paths) = (self.pass.nodes.len() as u32, self.light_paths());
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let items = if self.config.radius.needs_footprint() { self.pixels } else { 0 };
                Phase { name: "footprint", id: phase::FOOTPRINT, pass: None, items, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, 0) => Phase { name: "light paths", id: phase::PATHS, pass: Some(pass), items: self.light_paths(), chunk: CHUNK, samples: true },
            Stage::Pass(pass, 1) => {
                Phase { name: "denominators", id: phase::DENOMINATORS, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false }
            }
            Stage::Pass(pass, 2) => Phase { name: "filter", id: phase::ROWS, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false },
            Stage::Pass(pass, i) if i < 3 + self.sweeps => {
                Phase { name: "propagate", id: i + 1, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false }
            }
            Stage::Pass(pass, i) => Phase { name: "camera", id: i + 1, pass: Some(pass), items: self.pixels, chunk: CHUNK, samples: false },
        })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer) = (ctx.scene, ctx.tracer);
        let items = out.items.clone();
        if phase.id == phase::FOOTPRINT {
            crate::estimators::map_footprint(scene, tracer, out);
            return;
        }
        let Some(pass) = phase.pass else { return };
        let range = items.start as usize..items.end as usize;
        if phase.id == phase::FIRST_SWEEP + self.sweeps {
            out.counters = gather_pixels(scene, tracer, &self.params, self.config.glossy_alpha, &self.pass, pass, items, out.pixel_buffer());
            return;
        }
        let chunk = out.data.filter_chunk();
        match phase.id {
            phase::PATHS => {
                let c = trace_light_nodes(
                    scene,
                    tracer,
                    &self.params,
                    self.segments,
                    self.light_paths(),
                    pass,
                    items,
                    false,
                    false,
                    &mut chunk.nodes,
                    &mut chunk.links,
                    &mut chunk.values,
                );
                scale_kernels(scene, self.config.glossy_alpha, &mut chunk.nodes);
                out.counters = c;
            }
            phase::DENOMINATORS => self.pass.map_denominators(scene, range, &mut chunk.dens, |hood, i| hood.denominators(i)),
            phase::ROWS => {
                self.pass.map_rows(scene, range, chunk, |hood, u, pairs| hood.light_row::<f32>(self.pass.links[u], self.pass.values[u], &self.pass.dens, pairs))
            }
            _ => self.pass.map_sweep(range, chunk),
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match phase.id {
            phase::FOOTPRINT => self.r0 = self.config.radius.initial_radius(ctx.scene, &crate::estimators::reduce_footprint(outputs)),
            id if id == phase::FIRST_SWEEP + self.sweeps => {
                for out in outputs.iter() {
                    film.set_camera_samples(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
                }
            }
            id => {
                self.pass.reduce_phase(id, outputs, self.radius(phase.pass.unwrap_or(0)), self.config.neighbours);
                if id == phase::DENOMINATORS {
                    // Each row where its kernel lies: at the node's predecessor.
                    self.pass.order_rows(0..self.pass.nodes.len(), |pass, v| pass.links[v]);
                }
            }
        }
        // Before the gather: its kernel keeps the progressive radius (the neighbour
        // budget bounds the cost of the rows only; the gather is linear in photons).
        if phase.id == 3 + self.sweeps {
            self.pass.rebuild_grid(self.radius(phase.pass.unwrap_or(0)));
        }
        if self.cursor.advance() {
            film.end_pass(1.0);
        }
    }
}

/// The camera side: for each pixel, the camera ray through Dirac and near-specular
/// bounces to the first other vertex c, its emission there and Σ_u K(c → u) f_r(c) A(u)
/// over the light nodes in c's kernel.
///
/// A near-specular vertex (microfacet roughness below `glossy_alpha`: `nodes::near_specular`,
/// the rule that narrows the reuse kernels) is passed through like a Dirac one, as SPPM passes
/// glossy surfaces: a density estimate there multiplies each photon by a lobe of height
/// ~1/α², and on veach-mis's α = 0.01 plate a few photons made the image's fireflies.
/// Light reaching it from an area or infinite light is found by the BSDF sample hitting
/// the light (counted with weight 1, as after a Dirac bounce: nothing else estimates it);
/// from a Dirac light, which no sample can hit, by next-event estimation to every Dirac
/// light ([`dirac_light_at`]).
#[allow(clippy::too_many_arguments)]
fn gather_pixels<Q: RayQuery + ?Sized>(
    scene: &Scene,
    tracer: &Q,
    params: &RenderParams,
    glossy_alpha: f32,
    pass_data: &FilterPass,
    pass: u32,
    pixels: core::ops::Range<u32>,
    out: &mut [Rgb],
) -> Counters {
    let mut counters = Counters::default();
    let width = scene.camera.width().max(1);
    let kernel = Kernel::Disk { radius: pass_data.r };
    for (slot, pixel) in out.iter_mut().zip(pixels) {
        let mut rng = SampleStream::for_sample(params.seed, Stream::Camera, pixel, pass, 0);
        let Some(primary) = scene.camera.sample_ray(pixel % width, pixel / width, &mut rng) else {
            *slot = Rgb::ZERO;
            continue;
        };
        // The film applies the pixel filter (`render::Film`): the throughput starts at 1.
        let first_dim = rng.dimension();
        let mut path = PathState::new(primary.ray, Rgb::ONE, first_dim);
        let mut l = Rgb::ZERO;
        while params.max_depth.allows(path.segments) && path.segments <= MAX_CAMERA_BOUNCES {
            let Some(hit) = CAMERA_WALK.trace(tracer, &path, &mut counters) else {
                l += path.beta * environment(scene, path.ray.dir);
                break;
            };
            // Attenuate by an absorbing medium the segment crossed.
            Walk::pass_medium(scene, &mut path, &hit);
            let sp = SurfacePoint::new(hit, -path.ray.dir);
            if hit.emitter.is_some() {
                l += path.beta * emitted(scene, &hit, sp.wo);
            }
            let material = sp.material(scene);
            let pass_through = near_specular(&material, glossy_alpha).is_some();
            if !material.is_delta() && !pass_through {
                // The gather adds the light path's segments (at least one).
                if params.max_depth.allows(path.segments + 1) {
                    l += path.beta * gather(tracer, pass_data, &kernel, &sp, &material, params.seed, pixel, pass, &mut counters);
                }
                break;
            }
            if pass_through && params.max_depth.allows(path.segments + 1) {
                l += path.beta * dirac_light_at(scene, tracer, &sp, &material, &mut counters);
            }
            let Leave::Continues(_) = CAMERA_WALK.scatter(params, &mut path, &sp, sp.frame.to_local(sp.wo), &material, None, Roulette::Never, &mut rng) else {
                break;
            };
        }
        *slot = counters.sanitize(l);
    }
    counters
}

/// Σ over the Dirac lights (point, spot, directional) of f_r |cos| L / p at `sp`: their
/// direct light, which a BSDF sample cannot find.
fn dirac_light_at<Q: RayQuery + ?Sized>(scene: &Scene, tracer: &Q, sp: &SurfacePoint, material: &crate::bsdf::Material, counters: &mut Counters) -> Rgb {
    let wo = sp.frame.to_local(sp.wo);
    let mut l = Rgb::ZERO;
    for light in scene.lights.iter().filter(|light| light.is_delta()) {
        let Some(ls) = light.sample_li(sp.reflection_origin(), crate::math::Vec2::ZERO) else { continue };
        if !ls.pdf.is_positive() || ls.radiance.is_black() {
            continue;
        }
        let wi = sp.frame.to_local(ls.wi);
        let f = material.eval(wo, wi, TransportMode::Radiance);
        if f.is_black() {
            continue;
        }
        counters.rays += 1;
        let shadow = if ls.dist.is_finite() { sp.spawn_to(ls.p, ls.n) } else { sp.spawn(ls.wi) };
        if !tracer.occluded(&shadow) {
            // Across an absorbing medium (a rough dielectric's interior), T.
            let tr = scene.transmittance_to(ls.p, sp.hit.p, sp.hit.ng, sp.hit.material).unwrap_or(Rgb::ONE);
            l += f * ls.radiance * tr * (wi.z.abs() / ls.pdf.0);
        }
    }
    l
}

/// Σ_u K(c → u) f_r(c) A(u) / ∫K at camera vertex `sp`: the light nodes in its kernel,
/// the kernel normalised over the part of the disk on surfaces (without it the estimate
/// falls short within r of every edge).
#[allow(clippy::too_many_arguments)]
fn gather<Q: RayQuery + ?Sized>(
    tracer: &Q,
    pass_data: &FilterPass,
    kernel: &Kernel,
    sp: &SurfacePoint,
    material: &crate::bsdf::Material,
    seed: u64,
    pixel: u32,
    pass: u32,
    counters: &mut Counters,
) -> Rgb {
    let hit = &sp.hit;
    let mut share_rng = SampleStream::for_sample(seed, Stream::Aux, pixel, pass, GATHER_SHARE_KEY);
    let share = kernel.surface_share(tracer, hit, sp.wo, SHARE_STRATA, &mut share_rng);
    counters.rays += (SHARE_STRATA * SHARE_STRATA) as u64;
    if !(share > 0.0) {
        return Rgb::ZERO;
    }
    let wo = sp.frame.to_local(sp.wo);
    let mut gathered = Rgb::ZERO;
    pass_data.grid.query(hit.p, |i| {
        let u = &pass_data.nodes[i as usize];
        let k = kernel.density(hit, sp.wo, u.hit.p, u.hit.ng).0;
        if k > 0.0 {
            gathered += material.eval(wo, sp.frame.to_local(u.wo), TransportMode::Radiance) * pass_data.value(i) * k;
        }
    });
    gathered / share
}
