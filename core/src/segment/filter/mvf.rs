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

use super::graph::{FilterGraph, Rgb3};
use super::nodes::{NONE, Node, trace_camera_nodes};
use super::weights::{Denominators, Neighbourhood};
use crate::geometry::RayQuery;
use crate::integrator::RenderParams;
use crate::merge::{Footprint, HashGrid, progressive_radius};
use crate::render::{ChunkOutput, Context, Cursor, Film, FilterConfig, Phase, Phased, Stage};
use crate::segment::Kernel;
use crate::spectrum::Rgb;

/// Items per chunk.
const CHUNK: u32 = 1024;

/// What one chunk of a filtering phase produces (reused across passes).
#[derive(Clone, Debug, Default)]
pub struct FilterChunk {
    /// `camera paths`: the chunk's nodes, indices local to it.
    pub nodes: Vec<Node>,
    /// `camera paths`: per pixel, its first node (local) or [`NONE`].
    pub first: Vec<u32>,
    /// `camera paths`: per pixel, the environment radiance if its camera ray escaped.
    pub sky: Vec<Rgb>,
    /// `denominators`: per node.
    pub dens: Vec<Denominators>,
    /// `filter`: the rows of the chunk's nodes (targets global).
    pub rows: FilterGraph<f32>,
    /// `propagate`: L_i of the chunk's nodes.
    pub radiance: Vec<Rgb3<f32>>,
}

impl FilterChunk {
    /// Forget everything, keeping the storage.
    pub fn clear(&mut self) {
        self.nodes.clear();
        self.first.clear();
        self.sky.clear();
        self.dens.clear();
        self.rows.clear();
        self.radiance.clear();
    }

    /// Bytes held (capacity).
    pub fn size_bytes(&self) -> usize {
        self.nodes.capacity() * core::mem::size_of::<Node>()
            + self.first.capacity() * 4
            + self.sky.capacity() * core::mem::size_of::<Rgb>()
            + self.dens.capacity() * core::mem::size_of::<Denominators>()
            + self.rows.size_bytes()
            + self.radiance.capacity() * core::mem::size_of::<Rgb3<f32>>()
    }
}

/// Multi-vertex path filtering configured for one film, with the current pass's nodes.
#[derive(Clone, Debug)]
pub struct Mvf {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: FilterConfig,
    /// r₀ (set by the setup phase).
    pub r0: f32,
    /// The current pass's kernel radius.
    pub r: f32,
    /// Segments per path.
    pub segments: u32,
    pixels: u32,
    /// The pass's nodes, first node and sky per pixel, grid, denominators, rows and L.
    pub nodes: Vec<Node>,
    first: Vec<u32>,
    sky: Vec<Rgb>,
    grid: HashGrid,
    dens: Vec<Denominators>,
    graph: FilterGraph<f32>,
    radiance: Vec<Rgb3<f32>>,
    pixel_values: Vec<Rgb>,
    cursor: Cursor,
}

impl Mvf {
    /// The estimator for a film of `pixels` pixels (r₀ is set by the setup phase).
    pub fn new(params: RenderParams, config: FilterConfig, pixels: u32) -> Self {
        let segments = config.segments(params.max_depth);
        let sweeps = segments.saturating_sub(1).min(250) as u8;
        Self {
            params,
            config,
            r0: 0.0,
            r: 0.0,
            segments,
            pixels,
            nodes: Vec::new(),
            first: Vec::new(),
            sky: Vec::new(),
            grid: HashGrid::new(),
            dens: Vec::new(),
            graph: FilterGraph::new(),
            radiance: Vec::new(),
            pixel_values: Vec::new(),
            cursor: Cursor::new(1, 3 + sweeps),
        }
    }

    /// The kernel radius of global pass `pass`.
    pub fn radius(&self, pass: u32) -> f32 {
        progressive_radius(self.r0, self.config.alpha, pass)
    }

    /// Bytes held by the pass's nodes, grid, denominators, rows and radiance.
    pub fn size_bytes(&self) -> usize {
        self.nodes.capacity() * core::mem::size_of::<Node>()
            + (self.first.capacity()) * 4
            + self.sky.capacity() * core::mem::size_of::<Rgb>()
            + self.grid.size_bytes()
            + self.dens.capacity() * core::mem::size_of::<Denominators>()
            + self.graph.size_bytes()
            + self.radiance.capacity() * core::mem::size_of::<Rgb3<f32>>()
    }

    /// Reused segments (row entries) of the last pass.
    pub fn pairs(&self) -> usize {
        self.graph.targets.len()
    }

    fn neighbourhood<'a>(&'a self, scene: &'a crate::scene::Scene) -> Neighbourhood<'a> {
        Neighbourhood { scene, nodes: &self.nodes, grid: &self.grid, kernel: Kernel::Disk { radius: self.r } }
    }

