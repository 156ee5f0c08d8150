//! The merging estimators' phases (the render protocol, [`crate::render`]):
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `footprint` | W·H pixels (none unless r₀ is in pixel footprints) | mean footprint → r₀ |
//! | pass 0 | `light paths` | N_L light paths (t = 1 splats in VCM) | paths and prefix sums appended in order, photons collected, grid built for r_pass |
//! | pass 1 | `camera` | W·H pixels | camera samples staged; pass committed with splat factor 1/N_L |

use alloc::vec::Vec;

use super::mis::Techniques;
use super::{MergeMode, PassInputs, Photon, photon_position, render_pixels, trace_light_paths};
use crate::camera::CameraPass;
use crate::estimators::MergingConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::merge::{HashGrid, progressive_radius};
use crate::path::{CacheEntry, LightPaths};
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage, chunk_for};
use crate::transport::RenderParams;

/// Items per chunk.
const CHUNK: u32 = 1024;

/// PPM, BPM or VCM configured for one film, with the current pass's light paths,
/// photons and grid.
#[derive(Clone, Debug)]
pub struct Vcm {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// Which estimator.
    pub mode: MergeMode,
    /// The configuration it was built with.
    pub config: MergingConfig,
    /// N_L.
    pub light_paths: u32,
    pixels: u32,
    /// r₀ (set by the setup phase).
    pub r0: f32,
    /// The current pass's light paths.
    pub paths: LightPaths,
    /// Their prefix sums, one per vertex.
    pub prefix: Vec<f64>,
    /// The current pass's photons.
    pub photons: Vec<CacheEntry>,
    /// The grid over them.
    pub grid: HashGrid,
    /// What merges read of them, in the grid's slot order.
    pub records: Vec<Photon>,
    cursor: Cursor,
}

impl Vcm {
    /// The estimator for a film of `pixels` pixels (r₀ is set by the setup phase).
    pub fn new(params: RenderParams, mode: MergeMode, config: MergingConfig, pixels: u32) -> Self {
        Self {
            params,
            mode,
            config,
            light_paths: config.light_paths_for(pixels),
            pixels,
            r0: 0.0,
            paths: LightPaths::new(),
            prefix: Vec::new(),
            photons: Vec::new(),
            grid: HashGrid::new(),
            records: Vec::new(),
            cursor: Cursor::new(1, 2),
        }
    }

    /// The merging radius of global pass `pass`.
    pub fn radius(&self, pass: u32) -> f32 {
        progressive_radius(self.r0, self.config.alpha, pass)
    }

    /// The techniques' counts in pass `pass`.
    pub fn techniques(&self, pass: u32) -> Techniques {
        let r = self.radius(pass) as f64;
        let eta = self.light_paths as f64 * core::f64::consts::PI * r * r;
        let connect = self.mode == MergeMode::Vcm && self.config.connections;
        let merge = self.config.merges(self.mode);
        let c = if connect { 1.0 } else { 0.0 };
        Techniques {
            emission: 1.0,
            next_event: c,
            light_tracing: c * self.light_paths as f64 / self.pixels.max(1) as f64,
            connection: c,
            merge: if merge { eta } else { 0.0 },
        }
    }

    /// Bytes held by the pass's light paths, prefix sums, photons and grid.
    pub fn size_bytes(&self) -> usize {
        self.paths.size_bytes()
            + self.prefix.capacity() * core::mem::size_of::<f64>()
            + self.photons.capacity() * core::mem::size_of::<CacheEntry>()
            + self.grid.size_bytes()
            + self.records.capacity() * core::mem::size_of::<Photon>()
    }
}

/// The merging estimators' phase ids: the footprint (setup), then per pass the light paths and the camera.
mod phase {
    pub const FOOTPRINT: u8 = 0;
    pub const LIGHT_PATHS: u8 = 1;
    pub const CAMERA: u8 = 2;
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Vcm {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let items = if self.config.merges(self.mode) && self.config.radius.needs_footprint() { self.pixels } else { 0 };
                Phase { name: "footprint", id: phase::FOOTPRINT, pass: None, items, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, 0) => Phase {
                name: "light paths",
                id: phase::LIGHT_PATHS,
                pass: Some(pass),
                items: self.light_paths,
                chunk: chunk_for(self.light_paths),
                samples: true,
            },
            Stage::Pass(pass, _) => {
                Phase { name: "camera", id: phase::CAMERA, pass: Some(pass), items: self.pixels, chunk: chunk_for(self.pixels), samples: true }
            }
        })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer, params) = (ctx.scene, ctx.tracer, &self.params);
        let items = out.items.clone();
        match (phase.id, phase.pass) {
            (phase::FOOTPRINT, _) => crate::estimators::map_footprint(scene, tracer, out),
            (phase::LIGHT_PATHS, Some(pass)) => {
                let tech = self.techniques(pass);
                let mut splats = core::mem::take(&mut out.splats);
                let (paths, sums) = out.data.paths_with_sums();
                out.counters = trace_light_paths(scene, tracer, params, &tech, pass, items, paths, sums, &mut |s| splats.push(s));
                out.splats = splats;
            }
            (phase::CAMERA, Some(pass)) => {
                let inputs = PassInputs {
                    paths: &self.paths,
                    prefix: &self.prefix,
                    photons: &self.records,
                    grid: &self.grid,
                    tech: self.techniques(pass),
                    light_paths: self.light_paths,
                };
                out.counters = render_pixels(scene, tracer, params, self.mode, &inputs, pass, items, out.pixel_buffer());
            }
            _ => {}
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match (phase.id, phase.pass) {
            (phase::FOOTPRINT, _) => self.r0 = self.config.radius.initial_radius(ctx.scene, &crate::estimators::reduce_footprint(outputs)),
            (phase::LIGHT_PATHS, pass) => {
                self.paths.clear();
                self.prefix.clear();
                self.photons.clear();
                for out in outputs.iter() {
                    if let PhaseData::PathsWithSums { paths, sums } = &out.data {
                        self.paths.append(paths);
                        self.prefix.extend_from_slice(sums);
                    }
                    film.push_splats(&out.splats);
                }
                let pass = pass.unwrap_or(0);
                let tech = self.techniques(pass);
                self.records.clear();
                // Without merging (VCM with it left out) no photon, grid or record is
                // built: their memory is never allocated.
                if tech.merge > 0.0 {
                    crate::path::cacheable_entries(ctx.scene, &self.paths, &mut self.photons);
                    let paths = &self.paths;
                    self.grid.build(self.photons.iter().map(|e| photon_position(paths, e)), self.radius(pass));
                    // The records in slot order, built in the photons' own (path) order.
                    let weighted = (self.mode != MergeMode::Ppm).then_some(&tech);
                    self.records.resize(self.grid.len(), Photon::default());
                    for (e, &k) in self.photons.iter().zip(self.grid.slot_of()) {
                        if let Some(record) = self.records.get_mut(k as usize) {
                            *record = Photon::new(ctx.scene, weighted, &self.paths, &self.prefix, e);
                        }
                    }
                }
            }
            _ => {
                for out in outputs.iter() {
                    film.set_camera_samples(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
                }
            }
        }
        if self.cursor.advance() {
            film.end_pass(1.0 / self.light_paths.max(1) as f64);
        }
    }
}
