//! LVCBPT's phases (the render protocol, [`crate::render`]):
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `c̄ probe` | `probe_paths` preprocessing light paths | c̄ = Σ cacheable / paths → strategy counts |
//! | pass 0 | `light paths` | M light paths (t = 1 splats) | paths appended in order, cache built, splats staged |
//! | pass 1 | `camera` | W·H pixels | camera samples staged; pass committed with splat factor 1/M |

use alloc::vec::Vec;

use super::{PassInputs, StrategyCounts, count_cacheable, render_pixels, trace_light_paths};
use crate::camera::CameraPass;
use crate::estimators::LvcbptConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::path::{CacheEntry, LightPaths};
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage, chunk_for};
use crate::transport::RenderParams;

/// Light paths per chunk.
const CHUNK: u32 = 1024;

/// LVCBPT configured for one film: settings, the strategy counts (after setup) and the
/// current pass's light paths and cache.
#[derive(Clone, Debug)]
pub struct Lvcbpt {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: LvcbptConfig,
    /// M.
    pub light_paths: u32,
    pixels: u32,
    /// The strategies' sample counts (fixed by the setup phase).
    pub counts: StrategyCounts,
    /// The current pass's light paths.
    pub paths: LightPaths,
    /// The current pass's cache.
    pub cache: Vec<CacheEntry>,
    cursor: Cursor,
}

impl Lvcbpt {
    /// LVCBPT for a film of `pixels` pixels (the counts are set by the setup phase).
    pub fn new(params: RenderParams, config: LvcbptConfig, pixels: u32) -> Self {
        let light_paths = config.light_paths_for(pixels);
        let counts = StrategyCounts::new(light_paths, config.connections, pixels, 1.0);
        Self { params, config, light_paths, pixels, counts, paths: LightPaths::new(), cache: Vec::new(), cursor: Cursor::new(1, 2) }
    }

    /// Bytes held by the pass's light paths and cache.
    pub fn size_bytes(&self) -> usize {
        self.paths.size_bytes() + self.cache.capacity() * core::mem::size_of::<CacheEntry>()
    }
}

/// LVCBPT's phase ids: the c̄ probe (setup), then per pass the light paths and the camera.
mod phase {
    pub const PROBE: u8 = 0;
    pub const LIGHT_PATHS: u8 = 1;
    pub const CAMERA: u8 = 2;
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Lvcbpt {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => Phase { name: "c̄ probe", id: phase::PROBE, pass: None, items: self.config.probe_paths, chunk: CHUNK, samples: false },
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
            (phase::PROBE, _) => {
                let (n, counters) = count_cacheable(scene, tracer, params, items);
                out.data = PhaseData::Count(n);
                out.counters = counters;
            }
            (phase::LIGHT_PATHS, Some(pass)) => {
                // The splat list is taken out while the light-path store is borrowed.
                let mut splats = core::mem::take(&mut out.splats);
                let (paths, _) = out.data.light_paths();
                out.counters = trace_light_paths(scene, tracer, params, &self.counts, pass, items, paths, &mut |s| splats.push(s));
                out.splats = splats;
            }
            (phase::CAMERA, Some(pass)) => {
                let inputs = PassInputs {
                    paths: &self.paths,
                    cache: &self.cache,
                    light_paths: self.light_paths,
                    connections: self.config.connections,
                    counts: self.counts,
                };
                out.counters = render_pixels(scene, tracer, params, &inputs, pass, items, out.pixel_buffer());
            }
            _ => {}
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match phase.id {
            phase::PROBE => {
                let cacheable: u64 = outputs.iter().map(|o| if let PhaseData::Count(n) = o.data { n } else { 0 }).sum();
                let mean = cacheable as f64 / self.config.probe_paths.max(1) as f64;
                self.counts = StrategyCounts::new(self.light_paths, self.config.connections, self.pixels, mean);
            }
            phase::LIGHT_PATHS => {
                self.paths.clear();
                self.cache.clear();
                for out in outputs.iter() {
                    if let PhaseData::LightPaths { paths, .. } = &out.data {
                        self.paths.append(paths);
                    }
                    film.push_splats(&out.splats);
                }
                crate::path::cacheable_entries(ctx.scene, &self.paths, &mut self.cache);
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