    /// Each pixel's estimate from the current L: L of the node its camera ray reached.
    fn commit(&mut self, film: &mut Film) {
        self.pixel_values.clear();
        for (&f, &sky) in self.first.iter().zip(&self.sky) {
            let v = if f == NONE { sky } else { self.radiance.get(f as usize).map_or(Rgb::ZERO, |l| Rgb::new(l[0], l[1], l[2])) };
            self.pixel_values.push(v);
        }
        film.set_camera_samples(0..self.pixels, &self.pixel_values);
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Mvf {
    fn next_phase(&self) -> Option<Phase> {
        let nodes = self.nodes.len() as u32;
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let items = if self.config.radius.needs_footprint() { self.pixels } else { 0 };
                Phase { name: "footprint", id: 0, pass: None, items, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, 0) => Phase { name: "camera paths", id: 1, pass: Some(pass), items: self.pixels, chunk: CHUNK, samples: true },
            Stage::Pass(pass, 1) => Phase { name: "denominators", id: 2, pass: Some(pass), items: nodes, chunk: CHUNK, samples: false },
            Stage::Pass(pass, 2) => Phase { name: "filter", id: 3, pass: Some(pass), items: nodes, chunk: CHUNK, samples: false },
            Stage::Pass(pass, i) => Phase { name: "propagate", id: i.saturating_add(1), pass: Some(pass), items: nodes, chunk: CHUNK, samples: false },
        })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer) = (ctx.scene, ctx.tracer);
        let items = out.items.clone();
        if phase.id == 0 {
            Footprint::map_chunk(scene, tracer, out);
            return;
        }
        let Some(pass) = phase.pass else { return };
        let chunk = out.filter_chunk();
        let range = items.start as usize..items.end as usize;
        let counters = match phase.id {
            1 => trace_camera_nodes(scene, tracer, &self.params, self.segments, pass, items, &mut chunk.nodes, &mut chunk.first, &mut chunk.sky),
            2 => {
                let hood = self.neighbourhood(scene);
                chunk.dens.extend(self.nodes[range].iter().map(|u| hood.denominators(u)));
                Default::default()
            }
            3 => {
                let hood = self.neighbourhood(scene);
                let mut pairs = Vec::new();
                for v in &self.nodes[range] {
                    let (emission, direct) = hood.row::<f32>(v, &self.dens, &mut pairs);
                    chunk.rows.push_row(emission, direct, pairs.iter().copied());
                }
                Default::default()
            }
            _ => {
                self.graph.sweep(Some(&self.radiance), range, &mut chunk.radiance);
                Default::default()
            }
        };
        out.counters = counters;
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match phase.id {
            0 => self.r0 = self.config.radius.initial_radius(ctx.scene, &Footprint::reduce_chunks(outputs)),
            1 => {
                self.nodes.clear();
                self.first.clear();
                self.sky.clear();
                for out in outputs.iter_mut() {
                    let chunk = out.filter_chunk();
                    let offset = self.nodes.len() as u32;
                    let shift = |i: u32| if i == NONE { NONE } else { i + offset };
                    self.nodes.extend(chunk.nodes.iter().map(|n| {
                        let mut n = *n;
                        n.next.node = shift(n.next.node);
                        n
                    }));
                    self.first.extend(chunk.first.iter().map(|&i| shift(i)));
                    self.sky.extend_from_slice(&chunk.sky);
                }
                debug_assert!(self.nodes.iter().all(|n| n.next.node == NONE || (n.next.node as usize) < self.nodes.len()), "node index out of range");
                self.r = self.radius(phase.pass.unwrap_or(0));
                // The disk kernel's support (within r of the tangent plane, inside the disk)
                // reaches √2 r from its centre.
                self.grid.build(self.nodes.iter().map(|n| n.hit.p), self.r * core::f32::consts::SQRT_2);
            }
            2 => {
                self.dens.clear();
                for out in outputs.iter_mut() {
                    self.dens.extend_from_slice(&out.filter_chunk().dens);
                }
            }
            3 => {
                self.graph.clear();
                for out in outputs.iter_mut() {
                    self.graph.append(&out.filter_chunk().rows, 0);
                }
                self.radiance.clear();
                self.radiance.extend_from_slice(&self.graph.emission);
            }
            _ => {
                self.radiance.clear();
                for out in outputs.iter_mut() {
                    self.radiance.extend_from_slice(&out.filter_chunk().radiance);
                }
            }
        }
        // The pass ends after `filter` (no sweep) or after the last sweep: L is final.
        if self.cursor.advance() {
            self.commit(film);
            film.end_pass(1.0);
        }
    }
}
