//! Bidirectional path filtering (Wang, West and Hachisuka 2025, §5, Fig. 3): recursive
//! MMIS (eq. 18–19) over the segments of camera paths and light paths together.
//!
//! Each pass traces one camera path per pixel, as multi-vertex path filtering does, and
//! N_L = β · W·H light paths, as photon filtering does. Both walks are the sequential
//! segment sampler (eq. 15) with virtual perturbation. Every junction of a camera path,
//! and of a light path, then reuses every segment whose start lies in its kernel: the
//! continuations and light samples of camera nodes, and the segments of light paths
//! arriving near it. Each reused segment is divided by the sum of the densities of every
//! technique able to draw it ([`super::bidir`]): the camera continuations and light
//! samples conditioned on the camera nodes around its start, the light continuations
//! conditioned on the light nodes around its end, and the emission. The pixel is the
//! radiance along its camera segment (eq. 19). Each light node also has a twin, a camera
//! node at it with a walk of its own, so that a light junction reuses a continuation
//! drawn from itself as a camera junction does ([`super::bidir`], "Twins"). A camera
//! path meeting a light path inside one kernel is bidirectional photon mapping's merge;
//! a camera path continuing through another camera path's segment is multi-vertex path
//! filtering; a light path through another's, photon filtering; the set of segment paths
//! contains BPM's.
//!
//! The radiance along every segment follows by propagation, as for MVF ([`super::graph`]):
//! a light node's row sits at its predecessor (the light side of its segment), so that
//! radiance flows from the lights through light paths, camera paths, and back, in d
//! sweeps for segment paths of d + 1 segments.
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `footprint` | W·H pixels (none unless r₀ is in pixel footprints) | mean footprint → r₀ |
//! | pass 0 | `paths` | W·H camera paths, then N_L light paths (each light node's twin and its camera walk after its path) | nodes appended, grid built for r_pass |
//! | (pass 0½) | `bridges` (with bridges only) | nodes | bridge nodes appended, grid rebuilt |
//! | pass 1 | `denominators` | nodes | D of every reusable segment |
//! | pass 2 | `filter` | nodes | rows appended; L₀ = L_e |
//! | pass 3 … 2 + d | `propagate` | nodes | L_i from L_{i−1}; after the last, each pixel's L |
//!
//! d = (segments per path) − 1 sweeps; committed with splat factor 1 (no splats).
//!
//! **Bridge segments** ([`crate::estimators::FilterReuse::Bridges`], §6.4 and Fig. 7): each
//! camera node that may take another segment also joins one light node of the pass,
//! drawn uniformly among its M non-Dirac light nodes, by a shadow ray. A bridge is
//! reused like a light segment arriving at the camera node, and its radiance is the
//! light node's reflection toward it, from that node's row. Its technique enters every
//! D as (1 / M) Σ K(c → x) Σ K(l → y) d² / |n_y·ŝ|, which costs nothing beyond the two
//! grid queries each D already makes ([`super::bidir`]); what it adds is pool: one more
//! reusable segment per camera node, so more pairs per row.

use alloc::vec::Vec;

use super::bidir::Bidirectional;
use super::bridge::{bridge_end, trace_bridges};
use super::nodes::{scale_kernels, trace_camera_nodes, trace_light_nodes};
use super::pass::{CHUNK, FilterPass, node_chunk, phase};
use crate::camera::CameraPass;
use crate::estimators::FilterConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::merge::progressive_radius;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage};
use crate::spectrum::Rgb;
use crate::transport::RenderParams;

/// Bidirectional path filtering configured for one film, with the current pass's nodes.
#[derive(Clone, Debug)]
pub struct Bpf {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: FilterConfig,
    /// r₀ (set by the setup phase).
    pub r0: f32,
    /// Segments per path.
    pub segments: u32,
    pixels: u32,
    /// The pass's camera and light nodes (`links`: each pixel's first node; `values`: its
    /// sky radiance).
    pub pass: FilterPass,
    pixel_values: Vec<Rgb>,
    /// With bridges: the pass's bridge ends (node indices), set when its nodes are
    /// gathered.
    bridge_ends: Vec<u32>,
    cursor: Cursor,
}

impl Bpf {
    /// The estimator for a film of `pixels` pixels (r₀ is set by the setup phase).
    pub fn new(params: RenderParams, config: FilterConfig, pixels: u32) -> Self {
        let segments = config.segments(params.max_depth);
        let sweeps = segments.saturating_sub(1) as u8;
        let stages = 3 + sweeps + config.bridges() as u8;
        Self {
            params,
            config,
            r0: 0.0,
            segments,
            pixels,
            pass: FilterPass::default(),
            pixel_values: Vec::new(),
            bridge_ends: Vec::new(),
            cursor: Cursor::new(1, stages),
        }
    }

