//! Multi-vertex path filtering's phases (the render protocol, [`crate::render`]):
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `footprint` | W·H pixels (none unless r₀ is in pixel footprints) | mean footprint → r₀ |
//! | pass 0 | `camera paths` | W·H pixels | nodes appended (indices shifted), grid over their ends built for r_pass |
//! | pass 1 | `denominators` | nodes | D of each node's continuation and light segment |
//! | pass 2 | `filter` | nodes | rows appended; L₀ = L_e |
//! | pass 3 … 2 + d | `propagate` | nodes | L_i from L_{i−1}; after the last, each pixel's L of its camera segment |
//!
//! d = (segments per path) − 1 sweeps; the pass is committed with splat factor 1 (no splats).

use alloc::vec::Vec;

use super::nodes::{scale_kernels, trace_camera_nodes};
use super::pass::{CHUNK, FilterPass, node_chunk, phase};
use crate::camera::CameraPass;
use crate::estimators::FilterConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::merge::progressive_radius;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage};
use crate::spectrum::Rgb;
use crate::transport::RenderParams;

/// Multi-vertex path filtering configured for one film, with the current pass's nodes.
#[derive(Clone, Debug)]
pub struct Mvf {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: FilterConfig,
    /// r₀ (set by the setup phase).
    pub r0: f32,
    /// Segments per path.
    pub segments: u32,
    pixels: u32,
    /// The pass's nodes (`links`: each pixel's first node; `values`: its sky radiance).
    pub pass: FilterPass,
    pixel_values: Vec<Rgb>,
    cursor: Cursor,
}

impl Mvf {
    /// The estimator for a film of `pixels` pixels (r₀ is set by the setup phase).
    pub fn new(params: RenderParams, config: FilterConfig, pixels: u32) -> Self {
        let segments = config.segments(params.max_depth);
        let sweeps = segments.saturating_sub(1) as u8;
        Self { params, config, r0: 0.0, segments, pixels, pass: FilterPass::default(), pixel_values: Vec::new(), cursor: Cursor::new(1, 3 + sweeps) }
    }

    /// The kernel radius of global pass `pass`.
    pub fn radius(&self, pass: u32) -> f32 {
        progressive_radius(self.r0, self.config.alpha, pass)
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Mvf {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let (nodes, paths) = (self.pass.nodes.len() as u32, self.pixels);
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let items = if self.config.radius.needs_footprint() { self.pixels } else { 0 };
                Phase { name: "footprint", id: phase::FOOTPRINT, pass: None, items, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, 0) => Phase { name: "camera paths", id: phase::PATHS, pass: Some(pass), items: self.pixels, chunk: CHUNK, samples: true },
            Stage::Pass(pass, 1) => {
                Phase { name: "denominators", id: phase::DENOMINATORS, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false }
            }
            Stage::Pass(pass, 2) => Phase { name: "filter", id: phase::ROWS, pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false },
            Stage::Pass(pass, i) => {
                Phase { name: "propagate", id: i.saturating_add(1), pass: Some(pass), items: nodes, chunk: node_chunk(nodes, paths), samples: false }
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
                let c = trace_camera_nodes(scene, tracer, &self.params, self.segments, pass, items, &mut chunk.nodes, &mut chunk.links, &mut chunk.values);
                scale_kernels(scene, self.config.glossy_alpha, &mut chunk.nodes);
                out.counters = c;
            }
            phase::DENOMINATORS => self.pass.map_denominators(scene, range, &mut chunk.dens, |hood, i| hood.denominators(i)),
            phase::ROWS => self.pass.map_rows(scene, range, chunk, |hood, i, pairs| hood.row::<f32>(&self.pass.nodes[i], &self.pass.dens, pairs)),
            _ => self.pass.map_sweep(range, chunk),
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match phase.id {
            phase::FOOTPRINT => self.r0 = self.config.radius.initial_radius(ctx.scene, &crate::estimators::reduce_footprint(outputs)),
            id => self.pass.reduce_phase(id, outputs, self.radius(phase.pass.unwrap_or(0)), self.config.neighbours),
        }
        // The pass ends after `filter` (no sweep) or after the last sweep: L is final.
        if self.cursor.advance() {
            self.pass.commit_pixels(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, &mut self.pixel_values, film);
        }
    }
}