    /// The phase id of stage `i` of a pass: 1 the paths, [`phase::BRIDGES`], then 2 the
    /// denominators, 3 the rows, 4 … the sweeps.
    fn phase_id(&self, i: u8) -> u8 {
        match (self.config.bridges(), i) {
            (_, 0) => phase::PATHS,
            (true, 1) => phase::BRIDGES,
            (true, i) => i,
            (false, i) => i.saturating_add(1),
        }
    }

    /// The kernel radius of global pass `pass`.
    pub fn radius(&self, pass: u32) -> f32 {
        progressive_radius(self.r0, self.config.alpha, pass)
    }

    /// Light paths per pass, N_L = β · pixels (rounded; at least one where β > 0).
    pub fn light_paths(&self) -> u32 {
        self.config.light_paths(self.pixels)
    }

    /// Do light nodes get twins ([`super::nodes::trace_light_nodes`])? Not with merges
    /// only, whose light junctions follow their own paths.
    pub fn twins(&self) -> bool {
        self.config.reuse != crate::estimators::FilterReuse::Merges
    }

    /// The weights over the current pass.
    pub fn weights<'a>(&'a self, scene: &'a crate::scene::Scene) -> Bidirectional<'a> {
        Bidirectional {
            hood: self.pass.neighbourhood(scene),
            light_paths: self.light_paths() as f64,
            merges_only: self.config.reuse == crate::estimators::FilterReuse::Merges,
            bridge_choice: (self.config.bridges() && !self.bridge_ends.is_empty()).then(|| 1.0 / self.bridge_ends.len() as f64),
        }
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Bpf {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let (nodes, paths) = (self.pass.nodes.len() as u32, self.pixels.saturating_add(self.light_paths()));
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let items = if self.config.radius.needs_footprint() { self.pixels } else { 0 };
                Phase { name: "footprint", id: phase::FOOTPRINT, pass: None, items, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, i) => {
                let (name, id) = match self.phase_id(i) {
                    1 => return Some(Phase { name: "paths", id: phase::PATHS, pass: Some(pass), items: paths, chunk: CHUNK, samples: true }),
                    phase::BRIDGES => ("bridges", phase::BRIDGES),
                    phase::DENOMINATORS => ("denominators", phase::DENOMINATORS),
                    phase::ROWS => ("filter", phase::ROWS),
                    id => ("propagate", id),
                };
                Phase { name, id, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false }
            }
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
        let chunk = out.data.filter_chunk();
        match phase.id {
            phase::PATHS => {
                // Items below W·H are pixels, the rest light paths.
                let p = self.pixels;
                let camera = items.start.min(p)..items.end.min(p);
                let light = items.start.max(p) - p..items.end.max(p) - p;
                let mut c = trace_camera_nodes(scene, tracer, &self.params, self.segments, pass, camera, &mut chunk.nodes, &mut chunk.links, &mut chunk.values);
                if !light.is_empty() {
                    let (pred, base) = &mut chunk.light_scratch;
                    let l = trace_light_nodes(
                        scene,
                        tracer,
                        &self.params,
                        self.segments,
                        self.light_paths(),
                        pass,
                        light,
                        true,
                        self.twins(),
                        &mut chunk.nodes,
                        pred,
                        base,
                    );
                    c += l;
                }
                scale_kernels(scene, self.config.glossy_alpha, &mut chunk.nodes);
                out.counters = c;
            }
            phase::BRIDGES => {
                chunk.nodes.clear();
                out.counters = trace_bridges(scene, tracer, self.params.seed, pass, &self.pass.nodes, &self.bridge_ends, range, &mut chunk.nodes);
            }
            phase::DENOMINATORS => {
                let w = self.weights(scene);
                self.pass.map_denominators(scene, range, &mut chunk.bidir_dens, |_, i| w.denominators(i));
            }
            phase::ROWS => {
                let w = self.weights(scene);
                self.pass.map_rows(scene, range, chunk, |_, i, pairs| w.row::<f32>(i as u32, &self.pass.bidir_dens, pairs));
            }
            _ => self.pass.map_sweep(range, chunk),
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match phase.id {
            phase::FOOTPRINT => self.r0 = self.config.radius.initial_radius(ctx.scene, &crate::estimators::reduce_footprint(outputs)),
            phase::BRIDGES => self.pass.append_nodes(outputs),
            id => {
                self.pass.reduce_phase(id, outputs, self.radius(phase.pass.unwrap_or(0)), self.config.neighbours);
                if id == phase::DENOMINATORS {
                    // A light node's row where its kernel lies, at its predecessor: the
                    // light side's rows (contiguous in grid order) in their predecessors'
                    // order; camera rows stay in node order.
                    self.pass.order_rows(self.pass.light_side(), |pass, v| pass.nodes[v].pred);
                }
                if id == phase::PATHS && self.config.bridges() {
                    self.bridge_ends.clear();
                    self.bridge_ends.extend(self.pass.nodes.iter().enumerate().filter(|(_, n)| bridge_end(n)).map(|(i, _)| i as u32));
                }
            }
        }
        if self.cursor.advance() {
            self.pass.commit_pixels(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, &mut self.pixel_values, film);
        }
    }
}
